"""mirage_air.ensemble, render_frames and write_video on executors.

Each member or frame is one task; on a Dask ``LocalCluster`` of two worker
processes (loopback only, started and stopped here), on process and thread
pools, the results are bit for bit those of the local run (the library's own
threads), and the ensemble is ``mirage ensemble``'s JSON. A worker killed in
the middle of an ensemble loses nothing. Bad arguments raise before any work,
naming the argument or the field, and every result pickles.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import pickle
import re
import signal
import sys
import threading
import time
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import mirage_air
from mirage_air import InputError

from test_mirage_air import ROOT, SCENE, cli, needs_cli

COLD = ROOT / "problems" / "cold-sea.json"
# Real air: a member's fit takes ~0.1 s on one thread, so a worker can be
# killed while it runs one.
KELVIN = ROOT / "problems" / "cold-sea-kelvin.json"


def without_time(text: str) -> str:
    """A report's JSON without its wall-clock line (all else must match)."""
    return re.sub(r'\n  "wall_time_s": [^\n]*\n', "\n", text)


def assert_same_ensemble(a: mirage_air.EnsembleResult, b: mirage_air.EnsembleResult) -> None:
    assert without_time(a.to_json()) == without_time(b.to_json())
    assert np.array_equal(a.members, b.members)
    assert np.array_equal(a.temperature.percentiles, b.temperature.percentiles)


def heating_road(count: int):
    """The road scene with its hot patch growing from nothing to full."""
    base = json.loads(SCENE.read_text())
    scenes = []
    for s in np.linspace(0.0, 1.0, count):
        doc = json.loads(json.dumps(base))
        doc["medium"]["hotspots"][0]["n"] = -3.0 * float(s)
        scenes.append(doc)
    return scenes


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed")
    import logging

    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=logging.CRITICAL) as cluster:
        with distributed.Client(cluster) as client:
            client.wait_for_workers(2, timeout=60)
            yield client


class Counting(Executor):
    """An executor that runs nothing and counts what it was given."""

    def __init__(self) -> None:
        self.submitted = 0

    def submit(self, fn, *args, **kwargs):
        self.submitted += 1
        raise AssertionError("a task was submitted")


@needs_cli
def test_ensemble_on_dask_equals_the_local_run_and_the_cli(dask_client, tmp_path):
    kw = dict(n=8, noise=0.02, seed=3, truth=COLD)
    local = mirage_air.ensemble(COLD, **kw)
    on_dask = mirage_air.ensemble(COLD, executor=dask_client, **kw)
    assert_same_ensemble(local, on_dask)
    out = tmp_path / "ensemble.json"
    cli("ensemble", COLD, "-n", 8, "--noise", 0.02, "--seed", 3, "--truth", COLD, "-o", out)
    assert without_time(out.read_text()) == without_time(local.to_json())
    assert local.members.shape == (8, 3) and local.temperature.truth is not None
    assert list(local.parameters) == [p["name"] for p in json.loads(out.read_text())["parameters"]]
    # Bootstrap through the client's executor: the same as here too.
    boot = dict(n=6, bootstrap=True, seed=5)
    assert_same_ensemble(mirage_air.ensemble(COLD, **boot),
                         mirage_air.ensemble(COLD, executor=dask_client.get_executor(), **boot))


def test_render_frames_on_dask_equal_the_local_run(dask_client):
    scenes = heating_road(3)
    size = dict(width=64, height=36)
    local = mirage_air.render_frames(scenes, **size)
    on_dask = mirage_air.render_frames(scenes, executor=dask_client, **size)
    assert len(on_dask) == 3
    for a, b in zip(local, on_dask):
        assert a.dtype == np.float32 and a.shape == (36, 64, 3)
        assert np.array_equal(a, b)
    # In order, and each the frame `render` gives: the road changes as it heats.
    assert np.array_equal(local[1], mirage_air.render(scenes[1], **size))
    assert np.abs(local[0] - local[2]).max() > 1e-3
    srgb = mirage_air.render_frames(scenes, executor=dask_client, srgb=True, **size)
    for a, b in zip(srgb, mirage_air.render_frames(scenes, srgb=True, **size)):
        assert a.dtype == np.uint8 and np.array_equal(a, b)


def test_process_and_thread_pools_give_the_local_results():
    kw = dict(n=5, noise=0.02, seed=11)
    local = mirage_air.ensemble(COLD, **kw)
    with ThreadPoolExecutor(2) as pool:
        assert_same_ensemble(local, mirage_air.ensemble(COLD, executor=pool, **kw))
        frames = mirage_air.render_frames(heating_road(2), executor=pool, width=48, height=27)
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        assert_same_ensemble(local, mirage_air.ensemble(COLD, executor=pool, **kw))
        in_processes = mirage_air.render_frames(heating_road(2), executor=pool, width=48, height=27)
    for a, b, c in zip(frames, in_processes, mirage_air.render_frames(heating_road(2), width=48, height=27)):
        assert np.array_equal(a, c) and np.array_equal(b, c)


def test_bad_arguments_raise_before_any_work(tmp_path):
    pool = Counting()
    doc = json.loads(COLD.read_text())
    unknown = dict(doc, colour="red")
    no_free = dict(doc, free=[], bounds={})
    bad_truth = json.loads(COLD.read_text())["medium"]
    bad_truth["background"]["a"] = 0.0
    for kwargs, field in [
        (dict(n=0), "n"),
        (dict(n=-3), "n"),
        (dict(n=2.5), "n"),
        (dict(n=4, noise=-1.0), "noise"),
        (dict(n=4, noise=float("nan")), "noise"),
        (dict(n=4, noise="big"), "noise"),
        (dict(n=4, noise=0.1, bootstrap=True), "bootstrap"),
        (dict(n=4, seed=-1), "seed"),
        (dict(n=4, threads=0), "threads"),
        (dict(n=4, truth=bad_truth), "medium.background.a"),
        (dict(problem=unknown, n=4), "colour"),
        (dict(problem=no_free, n=4), "free"),
    ]:
        problem = kwargs.pop("problem", COLD)
        with pytest.raises(InputError) as e:
            mirage_air.ensemble(problem, executor=pool, **kwargs)
        assert field in (e.value.field or "") or field in str(e.value), (kwargs, str(e.value))
        if field in ("n", "noise", "bootstrap", "seed", "threads", "free"):
            assert e.value.field == field, (kwargs, e.value.field)
    with pytest.raises(InputError) as e:
        mirage_air.ensemble(COLD, n=4, executor="a cluster")
    assert e.value.field == "executor"
    scenes = heating_road(3)
    scenes[1]["camera"]["vertical_fov"] = -1.0
    with pytest.raises(InputError) as e:
        mirage_air.render_frames(scenes, executor=pool)
    assert e.value.field.startswith("scenes[1].camera"), e.value.field
    for kwargs, field in [(dict(width=0), "width"), (dict(spp=10**9), "spp"), (dict(height=-1), "height")]:
        with pytest.raises(InputError) as e:
            mirage_air.render_frames(heating_road(2), executor=pool, **kwargs)
        assert e.value.field == field
    assert pool.submitted == 0
    frames = [np.zeros((4, 6, 3), np.uint8), np.zeros((4, 8, 3), np.uint8)]
    for bad, field in [(frames, "frames"), ([np.zeros((4, 6, 3))], "frames"), ([], "frames")]:
        with pytest.raises(InputError) as e:
            mirage_air.write_video(bad, tmp_path / "v.mp4")
        assert e.value.field == field
    with pytest.raises(InputError) as e:
        mirage_air.write_video(frames[:1], tmp_path / "v.mp4", fps=0)
    assert e.value.field == "fps"
    assert not (tmp_path / "v.mp4").exists()


def test_every_result_pickles():
    def again(x):
        return pickle.loads(pickle.dumps(x))

    r = mirage_air.ensemble(COLD, n=4, noise=0.02, truth=COLD)
    back = again(r)
    assert isinstance(back, mirage_air.EnsembleResult) and back.to_json() == r.to_json()
    assert back.report == r.report and np.array_equal(back.members, r.members)
    assert np.array_equal(back.delta.truth, r.delta.truth)
    assert back.parameters["inversion.height"].percentiles.tolist() == r.parameters["inversion.height"].percentiles.tolist()
    problem = mirage_air.load(COLD)
    fit = mirage_air.fit(again(problem), threads=1)
    assert again(fit).to_json() == fit.to_json() and again(fit).history.params.tolist() == fit.history.params.tolist()
    trace = mirage_air.trace(problem)
    assert np.array_equal(again(trace).endpoints, trace.endpoints) and again(trace).report == trace.report
    scene = mirage_air.load(SCENE)
    assert again(scene).to_dict() == scene.to_dict()
    medium = mirage_air.Medium(fit.medium)
    pts = [[0.0, 5.0, 1000.0]]
    assert np.array_equal(again(medium).delta(pts), medium.delta(pts))
    frame = mirage_air.render_frames([scene], width=16, height=9, threads=1)[0]
    assert np.array_equal(again(frame), frame)


@needs_cli
def test_srgb_frames_are_the_cli_png(tmp_path):
    iio = pytest.importorskip("imageio.v3")
    cli("render", SCENE, "--width", 96, "--height", 54, "-o", tmp_path / "r.png", "-q")
    ref = iio.imread(tmp_path / "r.png")
    got = mirage_air.render(SCENE, width=96, height=54, srgb=True)
    assert got.dtype == np.uint8 and got.shape == ref.shape == (54, 96, 3)
    assert np.array_equal(got, ref)


def test_write_video_writes_the_frames_as_mp4(tmp_path):
    iio = pytest.importorskip("imageio.v3")
    frames = mirage_air.render_frames(heating_road(4), width=64, height=35, srgb=True)
    path = mirage_air.write_video(frames, tmp_path / "road.mp4", fps=8)
    assert path == tmp_path / "road.mp4" and path.stat().st_size > 1000
    back = iio.imread(path, plugin="FFMPEG", index=None)
    # Four frames, the odd height padded to 36, the pictures kept in their
    # order: H.264 is lossy (chroma at half resolution), but each frame read
    # back is nearest the frame it was made from.
    assert back.shape == (4, 36, 64, 3)
    miss = np.array([[np.abs(a.astype(float) - b[:35].astype(float)).mean() for a in frames] for b in back])
    assert (miss.argmin(axis=1) == np.arange(4)).all(), miss
    assert miss.diagonal().max() < 8.0, miss


def test_write_video_names_its_optional_dependencies(monkeypatch, tmp_path):
    for name in ("imageio", "imageio.v2", "imageio_ffmpeg"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(ImportError) as e:
        mirage_air.write_video([np.zeros((4, 4, 3), np.uint8)], tmp_path / "v.mp4")
    assert "pip install imageio imageio-ffmpeg" in str(e.value)


def test_a_worker_killed_in_the_middle_of_an_ensemble_loses_nothing(dask_client):
    kw = dict(n=16, noise=0.01, seed=1)
    local = mirage_air.ensemble(KELVIN, **kw)
    box = {}

    def run():
        try:
            box["result"] = mirage_air.ensemble(KELVIN, executor=dask_client, **kw)
        except BaseException as e:  # reported below
            box["error"] = e

    thread = threading.Thread(target=run)
    thread.start()
    victim, deadline = None, time.monotonic() + 60
    while victim is None and time.monotonic() < deadline and thread.is_alive():
        for worker, keys in dask_client.processing().items():
            if any("_ensemble_member" in str(k) for k in keys):
                victim = worker
                break
        else:
            time.sleep(0.01)
    assert victim is not None, "no member task was seen running"
    pid = dask_client.run(os.getpid, workers=[victim])[victim]
    still_running = thread.is_alive()
    os.kill(pid, signal.SIGKILL)
    thread.join(120)
    assert not thread.is_alive() and "error" not in box, box.get("error")
    assert still_running, "the ensemble ended before the worker was killed"
    assert victim not in dask_client.scheduler_info()["workers"]
    assert_same_ensemble(local, box["result"])
    # The nanny restarts the worker; leave the cluster as it was found.
    dask_client.wait_for_workers(2, timeout=60)
