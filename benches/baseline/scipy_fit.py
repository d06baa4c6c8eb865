#!/usr/bin/env python3
"""By-hand baseline for mirage: the same fit, written the way a scientist would in SciPy.

    python scipy_fit.py PROBLEM.json [--rtol R] [--method RK45|DOP853] [--max-time S]
    python scipy_fit.py PROBLEM.json --trace-only     # F of the file's medium, no fit

It implements the contract of ``docs/model.md`` independently of mirage:

* the logistic medium (background, inversion, areal hot spots), with δ and its
  analytic gradient and an overflow-safe logistic function;
* rays by ``scipy.integrate.solve_ivp`` on the arc-length form of the ray equation
  (``dx/ds = v/n, dv/ds = ∇n``), with a terminal event for the pair's target plane,
  so the endpoint is located on the integrator's dense output; ``max_length`` is
  4 × |target − origin|;
* the stacked residuals ``w_i (e_i − target_i)`` over the problem's ``free``
  parameters, minimised by ``scipy.optimize.least_squares`` with a 2-point
  finite-difference Jacobian, starting from the file's medium, inside its bounds.

It prints one JSON object: the final objective F = ½ Σ|r_i|² (evaluated by this
script's own tracer at the fit's tolerance, and again at a tight reference
tolerance, ``objective_ref``, so fits made at different tolerances can be compared
on one scale), the fitted parameters, evaluation counts, wall time, tolerances and
the solver's status.

This is meant to be a faithful, straightforward implementation: idiomatic NumPy,
no JIT, no vectorisation across rays, no hand-written Jacobian, one process.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

C = 0.003  # docs/model.md: δ = C·|k_s|·D/S
DEFAULT_EDGE = 10.0  # docs/model.md: hot spot rim sharpness, 1/m
REF_RTOL = 1e-13  # tolerance of the reference tracer used for objective_ref
REF_METHOD = "DOP853"  # high order: the reference F costs a few rays, not a fit


# --------------------------------------------------------------------------------------
# The medium
# --------------------------------------------------------------------------------------


def sigmoid(t):
    """Logistic σ(t) and its derivative σ'(t) = σ(1 − σ), from e^(−|t|).

    Written with e^(−|t|) so that no finite t overflows (docs/model.md), and σ' as
    e/(1+e)² rather than σ(1−σ), which would cancel to 0 for large t.
    """
    e = np.exp(-np.abs(t))
    inv = 1.0 / (1.0 + e)
    s = np.where(t >= 0.0, inv, e * inv)
    return s, e * inv * inv


class Medium:
    """The logistic refractive model of docs/model.md, built from a problem's medium dict.

    Terms that the dict does not have are not modelled (absent from D and from S).
    """

    def __init__(self, m: dict):
        self.k = abs(float(m.get("scale", 1.0)))
        bg, inv, hots = m.get("background"), m.get("inversion"), m.get("hotspots") or []
        self.bg = (float(bg["n"]), float(bg["a"])) if bg else None
        self.inv = (float(inv["n"]), float(inv["a"]), float(inv["height"])) if inv else None
        # Hot spots as arrays, so every spot is evaluated in one NumPy expression.
        self.hx = np.array([float(h["x"]) for h in hots])
        self.hz = np.array([float(h["z"]) for h in hots])
        self.hR = np.array([float(h["radius"]) for h in hots])
        self.hn = np.array([float(h["n"]) for h in hots])
        self.ha = np.array([float(h["a"]) for h in hots])
        self.he = np.array([float(h.get("edge", DEFAULT_EDGE)) for h in hots])
        rates = [t[1] for t in (self.bg, self.inv) if t] + list(self.ha)
        if any(a == 0.0 for a in rates):
            raise ValueError("a rate `a` is zero")
        S = (abs(self.bg[0]) if self.bg else 0.0) + (abs(self.inv[0]) if self.inv else 0.0)
        S += float(np.sum(np.abs(self.hn)))
        if S == 0.0:
            raise ValueError("all amplitudes are zero")
        self.factor = C * self.k / S
        self.has_hot = len(hots) > 0

    def delta_grad(self, p):
        """δ(p) and ∇δ(p) (a 3-vector) at one point p = (x, y, z)."""
        x, y, z = p
        D = 0.0
        gx = gy = gz = 0.0
        if self.bg is not None:
            n, a = self.bg
            s, ds = sigmoid(y / a)
            D += n * s
            gy += n * ds / a
        if self.inv is not None:
            n, a, h = self.inv
            s, ds = sigmoid((h - y) / a)
            D += n * s
            gy -= n * ds / a
        if self.has_hot:
            dx, dz = x - self.hx, z - self.hz
            rho = np.hypot(dx, dz)
            # Rim weight w = 1 − σ(e(ρ − R)) = σ(−e(ρ − R)); dw/dρ = −e σ'(e(ρ − R)).
            w, dsr = sigmoid(-self.he * (rho - self.hR))
            dw = -self.he * dsr
            sy, dsy = sigmoid(y / self.ha)
            # At ρ = 0 (the cone tip) the horizontal derivative is taken as 0.
            safe = np.where(rho > 0.0, rho, 1.0)
            ux, uz = np.where(rho > 0.0, dx / safe, 0.0), np.where(rho > 0.0, dz / safe, 0.0)
            D += np.sum(self.hn * w * sy)
            gx += np.sum(self.hn * dw * ux * sy)
            gz += np.sum(self.hn * dw * uz * sy)
            gy += np.sum(self.hn * w * dsy / self.ha)
        f = self.factor
        return f * D, np.array([f * gx, f * gy, f * gz])


# --------------------------------------------------------------------------------------
# Rays and point pairs
# --------------------------------------------------------------------------------------


class RoundEarth:
    """A medium over the sphere of radius R touching y = 0 at the origin (docs/air.md,
    "How mirage implements the round earth"): δ is evaluated at (x, h, z), h the height
    above the sphere, and ∇δ = (∂δ/∂x, 0, ∂δ/∂z) + ∂δ/∂h · ∇h."""

    def __init__(self, medium, radius):
        self.medium, self.R = medium, float(radius)
        self.centre = np.array([0.0, -self.R, 0.0])

    def height(self, p):
        x, y, z = p
        return (x * x + z * z + y * (2.0 * self.R + y)) / (np.linalg.norm(p - self.centre) + self.R)

    def up(self, p):
        d = p - self.centre
        return d / np.linalg.norm(d)

    def delta_grad(self, p):
        p = np.asarray(p, float)
        d, g = self.medium.delta_grad(np.array([p[0], self.height(p), p[2]]))
        return d, np.array([g[0], 0.0, g[2]]) + g[1] * self.up(p)


class Pair:
    """A point pair: launch direction, target plane (normal = horizontal target − origin,
    horizontal at the target: perpendicular to its local vertical over the round earth)."""

    def __init__(self, d: dict, earth=None):
        self.origin = np.asarray(d["origin"], float)
        self.target = np.asarray(d["target"], float)
        through = np.asarray(d["through"], float)
        self.weight = float(d.get("weight", 1.0))
        self.direction = (through - self.origin) / np.linalg.norm(through - self.origin)
        m = self.target - self.origin
        if earth is None:
            m[1] = 0.0
        else:
            up = earth.up(self.target)
            m = m - (m @ up) * up
        if np.linalg.norm(m) == 0.0:
            raise ValueError("target straight above or below origin")
        self.normal = m / np.linalg.norm(m)
        self.max_length = 4.0 * float(np.linalg.norm(self.target - self.origin))


def ray_rhs(s, state, medium):
    """Arc-length form of the ray equation: dx/ds = v/n, dv/ds = ∇n = ∇δ."""
    delta, grad = medium.delta_grad(state[:3])
    return np.concatenate((state[3:] / (1.0 + delta), grad))


def trace(medium, pair, rtol, atol, method):
    """Trace one pair's ray to its target plane.

    Returns (endpoint, unreachable, number of RHS evaluations). The endpoint is where
    the ray first crosses the plane, found by solve_ivp's event location on the
    step's dense output. A ray that does not reach the plane within max_length
    ends at its traced point nearest the plane (docs/model.md), so F stays finite.
    """
    delta0, _ = medium.delta_grad(pair.origin)
    y0 = np.concatenate((pair.origin, (1.0 + delta0) * pair.direction))

    def plane(s, state, _medium):  # solve_ivp passes `args` to events too
        return pair.normal @ (state[:3] - pair.target)

    plane.terminal = True
    plane.direction = 1.0  # the origin lies behind the plane; only crossing forward counts

    sol = solve_ivp(ray_rhs, (0.0, pair.max_length), y0, method=method, rtol=rtol,
                    atol=atol, events=plane, args=(medium,))
    if sol.status == -1:
        raise RuntimeError(f"integration failed: {sol.message}")
    if sol.t_events[0].size:
        return sol.y_events[0][0][:3], False, sol.nfev
    dist = np.abs(pair.normal @ (sol.y[:3] - pair.target[:, None]))
    return sol.y[:3, np.argmin(dist)], True, sol.nfev


# --------------------------------------------------------------------------------------
# Parameters by path name
# --------------------------------------------------------------------------------------

_PATH = re.compile(r"^(?:(scale)|(background|inversion)\.(\w+)|hotspots\[(\d+)\]\.(\w+))$")


def _slot(medium: dict, path: str):
    """The (container, key) that a parameter path such as `hotspots[0].radius` names."""
    m = _PATH.match(path)
    if not m:
        raise ValueError(f"bad parameter name {path!r}")
    if m.group(1):
        return medium, "scale"
    if m.group(2):
        term = medium.get(m.group(2))
        ok = ("n", "a", "height") if m.group(2) == "inversion" else ("n", "a")
        if term is None or m.group(3) not in ok:
            raise ValueError(f"{path!r} is not a parameter of this medium")
        return term, m.group(3)
    j, key = int(m.group(4)), m.group(5)
    hots = medium.get("hotspots") or []
    if j >= len(hots) or key not in ("x", "z", "radius", "n", "a", "edge"):
        raise ValueError(f"{path!r} is not a parameter of this medium")
    return hots[j], key


def get_param(medium, path):
    box, key = _slot(medium, path)
    return float(box.get(key, DEFAULT_EDGE if key == "edge" else 1.0))


def set_param(medium, path, value):
    box, key = _slot(medium, path)
    box[key] = float(value)


# --------------------------------------------------------------------------------------
# The fit
# --------------------------------------------------------------------------------------


class TimeUp(Exception):
    """Raised from the residual function when the wall-time cap is reached."""


class Objective:
    """Stacked residuals w·(e − target) as a function of the free parameters.

    Counts residual evaluations (finite-difference ones included), rays and RHS
    evaluations, and remembers the best point seen, so a fit stopped by the time cap
    still reports where it got to.
    """

    def __init__(self, problem, rtol, atol, method, deadline=None):
        self.base = problem["medium"]
        self.free = list(problem.get("free") or [])
        radius = (problem.get("earth") or {}).get("radius")
        # Pairs need only the geometry (the up vector) of the sphere.
        self.earth = RoundEarth(None, radius) if radius else None
        self.pairs = [Pair(p, self.earth) for p in problem["pairs"]]
        self.rtol, self.atol, self.method = rtol, atol, method
        self.deadline = deadline
        self.nres = self.nrays = self.nrhs = 0
        self.best = (math.inf, None)

    def medium_dict(self, theta):
        m = json.loads(json.dumps(self.base))  # deep copy
        for path, value in zip(self.free, theta):
            set_param(m, path, value)
        return m

    def residuals(self, theta, rtol=None, atol=None, method=None, count=True):
        if count and self.deadline is not None and time.perf_counter() > self.deadline:
            raise TimeUp
        medium = Medium(self.medium_dict(theta))
        if self.earth is not None:
            medium = RoundEarth(medium, self.earth.R)
        r = np.empty(3 * len(self.pairs))
        for i, p in enumerate(self.pairs):
            e, _, nfev = trace(medium, p, rtol or self.rtol, atol or self.atol,
                               method or self.method)
            r[3 * i:3 * i + 3] = p.weight * (e - p.target)
            if count:
                self.nrays += 1
                self.nrhs += nfev
        if count:
            self.nres += 1
            F = 0.5 * float(r @ r)
            if F < self.best[0]:
                self.best = (F, np.array(theta, float))
        return r

    def objective(self, theta, **kw):
        r = self.residuals(theta, count=False, **kw)
        return 0.5 * float(r @ r)


def fit(problem, rtol, atol, method, solver, max_time, ftol, xtol, gtol, x_scale="jac",
        diff_step=None):
    obj = Objective(problem, rtol, atol, method)
    free = obj.free
    if not free:
        raise ValueError("no free parameters")
    x0 = np.array([get_param(obj.base, p) for p in free])
    bounds = problem.get("bounds") or {}
    lo = np.array([bounds.get(p, [-np.inf, np.inf])[0] for p in free], float)
    hi = np.array([bounds.get(p, [-np.inf, np.inf])[1] for p in free], float)
    if solver == "auto":  # MINPACK's LM cannot take bounds; TRF can
        solver = "trf" if np.isfinite(lo).any() or np.isfinite(hi).any() else "lm"
    # The parameters span 1e-1 … 1e3 (a rate vs a radius): scale them by the Jacobian.
    x_scale = x_scale if x_scale == "jac" else float(x_scale)
    kw = dict(jac="2-point", method=solver, ftol=ftol, xtol=xtol, gtol=gtol, x_scale=x_scale,
              diff_step=diff_step)
    if solver != "lm":
        kw["bounds"] = (lo, hi)
    t0, c0 = time.perf_counter(), time.process_time()
    obj.deadline = t0 + max_time if max_time else None
    try:
        res = least_squares(obj.residuals, x0, **kw)
        theta, status, message = res.x, int(res.status), res.message
        success, nfev, njev = bool(res.success), int(res.nfev), int(res.njev or 0)
    except TimeUp:
        theta, status, message = obj.best[1], None, f"stopped by the time cap ({max_time} s)"
        success, nfev, njev = False, None, None
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    F = obj.objective(theta)
    F_ref = obj.objective(theta, rtol=REF_RTOL, atol=REF_RTOL, method=REF_METHOD)
    return dict(
        problem=problem.get("name"),
        objective=F,
        objective_ref=F_ref,
        parameters={p: float(v) for p, v in zip(free, theta)},
        start={p: float(v) for p, v in zip(free, x0)},
        wall_time_s=wall,
        cpu_time_s=cpu,  # less sensitive than wall time to other processes on the machine
        nfev=nfev,
        njev=njev,
        residual_evaluations=obj.nres,
        rays=obj.nrays,
        rhs_evaluations=obj.nrhs,
        rtol=rtol,
        atol=atol,
        integrator=method,
        solver=solver,
        x_scale=x_scale,
        diff_step=diff_step,
        success=success,
        status=status,
        message=message,
        reference=dict(rtol=REF_RTOL, method=REF_METHOD),
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("problem")
    ap.add_argument("--rtol", type=float, default=1e-8, help="solve_ivp relative tolerance")
    ap.add_argument("--atol", type=float, default=None,
                    help="absolute tolerance (m, and 1 for v); default: equal to rtol")
    ap.add_argument("--method", default="RK45", choices=["RK45", "DOP853"],
                    help="solve_ivp integrator (RK45 is the Dormand–Prince 5(4) pair mirage uses)")
    ap.add_argument("--solver", default="auto", choices=["auto", "trf", "lm"],
                    help="least_squares method; auto: trf if the file has bounds, else lm")
    ap.add_argument("--max-time", type=float, default=120.0,
                    help="wall-time cap in seconds (0: none); the best point so far is reported")
    ap.add_argument("--x-scale", default="jac", help="least_squares x_scale: 'jac' or a number")
    ap.add_argument("--diff-step", type=float, default=None,
                    help="least_squares diff_step (relative FD step); default: SciPy's, √eps")
    for name in ("ftol", "xtol", "gtol"):  # least_squares' stopping tolerances, its defaults
        ap.add_argument(f"--{name}", type=float, default=1e-8, help=f"least_squares {name}")
    ap.add_argument("--trace-only", action="store_true",
                    help="print F of the file's medium at --rtol and at the reference tolerance")
    args = ap.parse_args(argv)
    with open(args.problem) as f:
        problem = json.load(f)
    atol = args.rtol if args.atol is None else args.atol
    if args.trace_only:
        obj = Objective(problem, args.rtol, atol, args.method)
        theta = [get_param(obj.base, p) for p in obj.free]
        t0 = time.perf_counter()
        F = obj.objective(theta)
        wall = time.perf_counter() - t0
        out = dict(problem=problem.get("name"), objective=F, trace_time_s=wall,
                   objective_ref=obj.objective(theta, rtol=REF_RTOL, atol=REF_RTOL,
                                               method=REF_METHOD),
                   rtol=args.rtol, atol=atol, integrator=args.method)
    else:
        out = fit(problem, args.rtol, atol, args.method, args.solver, args.max_time,
                  args.ftol, args.xtol, args.gtol, args.x_scale, args.diff_step)
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
