"""Times a 200-member `mirage_air.ensemble` on a Dask LocalCluster of 1 and of
2 worker processes (one thread each), and on the library's own threads, and
checks that all give the same members bit for bit. The README's table
("How sure") is this script's output:

    notebooks/.venv/bin/python notebooks/bench_ensemble.py [--problem P] [-n 200] [--noise 0.01] [--workers 1 2]

Each member is one task; the best fit runs in this process before them (in
every timing). Each run is repeated (``--repeat``, default 2) and the fastest
reported: the machine may be shared. Workers are pinned to one thread each (``threads_per_worker=1``,
``RAYON_NUM_THREADS=1`` and one thread per task), so the speed-up is that of
processes, not of threads within one.
"""

from __future__ import annotations

import argparse
import logging
import os
import platform
import subprocess
import time
from pathlib import Path

import numpy as np
from dask.distributed import Client, LocalCluster

import mirage_air

ROOT = Path(__file__).resolve().parents[1]


def cpu() -> str:
    """The CPU model and its widest vector instructions, from lscpu."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return platform.processor() or "unknown CPU"
    fields = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
    model = fields.get("Model name", "unknown").strip()
    flags = fields.get("Flags", "").split()
    isa = next((f for f in ("avx512f", "avx2", "avx", "sse4_2") if f in flags), "baseline")
    return f"{model}, {os.cpu_count()} cores, {isa.upper().replace('_', '.')}"


def timed(call):
    t0 = time.perf_counter()
    result = call()
    return time.perf_counter() - t0, result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problem", default=str(ROOT / "problems" / "cold-sea-kelvin.json"))
    ap.add_argument("-n", type=int, default=200)
    ap.add_argument("--noise", type=float, default=0.01)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=2, help="runs of each; the fastest is reported")
    args = ap.parse_args()
    load = os.getloadavg()[0]
    problem = mirage_air.load(args.problem)
    kw = dict(n=args.n, noise=args.noise, seed=1)

    rows = []
    reference = None
    for w in args.workers:
        with LocalCluster(n_workers=w, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None, silence_logs=logging.ERROR,
                          env={"RAYON_NUM_THREADS": "1"}) as cluster, Client(cluster) as client:
            client.wait_for_workers(w)
            # Warm the workers (imports) outside the timing.
            mirage_air.ensemble(problem, executor=client, **dict(kw, n=2 * w))
            seconds, r = min((timed(lambda: mirage_air.ensemble(problem, executor=client, **kw))
                              for _ in range(args.repeat)), key=lambda t: t[0])
        if reference is None:
            reference = r
        assert np.array_equal(r.members, reference.members), "members differ between runs"
        rows.append((f"Dask LocalCluster, {w} worker process{'es' if w > 1 else ''} × 1 thread", seconds))
    seconds, r = min((timed(lambda: mirage_air.ensemble(problem, **kw)) for _ in range(args.repeat)),
                     key=lambda t: t[0])
    assert np.array_equal(r.members, reference.members), "the local run differs"
    rows.append((f"`executor=None` (the library's threads, {os.cpu_count()})", seconds))

    base = rows[0][1]
    print(f"{problem.name}: {args.n} members, σ = {args.noise}; {cpu()}; load average at the start {load:.2f}")
    print("| run | seconds | speed-up |")
    print("| --- | ---: | ---: |")
    for label, s in rows:
        print(f"| {label} | {s:.1f} | {base / s:.2f}× |")


if __name__ == "__main__":
    main()
