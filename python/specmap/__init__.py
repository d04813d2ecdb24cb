"""specmap for Python: spectra, colour, the paper's fit, thin films, spectral environment maps
and the spectral renderer, with numpy arrays in and out, the work done in Rust with the GIL
released (see docs/python.md).

Every function raises ``FileNotFoundError`` for a missing file, ``OSError`` for another
failure of the system and ``ValueError`` for bad input, with specmap's own message.
"""

from ._specmap import __version__
from ._spectra import Spectrum, spectrum, xyz, fit, Fit
from ._films import thinfilm
from ._maps import inspect, convert, read_spectral, upsample
from ._render import render

__all__ = [
    "__version__",
    "Spectrum",
    "spectrum",
    "xyz",
    "fit",
    "Fit",
    "thinfilm",
    "inspect",
    "convert",
    "read_spectral",
    "upsample",
    "render",
]
