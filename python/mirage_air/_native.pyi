"""Type stubs of the compiled module (src/python.rs); use the functions of
``mirage_air`` itself, which wrap these with NumPy arrays and result classes."""

from typing import List, Optional, Tuple

__version__: str

class InputError(ValueError):
    """Bad input (the CLI's exit code 2)."""

    file: Optional[str]
    field: Optional[str]

def load(kind: str, text: str, path: str) -> str: ...
def trace(text: str, path: str, threads: Optional[int] = None) -> str: ...
def fit(
    text: str,
    path: str,
    method: Optional[str] = None,
    grow: bool = False,
    noise: Optional[float] = None,
    max_terms: Optional[int] = None,
    threads: Optional[int] = None,
) -> str: ...
def render(
    text: str,
    path: str,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    albedo: bool = False,
    straight: bool = False,
    threads: Optional[int] = None,
    srgb: bool = False,
) -> Tuple[int, int, bytes]: ...
def overlay(
    text: str, path: str, photo: Optional[str] = None, threads: Optional[int] = None
) -> Tuple[int, int, bytes]: ...
def render_check(width: Optional[int] = None, height: Optional[int] = None, spp: Optional[int] = None) -> None: ...
def sounding(path: str, format: Optional[str] = None, site_height: Optional[float] = None) -> str: ...
def medium_eval(medium: str, points: bytes, earth_radius: Optional[float] = None) -> Tuple[bytes, bytes]: ...
def ensemble(
    text: str,
    path: str,
    n: int,
    noise: Optional[float] = None,
    bootstrap: bool = False,
    seed: int = 0,
    truth: Optional[str] = None,
    truth_path: str = "<truth>",
    threads: Optional[int] = None,
) -> str: ...
def ensemble_plan(
    text: str,
    path: str,
    n: int,
    noise: Optional[float] = None,
    bootstrap: bool = False,
    seed: int = 0,
    truth: Optional[str] = None,
    truth_path: str = "<truth>",
    threads: Optional[int] = None,
) -> str: ...
def ensemble_member(plan: str, k: int, threads: Optional[int] = None) -> Tuple[List[float], float]: ...
def ensemble_summarise(plan: str, members: List[Tuple[List[float], float]], wall_time_s: float) -> str: ...
