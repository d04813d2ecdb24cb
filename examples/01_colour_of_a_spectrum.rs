//! 01: the colour of a spectrum, from a built-in table or from a CSV of your own.
//!
//! Reads D65 and a ColorChecker patch from the built-in tables, then a small lamp written as
//! CSV text, and prints each one's CIE XYZ, chromaticity, correlated colour temperature and
//! sRGB (the numbers `specmap color` prints).
//!
//! `cargo run --example 01_colour_of_a_spectrum`

use specmap::colorimetry::{cct, srgb8, Cmfs, Observer, RgbSpace, Xyz};
use specmap::data::{self, Origin, Table};
use specmap::spectrum::{Interpolation, Rule, Spectrum, Tabulated, WavelengthGrid};
use std::path::Path;

/// A user's table: a header `wavelength_nm,<column>,...`, then rows; `#` starts a comment.
/// Wavelengths need not be evenly spaced.
const LAMP_CSV: &str = "\
# a warm lamp, measured every 20 nm
wavelength_nm,power
380,0.10
400,0.18
420,0.28
440,0.40
460,0.52
480,0.64
500,0.75
520,0.85
540,0.93
560,1.00
580,1.05
600,1.09
620,1.12
640,1.14
660,1.15
680,1.16
700,1.16
720,1.15
740,1.14
760,1.13
780,1.12
";

fn main() -> specmap::Result<()> {
    // Every colour is computed on one wavelength grid: 380..780 nm at 1 nm, the paper's.
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;

    // 1. A light from the built-in tables. Tables hold spectra at the wavelengths they were
    //    published at; `resample` puts them on the grid (lights linearly, so lines stay >= 0).
    let d65 = data::spectrum("D65")?; // also "TABLE:COLUMN" or a path to a CSV
    let d65 = d65.data.resample(&grid, Interpolation::LIGHT);
    describe("D65 as a light", cmfs.light_xyz(&d65, Rule::Riemann)?)?;

    // 2. A reflectance under that light (Eq. 10/11: Y = 100 for a perfect white). Smooth
    //    spectra are resampled by CIE 167's rule.
    let red = data::spectrum("colorchecker:red")?;
    let red = red.data.resample(&grid, Interpolation::SMOOTH);
    describe(
        "ColorChecker red under D65",
        cmfs.reflectance_xyz(&red, &d65, Rule::Riemann)?,
    )?;

    // 3. A user's CSV. `Table::from_file(path)` reads one from disk; here it is parsed from a
    //    string (the path only names it in error messages).
    let table = Table::parse_csv(
        LAMP_CSV,
        "lamp",
        Origin::File("lamp.csv".into()),
        Path::new("lamp.csv"),
    )?;
    let lamp: Tabulated = table.column("power")?;
    let lamp: Spectrum = lamp.resample(&grid, Interpolation::LIGHT);
    describe("lamp.csv as a light", cmfs.light_xyz(&lamp, Rule::Riemann)?)?;
    Ok(())
}

/// Prints XYZ, xy, CCT (with its distance from the black-body locus) and sRGB of one colour.
fn describe(what: &str, xyz: Xyz) -> specmap::Result<()> {
    let [x, y] = xyz.xy();
    let temperature = cct(xyz)?;
    let linear = RgbSpace::SRGB.rgb_from_xyz(xyz); // RGB is on 0..1: XYZ / 100 through the matrix
    println!("{what}");
    println!("  XYZ   {:9.4} {:9.4} {:9.4}", xyz.x(), xyz.y(), xyz.z());
    println!("  xy    {x:9.5} {y:9.5}");
    match temperature.kelvin {
        Some(k) => println!("  CCT   {k:9.1} K (Duv {:+.5})", temperature.duv),
        None => println!("  CCT   undefined (Duv {:+.5})", temperature.duv),
    }
    println!(
        "  sRGB  linear {:.4} {:.4} {:.4}, 8-bit {:?}",
        linear[0],
        linear[1],
        linear[2],
        srgb8(linear)
    );
    Ok(())
}
