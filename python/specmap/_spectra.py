"""Spectra, colour and the paper's fit: :class:`Spectrum`, :func:`spectrum`, :func:`xyz`,
:func:`fit` and :class:`Fit`.

The work is done by specmap's Rust code (the native module ``specmap._specmap``); these
wrappers turn names, paths, :class:`Spectrum` objects and ``colour.SpectralDistribution``
objects into the arrays and flags it takes, and its answers into numpy arrays.
"""

from __future__ import annotations

import json
import math
import os
import re
import tempfile
from dataclasses import dataclass, field
from typing import (
    TYPE_CHECKING,
    Any,
    Dict,
    List,
    Literal,
    Optional,
    Protocol,
    Sequence,
    Tuple,
    Union,
    runtime_checkable,
)

import numpy as np
import numpy.typing as npt

from . import _specmap

if TYPE_CHECKING:  # only for the annotation of Spectrum.to_colour; colour is optional
    from colour import SpectralDistribution

__all__ = [
    "Spectrum",
    "spectrum",
    "xyz",
    "fit",
    "Fit",
    "SpectralData",
    "SpectrumLike",
    "Interpolation",
    "Observer",
    "Rule",
    "FitMode",
    "RgbSpace",
]

FloatArray = npt.NDArray[np.float64]

Interpolation = Literal["linear", "cie167"]
"""How tabulated values are filled in between samples: ``"linear"`` (CIE 15, for lights) or
``"cie167"`` (Sprague for uniform data of at least 6 samples, else a not-a-knot cubic spline,
CIE 167, for smooth data such as reflectances and colour-matching functions)."""

Observer = Literal["CIE 1931", "CIE 1964"]
"""The CIE standard observer: ``"CIE 1931"`` (2 degrees) or ``"CIE 1964"`` (10 degrees).
``"cie1931"``, ``"1931"``, ``"2"`` and the like are taken too."""

Rule = Literal["riemann", "trapezoid", "simpson"]
"""The rule integrating over wavelength; ``"riemann"`` (sum times step) is CIE 15's and the
paper's."""

FitMode = Literal["paper", "exact", "nonneg"]
"""How the fit turns RGB into a spectrum: ``"paper"`` (the paper's three weights, exact for
white only), ``"exact"`` (a 3x3 matrix: every colour comes back exactly, the spectrum may go
negative) or ``"nonneg"`` (exact where the spectrum stays non-negative, else the nearest
non-negative one by CIEDE2000)."""

RgbSpace = Literal["srgb", "srgb-paper", "rec2020", "acescg", "display-p3"]
"""The RGB space a fit is solved in (``specmap fit --space``)."""

_LIGHT_KINDS = ("illuminant", "light")


@runtime_checkable
class SpectralData(Protocol):
    """Anything with ``wavelengths`` (nm) and ``values``, one per wavelength: a
    ``colour.SpectralDistribution`` or a :class:`Spectrum`."""

    @property
    def wavelengths(self) -> Any:
        """Wavelengths in nm, increasing."""
        ...

    @property
    def values(self) -> Any:
        """One value per wavelength."""
        ...


@dataclass(frozen=True, eq=False, repr=False)
class Spectrum:
    """A spectrum tabulated at wavelengths: a light, a reflectance or a colour-matching function.

    Made by :func:`spectrum`; may be made directly too (the arrays are copied to float64).

    Parameters
    ----------
    name : str
        What the spectrum is called: the table's name (``"D65"``), ``TABLE:COLUMN``
        (``"colorchecker:red"``) or a file's stem.
    wavelengths : array_like
        Wavelengths in nm, increasing (any spacing), shape ``(N,)``.
    values : array_like
        One value per wavelength, shape ``(N,)``.
    kind : str or None, optional
        The built-in table's kind (``"illuminant"``, ``"light"``, ``"reflectance"``,
        ``"cmf"``, ``"basis"``), or None for a spectrum from a file or ``colour``.
        ``"illuminant"`` and ``"light"`` make linear interpolation the default when the
        spectrum is resampled.

    Attributes
    ----------
    name : str
    wavelengths : numpy.ndarray
        float64, shape ``(N,)``, nm.
    values : numpy.ndarray
        float64, shape ``(N,)``.
    kind : str or None

    Raises
    ------
    ValueError
        If the arrays are not 1-D, are empty, differ in length, or the wavelengths do not
        increase.

    Examples
    --------
    >>> d65 = specmap.spectrum("D65")
    >>> d65
    Spectrum('D65', kind='illuminant', 300..780 nm, 97 samples)
    >>> len(d65), float(d65.values[0])
    (97, 0.0341)
    >>> np.asarray(d65).shape  # the values
    (97,)
    """

    name: str
    wavelengths: FloatArray
    values: FloatArray
    kind: Optional[str] = None

    def __post_init__(self) -> None:
        w = np.array(self.wavelengths, dtype=np.float64)
        v = np.array(self.values, dtype=np.float64)
        if w.ndim != 1 or v.ndim != 1:
            raise ValueError(
                f"Spectrum {self.name!r}: wavelengths and values must be 1-D "
                f"(got shapes {w.shape} and {v.shape})"
            )
        if len(w) == 0 or len(w) != len(v):
            raise ValueError(
                f"Spectrum {self.name!r}: {len(w)} wavelengths and {len(v)} values; "
                "one value per wavelength, at least one"
            )
        if len(w) > 1 and not np.all(np.diff(w) > 0):
            raise ValueError(f"Spectrum {self.name!r}: wavelengths must increase")
        object.__setattr__(self, "name", str(self.name))
        object.__setattr__(self, "wavelengths", w)
        object.__setattr__(self, "values", v)

    def __repr__(self) -> str:
        kind = f", kind={self.kind!r}" if self.kind is not None else ""
        lo, hi = _fmt_nm(self.wavelengths[0]), _fmt_nm(self.wavelengths[-1])
        return f"Spectrum({self.name!r}{kind}, {lo}..{hi} nm, {len(self)} samples)"

    def __len__(self) -> int:
        """The number of samples N."""
        return len(self.values)

    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> FloatArray:
        """The values, so that ``np.asarray(spectrum)`` is ``spectrum.values``."""
        if copy:
            return np.array(self.values, dtype=dtype, copy=True)
        return np.asarray(self.values, dtype=dtype)

    @property
    def is_light(self) -> bool:
        """True for a built-in illuminant or light (interpolated linearly by default)."""
        return self.kind in _LIGHT_KINDS

    def resample(
        self,
        wavelengths: npt.ArrayLike,
        interpolation: Optional[Interpolation] = None,
    ) -> "Spectrum":
        """This spectrum at other wavelengths; ``spectrum(self, wavelengths, interpolation)``.

        Parameters
        ----------
        wavelengths : array_like
            The wavelengths wanted, nm, increasing (any spacing).
        interpolation : {"linear", "cie167"} or None, optional
            None: ``"linear"`` for an illuminant or light, else ``"cie167"``.

        Returns
        -------
        Spectrum
            The same name and kind, at ``wavelengths``; the end values held outside this
            spectrum's range.
        """
        return spectrum(self, wavelengths=wavelengths, interpolation=interpolation)

    def to_colour(self) -> "SpectralDistribution":
        """This spectrum as a ``colour.SpectralDistribution`` (colour-science).

        The values are copied as they are. An illuminant or light gets colour's
        ``LinearInterpolator`` (CIE 15), anything else colour's default (Sprague, or a cubic
        spline for non-uniform data: CIE 167), so that colour interpolates it as specmap does.

        Returns
        -------
        colour.SpectralDistribution
            Named ``self.name``, on ``self.wavelengths``.

        Raises
        ------
        ImportError
            If colour-science is not installed (``pip install colour-science``).

        Examples
        --------
        >>> sd = specmap.spectrum("FL2").to_colour()
        >>> sd.interpolator.__name__
        'LinearInterpolator'
        >>> bool((specmap.spectrum(sd).values == specmap.spectrum("FL2").values).all())
        True
        """
        try:
            import colour
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError(
                "Spectrum.to_colour needs colour-science, which is not installed: "
                "pip install colour-science"
            ) from e
        kwargs: Dict[str, Any] = {"name": self.name}
        if self.is_light:
            kwargs["interpolator"] = colour.LinearInterpolator
        return colour.SpectralDistribution(self.values.copy(), self.wavelengths.copy(), **kwargs)


SpectrumLike = Union[str, "os.PathLike[str]", Spectrum, SpectralData]
"""A spectrum as the functions here take it: a built-in table's name (``"D65"``),
``TABLE:COLUMN`` (``"colorchecker:red"``), a CSV path (``str`` or ``os.PathLike``, optionally
``PATH:COLUMN``), a :class:`Spectrum` or a ``colour.SpectralDistribution``."""


def spectrum(
    name_or_csv_or_sd: SpectrumLike,
    wavelengths: Optional[npt.ArrayLike] = None,
    interpolation: Optional[Interpolation] = None,
) -> Spectrum:
    """A spectrum by name, from a CSV file, or from ``colour``; resampled if asked.

    Parameters
    ----------
    name_or_csv_or_sd : str, os.PathLike, Spectrum or colour.SpectralDistribution
        A built-in table (``"D65"``, ``"FL2"``, ``"lps"``; case-insensitive; ``specmap data
        list`` lists them), one column of a table (``"colorchecker:red"``, ``"cie1931:y"``),
        a CSV file (``"lamp.csv"``, ``"lamp.csv:spd"``, a ``pathlib.Path``): a
        ``wavelength_nm`` column then one column per spectrum. Or anything with
        ``wavelengths`` and ``values`` (a :class:`Spectrum`, a ``colour.SpectralDistribution``),
        whose values are taken as they are (not renormalised).
    wavelengths : array_like, optional
        Wavelengths (nm, increasing, any spacing) to resample onto; None keeps the tabulated
        ones. Outside the table's range the end values are held.
    interpolation : {"linear", "cie167"} or None, optional
        How to resample. None chooses as ``specmap data show --range`` does: ``"linear"`` for
        a built-in illuminant or light, ``"cie167"`` for the rest (reflectances,
        colour-matching functions, a user's CSV file). A ``colour.SpectralDistribution`` whose
        interpolator is colour's ``LinearInterpolator`` (as :meth:`Spectrum.to_colour` gives
        lights) is resampled linearly, any other with ``"cie167"``. Pass ``"linear"`` for a
        light of your own.

    Returns
    -------
    Spectrum
        With the table's label as ``name`` (``"colorchecker:red"``), its ``kind`` (None for a
        file or a ``colour`` object), float64 ``wavelengths`` and ``values``.

    Raises
    ------
    FileNotFoundError
        If a CSV path does not exist.
    ValueError
        If the name is no built-in table or column (the message suggests the closest: "did
        you mean D60, D65, ID65?"), a table has several columns and none was named, the file
        is not a valid spectral CSV, ``wavelengths`` do not increase, or ``interpolation`` is
        neither choice.

    Examples
    --------
    >>> specmap.spectrum("colorchecker:red", wavelengths=np.arange(400, 701, 5))
    Spectrum('colorchecker:red', kind='reflectance', 400..700 nm, 61 samples)
    >>> specmap.spectrum("FL2", wavelengths=[552.0]).values  # linear: a light
    array([15.82])
    >>> specmap.spectrum(colour.SDS_ILLUMINANTS["A"]).name
    'A'
    """
    src = name_or_csv_or_sd
    if isinstance(src, Spectrum):
        s = Spectrum(src.name, src.wavelengths, src.values, src.kind)
        default: Interpolation = "linear" if s.is_light else "cie167"
    elif isinstance(src, (str, os.PathLike)):
        label, w, v, kind = _specmap.table(_spec_text(src, "spectrum: "))
        s = Spectrum(label, w, v, kind)
        default = "linear" if s.is_light else "cie167"
    elif isinstance(src, SpectralData):
        name = getattr(src, "name", None)
        s = Spectrum(str(name) if name else "spectrum", src.wavelengths, src.values, None)
        default = "linear" if _has_linear_interpolator(src) else "cie167"
    else:
        raise TypeError(
            "spectrum: expected a table name, TABLE:COLUMN, a CSV path, a Spectrum or a "
            f"colour.SpectralDistribution, not {type(src).__name__}"
        )
    if wavelengths is None:
        if interpolation is not None:
            _check_interpolation(interpolation)
        return s
    method = _check_interpolation(interpolation if interpolation is not None else default)
    at = _as_1d(wavelengths, "wavelengths")
    values: FloatArray = _specmap.resample(s.wavelengths, s.values, at, method)
    return Spectrum(s.name, at, values, s.kind)


def xyz(
    values: npt.ArrayLike,
    wavelengths: npt.ArrayLike,
    light: Union[SpectrumLike, npt.ArrayLike, None] = None,
    k: Optional[float] = None,
    observer: Observer = "CIE 1931",
    rule: Rule = "riemann",
) -> FloatArray:
    """CIE XYZ of spectra on a uniform wavelength grid, vectorised over leading axes.

    With ``light``, ``values`` are reflectances (or transmittances) seen under it, and XYZ is
    the paper's Eq. 10/11 (CIE 15): ``X = k sum(R S xbar) dlambda`` with ``k = 100 / sum(S
    ybar) dlambda``, so a perfect white has Y = 100. Without, ``values`` are lights
    (spectral power) and ``X = k sum(values xbar) dlambda`` with the ``k`` given (1 if None;
    683.002 lm/W makes Y a luminance from W/(sr m^2 nm)).

    Parameters
    ----------
    values : array_like
        Spectra, shape ``(..., N)``: the last axis holds the N wavelengths.
    wavelengths : array_like
        N wavelengths in nm, uniformly spaced (resample other data first, e.g. with
        :func:`spectrum` and ``wavelengths=``).
    light : str, os.PathLike, Spectrum, colour.SpectralDistribution or array_like, optional
        The light the reflectances are seen under. A name, path, :class:`Spectrum` or
        ``colour.SpectralDistribution`` is resampled onto ``wavelengths`` linearly (CIE 15, as
        :func:`fit` does); an array must hold N values at ``wavelengths``.
    k : float, optional
        The normalising constant, for lights only (with ``light`` it is Eq. 11's).
    observer : {"CIE 1931", "CIE 1964"}, optional
        The standard observer's colour-matching functions (interpolated onto ``wavelengths``
        by CIE 167 where they are not tabulated).
    rule : {"riemann", "trapezoid", "simpson"}, optional
        The integration rule; ``"riemann"`` is CIE 15's sum times the step.

    Returns
    -------
    numpy.ndarray
        float64, shape ``(..., 3)``: X, Y, Z of each spectrum.

    Raises
    ------
    ValueError
        If the wavelengths are not uniformly spaced, the last axis of ``values`` is not N long,
        ``light`` has another length, both ``light`` and ``k`` are given, or ``observer`` or
        ``rule`` is unknown.
    FileNotFoundError
        If ``light`` names a CSV file that does not exist.

    Examples
    --------
    >>> wl = np.arange(380.0, 781.0, 5.0)
    >>> red = specmap.spectrum("colorchecker:red", wavelengths=wl).values
    >>> specmap.xyz(red, wl, light="D65").round(4)
    array([19.572 , 11.7003,  5.0283])
    >>> specmap.xyz(np.ones((2, 3, len(wl))), wl, light="A")[..., 1].round(10)
    array([[100., 100., 100.],
           [100., 100., 100.]])
    >>> specmap.xyz(specmap.spectrum("FL2", wl).values, wl, k=683.002).round(1)
    array([ 991894.3, 1000037. ,  673962.8])
    """
    wl = _as_1d(wavelengths, "wavelengths")
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 0:
        raise ValueError("values: an array of spectra, shape (..., N), not a scalar")
    s: Optional[FloatArray]
    if light is None:
        s = None
    elif isinstance(light, (str, os.PathLike, Spectrum, SpectralData)):
        s = spectrum(light, wavelengths=wl, interpolation="linear").values
    else:
        s = np.asarray(light, dtype=np.float64)
        if s.ndim != 1:
            raise ValueError(
                f"light: one spectrum of N values at the wavelengths, not shape {s.shape}"
            )
        s = np.ascontiguousarray(s)
    out: FloatArray = _specmap.xyz(v, wl, s, k, observer, rule)
    return out


@dataclass(frozen=True, eq=False, repr=False)
class Fit:
    """The paper's fit of three basis reflectances to a main light, as :func:`fit` returns it.

    A pixel's linear RGB becomes the spectrum ``light_spd * (a @ basis)`` with coefficients
    ``a = matrix @ rgb`` (in ``"nonneg"`` mode, for colours whose spectrum would go negative,
    the nearest non-negative one instead). In ``"paper"`` mode ``matrix`` is
    ``diag(weights)``.

    Attributes
    ----------
    light : str
        The main light's label (the table's name, or the :class:`Spectrum`'s name).
    mode : {"paper", "exact", "nonneg"}
    space : str
        The RGB space the fit was solved in (``"srgb"``, ...).
    observer : str
        ``"cie1931"`` or ``"cie1964"``.
    rule : str
        The integration rule.
    wavelengths : numpy.ndarray
        The fit's uniform grid, shape ``(N,)``, nm.
    weights : numpy.ndarray
        The paper's ``w_R, w_G, w_B``, shape ``(3,)``: under the light, ``weights @ basis``
        has the light's own colour.
    matrix : numpy.ndarray
        ``W``, shape ``(3, 3)``: the basis coefficients ``a = W @ rgb``.
    basis : numpy.ndarray
        The basis reflectances ``MCC_R, MCC_G, MCC_B`` on ``wavelengths``, shape ``(3, N)``,
        as the fit file holds them.
    basis_names : tuple of str
        How the three basis reflectances were named.
    light_spd : numpy.ndarray
        The main light on ``wavelengths`` (interpolated linearly), shape ``(N,)``.
    light_rgb : numpy.ndarray
        The light's linear RGB at Y = 1, shape ``(3,)``.
    condition_number : float
        The 2-norm condition number of the basis colours under the light.
    regularized : bool
        True when that was too ill-conditioned (a near-monochromatic light): the reduced
        solution is used.
    lost_information : str or None
        In words, the colour information that cannot survive under this light.
    roundtrip : dict
        The RGB -> spectrum -> RGB round trip over a 17^3 RGB grid: ``colours``,
        ``mean_dE2000``, ``p95_dE2000``, ``max_dE2000``, ``negative_fraction``.
    pixel : dict or None
        ``fit(..., rgb=...)``'s pixel: ``rgb``, ``coefficients``, ``spd``, ``rendered_rgb``,
        ``dE2000``, ``min_spd``.
    report : dict
        The whole report, as ``specmap fit --json`` prints it.
    data : dict
        The fit as ``specmap fit -o FIT.json`` writes it (see :meth:`save`).
    """

    light: str
    mode: str
    space: str
    observer: str
    rule: str
    wavelengths: FloatArray
    weights: FloatArray
    matrix: FloatArray
    basis: FloatArray
    basis_names: Tuple[str, str, str]
    light_spd: FloatArray
    light_rgb: FloatArray
    condition_number: float
    regularized: bool
    lost_information: Optional[str]
    roundtrip: Dict[str, Any]
    pixel: Optional[Dict[str, Any]]
    report: Dict[str, Any]
    data: Dict[str, Any]
    _text: str = field(default="", repr=False)

    @property
    def weighted_basis(self) -> FloatArray:
        """The paper's basis spectra ``B_j = w_j MCC_j SPD_light``, shape ``(3, N)``: their
        sum is the spectrum of RGB white (in ``"paper"`` mode)."""
        return self.weights[:, None] * self.basis * self.light_spd[None, :]

    def __repr__(self) -> str:
        w = ", ".join(f"{x:.6g}" for x in self.weights)
        rt = self.roundtrip
        return (
            f"Fit(light={self.light!r}, mode={self.mode!r}, space={self.space!r}, "
            f"weights=[{w}], mean_dE2000={rt.get('mean_dE2000', float('nan')):.4g})"
        )

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the fit file ``specmap fit -o`` writes, for ``convert`` and ``render``.

        Parameters
        ----------
        path : str or os.PathLike
            The JSON file to write (replaced if it exists).
        """
        with open(path, "w", encoding="utf-8") as f:
            f.write(self._text if self._text else json.dumps(self.data))
            f.write("\n")


def fit(
    light: SpectrumLike,
    mode: FitMode = "paper",
    space: RgbSpace = "srgb",
    wavelengths: Union[npt.ArrayLike, range, str, None] = None,
    *,
    basis: Optional[Sequence[SpectrumLike]] = None,
    observer: Observer = "CIE 1931",
    rule: Rule = "riemann",
    rgb: Optional[Sequence[float]] = None,
) -> Fit:
    """The paper's basis weights for a main light (``specmap fit``).

    Finds ``w_R, w_G, w_B`` such that ``w_R MCC_R + w_G MCC_G + w_B MCC_B`` seen under the
    light has the light's own colour (RGB white comes back white), and in the ``"exact"`` and
    ``"nonneg"`` modes the matrix that brings every colour back. The same code as ``specmap
    fit --json``: ``fit("FL2", "exact")`` is ``specmap fit --light FL2 --mode exact``.

    Parameters
    ----------
    light : str, os.PathLike, Spectrum or colour.SpectralDistribution
        The main light: a built-in table (``"D65"``, ``"A"``, ``"FL2"``, ``"lps"``),
        ``TABLE:COLUMN``, a CSV path, or a spectrum (written to a temporary CSV named after
        it, other characters than letters, digits and ``._+-`` made ``_``: that is
        :attr:`Fit.light`). It is interpolated linearly onto the grid.
    mode : {"paper", "exact", "nonneg"}, optional
        How RGB becomes a spectrum (see :data:`FitMode`).
    space : {"srgb", "srgb-paper", "rec2020", "acescg", "display-p3"}, optional
        The RGB space the weights are solved in.
    wavelengths : array_like, range, str or None, optional
        The fit's uniform grid: None for 380..780 nm by 1 nm, a ``"START:END:STEP"`` string, a
        ``range`` (``range(380, 781, 5)``) or uniformly spaced wavelengths.
    basis : sequence of three spectra, optional
        The basis reflectances for R, G and B (names, paths, :class:`Spectrum` or ``colour``
        objects); default the paper's ``colorchecker:red``, ``:green``, ``:blue``.
        Interpolated onto the grid by CIE 167.
    observer : {"CIE 1931", "CIE 1964"}, optional
        The standard observer.
    rule : {"riemann", "trapezoid", "simpson"}, optional
        The integration rule.
    rgb : sequence of 3 floats, optional
        A linear RGB colour whose coefficients, spectrum and round-trip error the fit also
        reports (:attr:`Fit.pixel`).

    Returns
    -------
    Fit
        The weights, matrix, basis and light on the grid, and the round trip's statistics.

    Raises
    ------
    FileNotFoundError
        If a CSV path does not exist.
    ValueError
        If a name is unknown, an option is not one of its choices, the wavelengths are not a
        uniform grid, or ``basis`` or ``rgb`` does not hold three.

    Examples
    --------
    >>> f = specmap.fit("FL2", mode="exact")
    >>> f.weights.round(6)  # w_R, w_G, w_B
    array([2.093858, 2.846186, 2.543709])
    >>> f.roundtrip["max_dE2000"] < 1e-9
    True
    >>> specmap.fit(specmap.spectrum("D65"), wavelengths=range(380, 781, 5)).light
    'D65'
    """
    if basis is not None and len(basis) != 3:
        raise ValueError(
            f"basis: three spectra (for R, G and B), not {len(basis)}"
        )
    if rgb is not None and len(rgb) != 3:
        raise ValueError(f"rgb: three values (linear R, G, B), not {len(rgb)}")
    with tempfile.TemporaryDirectory(prefix="specmap-fit-") as tmp:
        argv = [
            "--light=" + _as_spec(light, tmp, "light"),
            "--mode=" + str(mode).lower(),
            "--space=" + str(space).lower(),
            "--observer=" + _observer_flag(observer),
            "--rule=" + str(rule).lower(),
        ]
        if basis is not None:
            specs = [_as_spec(b, tmp, f"basis{i}") for i, b in enumerate(basis)]
            argv.append("--basis=" + ",".join(specs))
        if wavelengths is not None:
            argv.append("--range=" + _range_flag(wavelengths))
        if rgb is not None:
            argv.append("--rgb=" + ",".join(repr(float(x)) for x in rgb))
        report_text, fit_text = _specmap.fit(argv)
    report = json.loads(report_text)
    data = json.loads(fit_text)
    grid = data["grid"]
    wl = grid["start_nm"] + grid["step_nm"] * np.arange(grid["len"], dtype=np.float64)
    return Fit(
        light=data["light"],
        mode=data["mode"],
        space=data["space"],
        observer=data["observer"],
        rule=data["rule"],
        wavelengths=wl,
        weights=np.array(data["weights"], dtype=np.float64),
        matrix=np.array(data["matrix"], dtype=np.float64),
        basis=np.array(data["basis_reflectance"], dtype=np.float64),
        basis_names=tuple(data["basis"]),
        light_spd=np.array(data["light_spd"], dtype=np.float64),
        light_rgb=np.array(data["light_rgb"], dtype=np.float64),
        condition_number=float(data["condition_number"]),
        regularized=bool(data["regularized"]),
        lost_information=data["lost_information"],
        roundtrip=dict(report["roundtrip"]),
        pixel=report.get("pixel"),
        report=report,
        data=data,
        _text=fit_text,
    )


# --- helpers ------------------------------------------------------------------------------


def _fmt_nm(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else repr(float(x))


def _path_part(spec: str) -> str:
    """The file of ``PATH`` or ``PATH:COLUMN`` (the whole when that exists)."""
    if os.path.exists(spec):
        return spec
    head, sep, tail = spec.rpartition(":")
    return head if sep and head and tail and os.path.exists(head) else spec


def _check_interpolation(method: str) -> Interpolation:
    if method not in ("linear", "cie167"):
        raise ValueError(f'interpolation {method!r}: use "linear" or "cie167"')
    return method  # type: ignore[return-value]


def _has_linear_interpolator(sd: Any) -> bool:
    interp = getattr(sd, "interpolator", None)
    return getattr(interp, "__name__", "") == "LinearInterpolator"


def _as_1d(x: npt.ArrayLike, what: str) -> FloatArray:
    a = np.ascontiguousarray(np.asarray(x, dtype=np.float64))
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise ValueError(f"{what}: a 1-D array of wavelengths in nm, not shape {a.shape}")
    return a


def _observer_flag(observer: str) -> str:
    key = re.sub(r"[ _-]", "", str(observer).lower())
    if key in ("cie1931", "1931", "cie19312", "2"):
        return "cie1931"
    if key in ("cie1964", "1964", "cie196410", "10"):
        return "cie1964"
    raise ValueError(
        f'observer {observer!r}: use "CIE 1931" (2 degrees) or "CIE 1964" (10 degrees)'
    )


def _num(x: float) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"wavelengths: {x} is not a wavelength")
    return str(int(x)) if x.is_integer() else repr(x)


def _range_flag(wavelengths: Union[npt.ArrayLike, range, str]) -> str:
    """``START:END:STEP`` for the fit's ``--range``."""
    if isinstance(wavelengths, str):
        return wavelengths
    if isinstance(wavelengths, range):
        if len(wavelengths) < 2:
            raise ValueError(f"wavelengths: {wavelengths} holds fewer than 2 wavelengths")
        return f"{wavelengths[0]}:{wavelengths[-1]}:{wavelengths.step}"
    w = _as_1d(wavelengths, "wavelengths")
    if len(w) < 2:
        raise ValueError(f"wavelengths: {len(w)} given; a grid needs at least 2")
    steps = np.diff(w)
    step = float(steps[0])
    if step <= 0 or np.any(np.abs(steps - step) > 1e-6 * abs(step)):
        raise ValueError(
            "wavelengths must be uniformly spaced and increasing for a fit (a grid "
            f"START:END:STEP); got steps from {steps.min()} to {steps.max()} nm"
        )
    # The step as the grid will have it: (end - start) / (N - 1), so the ends are exact.
    start, end = float(w[0]), float(w[-1])
    return f"{_num(start)}:{_num(end)}:{_num((end - start) / (len(w) - 1))}"


def _spec_text(src: Union[str, "os.PathLike[str]"], prefix: str = "") -> str:
    """A name, TABLE:COLUMN or path as the CLI takes it. A path object that is missing is a
    FileNotFoundError (rather than "no built-in table named ..."); a str may be a table's name."""
    spec = os.fspath(src)
    if not isinstance(spec, str):
        raise TypeError(f"{prefix}a path must be text, not {type(spec).__name__}")
    if not isinstance(src, str) and not os.path.exists(_path_part(spec)):
        raise FileNotFoundError(2, "No such file or directory", spec)
    return spec


def _as_spec(s: SpectrumLike, tmp: str, fallback: str) -> str:
    """A name or path as the CLI takes it; a spectrum written to a CSV in ``tmp`` first."""
    if isinstance(s, (str, os.PathLike)):
        return _spec_text(s)
    if not isinstance(s, (Spectrum, SpectralData)):
        raise TypeError(
            "expected a table name, TABLE:COLUMN, a CSV path, a Spectrum or a "
            f"colour.SpectralDistribution, not {type(s).__name__}"
        )
    sp = s if isinstance(s, Spectrum) else spectrum(s)
    # The file's stem is the label the fit reports: the spectrum's name, made file-safe.
    name = re.sub(r"[^A-Za-z0-9._+-]+", "_", sp.name).strip("._") or fallback
    sub = os.path.join(tmp, fallback)
    os.makedirs(sub, exist_ok=True)
    path = os.path.join(sub, name + ".csv")
    lines = [f"wavelength_nm,{name}"]
    lines += [f"{w!r},{v!r}" for w, v in zip(sp.wavelengths.tolist(), sp.values.tolist())]
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    return path

