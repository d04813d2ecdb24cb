"""Type stubs of the native module ``specmap._specmap`` (python/src/*.rs). Users call the
wrappers in ``specmap`` (specmap/__init__.py), which document each call; these are what they
call. ``argv`` arguments are the CLI's flags, parsed by the CLI's own clap definitions."""

from typing import List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]
Medium = Union[str, Tuple[float, float]]

# spectra.rs
def table(spec: str) -> Tuple[str, F64, F64, Optional[str]]:
    """(label, wavelengths, values, built-in kind or None) of a table, TABLE:COLUMN or CSV."""

def names() -> List[Tuple[str, str]]:
    """Every built-in table as (kind, name)."""

def resample(wavelengths: F64, values: F64, at: F64, interpolation: str) -> F64:
    """Values at ``at`` (nm): "linear" or "cie167"; end values held outside the table."""

def xyz(
    values: npt.NDArray[np.float64],
    wavelengths: F64,
    light: Optional[F64] = None,
    k: Optional[float] = None,
    observer: str = "CIE 1931",
    rule: str = "riemann",
) -> npt.NDArray[np.float64]:
    """(..., 3) XYZ of (..., N) spectra on a uniform grid (Eq. 10/11 with a light)."""

def fit(argv: List[str]) -> Tuple[str, str]:
    """(``specmap fit --json``'s report, the ``-o`` fit file) as JSON text."""

# films.rs
def thinfilm(
    layers: Sequence[Tuple[Medium, float]],
    substrate: Medium,
    ambient: Medium,
    wavelengths: F64,
    angles_deg: F64,
    scales: F64,
    pol: str,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(R, T), each (scales, angles, wavelengths)."""

# maps.rs
def inspect(argv: List[str]) -> str:
    """``specmap inspect ARGV --json`` as JSON text."""

def convert_file(argv: List[str]) -> str:
    """``specmap convert ARGV --json``'s report as JSON text (the file written)."""

def convert_in_memory(argv: List[str]) -> Tuple[str, F64, F32, F32, F32]:
    """(report JSON, wavelengths, spectra (H, W, N), rgb (H, W, 3), sun (H, W))."""

def convert_image(
    rgb: F32, width: int, argv: List[str]
) -> Tuple[str, F64, F32, F32, F32]:
    """``convert_in_memory`` of an (H*W, 3) array ``width`` pixels wide."""

def upsample_colours(
    rgb: F32, light: Optional[str], argv: List[str]
) -> Tuple[F64, F32, int]:
    """(wavelengths, (n, N) spectra, colours not exact) of (n, 3) linear RGB colours."""

def read_spectral(path: str) -> Tuple[F64, F32, Optional[F32], str]:
    """(wavelengths, (H, W, N) spectra, (H, W, 3) rgb or None, header JSON)."""

# render.rs
def render(argv: List[str]) -> Tuple[F32, str]:
    """((H, W, 3) linear RGB, ``specmap render --json``'s report as JSON text)."""
