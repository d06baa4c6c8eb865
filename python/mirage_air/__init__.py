"""mirage from Python: the inverse design of atmospheric mirages.

The same library as the ``mirage`` command line, compiled into this package:
problems and scenes are the same JSON documents (a path or a dict), validated by
the same code with the same messages, and every result is the CLI's result bit
for bit (``fit(p).to_json()`` is what ``mirage fit p -o result.json`` writes).

>>> import mirage_air
>>> result = mirage_air.fit("problems/hot-road.json")
>>> result.values["hotspots[0].n"]
-3.0000000000...
>>> photo = mirage_air.fit("problems/photo/looming.json")     # marks on a photo
>>> photo.photo["rms_pixels"]
0.4...
>>> mirage_air.overlay("problems/photo/looming.json", photo).shape
(600, 1200, 3)
>>> image = mirage_air.render("problems/scenes/road.json", width=160)
>>> image.shape, image.dtype
((90, 160, 3), dtype('float32'))
>>> spread = mirage_air.ensemble("problems/cold-sea.json", n=50, noise=0.02)
>>> spread.parameters["inversion.height"].percentiles   # 2.5 … 97.5 %
array([...])

Many independent items (an ensemble's members, an animation's frames) run as
one task each on any ``concurrent.futures.Executor`` or a Dask ``Client``
(``executor=``), with the same results bit for bit as on the library's own
threads; every result pickles.

Arrays come back as NumPy arrays (float64 for geometry, float32 linear radiance
for renders). Bad input raises :class:`InputError` (a ``ValueError``) whose
``.file`` and ``.field`` name the document and the field path. Long calls release
the GIL and stop on Ctrl-C (the computation they abandon ends on its own thread).
"""

from __future__ import annotations

import concurrent.futures
import json
import numbers
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import InputError

__all__ = [
    "InputError",
    "Problem",
    "Scene",
    "Medium",
    "TraceResult",
    "FitResult",
    "Sightlines",
    "History",
    "EnsembleResult",
    "ParameterSpread",
    "Envelope",
    "load",
    "trace",
    "fit",
    "render",
    "overlay",
    "sounding",
    "ensemble",
    "render_frames",
    "write_video",
    "__version__",
]

__version__: str = _native.__version__

#: Where a document given as a dict is said to come from, in messages; a
#: scene's ``medium_from`` is then read relative to the working directory.
DICT_SOURCE = "<dict>"

Source = Union[str, "os.PathLike[str]", Mapping[str, Any], "Problem", "Scene"]


class _Document:
    """A validated document: its JSON text and where it came from."""

    kind = ""

    def __init__(self, text: str, path: str) -> None:
        # Validate now, as the CLI does on reading; keep the text as given so
        # that every later call parses exactly what the user wrote.
        self._normalized = json.loads(_native.load(self.kind, text, path))
        self._text = text
        self.path = path

    def to_dict(self) -> Dict[str, Any]:
        """The document as mirage reads it (defaults filled in), as a dict
        in the file schema: ``json.dump`` it to get a file mirage reads back."""
        return json.loads(json.dumps(self._normalized))

    @property
    def name(self) -> Optional[str]:
        """The document's ``name`` field, if any."""
        return self._normalized.get("name")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.path!r})"


class Problem(_Document):
    """A problem: a medium, the free parameters and the point pairs
    (``docs/problem-format.md``). Made by :func:`load`."""

    kind = "problem"


class Scene(_Document):
    """A scene to render (``docs/scene-format.md``). Made by :func:`load`."""

    kind = "scene"


def _read(source: Union[str, "os.PathLike[str]", Mapping[str, Any]]):
    """The JSON text of a source and the path that names it in messages."""
    if isinstance(source, Mapping):
        try:
            return json.dumps(source, allow_nan=False), DICT_SOURCE
        except (TypeError, ValueError) as e:
            err = InputError(f"{DICT_SOURCE}: -: not a JSON document: {e}")
            err.file, err.field = DICT_SOURCE, "-"
            raise err from None
    path = os.fspath(source)
    try:
        return Path(path).read_text(encoding="utf-8"), path
    except (OSError, UnicodeDecodeError) as e:
        err = InputError(f"{path}: -: cannot read the file: {e}")
        err.file, err.field = path, "-"
        raise err from None


def _kind_of(text: str) -> str:
    """``problem`` or ``scene``, by content: a scene has a camera, a problem
    pairs. Text that is not a JSON object is left to the problem parser,
    whose message says what is wrong."""
    try:
        doc = json.loads(text)
    except ValueError:
        return "problem"
    if isinstance(doc, dict) and "camera" in doc and "pairs" not in doc:
        return "scene"
    return "problem"


def load(source: Union[str, "os.PathLike[str]", Mapping[str, Any]]) -> Union[Problem, Scene]:
    """Reads a problem or a scene (by content) from a path or a dict and
    validates it as the CLI does. Raises :class:`InputError` naming the file
    and the field for anything the CLI would reject."""
    text, path = _read(source)
    return Scene(text, path) if _kind_of(text) == "scene" else Problem(text, path)


def _problem(source: Source) -> Problem:
    if isinstance(source, Problem):
        return source
    if isinstance(source, Scene):
        raise TypeError("expected a problem, got a scene")
    text, path = _read(source)
    return Problem(text, path)


def _scene(source: Source) -> Scene:
    if isinstance(source, Scene):
        return source
    if isinstance(source, Problem):
        raise TypeError("expected a scene, got a problem")
    text, path = _read(source)
    return Scene(text, path)


@dataclass(frozen=True)
class Sightlines:
    """Each pair's line of sight over the round earth (``docs/geo.md``), one
    entry per pair, in the pairs' order.

    ``apparent_elevation``, ``geometric_elevation``, ``horizon_elevation``:
    degrees above the origin's horizontal (the launch direction, the straight
    line to the target, the sea's geometric horizon); ``refraction_arcsec``:
    apparent − geometric (″); ``k``: 2·R·refraction / s, the refraction
    coefficient the sighting implies; ``arc_distance``: s (m);
    ``below_horizon``: the target lies below the geometric horizon;
    ``clearance``: the straight line's least height above the sea (m);
    ``miss_up_arcsec``: the traced ray's miss, up positive (″);
    ``air_refraction_arcsec`` and ``air_k``: the refraction and k of the air
    itself (the sighting's less the miss)."""

    apparent_elevation: np.ndarray
    geometric_elevation: np.ndarray
    refraction_arcsec: np.ndarray
    k: np.ndarray
    arc_distance: np.ndarray
    horizon_elevation: np.ndarray
    below_horizon: np.ndarray
    clearance: np.ndarray
    miss_up_arcsec: np.ndarray
    air_refraction_arcsec: np.ndarray
    air_k: np.ndarray

    @classmethod
    def _of(cls, pairs: List[Dict[str, Any]]) -> Optional["Sightlines"]:
        if not pairs or any(p.get("sightline") is None for p in pairs):
            return None
        s = [p["sightline"] for p in pairs]

        def col(key: str, dtype: Any = np.float64) -> np.ndarray:
            return np.array([np.nan if x.get(key) is None else x[key] for x in s], dtype=dtype)

        return cls(
            apparent_elevation=col("apparent_elevation"),
            geometric_elevation=col("geometric_elevation"),
            refraction_arcsec=col("refraction_arcsec"),
            k=col("k"),
            arc_distance=col("arc_distance"),
            horizon_elevation=col("horizon_elevation"),
            below_horizon=np.array([bool(x["below_horizon"]) for x in s], dtype=bool),
            clearance=col("clearance"),
            miss_up_arcsec=col("miss_up_arcsec"),
            air_refraction_arcsec=col("air_refraction_arcsec"),
            air_k=col("air_k"),
        )


@dataclass(frozen=True)
class TraceResult:
    """Every pair traced through a medium (``mirage trace -o``'s report).

    ``endpoints``, ``targets``, ``directions``: ``(m, 3)`` float64 (metres, unit
    vectors); ``distances``: ``(m,)``; ``occluded``, ``unreachable``: ``(m,)``
    bool; ``objective``: F = ½ Σ |r|² (m², or rad² with angle residuals);
    ``sightlines``: each line of sight over the round earth (:class:`Sightlines`;
    ``None`` over the flat ground); ``report``: the whole report."""

    endpoints: np.ndarray
    targets: np.ndarray
    directions: np.ndarray
    distances: np.ndarray
    occluded: np.ndarray
    unreachable: np.ndarray
    objective: float
    sightlines: Optional[Sightlines] = field(repr=False)
    report: Dict[str, Any] = field(repr=False)

    @classmethod
    def _of(cls, report: Dict[str, Any]) -> "TraceResult":
        pairs = report["pairs"]

        def rows(key: str) -> np.ndarray:
            return np.array([p[key] for p in pairs], dtype=np.float64).reshape(len(pairs), 3)

        return cls(
            endpoints=rows("endpoint"),
            targets=rows("target"),
            directions=rows("direction"),
            distances=np.array([p["distance"] for p in pairs], dtype=np.float64),
            occluded=np.array([p["occluded"] for p in pairs], dtype=bool),
            unreachable=np.array([p["unreachable"] for p in pairs], dtype=bool),
            objective=float(report["objective"]),
            sightlines=Sightlines._of(pairs),
            report=report,
        )


@dataclass(frozen=True)
class History:
    """A fit's iterations, run after run: per record the run's index (into
    ``labels``), its iteration number, F and the parameters (columns in the
    order of ``names``)."""

    names: List[str]
    labels: List[str]
    run: np.ndarray
    iteration: np.ndarray
    objective: np.ndarray
    params: np.ndarray


@dataclass(frozen=True)
class FitResult:
    """A fit (``mirage fit -o``'s result).

    ``medium``: the fitted medium as a dict in the file schema; ``values`` and
    ``standard_errors``: by parameter path (``None`` where the pairs do not
    determine it); ``objective``: F (m²); ``history``: the iterations;
    ``undetermined``: parameter combinations the pairs cannot determine;
    ``grow``: what growing the model did (each step's terms, F, criterion,
    and why it stopped), ``None`` for a plain fit; ``sightlines``: each line
    of sight through the fitted air over the round earth (:class:`Sightlines`,
    ``None`` over the flat ground); ``photo``: for a photo problem, the
    result's ``photo`` section (the camera's numbers, each mark's residual,
    marked, fitted and straight-ray pixel, the RMS residual in pixels, the
    apparent horizon: ``docs/photo.md``), else ``None``; ``report``: the
    whole result."""

    medium: Dict[str, Any]
    values: Dict[str, float]
    standard_errors: Dict[str, Optional[float]]
    objective: float
    history: History
    undetermined: List[Dict[str, Any]]
    grow: Optional[Dict[str, Any]]
    sightlines: Optional[Sightlines] = field(repr=False)
    report: Dict[str, Any] = field(repr=False)
    _json: str = field(repr=False, default="")
    photo: Optional[Dict[str, Any]] = field(repr=False, default=None)

    def to_json(self) -> str:
        """The result as ``mirage fit -o`` writes it, byte for byte."""
        return self._json

    @classmethod
    def _of(cls, text: str) -> "FitResult":
        r = json.loads(text)
        h = r["history"]
        records = [(i, rec) for i, run in enumerate(h["runs"]) for rec in run["records"]]
        k = len(h["param_names"])
        history = History(
            names=list(h["param_names"]),
            labels=[run["label"] for run in h["runs"]],
            run=np.array([i for i, _ in records], dtype=np.int64),
            iteration=np.array([rec["iteration"] for _, rec in records], dtype=np.int64),
            objective=np.array([rec["objective"] for _, rec in records], dtype=np.float64),
            params=np.array([rec["params"] for _, rec in records], dtype=np.float64).reshape(len(records), k),
        )
        return cls(
            medium=r["medium"],
            values={p["name"]: p["value"] for p in r["parameters"]},
            standard_errors={p["name"]: p["standard_error"] for p in r["parameters"]},
            objective=float(r["objective"]),
            history=history,
            undetermined=r["undetermined"],
            grow=r.get("grow"),
            sightlines=Sightlines._of(r.get("pairs", [])),
            report=r,
            _json=text + "\n",
            photo=r.get("photo"),
        )


def trace(problem: Source, threads: Optional[int] = None) -> TraceResult:
    """Traces every pair of a problem through its own medium, as
    ``mirage trace`` does. ``threads``: worker threads (default: all cores);
    the result does not depend on it."""
    p = _problem(problem)
    return TraceResult._of(json.loads(_native.trace(p._text, p.path, threads)))


def fit(
    problem: Source,
    method: Optional[str] = None,
    grow: bool = False,
    noise: Optional[float] = None,
    max_terms: Optional[int] = None,
    threads: Optional[int] = None,
) -> FitResult:
    """Fits a problem's free parameters, as ``mirage fit`` does (the same
    numbers bit for bit). ``method``: ``"lm"``, ``"nelder-mead"`` or
    ``"auto"``, overriding the problem's ``solver.method``. ``grow=True``
    grows the model term by term from the problem's medium (``mirage fit
    --grow``), assuming endpoint noise ``noise`` (metres; default: estimated)
    and adding at most ``max_terms`` terms. ``threads``: worker threads
    (default: all cores); the result does not depend on it."""
    p = _problem(problem)
    return FitResult._of(_native.fit(p._text, p.path, method, grow, noise, max_terms, threads))


def render(
    scene: Source,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    albedo: bool = False,
    straight: bool = False,
    threads: Optional[int] = None,
    srgb: bool = False,
) -> np.ndarray:
    """Renders a scene as ``mirage render --exr`` does: an ``(H, W, 3)``
    float32 array of linear radiance, top row first. ``width``/``height``/
    ``spp`` override the scene's; ``albedo`` shows what each ray hits;
    ``straight`` traces straight rays (δ ≡ 0) for comparison. ``srgb=True``
    returns the pixels of ``mirage render``'s PNG instead: ``(H, W, 3)``
    uint8 sRGB, tone-mapped by the scene's ``exposure`` (what
    :func:`write_video` takes)."""
    s = _scene(scene)
    return _render_frame(s._text, s.path, width, height, spp, albedo, straight, threads, srgb)


def overlay(problem: Source, result: Optional[Union["FitResult", Mapping[str, Any]]] = None,
            threads: Optional[int] = None) -> np.ndarray:
    """A photo problem's overlay as an ``(H, W, 3)`` uint8 sRGB array, the
    pixels of the PNG the CLI writes: without ``result``, ``mirage overlay``'s
    (the marks where the problem's starting air and camera put them); with
    ``result`` (the :class:`FitResult` of :func:`fit` on this problem, or
    its ``report`` dict), ``mirage fit --overlay``'s (the fitted air and
    camera). Per mark: the marked pixel (a ring), where the air puts the
    target (a cross), where straight rays would (a square); the apparent
    horizon, the names and the RMS residual (``docs/photo.md``)."""
    p = _problem(problem)
    photo = None
    if result is not None:
        report = result.report if isinstance(result, FitResult) else result
        if not isinstance(report, Mapping):
            raise _argument_error("result", f"must be a FitResult or its report dict, got {type(result).__name__}")
        if report.get("photo") is None:
            raise _argument_error("result", "has no `photo` section: it is not the fit of a photo problem")
        photo = json.dumps(report["photo"])
    w, h, data = _native.overlay(p._text, p.path, photo, threads)
    return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3).copy()


def _render_frame(text: str, path: str, width: Optional[int], height: Optional[int],
                  spp: Optional[int], albedo: bool, straight: bool,
                  threads: Optional[int], srgb: bool) -> np.ndarray:
    """One frame (a task of :func:`render_frames`): the scene's text in, an
    array out."""
    w, h, data = _native.render(text, path, width, height, spp, albedo, straight, threads, srgb)
    if srgb:
        return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3).copy()
    return np.frombuffer(data, dtype="<f4").reshape(h, w, 3).copy()


def sounding(
    path: Union[str, "os.PathLike[str]"],
    format: Optional[str] = None,
    site_height: Optional[float] = None,
) -> Dict[str, Any]:
    """Reads a radiosonde or mast profile into a real-air medium, as ``mirage
    sounding`` does: the medium as a dict (``{"air": {...}}``), ready to be a
    problem's or scene's ``"medium"``. ``format``: ``"igra2"``, ``"wyoming"``
    or ``"csv"`` (default: from the file); ``site_height``: the observer's
    height above the sounding's lowest level (``--site-height``)."""
    return json.loads(_native.sounding(os.fspath(path), format, site_height))


class Medium:
    """A medium (the ``medium`` field of a problem or scene, as a dict) to
    evaluate: δ = n − 1 and its gradient at points. ``earth_radius``: heights
    above a sphere of that radius (m) centred at (0, −R, 0), as a problem's
    ``earth`` gives them; absent: the flat ground y = 0."""

    def __init__(self, medium: Mapping[str, Any], earth_radius: Optional[float] = None) -> None:
        self._text = json.dumps(dict(medium), allow_nan=False)
        self.earth_radius = earth_radius
        # Validate now (and name the field: `medium.background.a`).
        _native.medium_eval(self._text, b"", earth_radius)
        self.medium = json.loads(self._text)

    def _eval(self, points: Any):
        p = np.ascontiguousarray(points, dtype="<f8")
        if p.ndim != 2 or p.shape[1] != 3:
            err = InputError(f"points: must be a (k, 3) array, got shape {p.shape}")
            err.file, err.field = None, "points"
            raise err
        d, g = _native.medium_eval(self._text, p.tobytes(), self.earth_radius)
        k = p.shape[0]
        return np.frombuffer(d, dtype="<f8").copy(), np.frombuffer(g, dtype="<f8").reshape(k, 3).copy()

    def delta(self, points: Any) -> np.ndarray:
        """δ = n − 1 at each of the ``(k, 3)`` points (metres): ``(k,)`` float64."""
        return self._eval(points)[0]

    def gradient(self, points: Any) -> np.ndarray:
        """∇δ (1/m) at each of the ``(k, 3)`` points: ``(k, 3)`` float64."""
        return self._eval(points)[1]

    def __repr__(self) -> str:
        return f"Medium({self.medium!r})"


# ---------------------------------------------------------------------------
# Many independent items: ensembles and frames, on threads or on an executor.


def _argument_error(name: str, message: str) -> InputError:
    """An :class:`InputError` about an argument of a call (no file)."""
    err = InputError(f"{name}: {message}")
    err.file, err.field = None, name
    return err


def _whole(name: str, value: Any, low: int, high: Optional[int] = None, what: str = "") -> int:
    """``value`` as an int in [low, high], or an error naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise _argument_error(name, f"must be a whole number, got {value!r}")
    v = int(value)
    if v < low:
        raise _argument_error(name, f"must be at least {low}{what}, got {v}")
    if high is not None and v > high:
        raise _argument_error(name, f"must be at most {high}, got {v}")
    return v


def _is_dask_client(executor: Any) -> bool:
    """Whether ``executor`` is a Dask ``Client`` (by its interface)."""
    return not isinstance(executor, concurrent.futures.Executor) and all(
        callable(getattr(executor, name, None)) for name in ("map", "gather", "cancel", "get_executor"))


def _check_executor(executor: Any) -> None:
    """``None``, a ``concurrent.futures.Executor`` or a Dask ``Client``, or
    an error naming ``executor``."""
    if executor is None or isinstance(executor, concurrent.futures.Executor) or _is_dask_client(executor):
        return
    raise _argument_error(
        "executor",
        f"must be None, a concurrent.futures.Executor or a dask.distributed.Client, got {type(executor).__name__}",
    )


def _run_tasks(executor: Any, fn: Any, tasks: List[Tuple[Any, ...]]) -> List[Any]:
    """``fn(*args)`` for each ``args`` of ``tasks``, one task each on
    ``executor`` (a ``concurrent.futures.Executor`` or a Dask ``Client``:
    ``client.map``, whose batched submission costs the scheduler less than
    one ``submit`` a task); the results in the tasks' order. On the first
    failure the other tasks are cancelled and the failure raised."""
    if _is_dask_client(executor):
        futures = executor.map(fn, *zip(*tasks)) if tasks else []
        try:
            return list(executor.gather(futures))
        except BaseException:
            executor.cancel(futures)
            raise
    pending = [executor.submit(fn, *args) for args in tasks]
    try:
        return [f.result() for f in pending]
    except BaseException:
        for f in pending:
            f.cancel()
        raise


def _truth_of(truth: Any) -> Tuple[Optional[str], str]:
    """The text of a document with a ``medium`` (what ``mirage ensemble
    --truth`` reads) and the name that stands for it in messages."""
    if truth is None:
        return None, "<truth>"
    if isinstance(truth, FitResult):
        return json.dumps({"medium": truth.medium}, allow_nan=False), "<truth>"
    if isinstance(truth, (Problem, Scene)):
        return truth._text, truth.path
    if isinstance(truth, Medium):
        return json.dumps({"medium": truth.medium}, allow_nan=False), "<truth>"
    if isinstance(truth, Mapping):
        doc = truth if "medium" in truth else {"medium": dict(truth)}
        text, _ = _read(doc)
        return text, "<truth>"
    text, path = _read(truth)
    return text, path


@dataclass(frozen=True)
class ParameterSpread:
    """One parameter across an ensemble: the best fit's value, its
    linearised standard error (``None`` where the pairs do not determine
    it), the members' mean, standard deviation and values at
    :attr:`EnsembleResult.PERCENTILES` (``(5,)`` float64), and where the
    ensemble and the linearised error disagree, in words (else ``None``)."""

    best: float
    standard_error: Optional[float]
    mean: float
    std: float
    percentiles: np.ndarray
    disagreement: Optional[str]


@dataclass(frozen=True)
class Envelope:
    """A profile across an ensemble on :attr:`EnsembleResult.heights`: the
    best fit's value per height (``(H,)``), the members' values at
    :attr:`EnsembleResult.PERCENTILES` per height (``(5, H)``), and the
    truth's (``(H,)``) when one was given."""

    best: np.ndarray
    percentiles: np.ndarray
    truth: Optional[np.ndarray]


@dataclass(frozen=True)
class EnsembleResult:
    """An ensemble of fits (``mirage ensemble -o``'s report).

    ``parameters``: per parameter path, its :class:`ParameterSpread`;
    ``members``: ``(n, p)`` float64, member k's parameters in the order of
    ``parameters``; ``member_objectives``: ``(n,)``, each member's F;
    ``objective``: the best fit's F; ``medium``: the best fit's medium (a
    dict in the file schema); ``resampling``: how the observations were
    resampled (``kind``, ``noise``, ``noise_from``, ``seed``);
    ``heights``: the profiles' heights (m) at ``at`` (x, z);
    ``temperature`` (°C; ``implied`` for a medium other than real air) and
    ``delta`` (n − 1): :class:`Envelope`\\ s; ``wall_time_s``: seconds;
    ``report``: the whole report."""

    #: The percentiles (per cent) of ``ParameterSpread.percentiles`` and of
    #: the envelopes' rows.
    PERCENTILES: ClassVar[Tuple[float, ...]] = (2.5, 16.0, 50.0, 84.0, 97.5)

    parameters: Dict[str, ParameterSpread]
    members: np.ndarray
    member_objectives: np.ndarray
    objective: float
    medium: Dict[str, Any]
    resampling: Dict[str, Any]
    heights: np.ndarray
    at: Tuple[float, float]
    implied: bool
    temperature: Envelope
    delta: Envelope
    wall_time_s: float
    report: Dict[str, Any] = field(repr=False)
    _json: str = field(repr=False, default="")

    def to_json(self) -> str:
        """The report as ``mirage ensemble -o`` writes it, byte for byte
        (its ``wall_time_s`` aside)."""
        return self._json

    @classmethod
    def _of(cls, text: str) -> "EnsembleResult":
        r = json.loads(text)

        def envelope(e: Dict[str, Any]) -> Envelope:
            truth = e.get("truth")
            return Envelope(
                best=np.array(e["best"], dtype=np.float64),
                percentiles=np.array(e["percentiles"], dtype=np.float64),
                truth=None if truth is None else np.array(truth, dtype=np.float64),
            )

        params = {
            p["name"]: ParameterSpread(
                best=float(p["best"]),
                standard_error=p["standard_error"],
                mean=float(p["mean"]),
                std=float(p["std"]),
                percentiles=np.array(p["percentiles"], dtype=np.float64),
                disagreement=p.get("disagreement"),
            )
            for p in r["parameters"]
        }
        members = r["members"]
        prof = r["profiles"]
        return cls(
            parameters=params,
            members=np.array([m["params"] for m in members], dtype=np.float64).reshape(len(members), len(params)),
            member_objectives=np.array([m["objective"] for m in members], dtype=np.float64),
            objective=float(r["objective"]),
            medium=r["medium"],
            resampling=r["resampling"],
            heights=np.array(prof["heights"], dtype=np.float64),
            at=(float(prof["at"][0]), float(prof["at"][1])),
            implied=bool(prof["implied"]),
            temperature=envelope(prof["temperature"]),
            delta=envelope(prof["delta"]),
            wall_time_s=float(r["wall_time_s"]),
            report=r,
            _json=text + "\n",
        )


def _ensemble_member(plan: str, k: int, threads: Optional[int]) -> Tuple[List[float], float]:
    """Member k of a plan (a task of :func:`ensemble`): its parameters and F."""
    return _native.ensemble_member(plan, k, threads)


def ensemble(
    problem: Source,
    n: int,
    noise: Optional[float] = None,
    bootstrap: bool = False,
    seed: int = 0,
    executor: Any = None,
    truth: Any = None,
    threads: Optional[int] = None,
) -> EnsembleResult:
    """How sure a fit is, as ``mirage ensemble`` measures it
    (``docs/ensemble.md``): the problem fitted once, then ``n`` more times to
    observations resampled from the best fit, and the spread of the
    parameters and of the temperature and n − 1 profiles.

    ``noise``: the observations' σ (metres; arcseconds with angle
    residuals), default the pairs' own ``noise``, else the fit's residual
    scale; ``bootstrap=True`` draws the pairs with replacement instead;
    ``seed``: member k is seeded by ``seed`` and k alone. ``truth``: the true
    air, drawn beside the envelopes (a path or dict of a document with a
    ``medium``, a medium dict, a :class:`Problem`, a :class:`FitResult` or a
    :class:`Medium`).

    ``executor=None``: on the library's threads (``threads`` of them,
    default all cores), as the CLI. Otherwise a ``concurrent.futures``
    executor or a Dask ``Client``: the best fit runs here, then each member
    is one task there (on ``threads`` threads each, default 1), and the
    report is assembled here. A task lost with its worker is re-run by Dask
    with the same result. Either way the result is the CLI's bit for bit
    (``to_json()`` is ``mirage ensemble -o``'s file, ``wall_time_s`` aside).

    Bad arguments and a bad problem raise :class:`InputError` naming the
    argument or the field before any work."""
    p = _problem(problem)
    n = _whole("n", n, 1, what=" member")
    seed = _whole("seed", seed, 0, 2**64 - 1)
    if noise is not None and (isinstance(noise, bool) or not isinstance(noise, numbers.Real)):
        raise _argument_error("noise", f"must be a number, got {noise!r}")
    noise = None if noise is None else float(noise)
    if threads is not None:
        threads = _whole("threads", threads, 1)
    truth_text, truth_path = _truth_of(truth)
    _check_executor(executor)
    if executor is None:
        return EnsembleResult._of(_native.ensemble(
            p._text, p.path, n, noise, bool(bootstrap), seed, truth_text, truth_path, threads))
    started = time.perf_counter()
    plan = _native.ensemble_plan(p._text, p.path, n, noise, bool(bootstrap), seed, truth_text, truth_path)
    per_task = 1 if threads is None else threads
    members = _run_tasks(executor, _ensemble_member, [(plan, k, per_task) for k in range(n)])
    return EnsembleResult._of(_native.ensemble_summarise(plan, members, time.perf_counter() - started))


def render_frames(
    scenes: Iterable[Source],
    executor: Any = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    albedo: bool = False,
    straight: bool = False,
    srgb: bool = False,
    threads: Optional[int] = None,
) -> List[np.ndarray]:
    """Renders a list of scenes (an animation's frames), as :func:`render`
    renders one: a list of arrays in the scenes' order (``srgb=True``:
    uint8 sRGB frames for :func:`write_video`).

    ``executor=None``: frame after frame, each on the library's threads
    (``threads``, default all cores). Otherwise a ``concurrent.futures``
    executor or a Dask ``Client``: each frame is one task there (on
    ``threads`` threads each, default 1). The frames are the same bit for
    bit either way. A scene's ``medium_from`` file is read where the frame
    renders (relative to the scene's path): on a cluster of many machines,
    give the medium inline.

    Every scene and argument is checked before any frame renders; a bad one
    raises :class:`InputError` naming ``scenes[i]`` and its field."""
    docs: List[Scene] = []
    for i, source in enumerate(scenes):
        try:
            docs.append(_scene(source))
        except InputError as e:
            err = InputError(f"scenes[{i}]: {e}")
            err.file = e.file
            err.field = f"scenes[{i}]" if e.field in (None, "-") else f"scenes[{i}].{e.field}"
            raise err from None
        except TypeError as e:
            raise TypeError(f"scenes[{i}]: {e}") from None
    for name, v in (("width", width), ("height", height), ("spp", spp)):
        if v is not None:
            _whole(name, v, 1)
    _native.render_check(width, height, spp)
    if threads is not None:
        threads = _whole("threads", threads, 1)
    _check_executor(executor)
    args = (width, height, spp, bool(albedo), bool(straight))
    if executor is None:
        return [_render_frame(s._text, s.path, *args, threads, bool(srgb)) for s in docs]
    per_task = 1 if threads is None else threads
    return _run_tasks(executor, _render_frame, [(s._text, s.path, *args, per_task, bool(srgb)) for s in docs])


#: How to get :func:`write_video`'s optional dependencies.
VIDEO_DEPENDENCIES = "pip install imageio imageio-ffmpeg"


def write_video(frames: Sequence[np.ndarray], path: Union[str, "os.PathLike[str]"],
                fps: float = 12.0, quality: Optional[float] = 8.0) -> Path:
    """Writes frames as a video (MP4, H.264, by imageio with imageio-ffmpeg:
    optional dependencies, ``pip install imageio imageio-ffmpeg``): ``frames``
    are ``(H, W, 3)`` uint8 sRGB arrays of one size (``render_frames(...,
    srgb=True)``); an odd width or height is padded by one repeated column
    or row (H.264's colour planes need even sizes). ``fps``: frames a
    second; ``quality``: 0–10 (imageio's scale), ``None`` for ffmpeg's
    default bit rate. Returns the path."""
    try:
        import imageio.v2 as iio
        import imageio_ffmpeg  # noqa: F401  (the encoder imageio runs)
    except ImportError as e:
        raise ImportError(
            f"write_video needs imageio and imageio-ffmpeg, which are not installed: {VIDEO_DEPENDENCIES}"
        ) from e
    frames = list(frames)
    if not frames:
        raise _argument_error("frames", "must hold at least one frame")
    shape = None
    for i, f in enumerate(frames):
        a = np.asarray(f)
        if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3:
            raise _argument_error(
                "frames",
                f"frame {i} must be an (H, W, 3) uint8 sRGB array (render with srgb=True), got {a.dtype} {a.shape}",
            )
        if shape is None:
            shape = a.shape
        elif a.shape != shape:
            raise _argument_error("frames", f"frame {i} is {a.shape[1]}×{a.shape[0]}, frame 0 {shape[1]}×{shape[0]}")
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (np.isfinite(fps) and fps > 0):
        raise _argument_error("fps", f"must be a finite number > 0, got {fps!r}")
    if quality is not None and (isinstance(quality, bool) or not isinstance(quality, numbers.Real)
                                or not 0 <= quality <= 10):
        raise _argument_error("quality", f"must be a number from 0 to 10 or None, got {quality!r}")
    h, w = shape[0], shape[1]
    pad = ((0, h % 2), (0, w % 2), (0, 0))
    out = Path(os.fspath(path))
    with iio.get_writer(out, format="FFMPEG", mode="I", fps=float(fps), codec="libx264",
                        pixelformat="yuv420p", quality=quality, macro_block_size=1) as writer:
        for f in frames:
            a = np.asarray(f)
            writer.append_data(np.pad(a, pad, mode="edge") if h % 2 or w % 2 else a)
    return out
