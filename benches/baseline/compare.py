#!/usr/bin/env python3
"""Compare mirage's fit with the by-hand SciPy baseline (scipy_fit.py), problem by problem.

    python compare.py [PROBLEM.json ...] [--sweep] [--repeats N] [--max-time S]

Run it through ``compare.sh``, which makes the virtual environment and builds mirage.
Without problem files it takes every ``problems/*.json`` of the repository and the
extra problems in ``benches/baseline/problems/`` (the 15-pair bench problem).

For each problem:

* **mirage**: ``mirage --threads 1 fit -q PROBLEM -o out.json``, ``--repeats`` times
  (fits take milliseconds, so one run is noise); the median wall time of the whole
  process (what a user waits for: start, parsing, fit, identifiability, writing), the
  fit's own ``solver.wall_time_s`` beside it, and ``objective`` from out.json.
* **baseline**: ``scipy_fit.py`` at "the tolerance it needs to converge": the loosest
  rtol in {1e-6, 1e-8, 1e-10, 1e-12} (atol = rtol) whose fitted parameters reach the
  best objective of the sweep, within a factor ``CONVERGED_FACTOR``. "Objective" for
  this choice is ``objective_ref``: F re-evaluated by the baseline's tracer at a tight
  reference tolerance, because a fit at rtol 1e-6 reports F measured by its own
  1e-6 tracer, which can be small while the parameters are wrong. The sweep's
  results are stored in ``tolerances.json`` (per integrator, per problem);
  ``--sweep`` reruns it (5-15 minutes for all problems), and a problem missing from
  the file is swept first.
  Each baseline fit is capped at ``--max-time`` seconds (the best point so far counts).
  ``--rtol R`` fits the baseline at that rtol instead (no sweep): issue #14's peer is
  ``--method DOP853 --rtol 1e-12``.

The first table compares time and each program's F as measured by its own tracer
(what each would report to its user), plus a CPU-time ratio that the machine's other
load disturbs less. The second re-evaluates both fitted media on both tracers
(``mirage trace`` with the file's settings, and the baseline's reference tracer), and
gives the largest relative difference between the two fits' parameters: the problems'
targets were made with mirage's tracer, so each tracer favours its own fit at the level
of ~1e-8 m.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from scipy_fit import set_param

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RTOLS = [1e-6, 1e-8, 1e-10, 1e-12]
CONVERGED_FACTOR = 10.0  # "reaches its best objective": F_ref within this factor of the best
TOLERANCES = HERE / "tolerances.json"


def run_baseline(problem: Path, rtol: float, method: str, max_time: float, extra=()):
    """Run scipy_fit.py in its own process and return its JSON output."""
    cmd = [sys.executable, str(HERE / "scipy_fit.py"), str(problem), "--rtol", repr(rtol),
           "--method", method, "--max-time", str(max_time), *extra]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def run_mirage(mirage: str, problem: Path, repeats: int):
    """Fit with mirage on one thread `repeats` times.

    Returns the median wall time of the whole process (start, parsing, fit,
    identifiability, report, writing: what a user waits for), the median CPU time of the
    whole process (less disturbed than wall time by other load), the median of
    `solver.wall_time_s` (the fit alone), and the last result.
    """
    walls, times, cpus, result = [], [], [], None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.json"
        for _ in range(repeats):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run([mirage, "--threads", "1", "fit", "-q", str(problem), "-o", str(out)],
                           check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            result = json.loads(out.read_text())
            times.append(result["solver"]["wall_time_s"])
    return statistics.median(walls), statistics.median(cpus), statistics.median(times), result


def reference_objective(problem: Path, medium: dict, method: str):
    """F of `medium` on `problem`'s pairs, by the baseline's reference tracer."""
    p = json.loads(problem.read_text())
    p["medium"] = medium
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(p, f)
    try:
        return run_baseline(Path(f.name), 1e-12, method, 0, ["--trace-only"])["objective_ref"]
    finally:
        os.unlink(f.name)


def mirage_objective(mirage: str, problem: Path, free: dict):
    """F by mirage's tracer (the file's `trace` settings) with `free` set in the medium."""
    p = json.loads(problem.read_text())
    for path, value in free.items():
        set_param(p["medium"], path, value)
    with tempfile.TemporaryDirectory() as tmp:
        src, out = Path(tmp) / "p.json", Path(tmp) / "t.json"
        src.write_text(json.dumps(p))
        subprocess.run([mirage, "trace", str(src), "-o", str(out)], check=True,
                       capture_output=True)
        return json.loads(out.read_text())["objective"]


def max_rel_diff(a: dict, b: dict):
    """Largest relative difference between two parameter sets (same names)."""
    return max(abs(a[k] - b[k]) / max(abs(b[k]), 1e-300) for k in b)


def sweep(problem: Path, method: str, max_time: float):
    """Fit at every rtol of RTOLS; print one line per rtol; choose the converging one."""
    runs = []
    for rtol in RTOLS:
        r = run_baseline(problem, rtol, method, max_time)
        runs.append({k: r[k] for k in ("rtol", "objective", "objective_ref", "wall_time_s",
                                       "residual_evaluations", "rays", "rhs_evaluations",
                                       "status", "message", "parameters")})
        print(f"  {problem.stem:<16} rtol {rtol:<6g} F {r['objective']:10.3e}  "
              f"F_ref {r['objective_ref']:10.3e}  {r['wall_time_s']:8.2f} s  "
              f"{r['residual_evaluations']:4d} residual evals  {r['message']}", flush=True)
    best = min(r["objective_ref"] for r in runs)
    chosen = next(r for r in runs if r["objective_ref"] <= CONVERGED_FACTOR * best)
    print(f"  {problem.stem:<16} converging rtol: {chosen['rtol']:g} "
          f"(best F_ref {best:.3e})", flush=True)
    return {"rtol": chosen["rtol"], "best_objective_ref": best, "runs": runs}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("problems", nargs="*", type=Path)
    ap.add_argument("--mirage", default=str(ROOT / "target/release/mirage"))
    ap.add_argument("--repeats", type=int, default=7, help="mirage fits per problem (median)")
    ap.add_argument("--max-time", type=float, default=120.0, help="cap per baseline fit, s")
    ap.add_argument("--method", default="RK45", choices=["RK45", "DOP853"],
                    help="the baseline's solve_ivp integrator")
    ap.add_argument("--sweep", action="store_true",
                    help="rerun the rtol sweep for the problems given and update tolerances.json")
    ap.add_argument("--rtol", type=float, default=None,
                    help="fit the baseline at this rtol (atol = rtol) instead of the converging "
                         "one of tolerances.json (no sweep)")
    ap.add_argument("--goal", type=float, default=200.0,
                    help="the speed ratio every problem must reach (the last line says)")
    ap.add_argument("--json", type=Path, help="also write the table's data here")
    args = ap.parse_args()

    problems = args.problems or sorted((ROOT / "problems").glob("*.json")) + sorted(
        (HERE / "problems").glob("*.json"))
    problems = [p.resolve() for p in problems]
    # The by-hand baseline (scipy_fit.py) implements the logistic model only;
    # real-air problems (a medium with an `air` section) have no peer here.
    logistic = [p for p in problems if "air" not in json.loads(p.read_text()).get("medium", {})]
    for p in problems:
        if p not in logistic:
            print(f"{p.stem}: skipped (real air; the SciPy baseline implements the logistic model only)")
    problems = logistic
    # tolerances.json: {integrator: {problem: sweep result}}
    all_tolerances = json.loads(TOLERANCES.read_text()) if TOLERANCES.exists() else {}
    tolerances = all_tolerances.setdefault(args.method, {})

    if args.rtol is not None:
        tolerances = {p.stem: {"rtol": args.rtol} for p in problems}
    todo = [p for p in problems if args.sweep or p.stem not in tolerances]
    if todo:
        print(f"rtol sweep ({args.method}, atol = rtol, cap {args.max_time:g} s per fit):")
        for p in todo:
            tolerances[p.stem] = sweep(p, args.method, args.max_time)
            TOLERANCES.write_text(json.dumps(all_tolerances, indent=1) + "\n")
        print()

    rows = []
    for p in problems:
        tol = tolerances[p.stem]
        print(f"{p.stem}: mirage x{args.repeats}, baseline at rtol {tol['rtol']:g} ...",
              file=sys.stderr, flush=True)
        m_time, m_cpu, m_solver, m = run_mirage(args.mirage, p, args.repeats)
        b = run_baseline(p, tol["rtol"], args.method, args.max_time)
        m_ref = reference_objective(p, m["medium"], args.method)
        m_params = {q["name"]: q["value"] for q in m["parameters"]}
        b_mir = mirage_objective(args.mirage, p, b["parameters"])
        rows.append(dict(problem=p.stem, rtol=tol["rtol"], baseline_time_s=b["wall_time_s"],
                         baseline_F=b["objective"], baseline_F_ref=b["objective_ref"],
                         baseline_status=b["message"], baseline_parameters=b["parameters"],
                         baseline_cpu_s=b["cpu_time_s"], mirage_cpu_s=m_cpu,
                         cpu_ratio=b["cpu_time_s"] / m_cpu,
                         mirage_time_s=m_time, mirage_solver_s=m_solver,
                         mirage_F=m["objective"], mirage_F_ref=m_ref,
                         baseline_F_by_mirage=b_mir, mirage_parameters=m_params,
                         parameter_difference=max_rel_diff(b["parameters"], m_params),
                         ratio=b["wall_time_s"] / m_time))

    load = os.getloadavg()
    yes = lambda b: "yes" if b else "NO"  # noqa: E731
    print(f"Time to fit (s) and final objective F (m², each program's own tracer); "
          f"baseline: least_squares + solve_ivp {args.method}")
    head = (f"{'problem':<16} {'rtol':>6} {'baseline s':>10} {'baseline F':>10} "
            f"{'mirage s':>9} {'mirage F':>10} {'ratio':>8} {'mirage F <= baseline F':>23}"
            f" {'CPU ratio':>10} {'mirage fit s':>12}")
    print(head + "\n" + "-" * len(head))
    for r in rows:
        print(f"{r['problem']:<16} {r['rtol']:>6g} {r['baseline_time_s']:>10.3f} "
              f"{r['baseline_F']:>10.2e} {r['mirage_time_s']:>9.4f} {r['mirage_F']:>10.2e} "
              f"{r['ratio']:>7.0f}x {yes(r['mirage_F'] <= r['baseline_F']):>23}"
              f" {r['cpu_ratio']:>9.0f}x {r['mirage_solver_s']:>12.4f}")

    print("\nCross-check: both fitted media on one tracer (F, m²), and the parameters")
    head = (f"{'problem':<16} {'by mirage: baseline':>20} {'mirage':>9} "
            f"{'by SciPy ref: baseline':>23} {'mirage':>9} {'max rel. param diff':>20}")
    print(head + "\n" + "-" * len(head))
    for r in rows:
        print(f"{r['problem']:<16} {r['baseline_F_by_mirage']:>20.2e} {r['mirage_F']:>9.2e} "
              f"{r['baseline_F_ref']:>23.2e} {r['mirage_F_ref']:>9.2e} "
              f"{r['parameter_difference']:>20.1e}")

    ok = all(r["ratio"] >= args.goal and r["mirage_F"] <= r["baseline_F"] for r in rows)
    where = f"rtol {args.rtol:g}" if args.rtol is not None else "the rtol of tolerances.json"
    print(f"\nmirage: median of {args.repeats} whole `mirage --threads 1 fit` processes "
          f"(wall time; 'mirage fit s': the fit alone, solver.wall_time_s); "
          f"baseline: one fit (its in-script wall time), at {where}")
    print("CPU ratio: the baseline fit's CPU time over the CPU time of the whole mirage "
          "process (median), which changes less with the machine's load")
    print("'by mirage': `mirage trace` with the problem file's trace settings; "
          "'by SciPy ref': the baseline's tracer at DOP853 rtol 1e-13")
    print(f"load average at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
          f"({os.cpu_count()} cores)")
    print(f"every problem >= {args.goal:g}x faster with mirage at equal or lower F: {yes(ok)}")
    if args.json:
        args.json.write_text(json.dumps(dict(rows=rows, load=load, method=args.method,
                                             time=time.strftime("%Y-%m-%d %H:%M:%S")),
                                        indent=1) + "\n")


if __name__ == "__main__":
    main()
