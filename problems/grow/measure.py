#!/usr/bin/env python3
"""Measures `mirage fit --grow` on the bundled examples (README, "Growing the
model"): for each problem in this folder, the grown terms against the truth in
truths.json (the air its targets were traced through, as in tests/grow.rs),
each hot spot's centre error over its radius, the layer's error (the
inversion's height; real air's surface layer: its excess and scale height),
F grown / F true, the steps, and the time to grow (best of --repeat runs) on
one thread and on two.

    python3 problems/grow/measure.py [--mirage target/release/mirage] [--repeat 3] [--only NAME ...]
"""
import argparse
import json
import math
import os
import subprocess
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
NAMES = ["none", "inversion", "one-hot-spot", "two-hot-spots", "air-surface-layer",
         "air-hot-spot"]


def layers(m):
    """The medium's layers by kind: the logistic inversion, or real air's."""
    return m["air"]["temperature"] if "air" in m else m


def terms(m):
    t = ["surface layer"] if "exponential" in layers(m) else []
    t += ["inversion"] if "inversion" in layers(m) else []
    n = len(m.get("hotspots", []))
    if n:
        t.append(f"{n} hot spot{'s' if n > 1 else ''}")
    return ", ".join(t) or "none"


def run(mirage, args):
    out = subprocess.run([mirage] + args, capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mirage", default="target/release/mirage")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", nargs="*", default=NAMES, help="measure only these examples")
    a = ap.parse_args()
    truths = json.load(open(os.path.join(HERE, "truths.json")))
    mirage = a.mirage
    tmp = tempfile.mkdtemp()
    print("| example | true terms | grown terms | centre error / radius | layer error "
          "| F grown / F true | steps | time, 1 thread | time, 2 threads |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in a.only:
        path = os.path.join(HERE, f"{name}.json")
        truth = truths[name]
        # F at the truth: trace the problem with the true medium.
        p = json.load(open(path))
        p["medium"] = truth
        p["solver"] = {"method": "lm"}
        tp = os.path.join(tmp, f"{name}-truth.json")
        json.dump(p, open(tp, "w"))
        run(mirage, ["trace", tp, "-o", os.path.join(tmp, "t.json")])
        f_true = json.load(open(os.path.join(tmp, "t.json")))["objective"]
        times = {}
        for threads in ["1", "2"]:
            best = math.inf
            for _ in range(a.repeat):
                out = os.path.join(tmp, f"{name}-{threads}.json")
                t0 = time.perf_counter()
                run(mirage, ["--threads", threads, "fit", "-q", path, "-o", out])
                best = min(best, time.perf_counter() - t0)
            times[threads] = best
        r = json.load(open(out))
        m = r["medium"]
        errs = []
        for h in truth.get("hotspots", []):
            d = min((math.hypot(g["x"] - h["x"], g["z"] - h["z"]) for g in m.get("hotspots", [])),
                    default=math.inf)
            errs.append(f"{d / h['radius']:.3f}")
        inv = "–"
        lt, lm = layers(truth), layers(m)
        if "inversion" in lt and "inversion" in lm:
            t = lt["inversion"]["height"]
            inv = f"height {abs(lm['inversion']['height'] - t) / t * 100:.2f} %"
        if "exponential" in lt and "exponential" in lm:
            t, g = lt["exponential"], lm["exponential"]
            inv = (f"ΔT {abs(g['delta'] - t['delta']) / t['delta'] * 100:.2f} %, "
                   f"H {abs(g['scale_height'] - t['scale_height']) / t['scale_height'] * 100:.2f} %")
        g = r["grow"]
        steps = " → ".join(s["action"] for s in g["steps"][1:]) or "start only"
        print(f"| `{name}` | {terms(truth)} | {terms(m)} | {', '.join(errs) or '–'} | {inv} "
              f"| {r['objective'] / f_true:.3f} | {steps} | {times['1']:.2f} s | {times['2']:.2f} s |")


if __name__ == "__main__":
    main()
