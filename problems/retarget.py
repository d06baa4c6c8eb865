#!/usr/bin/env python3
"""Makes a bundled problem consistent with a known medium: each pair's target
becomes the endpoint of its ray through TRUTH (a medium JSON file), repeated
until the target plane (which depends on the target) is a fixed point; the
problem's own medium (the fit's start) is left as it is.

    python3 problems/retarget.py PROBLEM.json TRUTH.json [--mirage PATH]

It runs `mirage trace` on a copy of the problem with the true medium, so it
needs only the binary (default: target/release/mirage). This is how the
real-air problems (hot-road-kelvin, cold-sea-kelvin, wigner-water) were made.
"""
import argparse, json, os, subprocess, sys, tempfile

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("problem")
    ap.add_argument("truth")
    ap.add_argument("--mirage", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "mirage"))
    a = ap.parse_args()
    problem = json.load(open(a.problem))
    truth = json.load(open(a.truth))
    with tempfile.TemporaryDirectory() as d:
        for _ in range(6):
            trial = dict(problem, medium=truth)
            src, out = os.path.join(d, "p.json"), os.path.join(d, "r.json")
            json.dump(trial, open(src, "w"))
            subprocess.run([a.mirage, "trace", src, "-o", out], check=True, stdout=subprocess.DEVNULL)
            report = json.load(open(out))
            moved = 0.0
            for pair, r in zip(problem["pairs"], report["pairs"]):
                if r["unreachable"]:
                    sys.exit(f"a ray never reaches its plane: {pair}")
                moved = max(moved, max(abs(x - y) for x, y in zip(pair["target"], r["endpoint"])))
                pair["target"] = r["endpoint"]
            if moved < 1e-12:
                break
    lines = []
    for k, v in problem.items():
        if k == "pairs":
            rows = ",\n".join("    " + json.dumps(x, ensure_ascii=False) for x in v)
            lines.append(f'  "pairs": [\n{rows}\n  ]')
        else:
            lines.append(f"  {json.dumps(k)}: {json.dumps(v, ensure_ascii=False)}")
    open(a.problem, "w", encoding="utf-8").write("{\n" + ",\n".join(lines) + "\n}\n")
    print(f"{a.problem}: {len(problem['pairs'])} targets moved to the true medium's endpoints")

if __name__ == "__main__":
    main()
