#!/usr/bin/env python3
"""Write the sweep problems of benches/baseline/problems/: 6 to 36 pairs, 2 to 6 free
parameters, a full logistic medium (background, inversion, one hot spot) seen over
2.5 km, and the 36-pair, 6-parameter RK4 problem at 0.5 m steps.

Each problem's targets are where its rays land in the known air, made with mirage's own
tracer (``mirage trace``) to a fixed point (the target plane depends on the target), as
``make_15pair.py`` does; the fit starts from that air with every free parameter moved by
a few per cent.

    python make_sweep.py [--mirage target/release/mirage]

The output files are committed, so the comparison does not need to run this.
"""

import argparse
import json
import math
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent

KNOWN = {
    "scale": 1.0,
    "background": {"n": 1.0, "a": 40.0},
    "inversion": {"n": 0.35, "a": 2.0, "height": 14.0},
    "hotspots": [{"x": 40.0, "z": 1300.0, "radius": 420.0, "n": -2.4, "a": -0.5, "edge": 0.05}],
}
# The free parameters, in the order they are freed, and how far each starts off.
FREE = [
    ("hotspots[0].n", 0.06),
    ("hotspots[0].a", -0.05),
    ("hotspots[0].radius", 0.04),
    ("inversion.n", -0.05),
    ("inversion.height", 0.03),
    ("background.a", 0.05),
]
# (name, pairs, free parameters, trace)
PROBLEMS = [
    ("sweep-6x2", 6, 2, {"method": "dopri5", "tolerance": 1e-9}),
    ("sweep-12x3", 12, 3, {"method": "dopri5", "tolerance": 1e-9}),
    ("sweep-24x4", 24, 4, {"method": "dopri5", "tolerance": 1e-9}),
    ("sweep-36x6", 36, 6, {"method": "dopri5", "tolerance": 1e-9}),
    ("sweep-36x6-rk4", 36, 6, {"method": "rk4", "step": 0.5}),
]
DISTANCE = 2500.0
ORIGIN = [0.0, 1.8, 0.0]


def glances(count):
    """`count` lines of sight fanned over ±20° of azimuth and −0.25°…+0.1° of elevation."""
    out = []
    for i in range(count):
        u = (i + 0.5) / count
        az = math.radians(-20.0 + 40.0 * u)
        el = math.radians(-0.25 + 0.35 * ((i * 7) % count) / max(count - 1, 1))
        t = [ORIGIN[0] + DISTANCE * math.sin(az), ORIGIN[1] + DISTANCE * math.tan(el),
             ORIGIN[2] + DISTANCE * math.cos(az)]
        out.append({"origin": list(ORIGIN), "through": t, "target": list(t)})
    return out


def set_param(medium, path, value):
    head, field = path.rsplit(".", 1)
    node = medium["hotspots"][0] if head.startswith("hotspots") else medium[head]
    node[field] = value


def get_param(medium, path):
    head, field = path.rsplit(".", 1)
    node = medium["hotspots"][0] if head.startswith("hotspots") else medium[head]
    return node[field]


def targets(mirage, pairs, trace):
    """Each pair's target moved to where its ray lands in the known air (fixed point)."""
    known = {"name": "known", "medium": KNOWN, "pairs": pairs, "trace": trace}
    with tempfile.TemporaryDirectory() as tmp:
        prob, out = Path(tmp) / "p.json", Path(tmp) / "t.json"
        for _ in range(8):
            prob.write_text(json.dumps(known))
            subprocess.run([mirage, "trace", str(prob), "-o", str(out)], check=True,
                           capture_output=True)
            traced = json.loads(out.read_text())["pairs"]
            assert not any(p["unreachable"] for p in traced), "every ray reaches its plane"
            moved = max(math.dist(p["endpoint"], q["target"]) for p, q in zip(traced, pairs))
            for p, q in zip(traced, pairs):
                q["target"] = p["endpoint"]
            if moved < 1e-12 * DISTANCE:
                break
    return pairs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mirage", default=str(ROOT / "target/release/mirage"))
    args = ap.parse_args()
    for name, count, nfree, trace in PROBLEMS:
        pairs = targets(args.mirage, glances(count), trace)
        start = json.loads(json.dumps(KNOWN))
        free = [p for p, _ in FREE[:nfree]]
        for path, off in FREE[:nfree]:
            set_param(start, path, get_param(KNOWN, path) * (1.0 + off))
        problem = {
            "name": name,
            "description": (f"{count} glances over {DISTANCE:.0f} m through a full logistic "
                            f"medium, {nfree} free parameters started a few per cent off; "
                            "made by benches/baseline/make_sweep.py"),
            "medium": start,
            "free": free,
            "bounds": {"hotspots[0].a": [-5.0, -0.05]} if "hotspots[0].a" in free else {},
            "pairs": pairs,
            "trace": trace,
            "solver": {"method": "auto", "max_iterations": 200},
        }
        if not problem["bounds"]:
            del problem["bounds"]
        dest = HERE / "problems" / f"{name}.json"
        fields = [f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in problem.items() if k != "pairs"]
        body = ",\n".join("    " + json.dumps(p) for p in problem["pairs"])
        fields.insert(4, '  "pairs": [\n' + body + "\n  ]")
        dest.write_text("{\n" + ",\n".join(fields) + "\n}\n")
        print(f"wrote {dest.relative_to(ROOT)} ({count} pairs, {nfree} free)")


if __name__ == "__main__":
    main()
