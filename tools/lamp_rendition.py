#!/usr/bin/env python3
"""How much a wrong lamp costs: the 24 ColorChecker patches (Ohta) under one lamp against under
another, each adapted from its own white to D65 by CAT02 (as `specmap rendition` does), mean
CIEDE2000, all with colour-science. The ranks of src/envmap/scene/families.rs come from this,
and so does its sodium series: each measured sodium lamp against the mix of `hps` and CIE HP2
(each at luminance 1) whose white is nearest its own, found here by search over the share.

    .venv/bin/python tools/lamp_rendition.py
"""
import csv
import pathlib
import warnings

import numpy as np

warnings.filterwarnings("ignore")
import colour  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHAPE = colour.SpectralShape(380, 780, 5)
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE)
PATCHES = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
D65 = colour.xy_to_XYZ([0.3127, 0.3290])


def table(kind, name):
    rows = list(csv.reader(open(ROOT / "spectra" / kind / f"{name}.csv")))
    d = np.array([[float(v) for v in r[:2]] for r in rows[1:]])
    return colour.SpectralDistribution(dict(zip(d[:, 0], d[:, 1]))).copy().align(SHAPE)


def labs(light):
    one = colour.SpectralDistribution(dict(zip(light.wavelengths, np.ones(len(light.wavelengths)))))
    white = colour.sd_to_XYZ(one, CMFS, light) / 100
    out = []
    for p in PATCHES.values():
        xyz = colour.sd_to_XYZ(p.copy().align(SHAPE), CMFS, light) / 100
        adapted = colour.adaptation.chromatic_adaptation_VonKries(xyz, white, D65, transform="CAT02")
        out.append(colour.XYZ_to_Lab(adapted))
    return np.array(out)


GROUPS = {
    "sodium": (["c100s54", "c100s54c", "super-hps", "sdw-t-100w-lv"],
               [("light", "hps"), ("illuminant", "HP1"), ("illuminant", "HP2")]),
    "warm LED": (["luxeon-ww-2880", "phos-1", "phos-3", "4-led-1"],
                 [("illuminant", n) for n in ("LED-B1", "LED-B2", "LED-BH1", "LED-V1", "LED-RGB1")]),
    "4000 K": (["f32t8-tl841", "tl84", "t8-polylux-4000", "cool-white-fl", "mhc100-u-mp-4k"],
               [("illuminant", n) for n in ("FL11", "FL3.8", "FL3.5", "FL9", "FL6", "FL2", "LED-B3", "HP4")]
               + [("light", "mercury")]),
    "daylight white": (["phosphor-led", "kinoton-75p", "f40-c75"],
                       [("illuminant", n) for n in ("LED-B4", "LED-B5", "FL7", "FL8", "D65")]
                       + [("light", "kinoton-75p"), ("light", "phosphor-led")]),
}


def main():
    for group, (measured, catalogue) in GROUPS.items():
        print(f"## {group}: mean CIEDE2000, measured lamp (row) against catalogue table (column)")
        print("| lamp | " + " | ".join(n for _, n in catalogue) + " |")
        print("|---|" + "---:|" * len(catalogue))
        refs = [labs(table(k, n)) for k, n in catalogue]
        for m in measured:
            lab = labs(table("light", m))
            de = [colour.delta_E(lab, r, method="CIE 2000").mean() for r in refs]
            print(f"| {m} | " + " | ".join(f"{v:.2f}" for v in de) + " |")
        print()
    sodium_mixes()


def uv_of(sd):
    return colour.xy_to_UCS_uv(colour.XYZ_to_xy(colour.sd_to_XYZ(sd, CMFS)))


def at_unit_luminance(sd):
    return sd.values / colour.sd_to_XYZ(sd, CMFS)[1]


def sodium_mixes():
    a, b = table("light", "hps"), table("illuminant", "HP2")
    ua, ub = at_unit_luminance(a), at_unit_luminance(b)
    print("## sodium series: measured lamp against the mix of hps and HP2 of its white")
    print("| lamp | CCT (K) | HP2's share of the mix | mix | hps | HP2 |")
    print("|---|---:|---:|---:|---:|---:|")
    for m in GROUPS["sodium"][0]:
        lamp = table("light", m)
        target = uv_of(lamp)
        mixes = [(t, colour.SpectralDistribution(dict(zip(a.wavelengths, (1 - t) * ua + t * ub))))
                 for t in np.linspace(0, 1, 1001)]
        t, mix = min(mixes, key=lambda p: np.linalg.norm(uv_of(p[1]) - target))
        lab = labs(lamp)
        de = [colour.delta_E(lab, labs(s), method="CIE 2000").mean() for s in (mix, a, b)]
        cct = colour.uv_to_CCT(target, method="Ohno 2013")[0]
        inside = 0 < t < 1
        print(f"| {m} | {cct:.0f} | " + (f"{t:.2f}" if inside else "beyond an end") + " | "
              + (f"{de[0]:.2f}" if inside else "") + f" | {de[1]:.2f} | {de[2]:.2f} |")
    print()


if __name__ == "__main__":
    main()
