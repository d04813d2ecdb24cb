"""The spectral renderer: :func:`render`, ``specmap render`` with the image returned as a numpy
array instead of written to a file."""

from __future__ import annotations

import json
from typing import Any, Dict, Tuple

import numpy as np
import numpy.typing as npt

from . import _specmap
from ._options import argv_of

__all__ = ["render"]


def render(
    scene: str = "ball", **options: Any
) -> Tuple[npt.NDArray[np.float32], Dict[str, Any]]:
    """Render one of the paper's scenes spectrally, as ``specmap render`` does.

    The options are ``specmap render``'s and mean exactly what its flags mean: they are turned
    into the flags and parsed by the command line's own definitions, and the image is made by
    its own stages (the scene, the quadrature, the CPU or GPU renderer), so that
    ``render("ball", backend="cpu", size="48x32")`` gives the very values that
    ``specmap render --scene ball --backend cpu --size 48x32 -o out.exr`` writes.

    Parameters
    ----------
    scene : str, default "ball"
        The preset: ``"ball"`` (Fig. 6), ``"transparent-ball"`` (Fig. 7), ``"cylinders"``
        (Fig. 8), ``"chart"`` (Fig. 9) or ``"checker-spheres"``.
    **options
        ``specmap render``'s long flags with underscores for hyphens (``specmap render --help``
        says what each does), for example:

        - ``backend`` : ``"auto"`` (the GPU when an adapter exists, else the CPU with a notice
          on stderr; the default), ``"gpu"`` or ``"cpu"``.
        - ``size`` : ``"WxH"`` or a ``(width, height)`` tuple; the preset's size by default.
        - ``env`` : an environment map (RGB EXR/HDR, or a basis or spectral EXR from
          :func:`specmap.convert`); ``light`` : the main light (default ``"D65"``);
          ``background`` : ``"env"``, ``"flat"`` or ``"none"``.
        - ``film`` : film layers ``"INDEX:THICKNESS_NM[,...]"`` (``"2.7:270"``);
          ``substrate``, ``diffuse``, ``kd``, ``ks``, ``shininess`` : the main objects'
          surface.
        - ``step`` or ``samples`` : the uniform wavelength grid (default 81 samples, 5 nm);
          ``rule``, ``observer``; ``quadrature`` (``"uniform"``, ``"meyer"``, ``"scene"``);
          ``tolerance`` (CIEDE2000: the fewest wavelengths that keep it), ``max_nodes``,
          ``fit_range``, ``fit_budget``, ``no_cache``.
        - ``orbit`` : ``"YAW,PITCH"`` or a ``(yaw, pitch)`` tuple in degrees; ``zoom``.
        - ``exposure`` : stops; the image is multiplied by ``2**exposure`` (as an .exr output
          is).

        A value ``v`` becomes ``--name=v``; ``True`` the bare flag ``--name``; ``False`` and
        ``None`` leave the flag out; a list or tuple is joined by commas.

    Returns
    -------
    image : numpy.ndarray
        ``(height, width, 3)`` float32 linear RGB (sRGB primaries, D65 white), row 0 at the
        top: the renderer's output before tone mapping and sRGB encoding, bit for bit what
        ``specmap render -o out.exr`` writes for the same options.
    report : dict
        What ``specmap render --json`` prints for the same options: the scene, size, backend
        and GPU adapter, the wavelengths and weights of the quadrature (and how it was chosen,
        with ``tolerance``), the lights, the environment's report, the timings
        (``prepare_s``, ``render_s``, ``gpu_timing``) and ``exposure_ev``; there is no
        ``output``, as no file is written.

    Raises
    ------
    ValueError
        An unknown option or a value its flag refuses (the command line's message); an
        ``output`` (write the returned image yourself); a sweep (``sweep``) or a sequence
        (``turntable``, ``frames``, a film thickness range ``"2.7:100..400"``), which make many
        images: run ``specmap render`` for those. ``backend="gpu"`` without a GPU adapter.
    FileNotFoundError
        A missing ``env`` map (or another file an option names).
    OSError
        Another failure of the system reading a file.

    Notes
    -----
    The work is done in Rust with the GIL released. The GPU, where used, is opened for each
    call.

    Examples
    --------
    >>> import specmap
    >>> image, report = specmap.render("ball", backend="cpu", size=(64, 48), step=10)
    >>> image.shape, image.dtype, report["wavelengths"]
    ((48, 64, 3), dtype('float32'), 41)
    """
    if isinstance(options.get("size"), (list, tuple)):
        width, height = options["size"]
        options["size"] = f"{int(width)}x{int(height)}"
    image, report = _specmap.render(argv_of({"scene": scene, **options}))
    return image, json.loads(report)
