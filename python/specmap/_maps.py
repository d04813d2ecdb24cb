"""Environment maps: the scene's lights and the conversion's plan (``inspect``), RGB -> spectral
conversion to a file or into memory (``convert``), RGB arrays to emission spectra
(``upsample``), and spectral OpenEXR files read back (``read_spectral``)."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import _specmap
from ._options import argv_of

__all__ = ["inspect", "convert", "read_spectral", "upsample"]

PathLike = Union[str, "os.PathLike[str]"]


def _existing(path: PathLike, what: str = "map") -> str:
    """``path`` as a string; FileNotFoundError if no such file (a ``{face}`` pattern passes)."""
    text = os.fspath(path)
    if "{face}" not in text and not os.path.exists(text):
        raise FileNotFoundError(2, f"no such {what}", text)
    return text


def inspect(path: PathLike, **options: Any) -> Dict[str, Any]:
    """The lights a map holds and the conversion's plan, as ``specmap inspect --json`` prints
    them.

    Parameters
    ----------
    path:
        An OpenEXR or Radiance ``.hdr`` map (lat-long, cube, cross, strip; six face files as a
        pattern with ``{face}``).
    **options:
        ``specmap convert``'s flags by their long names, ``-`` written ``_``: ``light="D65"``,
        ``lights="one"``, ``sun="off"``, ``mode="exact"``, ``overlay="lights.png"`` (draws each
        light's region over the map)...

    Returns
    -------
    dict
        ``scene`` (each light: ``kind``, ``solid_angle_sr``, ``energy_share``, ``reason``...),
        ``plan`` (the file and the fit), ``space``, ``white`` and the rest of the JSON.

    Examples
    --------
    >>> lights = specmap.inspect("envmaps/sunrise.exr")["scene"]["lights"]
    >>> [(l["kind"], round(l["energy_share"], 3)) for l in lights]  # doctest: +SKIP
    """
    argv = [_existing(path), *argv_of(options)]
    return json.loads(_specmap.inspect(argv))


def convert(
    path: PathLike, output: Optional[PathLike] = None, **options: Any
) -> Dict[str, Any]:
    """Converts an RGB map to spectra, as ``specmap convert`` does.

    Parameters
    ----------
    path:
        The RGB map (OpenEXR or ``.hdr``, any layout ``specmap convert`` reads).
    output:
        A spectral OpenEXR to write (to a temporary file, then renamed; an input is never
        overwritten). ``None``: nothing is written, the spectra are returned in memory.
    **options:
        ``specmap convert``'s flags by their long names with ``_`` for ``-``:
        ``precision="float"``, ``light="D65"``, ``mode="exact"``, ``range="400:700:10"``,
        ``compression="piz"``, ``sun="off"``...

    Returns
    -------
    dict
        The report ``specmap convert --json`` prints (round trip, lights, spectra counts,
        notes). With ``output=None`` it also holds ``wavelengths`` (N,) float64, ``spectra``
        (H, W, N) float32 (the values a ``precision="float"`` file holds), ``rgb`` (H, W, 3)
        float32 and ``sun`` (H, W) float32 (1 on the sun's pixels).
    """
    source = _existing(path)
    if output is not None:
        argv = [source, "-o", os.fspath(output), *argv_of(options)]
        return json.loads(_specmap.convert_file(argv))
    report, wavelengths, spectra, rgb, sun = _specmap.convert_in_memory(
        [source, *argv_of(options)]
    )
    return _with_arrays(report, wavelengths, spectra, rgb, sun)


def _with_arrays(report: str, wavelengths, spectra, rgb, sun) -> Dict[str, Any]:
    out = json.loads(report)
    out.update(wavelengths=wavelengths, spectra=spectra, rgb=rgb, sun=sun)
    return out


def read_spectral(
    path: PathLike, with_rgb: bool = False
) -> Union[Tuple[np.ndarray, np.ndarray], Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]]:
    """Reads a spectral OpenEXR of Fichet et al.'s (2021) layout (``S0.<nm>nm`` channels; any
    writer's: specmap's, colour-science's, Mitsuba's): scan-line or tiled, any compression.

    Returns
    -------
    (wavelengths, spectra)
        (N,) float64 nm, sorted, and (H, W, N) float32, multiplied by 2^EV where the header
        has ``EV``. With ``with_rgb=True`` a third item: the R, G, B preview channels
        (H, W, 3), or ``None`` when the file has none.
    """
    wavelengths, spectra, rgb, _header = _specmap.read_spectral(_existing(path, "file"))
    if with_rgb:
        return wavelengths, spectra, rgb
    return wavelengths, spectra


def _grid_flag(wavelengths) -> Optional[str]:
    """``wavelengths`` (array or ``"START:END:STEP"``) as ``--range``'s value."""
    if wavelengths is None:
        return None
    if isinstance(wavelengths, str):
        return wavelengths
    w = np.asarray(wavelengths, dtype=np.float64)
    if w.ndim != 1 or len(w) < 2:
        raise ValueError("wavelengths: give at least two, evenly spaced, or 'START:END:STEP'")
    step = w[1] - w[0]
    if not np.allclose(np.diff(w), step, rtol=1e-9, atol=1e-9):
        raise ValueError(
            "wavelengths must be evenly spaced (the spectra are written on a grid); "
            f"{w[:4]}... is not"
        )
    return f"{w[0]!r}:{w[-1]!r}:{step!r}"


def _is_map_shape(shape) -> bool:
    """An (H, W, 3) array of a shape the converter lays out: lat-long 2:1, cube, cross, strip."""
    if len(shape) != 3:
        return False
    h, w = shape[0], shape[1]
    return (w == 2 * h) or (w * 6 == h) or (w == 6 * h) or (4 * h == 3 * w) or (3 * h == 4 * w)


def upsample(
    rgb,
    light: str = "auto",
    space: str = "sRGB",
    wavelengths=None,
    **options: Any,
) -> Tuple[np.ndarray, np.ndarray]:
    """Linear RGB *radiance* to non-negative emission spectra whose colour is the input's.

    colour-science's ``recovery`` module turns RGB into reflectances; this is the other half:
    lights, skies and environment maps.

    Parameters
    ----------
    rgb:
        An ``(..., 3)`` array of linear RGB in ``space`` (any float type).
    light:
        ``"auto"``: an ``(H, W, 3)`` array shaped like a map (lat-long 2:1, cube, cross, strip)
        is converted as ``convert`` converts a file (the scene's lights found, the sun given its
        own spectrum); any other array is read under CIE D65, daylight-coloured colours given the
        CIE daylight of their colour (NaN, infinite and negative values of a map are set to 0
        and counted in a ``RuntimeWarning``, as ``convert`` counts them; elsewhere a non-finite
        value is a ``ValueError``). A light's name (``"A"``, ``"FL11"``, a CSV file): every
        colour is that light's spectrum times a smooth modulation.
    space:
        The RGB space: ``"sRGB"`` (Rec.709 primaries, D65), ``"Rec2020"``, ``"ACEScg"``,
        ``"Display-P3"``, ``"sRGB-paper"``.
    wavelengths:
        An evenly spaced array or ``"START:END:STEP"`` (nm); default 380 to 780 nm by 5 nm.
    **options:
        With ``light="auto"`` on a map, any of ``convert``'s flags (``sun="off"``...).

    Returns
    -------
    (wavelengths, spectra)
        ``(N,)`` float64 and ``(..., N)`` float32. Each spectrum's colour (CIE 1931, specmap's
        luminance scale ``Y = sum(L ybar) / sum(ybar)``) is its RGB, exactly where the colour
        can be one the light makes; the others get the nearest non-negative spectrum and a
        ``RuntimeWarning`` says how many.
    """
    a = np.asarray(rgb, dtype=np.float32)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"rgb of shape {a.shape}: the last axis must hold R, G, B")
    flags = dict(options, space=_space_flag(space), range=_grid_flag(wavelengths))
    if light == "auto" and _is_map_shape(a.shape):
        h, w, _ = a.shape
        report, wl, spectra, _rgb, _sun = _specmap.convert_image(
            np.ascontiguousarray(a.reshape(h * w, 3)), w, argv_of(flags)
        )
        facts = json.loads(report)
        _warn_sanitized(facts["sanitized"])
        _warn_inexact(facts["spectra"].get("nearest", 0), a.shape[:-1])
        return wl, spectra
    if options:
        raise ValueError(
            f"{sorted(options)}: conversion flags apply to a map under light='auto' only"
        )
    flat = np.ascontiguousarray(a.reshape(-1, 3))
    wl, spectra, inexact = _specmap.upsample_colours(
        flat, None if light == "auto" else os.fspath(light), argv_of(flags)
    )
    _warn_inexact(inexact, a.shape[:-1])
    return wl, spectra.reshape(*a.shape[:-1], len(wl))


def _space_flag(space: str) -> str:
    return space.lower().replace("_", "-").replace(" ", "-")


def _warn_sanitized(sanitized: Dict[str, int]) -> None:
    """The converter's count of values it set to 0 (as ``convert`` reports them), as a warning."""
    bad, negative = sanitized.get("non_finite", 0), sanitized.get("negative", 0)
    if bad or negative:
        warnings.warn(
            f"{bad} NaN or infinite and {negative} negative channel values were set to 0 "
            "(the converter's premise; convert(..., strict=True) refuses NaN and infinities)",
            RuntimeWarning,
            stacklevel=3,
        )


def _warn_inexact(count: int, shape) -> None:
    if count:
        warnings.warn(
            f"{count} of {int(np.prod(shape))} colours cannot be made by the light's spectrum "
            "times a non-negative modulation: they got the nearest non-negative spectrum "
            "(their colour differs)",
            RuntimeWarning,
            stacklevel=3,
        )
