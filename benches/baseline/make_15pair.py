#!/usr/bin/env python3
"""Write problems/desert-lake-15.json: the 15-pair, 4-parameter hot-spot problem.

This is the problem of mirage's criterion bench (``benches/fit.rs``,
``fifteen_pair_problem``): ``desert-lake`` with three more glances, whose targets
are where their rays land in the known air (the fitted desert-lake medium). The
targets are made with mirage's own tracer (``mirage trace``), as the bench does
with ``retarget``: the target plane depends on the target, so the endpoint is
recomputed until it is a fixed point.

    python make_15pair.py [--mirage target/release/mirage]

Run from anywhere; paths are relative to the repository root. The output file is
committed, so the comparison does not need to run this.
"""

import argparse
import json
import math
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent

# The known air of desert-lake (what `mirage fit problems/desert-lake.json` recovers).
TRUE_HOTSPOT = {"x": 60.0, "z": 900.0, "radius": 260.0, "n": -2.5}
# (azimuth°, elevation°, distance m) of the three extra glances, as in benches/fit.rs.
EXTRA = [(-15.0, -0.12, 1250.0), (14.0, -0.17, 1400.0), (3.0, -0.22, 1300.0)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mirage", default=str(ROOT / "target/release/mirage"))
    args = ap.parse_args()
    base = json.loads((ROOT / "problems/desert-lake.json").read_text())
    o = base["pairs"][0]["origin"]
    extra = []
    for az, el, d in EXTRA:
        a, e = math.radians(az), math.radians(el)
        t = [o[0] + d * math.sin(a), o[1] + d * math.tan(e), o[2] + d * math.cos(a)]
        extra.append({"origin": list(o), "through": t, "target": list(t)})

    known = json.loads(json.dumps(base))
    known["medium"]["hotspots"][0].update(TRUE_HOTSPOT)
    known["pairs"] = extra
    known["free"] = []
    known.pop("bounds", None)
    with tempfile.TemporaryDirectory() as tmp:
        prob, out = Path(tmp) / "p.json", Path(tmp) / "t.json"
        for _ in range(6):  # fixed point: target = endpoint of the ray to its own plane
            prob.write_text(json.dumps(known))
            subprocess.run([args.mirage, "trace", str(prob), "-o", str(out)], check=True,
                           capture_output=True)
            traced = json.loads(out.read_text())["pairs"]
            assert not any(p["unreachable"] for p in traced)
            moved = max(math.dist(p["endpoint"], q["target"]) for p, q in zip(traced, known["pairs"]))
            for p, q in zip(traced, known["pairs"]):
                q["target"] = p["endpoint"]
            if moved < 1e-12 * 2000.0:
                break

    problem = json.loads(json.dumps(base))
    problem["name"] = "desert-lake-15"
    problem["description"] = ("desert-lake with three more glances (15 pairs, 4 free parameters): "
                              "the 15-pair hot-spot problem of benches/fit.rs, made by "
                              "benches/baseline/make_15pair.py.")
    problem["pairs"] = base["pairs"] + known["pairs"]
    dest = HERE / "problems/desert-lake-15.json"
    dest.parent.mkdir(exist_ok=True)
    # One field, and one pair, per line, like the bundled problems.
    fields = [f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in problem.items() if k != "pairs"]
    pairs = ",\n".join("    " + json.dumps(p) for p in problem["pairs"])
    fields.insert(5, '  "pairs": [\n' + pairs + "\n  ]")
    dest.write_text("{\n" + ",\n".join(fields) + "\n}\n")
    print(f"wrote {dest.relative_to(ROOT)} ({len(problem['pairs'])} pairs)")


if __name__ == "__main__":
    main()
