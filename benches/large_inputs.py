#!/usr/bin/env python3
"""Large inputs: time and peak memory of whole `mirage` processes as the input grows.

Prints a Markdown table (the README's "Large inputs" section is what this prints):

* `trace` of N pairs (25k ... 200k): a full medium (background, inversion, one hot
  spot), rays of 300 m at 1 m RK4 steps, one thread, with a JSON report written.
  Time and peak RSS should both grow linearly in N: the table gives them per pair.
* `trace` of 2,000 pairs of 1.5 km at 1 m RK4 steps through the same medium: the
  throughput of the whole process in million steps per second (best of 5).
* a problem file of ~50 and ~100 MB (pairs whose rays are 1 m long, so that reading,
  validating and writing dominate): parsing must not have a quadratic step, so the
  100 MB file should take about twice the 50 MB one.
* `render` of a plain scene at growing sizes, for the bytes per pixel behind the
  memory bound the README states for a 16,384 x 16,384 render.

Usage: python3 benches/large_inputs.py [--mirage target/release/mirage] [--quick]
Peak RSS is GNU time's "maximum resident set size" (/usr/bin/time).
"""

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile

MEDIUM = {
    "scale": 0.02,
    "background": {"n": 1.0, "a": 150.0},
    "inversion": {"n": 0.5, "a": 2.0, "height": 8.0},
    "hotspots": [{"x": 0.0, "z": 160.0, "radius": 80.0, "n": -2.2, "a": -0.5, "edge": 0.5}],
}


def problem(n_pairs, length, steps):
    """A problem of `n_pairs` pairs fanning out from one eye, rays `length` m long."""
    pairs = []
    for i in range(n_pairs):
        # a fan over ±10° of azimuth and 0.5° below to 0.5° above the horizon
        u = (i % 1000) / 999.0
        v = (i // 1000 % 200) / 199.0


        az = math.radians(-10 + 20 * u)
        el = math.radians(-0.5 + 1.0 * v)
        d = (math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el))
        through = [1.0 * d[0], 1.6 + 1.0 * d[1], 1.0 * d[2]]
        target = [length * d[0], 1.6 + length * d[1], length * d[2]]
        pairs.append({"origin": [0.0, 1.6, 0.0], "through": through, "target": target})
    return {
        "name": f"large-{n_pairs}",
        "medium": MEDIUM,
        "free": [],
        "pairs": pairs,
        "trace": steps,
    }


def measure(cmd):
    """(wall seconds, peak RSS in MiB) of one process; raises if it fails."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as t:
        r = subprocess.run(
            ["/usr/bin/time", "-f", "%e %M", "-o", t.name] + cmd,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        if r.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
        wall, kib = t.read().split()[-2:]
        return float(wall), int(kib) / 1024.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mirage", default="target/release/mirage")
    ap.add_argument("--quick", action="store_true", help="smaller sizes (a smoke run)")
    a = ap.parse_args()
    mirage = os.path.abspath(a.mirage)
    with open("/proc/loadavg") as f:
        load = f.read().split()[0]
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {load} at start\n")

    with tempfile.TemporaryDirectory() as d:
        # trace: N pairs, 300 m at 1 m RK4 steps
        sizes = [2_500, 5_000, 10_000] if a.quick else [25_000, 50_000, 100_000, 200_000]
        rk4 = {"method": "rk4", "step": 1.0}
        print("| `mirage --threads 1 trace` | file | wall | peak RSS | per pair |")
        print("|---|---|---|---|---|")
        for n in sizes:
            p = os.path.join(d, f"trace-{n}.json")
            with open(p, "w") as f:
                json.dump(problem(n, 300.0, rk4), f)
            mb = os.path.getsize(p) / 1e6
            out = os.path.join(d, f"trace-{n}.out.json")
            wall, rss = measure([mirage, "--threads", "1", "trace", p, "-o", out])
            os.remove(out)
            print(
                f"| {n:,} pairs, 300 m at 1 m RK4 | {mb:.1f} MB | {wall:.2f} s | {rss:.0f} MiB"
                f" | {wall / n * 1e6:.0f} µs, {rss * 1024 / n:.2f} KiB |"
            )

        # throughput of the whole process: 2,000 pairs of 1.5 km at 1 m RK4 steps
        # through the full medium (issue #14's figure: >= 20 M steps/s)
        print("\n| `mirage --threads 1 trace`, full medium | steps | wall | M RK4 steps/s, whole process |")
        print("|---|---|---|---|")
        n = 200 if a.quick else 2_000
        p = os.path.join(d, "speed.json")
        with open(p, "w") as f:
            json.dump(problem(n, 1500.0, rk4), f)
        out = os.path.join(d, "speed.out.json")
        best = min(measure([mirage, "--threads", "1", "trace", p, "-o", out])[0] for _ in range(5))
        with open(out) as f:
            steps = json.load(f)["stats"]["accepted_steps"]
        os.remove(out)
        print(f"| {n:,} pairs, 1.5 km at 1 m | {steps:,} | {best:.3f} s (best of 5) | {steps / best / 1e6:.1f} |")

        # parsing: ~50 and ~100 MB of 1 m rays
        print("\n| problem file | pairs | wall | peak RSS | per MB |")
        print("|---|---|---|---|---|")
        short = {"method": "rk4", "step": 0.5}
        for n in [50_000, 100_000] if a.quick else [350_000, 700_000]:
            p = os.path.join(d, f"parse-{n}.json")
            with open(p, "w") as f:
                json.dump(problem(n, 1.0, short), f, indent=1)
            mb = os.path.getsize(p) / 1e6
            out = os.path.join(d, f"parse-{n}.out.json")
            wall, rss = measure([mirage, "--threads", "1", "trace", p, "-o", out])
            os.remove(out)
            print(f"| {mb:.0f} MB | {n:,} | {wall:.2f} s | {rss:.0f} MiB | {wall / mb * 1e3:.1f} ms |")

        # render: bytes per pixel
        scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "problems", "scenes", "sea.json")
        print("\n| `mirage --threads 1 render sea.json --no-glare` | wall | peak RSS | per pixel |")
        print("|---|---|---|---|")
        for side in [512, 1024] if a.quick else [1024, 2048, 4096]:
            out = os.path.join(d, f"r{side}.png")
            wall, rss = measure(
                [mirage, "--threads", "1", "render", scene, "-o", out, "--width", str(side),
                 "--height", str(side), "--no-glare", "-q"]
            )
            print(f"| {side} x {side} | {wall:.2f} s | {rss:.0f} MiB | {rss * 2**20 / side**2:.1f} B |")


if __name__ == "__main__":
    main()
