"""Photo problems from Python (``docs/photo.md``): the bundled photograph
``problems/photo/looming.json`` fitted by :func:`mirage_air.fit`, and its
overlay from :func:`mirage_air.overlay` equal to the CLI's PNG pixel for pixel."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import mirage_air
from mirage_air import InputError

ROOT = Path(__file__).resolve().parents[2]
PHOTO = ROOT / "problems" / "photo" / "looming.json"
TRUTH = json.loads((ROOT / "problems" / "photo" / "looming-truth.json").read_text())


def mirage_bin():
    b = os.environ.get("MIRAGE_BIN") or str(ROOT / "target" / "release" / "mirage")
    return b if Path(b).exists() else None


needs_cli = pytest.mark.skipif(mirage_bin() is None, reason="no mirage binary (MIRAGE_BIN)")


def cli(*args):
    p = subprocess.run([mirage_bin(), *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p


@pytest.fixture(scope="module")
def fitted():
    return mirage_air.fit(PHOTO, threads=1)


def test_fit_takes_a_photo_problem_and_recovers_its_truth(fitted):
    for name, truth in TRUTH.items():
        se = fitted.standard_errors[name]
        assert se is not None and se > 0
        assert abs(fitted.values[name] - truth) <= 3 * se, (name, fitted.values[name], truth, se)
    photo = fitted.photo
    assert photo is not None and photo == fitted.report["photo"]
    assert len(photo["marks"]) == 10 and "EXIF" in photo["focal_source"]
    assert 0.2 < photo["rms_pixels"] < 0.75
    assert dict(photo["camera"])["camera.roll"] == fitted.values["camera.roll"]


def test_a_plain_fit_has_no_photo_section():
    assert mirage_air.fit(ROOT / "problems" / "hot-road.json").photo is None


@needs_cli
def test_overlay_equals_the_cli_png_pixel_for_pixel(fitted, tmp_path):
    out, result = tmp_path / "fitted.png", tmp_path / "result.json"
    cli("--threads", "1", "fit", PHOTO, "-o", result, "--overlay", out, "-q")
    png = np.asarray(Image.open(out).convert("RGB"))
    got = mirage_air.overlay(PHOTO, fitted)
    assert got.dtype == np.uint8 and got.shape == (600, 1200, 3)
    assert np.array_equal(got, png)
    # The CLI's result as a dict draws the same.
    assert np.array_equal(mirage_air.overlay(PHOTO, json.loads(result.read_text())), png)
    start = tmp_path / "start.png"
    cli("overlay", PHOTO, "-o", start)
    unfitted = mirage_air.overlay(PHOTO)
    assert np.array_equal(unfitted, np.asarray(Image.open(start).convert("RGB")))
    assert not np.array_equal(unfitted, got)


def test_overlay_bad_input_names_the_field_or_the_argument(fitted):
    with pytest.raises(InputError) as e:
        mirage_air.overlay(ROOT / "problems" / "hot-road.json")
    assert e.value.field == "photo" and e.value.file.endswith("hot-road.json")
    plain = mirage_air.fit(ROOT / "problems" / "hot-road.json")
    for bad in (plain, {"photo": {"image": "x.jpg"}}, 3):
        with pytest.raises(InputError) as e:
            mirage_air.overlay(PHOTO, bad)
        assert e.value.field == "result", bad
    other = json.loads(json.dumps(fitted.report))
    other["photo"]["marks"] = other["photo"]["marks"][:3]
    with pytest.raises(InputError) as e:
        mirage_air.overlay(PHOTO, other)
    assert e.value.field == "result" and "another photo problem" in str(e.value)
    with pytest.raises(InputError) as e:
        mirage_air.overlay(PHOTO, threads=0)
    assert e.value.field == "threads"
