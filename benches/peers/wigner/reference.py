#!/usr/bin/env python3
"""High-accuracy SciPy reference for the Wigner-mirage peer comparison.

Physical case ("water", flat earth, 2-D in (x, y), y up):
    T(h)  = 10.033 + 3.15 exp(-20.1 h)  [deg C]
    n - 1 = 0.079386 / (T + 273.15)     (constant pressure)
This is exactly the upstream Eikonal::getWaterRefract with its CLI defaults
tempAmb = 10, tempBase = 13:  T = 10 + 3 (0.011 + 1.05 exp(-20.1 h)).

The ray is integrated as y(x):  y'' = (1 + y'^2) (dn/dy) / n, which follows
from the Snell invariant n cos(theta) = const (flat earth, n = n(y)).
A ray that meets y = 0 before x_target is stopped there and flagged "ground".

Writes fan_reference.json next to this file (full double precision).

Usage:  python3 reference.py            (needs numpy + scipy)
"""
import json
import math
import os
import sys
import time
import warnings

import numpy as np
import scipy
from scipy.integrate import solve_ivp

A = 0.079386          # 7.86e-4 * 101 (kPa): n - 1 = A / T_K
T0 = 10.033 + 273.15  # K, far-field temperature
DT = 3.15             # K, surface excess
K = 20.1              # 1/m, decay rate

X_TARGET = 3000.0
ORIGIN = (0.0, 1.1)
RTOL = 1e-13
ATOL = 1e-15
METHOD = "DOP853"


def n_and_dndy(y):
    e = math.exp(-K * y)
    tk = T0 + DT * e
    n = 1.0 + A / tk
    dndy = A * DT * K * e / (tk * tk)
    return n, dndy


def rhs_yx(x, s):
    y, p = s
    n, dndy = n_and_dndy(y)
    return [p, (1.0 + p * p) * dndy / n]


def ground(x, s):
    return s[0]


ground.terminal = True
ground.direction = -1


def trace_yx(angle_deg, rtol=RTOL, atol=ATOL):
    """Return (y(X_TARGET), dy/dx(X_TARGET), hit_ground, x_end, nfev)."""
    p0 = math.tan(math.radians(angle_deg))
    sol = solve_ivp(rhs_yx, (0.0, X_TARGET), [ORIGIN[1], p0], method=METHOD,
                    rtol=rtol, atol=atol, events=ground)
    if sol.status == 1 and len(sol.t_events[0]) > 0:
        return (float(sol.y_events[0][0][0]), float(sol.y_events[0][0][1]),
                True, float(sol.t_events[0][0]), sol.nfev)
    if sol.status != 0:
        raise RuntimeError(sol.message)
    return float(sol.y[0, -1]), float(sol.y[1, -1]), False, float(sol.t[-1]), sol.nfev


def trace_tau(angle_deg, rtol=RTOL, atol=ATOL):
    """Cross-check: full ray equation in the optical parameter tau,
    dr/dtau = v, dv/dtau = n grad n, v = n t; event at x = X_TARGET."""
    a = math.radians(angle_deg)
    n0, _ = n_and_dndy(ORIGIN[1])

    def f(tau, s):
        x, y, vx, vy = s
        n, dndy = n_and_dndy(y)
        return [vx, vy, 0.0, n * dndy]

    def at_x(tau, s):
        return s[0] - X_TARGET

    at_x.terminal = True
    s0 = [ORIGIN[0], ORIGIN[1], n0 * math.cos(a), n0 * math.sin(a)]
    sol = solve_ivp(f, (0.0, 2.0 * X_TARGET), s0, method=METHOD, rtol=rtol,
                    atol=atol, events=[at_x, ground])
    if len(sol.t_events[0]) == 0:
        raise RuntimeError("tau integration did not reach x_target")
    x, y, vx, vy = sol.y_events[0][0]
    return float(y), float(vy / vx)


def single_ray_quadrature(angle_deg):
    """Independent check of one ray (no ODE solver): with the Snell invariant
    C = n cos(theta), dx/dy = C / sqrt(n^2 - C^2). Integrate down to the
    turning height y_min (n(y_min) = C; substitution y = y_min + u^2 removes
    the square-root singularity) and back up, then solve x(Y) = X_TARGET.
    Only valid for a ray that turns before reaching the ground."""
    from scipy.integrate import quad
    from scipy.optimize import brentq
    th = math.radians(angle_deg)
    nm1 = lambda y: A / (T0 + DT * math.exp(-K * y))
    cm1 = nm1(ORIGIN[1]) * math.cos(th) - 2.0 * math.sin(th / 2) ** 2  # C - 1
    ymin = brentq(lambda y: nm1(y) - cm1, 0.0, ORIGIN[1], xtol=1e-16, rtol=8.9e-16)
    c = 1.0 + cm1

    def g(u):
        y = ymin + u * u
        s = 2.0 + nm1(y) + cm1
        if u < 1e-7 or nm1(y) <= cm1:  # limit u -> 0 (relative error < 1e-12 here)
            _, dndy = n_and_dndy(ymin)
            return 2.0 * c / math.sqrt(s * dndy)
        return 2.0 * u * c / math.sqrt((nm1(y) - cm1) * s)

    def x_of(y):
        return quad(g, 0.0, math.sqrt(y - ymin), epsabs=0.0, epsrel=1.2e-14, limit=500)[0]

    xd = x_of(ORIGIN[1])
    return brentq(lambda y: xd + x_of(y) - X_TARGET, ymin + 1e-3, 50.0, xtol=1e-14, rtol=8.9e-16)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    expected = 5.0786772251

    y1, p1, g1, _, nfev1 = trace_yx(-0.12)
    y1t, p1t = trace_tau(-0.12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # quad's round-off warning near 1e-14
        y1q = single_ray_quadrature(-0.12)
    print(f"single ray -0.12 deg: y(3000) = {y1:.10f} m  (y(x) DOP853, nfev {nfev1})")
    print(f"                      y(3000) = {y1t:.10f} m  (tau form, event at x=3000)")
    print(f"                      y(3000) = {y1q:.10f} m  (quadrature of the Snell invariant)")
    print(f"                      expected  {expected:.10f}  -> "
          f"{'OK' if round(y1, 10) == expected else 'MISMATCH'}"
          f"  |y(x) - tau| = {abs(y1 - y1t):.2e} m, |y(x) - quad| = {abs(y1 - y1q):.2e} m")

    angles = np.linspace(-0.04, -0.14, 1000)
    t0 = time.perf_counter()
    ys, ps, gs, nfev = [], [], [], 0
    for a in angles:
        y, p, g, _, nf = trace_yx(float(a))
        ys.append(y); ps.append(p); gs.append(g); nfev += nf
    dt = time.perf_counter() - t0
    print(f"fan: 1000 rays in {dt:.1f} s, mean nfev/ray {nfev / 1000:.0f}, "
          f"ground hits {sum(gs)}, y range [{min(ys):.6f}, {max(ys):.6f}] m")

    # Self-consistency: the same fan at rtol 1e-11 (100x looser).
    loose = [trace_yx(float(a), rtol=1e-11, atol=1e-13)[0] for a in angles]
    dev = max(abs(a - b) for a, b in zip(ys, loose))
    print(f"self-check: max |y(rtol 1e-13) - y(rtol 1e-11)| = {dev:.2e} m")

    out = {
        "x_target": X_TARGET,
        "origin": list(ORIGIN),
        "angles_deg": [float(a) for a in angles],
        "y": ys,
        "dy_dx": ps,
        "ground": gs,
        "method": (f"scipy {scipy.__version__} solve_ivp {METHOD} on y(x): "
                   "y'' = (1+y'^2) n_y/n; n-1 = 0.079386/(T+273.15), "
                   "T = 10.033 + 3.15 exp(-20.1 y); terminal event y = 0 (ground: "
                   "y, dy_dx are then the values at the ground point)"),
        "rtol": RTOL,
        "atol": ATOL,
        "single_ray": {"angle_deg": -0.12, "y": y1, "dy_dx": p1, "y_tau_form": y1t,
                       "y_quadrature": y1q},
    }
    path = os.path.join(here, "fan_reference.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=0)
        fh.write("\n")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
