"""Type stubs of the compiled module (src/python.rs); use the functions of
``mirage_air`` itself, which wrap these with NumPy arrays and result classes."""

from typing import Optional, Tuple

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
) -> Tuple[int, int, bytes]: ...
def sounding(path: str, format: Optional[str] = None, site_height: Optional[float] = None) -> str: ...
def medium_eval(medium: str, points: bytes, earth_radius: Optional[float] = None) -> Tuple[bytes, bytes]: ...
