#!/usr/bin/env python3
"""Export the built-in spectral tables of specmap from colour-science's datasets.

Run from the repository root with a Python that has colour-science 0.4.7:

    .venv/bin/python tools/export_spectra.py

Every table is written at its published sampling (no resampling), values with full float64
precision (repr), header `wavelength_nm,<column>,...`, under spectra/<kind>/<name>.csv.
spectra/README.md documents where each dataset comes from.
"""
import pathlib
import re

import colour

ROOT = pathlib.Path(__file__).resolve().parent.parent / "spectra"

PATCHES = [
    "dark-skin", "light-skin", "blue-sky", "foliage", "blue-flower", "bluish-green",
    "orange", "purplish-blue", "moderate-red", "purple", "yellow-green", "orange-yellow",
    "blue", "green", "red", "yellow", "magenta", "cyan",
    "white-9.5", "neutral-8", "neutral-6.5", "neutral-5", "neutral-3.5", "black-2",
]

# colour-science light-source name -> specmap name, where the automatic slug is not the best name.
LIGHT_NAMES = {
    "Phosphor LED YAG": "phosphor-led",
    "Neodimium Incandescent": "neodymium-incandescent",
    "60 A/W (Soft White)": "60w-soft-white",
    "Philips TL-84": "tl84",
    "SA": "sa",
    "SC": "sc",
}

ILLUMINANTS = (
    ["A", "B", "C", "D50", "D55", "D60", "D65", "D75", "E", "ID50", "ID65"]
    + [f"FL{i}" for i in range(1, 13)]
    + [f"FL3.{i}" for i in range(1, 16)]
    + [f"HP{i}" for i in range(1, 6)]
    + ["LED-B1", "LED-B2", "LED-B3", "LED-B4", "LED-B5", "LED-BH1", "LED-RGB1", "LED-V1", "LED-V2"]
)


def slug(name):
    name = LIGHT_NAMES.get(name, name)
    base = name.split(" (")[0].lower()
    return re.sub(r"[^a-z0-9.]+", "-", base).strip("-")


def write(kind, name, wavelengths, columns):
    path = ROOT / kind / f"{name}.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="\n") as f:
        f.write("wavelength_nm," + ",".join(columns) + "\n")
        for i, w in enumerate(wavelengths):
            row = [repr(float(w))] + [repr(float(col[i])) for col in columns.values()]
            f.write(",".join(row) + "\n")
    return path


def main():
    for short, full in [("cie1931", "CIE 1931 2 Degree Standard Observer"),
                        ("cie1964", "CIE 1964 10 Degree Standard Observer")]:
        m = colour.MSDS_CMFS[full]
        write("cmf", short, m.wavelengths, {c: m.values[:, i] for i, c in enumerate("xyz")})

    for name in ILLUMINANTS:
        sd = colour.SDS_ILLUMINANTS[name]
        write("illuminant", name, sd.wavelengths, {name: sd.values})

    seen = {}
    for name, sd in colour.SDS_LIGHT_SOURCES.items():
        s = slug(name)
        assert s not in seen, (s, name, seen.get(s))
        seen[s] = name
        write("light", s, sd.wavelengths, {s: sd.values})

    for short, full in [("colorchecker", "BabelColor Average"),
                        ("colorchecker-ohta", "ColorChecker N Ohta")]:
        cc = colour.SDS_COLOURCHECKERS[full]
        sds = list(cc.values())
        assert len(sds) == 24
        for ours, theirs in zip(PATCHES, cc.keys()):
            assert theirs.split(" (")[0].replace(" ", "-") == ours, (ours, theirs)
        wl = sds[0].wavelengths
        write("reflectance", short, wl, {p: sd.values for p, sd in zip(PATCHES, sds)})

    basis = colour.colorimetry.SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES
    s0 = basis["S0"]
    write("basis", "cie-daylight", s0.wavelengths,
          {k: basis[k].values for k in ("S0", "S1", "S2")})

    print("light sources:")
    for s, name in sorted(seen.items()):
        print(f"| `{s}` | {name} |")


if __name__ == "__main__":
    main()
