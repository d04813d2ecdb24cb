"""Thin films: reflectance and transmittance of a multilayer stack (``specmap.thinfilm``)."""

from __future__ import annotations

import numbers
from typing import Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _specmap

#: A refractive index: a number (``1.5``), a complex number ``n + 1j*k`` (``k >= 0`` absorbs),
#: or a material specmap knows by name (``"bk7"``, ``"fused-silica"``) or an index written as the
#: CLI writes one (``"3.1+3.3i"``).
IndexLike = Union[float, complex, str]
ArrayLike = Union[float, Sequence[float], npt.NDArray[np.floating]]

__all__ = ["thinfilm"]


def _medium(value, what: str):
    """A medium for the native module: a name as it is, a number as ``(n, k)``."""
    if isinstance(value, str):
        return value
    if isinstance(value, numbers.Number) or (isinstance(value, np.ndarray) and value.ndim == 0):
        try:
            z = complex(value)
        except (TypeError, ValueError):
            pass
        else:
            return (z.real, z.imag)
    raise ValueError(
        f"{what}: {value!r} is not a refractive index: give a number (1.5), a complex number "
        f"n + 1j*k (k >= 0 absorbs) or a material's name ('bk7', 'fused-silica')"
    )


def _axis(value, what: str) -> Tuple[np.ndarray, bool]:
    """``value`` as a 1-D float64 array, and whether it was an array (an axis of the result)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: {value!r} is not a number or an array of numbers") from e
    if a.ndim > 1:
        raise ValueError(f"{what}: an array of shape {a.shape}; give a scalar or a 1-D array")
    return np.ascontiguousarray(a.reshape(-1)), a.ndim == 1


def thinfilm(
    layers: Sequence[Tuple[IndexLike, float]],
    substrate: IndexLike,
    wavelengths: ArrayLike,
    angles_deg: ArrayLike = 0.0,
    thickness_scale: Optional[ArrayLike] = None,
    pol: Literal["s", "p", "u"] = "u",
    ambient: IndexLike = 1.0,
) -> Tuple[np.ndarray, np.ndarray]:
    """Reflectance and transmittance of a multilayer thin film, for every combination of
    thickness scale, angle of incidence and wavelength at once.

    The stack is ``ambient | layers[0] | layers[1] | ... | substrate``, light arriving from the
    ambient medium. Every layer is coherent (thin-film interference; tmm's ``coh_tmm``), the
    ambient and the substrate are semi-infinite. The whole grid is computed in Rust, in
    parallel, with the GIL released.

    Parameters
    ----------
    layers : sequence of (index, thickness_nm)
        The layers from the ambient side, each a refractive index and a thickness in nm
        (finite, ``>= 0``). An empty sequence is the bare substrate.
    substrate : index
        The substrate's refractive index (may absorb, e.g. a metal ``3.1 + 3.3j``).
    wavelengths : float or 1-D array
        Vacuum wavelengths in nm (finite, positive, any order).
    angles_deg : float or 1-D array, default 0.0
        Angles of incidence in the ambient medium, degrees from the normal, in ``[0, 90)``.
    thickness_scale : None, float or 1-D array, default None
        Factors multiplying every layer's thickness at once (finite, ``>= 0``; 0 is the bare
        substrate), as when a film's thickness is dragged in a design tool. None is 1.
    pol : {"s", "p", "u"}, default "u"
        The polarisation of the incident light: ``"s"`` (TE), ``"p"`` (TM) or ``"u"``,
        unpolarised (the mean of the s and p powers).
    ambient : index, default 1.0
        The incident medium's index; it must be transparent (real).

    An index is a real number, a complex number ``n + 1j*k`` with ``k >= 0`` absorbing (the
    convention of tmm and of specmap's ``Index(n, k)``; ``k < 0``, a gain medium, is refused),
    a material specmap knows by name (``"bk7"``: Schott N-BK7, ``"fused-silica"``: Malitson
    1965; dispersive, evaluated at each wavelength) or an index as the CLI writes one
    (``"3.1+3.3i"``).

    Returns
    -------
    R, T : numpy.ndarray of float64
        The fraction of the incident power reflected, and the fraction entering the substrate
        (``1 - R - T`` is absorbed by the layers), each of shape ``(len(thickness_scale),
        len(angles_deg), len(wavelengths))``, where an axis is present only when its argument
        is an array: a scalar angle (or wavelength, or a scalar or None thickness scale) leaves
        its axis out, so all-scalar arguments give 0-d arrays.

    Raises
    ------
    ValueError
        For a negative or non-finite thickness or scale, an absorbing ambient, ``k < 0``, an
        angle outside ``[0, 90)``, a wavelength that is not positive, an argument of more than
        one dimension, an unknown material or polarisation.

    Examples
    --------
    A quarter-wave MgF2 layer on glass at its design wavelength, and the same layer at 0 to 80
    degrees and at half to twice its thickness:

    >>> import numpy as np, specmap
    >>> R, T = specmap.thinfilm([(1.38, 550 / (4 * 1.38))], 1.52, 550.0)
    >>> round(float(R), 6)  # ((1.52 - 1.38**2) / (1.52 + 1.38**2))**2
    0.012601
    >>> R, T = specmap.thinfilm([(1.38, 99.6)], "bk7", np.arange(380, 781, 5),
    ...                         angles_deg=np.arange(0, 81, 10),
    ...                         thickness_scale=np.linspace(0.5, 2, 31))
    >>> R.shape
    (31, 9, 81)
    """
    layer_list = list(layers)
    native_layers = []
    for i, layer in enumerate(layer_list):
        try:
            n, d = layer
        except (TypeError, ValueError) as e:
            raise ValueError(
                f"layer {i + 1}: {layer!r} must be a pair (index, thickness_nm)"
            ) from e
        try:
            d = float(d)
        except (TypeError, ValueError) as e:
            raise ValueError(f"layer {i + 1}: thickness {d!r} is not a number (nm)") from e
        native_layers.append((_medium(n, f"layer {i + 1}"), d))
    if not isinstance(pol, str):
        raise ValueError(f"pol {pol!r}: use 's', 'p' or 'u'")
    w, w_axis = _axis(wavelengths, "wavelengths")
    a, a_axis = _axis(angles_deg, "angles_deg")
    if thickness_scale is None:
        s, s_axis = np.ones(1), False
    else:
        s, s_axis = _axis(thickness_scale, "thickness_scale")
    R, T = _specmap.thinfilm(
        native_layers,
        _medium(substrate, "substrate"),
        _medium(ambient, "ambient"),
        w,
        a,
        s,
        pol,
    )
    index = (slice(None) if s_axis else 0, slice(None) if a_axis else 0,
             slice(None) if w_axis else 0)
    return np.asarray(R[index]), np.asarray(T[index])
