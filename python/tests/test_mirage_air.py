"""mirage_air against the CLI it shares its library with.

The comparisons with the command line need the ``mirage`` binary: ``MIRAGE_BIN``
(``cargo test`` sets it, `tests/python.rs`), else ``target/release/mirage`` if
built; without one they are skipped. The render comparison reads the CLI's EXR
with Mitsuba's ``Bitmap`` (in notebooks/.venv) and is skipped without it.
"""

from __future__ import annotations

import copy
import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import mirage_air
from mirage_air import InputError

ROOT = Path(__file__).resolve().parents[2]
PROBLEMS = sorted((ROOT / "problems").glob("*.json"))
SCENE = ROOT / "problems" / "scenes" / "road.json"


def mirage_bin():
    b = os.environ.get("MIRAGE_BIN") or str(ROOT / "target" / "release" / "mirage")
    return b if Path(b).exists() else None


needs_cli = pytest.mark.skipif(mirage_bin() is None, reason="no mirage binary (MIRAGE_BIN)")


def cli(*args):
    p = subprocess.run([mirage_bin(), *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p


def without_times(doc):
    """A fit result without its wall-clock fields (all else must match)."""
    d = copy.deepcopy(doc)
    d["solver"].pop("wall_time_s")
    for run in d["history"]["runs"]:
        for rec in run["records"]:
            rec.pop("elapsed_s")
    return d


def test_version_and_exports():
    assert mirage_air.__version__.count(".") == 2
    assert issubclass(InputError, ValueError)


def test_load_tells_problems_from_scenes_and_round_trips():
    p = mirage_air.load(ROOT / "problems" / "hot-road.json")
    assert isinstance(p, mirage_air.Problem) and p.name == "hot-road"
    s = mirage_air.load(SCENE)
    assert isinstance(s, mirage_air.Scene) and s.name == "road"
    for doc in (p, s):
        again = mirage_air.load(doc.to_dict())
        assert type(again) is type(doc)
        assert again.to_dict() == doc.to_dict()


@needs_cli
@pytest.mark.parametrize("path", PROBLEMS, ids=lambda p: p.stem)
def test_trace_equals_the_cli(path, tmp_path):
    out = tmp_path / "trace.json"
    cli("trace", path, "-o", out)
    ref = json.loads(out.read_text())
    got = mirage_air.trace(path)
    m = len(ref["pairs"])
    assert got.endpoints.shape == (m, 3) and got.endpoints.dtype == np.float64
    assert got.distances.shape == (m,) and got.occluded.dtype == bool
    assert np.array_equal(got.endpoints, np.array([p["endpoint"] for p in ref["pairs"]]))
    assert np.array_equal(got.directions, np.array([p["direction"] for p in ref["pairs"]]))
    assert np.array_equal(got.distances, np.array([p["distance"] for p in ref["pairs"]]))
    assert got.objective == ref["objective"]


@needs_cli
@pytest.mark.parametrize("name", ["hot-road", "desert-lake", "wigner-water"])
def test_fit_equals_the_cli_bit_for_bit(name, tmp_path):
    path = ROOT / "problems" / f"{name}.json"
    out = tmp_path / "fit.json"
    cli("--threads", "1", "fit", path, "-o", out, "-q")
    ref = json.loads(out.read_text())
    got = mirage_air.fit(path, threads=1)
    # The medium JSON identical, every number included.
    assert json.dumps(got.medium, sort_keys=True) == json.dumps(ref["medium"], sort_keys=True)
    assert got.values == {p["name"]: p["value"] for p in ref["parameters"]}
    assert got.standard_errors == {p["name"]: p["standard_error"] for p in ref["parameters"]}
    assert got.objective == ref["objective"]
    assert without_times(json.loads(got.to_json())) == without_times(ref)
    # The history as arrays, one row per record.
    h = got.history
    records = sum(len(r["records"]) for r in ref["history"]["runs"])
    assert h.params.shape == (records, len(got.values)) and h.objective.shape == (records,)
    assert h.objective[-1] >= got.objective or np.isclose(h.objective[-1], got.objective)


@needs_cli
def test_grow_equals_the_cli(tmp_path):
    path = ROOT / "problems" / "grow" / "one-hot-spot.json"
    out = tmp_path / "grow.json"
    cli("--threads", "1", "fit", path, "--grow", "--noise", "0.01", "-o", out, "-q")
    ref = json.loads(out.read_text())
    got = mirage_air.fit(path, grow=True, noise=0.01, threads=1)
    assert json.dumps(got.medium, sort_keys=True) == json.dumps(ref["medium"], sort_keys=True)
    assert len(got.medium["hotspots"]) == 1 and "inversion" not in got.medium
    assert got.grow is not None and len(got.grow["steps"]) == len(ref["grow"]["steps"])
    # The bundled growth problems say `"grow": true`; a plain problem does not.
    plain = ROOT / "problems" / "hot-road.json"
    assert mirage_air.fit(plain, threads=1).grow is None
    for kwargs, name in [({"noise": 0.01}, "noise"), ({"grow": True, "noise": -1.0}, "noise"),
                         ({"grow": True, "max_terms": 0}, "max_terms"),
                         ({"grow": True, "method": "nelder-mead"}, "method")]:
        with pytest.raises(InputError) as e:
            mirage_air.fit(plain, **kwargs)
        assert e.value.field == name, (kwargs, e.value.field, str(e.value))


def test_fit_from_a_dict_recovers_the_hot_road_and_is_thread_independent():
    doc = json.loads((ROOT / "problems" / "hot-road.json").read_text())
    one = mirage_air.fit(doc, threads=1)
    two = mirage_air.fit(doc, threads=2)
    assert one.values == two.values and one.medium == two.medium
    assert one.values["hotspots[0].n"] == pytest.approx(-3.0, abs=1e-9)
    assert one.values["hotspots[0].radius"] == pytest.approx(110.0, abs=1e-7)
    assert one.objective < 1e-20


def test_render_shape_dtype_and_threads():
    a = mirage_air.render(SCENE, width=64, height=36, threads=1)
    b = mirage_air.render(SCENE, width=64, height=36, threads=2)
    assert a.shape == (36, 64, 3) and a.dtype == np.float32
    assert np.array_equal(a, b)
    assert np.isfinite(a).all() and a.max() > 0
    straight = mirage_air.render(SCENE, width=64, height=36, straight=True)
    assert np.abs(straight - a).max() > 1e-3, "the mirage changes the picture"
    albedo = mirage_air.render(SCENE, width=64, height=36, albedo=True)
    assert albedo.max() <= 1.0 + 1e-6


@needs_cli
def test_render_equals_the_cli_exr(tmp_path):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    cli("render", SCENE, "--width", 96, "--height", 54, "-o", tmp_path / "r.png",
        "--exr", tmp_path / "r.exr", "-q")
    ref = np.array(mi.Bitmap(str(tmp_path / "r.exr")), dtype=np.float32)[..., :3]
    got = mirage_air.render(SCENE, width=96, height=54)
    assert got.shape == ref.shape
    assert np.abs(got - ref).max() <= 1e-6


def test_a_zero_rate_is_an_input_error_naming_the_field():
    doc = json.loads((ROOT / "problems" / "hot-road.json").read_text())
    doc["medium"]["background"]["a"] = 0.0
    for call in (mirage_air.load, mirage_air.trace, mirage_air.fit):
        with pytest.raises(InputError) as e:
            call(doc)
        assert "medium.background.a" in str(e.value)
        assert e.value.field == "medium.background.a"
        assert e.value.file == "<dict>"
    with pytest.raises(InputError) as e:
        mirage_air.Medium(doc["medium"])
    assert "medium.background.a" in str(e.value)


def test_bad_input_names_the_file_or_the_argument(tmp_path):
    with pytest.raises(InputError) as e:
        mirage_air.load(tmp_path / "missing.json")
    assert e.value.file.endswith("missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"medium": {"scale": 1.0, "background": {"n": 1.0, "a": 150.0}}, "pairs": [{"origin": [0, 1, 0], "through": [0, 1, 10], "target": "x"}]}')
    with pytest.raises(InputError) as e:
        mirage_air.load(bad)
    assert e.value.file == str(bad) and e.value.field.startswith("pairs[0].target")
    with pytest.raises(InputError) as e:
        mirage_air.fit(ROOT / "problems" / "hot-road.json", method="newton")
    assert e.value.field == "method"
    with pytest.raises(InputError) as e:
        mirage_air.trace(ROOT / "problems" / "hot-road.json", threads=0)
    assert e.value.field == "threads"
    with pytest.raises(InputError) as e:
        mirage_air.render(SCENE, width=0)
    assert e.value.field == "width"
    with pytest.raises(InputError):
        mirage_air.load({"camera": {"position": [0, 1, 0]}, "medium": {"scale": 1.0}})
    with pytest.raises(InputError):
        mirage_air.load({"medium": {"scale": float("nan")}, "pairs": []})
    with pytest.raises(TypeError):
        mirage_air.render(mirage_air.load(ROOT / "problems" / "hot-road.json"))


def test_medium_delta_and_gradient_against_differences():
    medium = json.loads((ROOT / "problems" / "desert-lake.json").read_text())["medium"]
    m = mirage_air.Medium(medium)
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(-200, 200, 40), rng.uniform(0.05, 3, 40), rng.uniform(0, 1500, 40)])
    d = m.delta(pts)
    g = m.gradient(pts)
    assert d.shape == (40,) and g.shape == (40, 3) and d.dtype == np.float64
    h = 1e-4
    for axis in range(3):
        e = np.zeros(3)
        e[axis] = h
        fd = (m.delta(pts + e) - m.delta(pts - e)) / (2 * h)
        assert np.allclose(g[:, axis], fd, rtol=1e-5, atol=1e-12 * np.abs(g).max())
    # float32 and list input are accepted; a wrong shape is an input error.
    assert np.array_equal(m.delta(pts.astype(np.float32).astype(np.float64)), m.delta(pts.astype(np.float32)))
    assert m.delta([[0.0, 1.0, 0.0]]).shape == (1,)
    with pytest.raises(InputError):
        m.delta(np.zeros((4, 2)))


def test_medium_over_the_round_earth_takes_heights_above_the_sphere():
    medium = json.loads((ROOT / "problems" / "cold-sea.json").read_text())["medium"]
    r = 6_371_000.0
    flat = mirage_air.Medium(medium)
    round_ = mirage_air.Medium(medium, earth_radius=r)
    # 8 km out, 5 m above the sphere: y = −drop + 5.
    x, z = 0.0, 8000.0
    drop = r - np.sqrt(r * r - z * z)
    on_sphere = round_.delta([[x, -drop + 5.0, z]])
    assert on_sphere == pytest.approx(flat.delta([[x, 5.0, z]]), rel=1e-9)
    with pytest.raises(InputError):
        mirage_air.Medium(medium, earth_radius=10.0)


def test_ctrl_c_interrupts_a_long_render():
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        mirage_air.render(SCENE, width=640, height=360, spp=16)
    assert time.perf_counter() - t0 < 2.0


@needs_cli
def test_sightlines_of_the_maine_surveyor_equal_the_cli(tmp_path):
    path = ROOT / "problems" / "maine-surveyor.json"
    out = tmp_path / "fit.json"
    cli("--threads", "1", "fit", path, "-o", out, "-q")
    ref = [p["sightline"] for p in json.loads(out.read_text())["pairs"]]
    got = mirage_air.fit(path, threads=1).sightlines
    assert got is not None and got.k.shape == (2,)
    for key in ("apparent_elevation", "geometric_elevation", "refraction_arcsec", "k",
                "clearance", "miss_up_arcsec", "air_refraction_arcsec", "air_k"):
        assert np.array_equal(getattr(got, key), np.array([s[key] for s in ref])), key
    # Bislin's analysis: k = 0.20 on both lines through the fitted air.
    assert np.allclose(got.air_k, 0.20, atol=0.01)
    assert not got.below_horizon.any()
    # The trace of the starting air has them too; the flat ground has none.
    assert mirage_air.trace(path).sightlines is not None
    assert mirage_air.trace(ROOT / "problems" / "hot-road.json").sightlines is None


def test_a_scene_by_latitude_and_longitude_loads_and_renders():
    path = ROOT / "problems" / "scenes" / "canigou.json"
    s = mirage_air.load(path)
    assert isinstance(s, mirage_air.Scene)
    assert s.to_dict()["objects"][0]["at"]["latitude"] == 42.51858
    img = mirage_air.render(path, width=8, albedo=True, threads=1)
    assert img.shape == (4, 8, 3) and np.isfinite(img).all()
    doc = s.to_dict()
    doc["site"]["latitude"] = 91
    with pytest.raises(InputError) as e:
        mirage_air.load(doc)
    assert e.value.field == "site.latitude"


@needs_cli
@pytest.mark.parametrize("name", ["igra2-good.txt", "wyoming-good.html", "mast.csv"])
def test_sounding_equals_the_cli(name, tmp_path):
    path = ROOT / "tests" / "data" / "sounding" / name
    out = tmp_path / "air.json"
    cli("sounding", path, "-o", out)
    assert mirage_air.sounding(path) == json.loads(out.read_text())
    # The medium drops into a problem as it is.
    doc = json.loads((ROOT / "problems" / "maine-surveyor.json").read_text())
    doc["medium"] = mirage_air.sounding(path)
    doc["free"] = []
    assert np.isfinite(mirage_air.trace(doc).distances).all()


def test_bad_soundings_name_the_line_or_the_argument():
    data = ROOT / "tests" / "data" / "sounding"
    with pytest.raises(InputError) as e:
        mirage_air.sounding(data / "igra2-height.txt")
    assert e.value.file.endswith("igra2-height.txt") and "line" in str(e.value)
    with pytest.raises(InputError) as e:
        mirage_air.sounding(data / "mast.csv", format="netcdf")
    assert e.value.field == "format"
    with pytest.raises(InputError) as e:
        mirage_air.sounding(data / "mast.csv", site_height=float("nan"))
    assert e.value.field == "site_height"
