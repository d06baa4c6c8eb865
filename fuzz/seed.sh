#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ (ignored by git) with seeds from the bundled
# problems and scenes, so that libFuzzer starts from inputs that get past the
# JSON syntax. Idempotent; the corpora themselves are not committed.
set -euo pipefail
cd "$(dirname "$0")"
root=..
c=corpus
mkdir -p "$c/problem" "$c/scene" "$c/fit_result" "$c/air" "$c/structured" "$c/sounding" "$c/geo" "$c/photo"

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
# Photo problems: the problem, a NUL, then the image's bytes (the target writes
# them as `image.bin`). Small PNGs written here (some with an eXIf chunk giving
# FocalLengthIn35mmFilm), problems over both earths with target and horizon
# marks, distortion and free camera numbers; and the bundled photo problems
# with their own images.
python3 - "$c/photo" <<'PY'
import json, struct, sys, zlib
out = sys.argv[1]

def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

def exif(focal35):
    # A little-endian TIFF header, IFD0 with one entry (the Exif IFD's
    # offset), and the Exif IFD with FocalLengthIn35mmFilm (SHORT).
    ifd0 = struct.pack("<H", 1) + struct.pack("<HHII", 0x8769, 4, 1, 26) + struct.pack("<I", 0)
    sub = struct.pack("<H", 1) + struct.pack("<HHIHH", 0xA405, 3, 1, focal35, 0) + struct.pack("<I", 0)
    return b"II*\x00" + struct.pack("<I", 8) + ifd0 + sub

def png(w, h, focal35=None):
    raw = b"".join(b"\x00" + bytes((x * 7 + y * 3) % 256 for x in range(w * 3)) for y in range(h))
    body = chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    if focal35:
        body += chunk(b"eXIf", exif(focal35))
    return b"\x89PNG\r\n\x1a\n" + body + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")

air = {"air": {"temperature": {"base": 12.0, "lapse": -0.0065}, "pressure": 101325.0, "humidity": 0.0}}
logistic = {"scale": 0.015, "background": {"n": 1.0, "a": 300.0}, "inversion": {"n": 0.9, "a": 2.0, "height": 15.0}}
cases = []
for k, (earth, medium, focal, horizon, dist, free) in enumerate([
    ("round", air, {"horizontal_fov": 10.0}, True, None, ["air.temperature.lapse", "camera.tilt"]),
    ("flat", air, {"horizontal_fov": 30.0}, False, {"k1": -0.05}, ["camera.tilt", "camera.roll", "camera.azimuth"]),
    ("round", logistic, {"focal_length": 50.0, "sensor_width": 36.0}, True, {"k1": -0.1, "k2": 0.01, "p1": 1e-3}, ["camera.tilt", "camera.distortion.k1"]),
    ("round", air, {}, True, None, ["camera.tilt", "camera.roll"]),
    ("flat", logistic, {"horizontal_fov": 8.0, "principal_point": [30.0, 25.0]}, False, None, []),
]):
    w, h = 64, 48
    cam = dict(focal, azimuth=0.0, tilt=0.0, roll=0.3, position=[0.0, 10.0, 0.0])
    if dist:
        cam["distortion"] = dist
    marks = [{"name": "lamp", "pixel": [33.5, 22.0], "target": [50.0, 20.0, 3000.0]},
             {"name": "mast", "pixel": [12.0, 25.5], "target": [-400.0, 5.0, 8000.0]}]
    if horizon:
        marks.append({"name": "sea", "pixel": [20.0, 30.0], "horizon": True})
    p = {"name": f"photo-{k}", "photo": {"image": "image.bin", "camera": cam}, "marks": marks,
         "noise": 0.5, "medium": medium, "free": free}
    if earth == "round":
        p["earth"] = {"radius": 6371000.0}
    cases.append((f"gen-{k}", json.dumps(p).encode(), png(w, h, 50 if not focal else None)))
for name, text, image in cases:
    with open(f"{out}/{name}", "wb") as f:
        f.write(text + b"\0" + image)
PY
for f in "$root"/problems/photo/*.json; do
    [ -e "$f" ] || continue
    # Only photo problems (the folder also holds the example's scene and truth).
    img=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1])).get("photo", {}).get("image", ""))' "$f")
    [ -n "$img" ] || continue
    python3 - "$f" "$(dirname "$f")/$img" "$c/photo/bundled-$(basename "$f")" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
p["photo"]["image"] = "image.bin"
with open(sys.argv[3], "wb") as out:
    out.write(json.dumps(p).encode() + b"\0" + open(sys.argv[2], "rb").read())
PY
done
echo "seeded: $(find "$c" -type f | wc -l) files in $c/"
