#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ (ignored by git) with seeds from the bundled
# problems and scenes, so that libFuzzer starts from inputs that get past the
# JSON syntax. Idempotent; the corpora themselves are not committed.
set -euo pipefail
cd "$(dirname "$0")"
root=..
c=corpus
mkdir -p "$c/problem" "$c/scene" "$c/fit_result" "$c/air" "$c/structured" "$c/sounding" "$c/geo"

# Problem files, as they are.
for f in "$root"/problems/*.json "$root"/problems/atmospheres/*.json "$root"/problems/grow/*.json; do
    cp "$f" "$c/problem/$(basename "$(dirname "$f")")-$(basename "$f")"
done

# Scenes: the scene, a NUL, then the sibling `medium_from` may name. Inline
# scenes get a problem as sibling; each also appears pointing at the sibling.
problems=("$root"/problems/*.json)
i=0
for f in "$root"/problems/scenes/*.json; do
    sib=${problems[$((i % ${#problems[@]}))]}
    i=$((i + 1))
    { cat "$f"; printf '\0'; cat "$sib"; } >"$c/scene/$(basename "$f")"
    python3 - "$f" "$sib" >"$c/scene/from-$(basename "$f")" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s.pop("medium", None)
s["medium_from"] = "sibling.json"
sys.stdout.write(json.dumps(s))
sys.stdout.write("\0")
sys.stdout.write(open(sys.argv[2]).read())
PY
done

# Fit results read back: any file with a `medium` (problems, scenes), and a
# result-shaped document around each medium.
for f in "$root"/problems/*.json "$root"/problems/atmospheres/*.json "$root"/problems/scenes/*.json; do
    cp "$f" "$c/fit_result/$(basename "$f")"
    python3 - "$f" >"$c/fit_result/result-$(basename "$f")" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["medium"]
print(json.dumps({"problem": "x.json", "medium": m, "totals": {"objective": 0.0}}))
PY
done

# Media alone, real air first.
for f in "$root"/problems/*.json "$root"/problems/atmospheres/*.json "$root"/problems/scenes/*.json; do
    python3 -c 'import json,sys; print(json.dumps(json.load(open(sys.argv[1]))["medium"]))' "$f" \
        >"$c/air/$(basename "$f")"
done

# The structured target starts from a few fixed byte strings.
for n in 0 1 2 3; do
    head -c 256 /dev/zero | tr '\0' "\\$((n + 1))" >"$c/structured/fill-$n"
done
# Soundings: the test files, each with a format byte (0 IGRA 2, 1 Wyoming,
# 2 CSV, 3 inferred) and a site byte (even: no site height).
for f in "$root"/tests/data/sounding/*; do
    for n in 0 1 2 3; do
        { printf "\\$((n))"; printf '\0'; cat "$f"; } >"$c/sounding/$n-$(basename "$f")"
    done
done
# Places and angles: a mode byte, then the input. 0: angle strings (the
# docs' examples and the elevations of the problems); 1: fixed byte strings
# for `arbitrary`; 2: problem files with a `site`, and variations of them
# (geographic origins and `through`, azimuths, an `earth`).
i=0
for a in "-0°02'47\"" "212°30′00″" "12d30m5.5s" "-0 2 47" "45°" "  7.25 " "30'" "+1°30'" \
    "−1°2′3.5″" "-0°05′09″" "-0.5" "90" "1°60'" "1.5°30'" "0°00′00.01″" "359º59’59.99s"; do
    { printf '\0'; printf '%s' "$a"; } >"$c/geo/angle-$i"
    i=$((i + 1))
done
for n in 0 1 2 3; do
    { printf '\001'; head -c 256 /dev/zero | tr '\0' "\\$((n + 2))"; } >"$c/geo/fill-$n"
done
for f in $(grep -l '"site"' "$root"/problems/*.json); do
    { printf '\002'; cat "$f"; } >"$c/geo/$(basename "$f")"
    python3 - "$f" "$c/geo/var-$(basename "$f" .json)" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
site = p["site"]
pairs = p["pairs"]
variants = []
# The origin at the site as a geographic point, the azimuth written out.
q = json.loads(json.dumps(p))
for pr in q["pairs"]:
    pr["origin"] = {"latitude": site["latitude"], "longitude": site["longitude"], "height": site["height"]}
    pr["azimuth"] = "212°30'00\""
variants.append(q)
# `through` a geographic point instead of an elevation; an earth of its own.
q = json.loads(json.dumps(p))
for pr in q["pairs"]:
    pr.pop("elevation", None)
    pr.pop("azimuth", None)
    pr["through"] = dict(pr["target"]) if isinstance(pr["target"], dict) else pr["target"]
q["earth"] = {"radius": 6371000.0}
variants.append(q)
# Across the antimeridian, near a pole.
q = json.loads(json.dumps(p))
q["site"] = {"latitude": 89.9, "longitude": 179.999, "height": 0}
variants.append(q)
for k, v in enumerate(variants):
    with open(f"{sys.argv[2]}-{k}", "w") as out:
        out.write("\x02")
        out.write(json.dumps(v))
PY
done
echo "seeded: $(find "$c" -type f | wc -l) files in $c/"
