#!/usr/bin/env python3
"""Compare fan.cpp output (file or stdin) with fan_reference.json.

Usage:  /tmp/wigner-mirage-build/fan > /tmp/fan.txt && python3 compare.py /tmp/fan.txt
Standard library only.
"""
import json
import math
import os
import sys


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ref = json.load(open(os.path.join(here, "fan_reference.json")))
    src = open(sys.argv[1]) if len(sys.argv) > 1 else sys.stdin
    rows = [l.split() for l in src if l.strip() and not l.startswith("#")]
    assert len(rows) == len(ref["y"]), (len(rows), len(ref["y"]))
    xt = ref["x_target"]
    worst_raw = worst_corr = worst_dir = worst_dx = 0.0
    arg_raw = None
    bad_angle = invalid = ground_mismatch = 0
    for r, a, yr, pr, g in zip(rows, ref["angles_deg"], ref["y"], ref["dy_dx"], ref["ground"]):
        i, ang, valid, x, y, d = int(r[0]), float(r[1]), int(r[2]), float(r[3]), float(r[4]), float(r[5])
        bad_angle += abs(ang - a) > 1e-15
        invalid += not valid
        ground_mismatch += (not valid) != g
        if g or not valid:
            continue
        e_raw = abs(y - yr)                                       # as returned (x >= x_target)
        e_corr = abs(y - (x - xt) * math.tan(math.radians(d)) - yr)  # moved back to x_target
        e_dir = abs(d - math.degrees(math.atan(pr)))
        if e_raw > worst_raw:
            worst_raw, arg_raw = e_raw, (i, ang)
        worst_corr = max(worst_corr, e_corr)
        worst_dir = max(worst_dir, e_dir)
        worst_dx = max(worst_dx, x - xt)
    print(f"rays {len(rows)}, angle mismatches {bad_angle}, invalid {invalid}, "
          f"ground-flag mismatches {ground_mismatch}")
    print(f"worst |y - y_ref| as returned by solve4x: {worst_raw:.3e} m at ray {arg_raw[0]} ({arg_raw[1]:.6f} deg)")
    print(f"worst |y - y_ref| moved back to x = {xt:g}:   {worst_corr:.3e} m")
    print(f"worst direction error: {worst_dir:.3e} deg; max x overshoot {worst_dx:.3e} m")


if __name__ == "__main__":
    main()
