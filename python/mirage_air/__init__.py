"""mirage from Python: the inverse design of atmospheric mirages.

The same library as the ``mirage`` command line, compiled into this package:
problems and scenes are the same JSON documents (a path or a dict), validated by
the same code with the same messages, and every result is the CLI's result bit
for bit (``fit(p).to_json()`` is what ``mirage fit p -o result.json`` writes).

>>> import mirage_air
>>> result = mirage_air.fit("problems/hot-road.json")
>>> result.values["hotspots[0].n"]
-3.0000000000...
>>> image = mirage_air.render("problems/scenes/road.json", width=160)
>>> image.shape, image.dtype
((90, 160, 3), dtype('float32'))

Arrays come back as NumPy arrays (float64 for geometry, float32 linear radiance
for renders). Bad input raises :class:`InputError` (a ``ValueError``) whose
``.file`` and ``.field`` name the document and the field path. Long calls release
the GIL and stop on Ctrl-C (the computation they abandon ends on its own thread).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Union

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
    "load",
    "trace",
    "fit",
    "render",
    "sounding",
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
    ``None`` over the flat ground); ``report``: the whole result."""

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
) -> np.ndarray:
    """Renders a scene as ``mirage render --exr`` does: an ``(H, W, 3)``
    float32 array of linear radiance, top row first. ``width``/``height``/
    ``spp`` override the scene's; ``albedo`` shows what each ray hits;
    ``straight`` traces straight rays (δ ≡ 0) for comparison."""
    s = _scene(scene)
    w, h, data = _native.render(s._text, s.path, width, height, spp, albedo, straight, threads)
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
