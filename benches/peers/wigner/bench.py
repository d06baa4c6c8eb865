#!/usr/bin/env python3
"""mirage against the Wigner lab's simulator on the same 1000-ray fan, in one run.

    python3 benches/peers/wigner/bench.py [--reps 10] [--tolerance 1e-6,2e-6]

Builds both (the peer with build.sh, beside the project; mirage with
`cargo build --release`), writes the fan of fan_reference.json as a mirage
problem (the Wigner water case, `problems/wigner-water.json`'s true air), and
times whole processes: `mirage --threads 1 trace` (parse, trace, write the
report) against the peer's driver (its rays only, best of its passes). Prints,
for each mirage tolerance, rays/s by wall clock and by the process's own CPU
time (user + system, which a busy machine disturbs less), right-hand sides a
ray and the worst endpoint error against the SciPy DOP853 reference; then the
peer's rays/s and worst error, and the ratios. Standard library only.
"""
import argparse, json, math, os, resource, statistics, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
AIR = {"air": {"temperature": {"base": 10.033, "exponential": {"delta": 3.15, "scale_height": 1 / 20.1}},
               "pressure": 101325.0, "hydrostatic": False, "refractivity": {"gladstone_dale": 0.079386}}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=10)
    ap.add_argument("--tolerance", default="1e-6,2e-6",
                    help="mirage's dopri5 tolerances, comma-separated")
    a = ap.parse_args()
    build = os.environ.get("BUILD_DIR", "/tmp/wigner-mirage-build")
    if not os.access(os.path.join(build, "fan"), os.X_OK):
        subprocess.run([os.path.join(HERE, "build.sh")], check=True)
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    mirage = os.path.join(ROOT, "target", "release", "mirage")
    ref = json.load(open(os.path.join(HERE, "fan_reference.json")))
    x, y0 = ref["x_target"], ref["origin"][1]
    pairs = [{"origin": [0.0, y0, 0.0], "through": [0.0, y0 + x * math.tan(math.radians(ang)), x],
              "target": [0.0, y, x]} for ang, y in zip(ref["angles_deg"], ref["y"])]
    tolerances = [float(t) for t in a.tolerance.split(",")]
    n = len(pairs)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for tol in tolerances:
            problem = {"name": "wigner-fan", "medium": AIR, "free": [], "pairs": pairs,
                       "trace": {"method": "dopri5", "tolerance": tol}}
            src, out = os.path.join(d, "fan.json"), os.path.join(d, "report.json")
            json.dump(problem, open(src, "w"))
            walls, cpus = [], []
            for _ in range(a.reps):
                r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                t0 = time.perf_counter()
                subprocess.run([mirage, "--threads", "1", "trace", src, "-o", out], check=True,
                               stdout=subprocess.DEVNULL)
                walls.append(time.perf_counter() - t0)
                r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpus.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
            report = json.load(open(out))
            worst = max(p["distance"] for p in report["pairs"])
            rhs = report["stats"]["rhs_evaluations"] / n
            rows.append((tol, n / min(walls), n / statistics.median(walls), n / min(cpus), rhs, worst))
        peer = subprocess.run([os.path.join(build, "fan"), "--reps", str(a.reps)], check=True,
                              capture_output=True, text=True).stdout
    best_peer = next(l for l in peer.splitlines() if l.startswith("# best"))
    peer_rate = float(best_peer.split("=")[1].split("rays/s")[0])
    worst_peer = 0.0
    for line, yr in zip((l for l in peer.splitlines() if not l.startswith("#")), ref["y"]):
        f = line.split()
        xr, yp, dr = float(f[3]), float(f[4]), float(f[5])
        worst_peer = max(worst_peer, abs(yp - (xr - x) * math.tan(math.radians(dr)) - yr))
    print(f"fan of {n} rays to {x:g} m, reference SciPy DOP853 rtol {ref['rtol']:g}; "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    print(f"peer solve4x (RKF45 1e-3, rays only, best of {a.reps}): {peer_rate:,.0f} rays/s; "
          f"worst error {worst_peer:.2e} m")
    print("| mirage --threads 1 trace, dopri5 | rays/s (best wall) | median wall | best CPU time "
          "| right-hand sides a ray | worst error | ratio to the peer (best wall) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for tol, best, median, cpu, rhs, worst in rows:
        print(f"| tolerance {tol:g} | {best:,.0f} | {median:,.0f} | {cpu:,.0f} | {rhs:.0f} "
              f"| {worst:.2e} m | {best / peer_rate:.1f}x |")


if __name__ == "__main__":
    sys.exit(main())
