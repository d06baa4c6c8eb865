#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ (ignored by git) with seeds from the bundled
# problems and scenes, so that libFuzzer starts from inputs that get past the
# JSON syntax. Idempotent; the corpora themselves are not committed.
set -euo pipefail
cd "$(dirname "$0")"
root=..
c=corpus
mkdir -p "$c/problem" "$c/scene" "$c/fit_result" "$c/air" "$c/structured" "$c/sounding"

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
echo "seeded: $(find "$c" -type f | wc -l) files in $c/"
