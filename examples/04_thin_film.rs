//! 04: a multilayer thin film's reflectance spectrum, and its colour under a light.
//!
//! Builds on 01 (a spectrum's colour under a light): here the spectrum is computed, not read.
//! Two layers on glass (magnesium fluoride 100 nm over a high-index oxide 130 nm, on BK7) are
//! solved by the Airy recursion (the paper's Eq. 2-7 for N layers) at every wavelength, at
//! normal incidence and at 60 degrees, and each reflectance is seen under D65 and under A.
//!
//! `cargo run --example 04_thin_film`

use specmap::colorimetry::{srgb8, Cmfs, Observer, RgbSpace};
use specmap::data;
use specmap::spectrum::{Interpolation, Rule, Spectrum, WavelengthGrid};
use specmap::thinfilm::{Coherence, Incidence, Index, Layer, Material, Polarization, Stack};

fn main() -> specmap::Result<()> {
    let grid = WavelengthGrid::new(380.0, 780.0, 5.0)?;
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;

    // Layers from the ambient side (air) down to the substrate. An index is n + ik (k > 0
    // absorbs, as a metal does); materials may also be dispersive (Cauchy, Sellmeier, a table).
    let air = Material::constant(Index::real(1.0)?);
    let layers = vec![
        Layer::new(Material::constant(Index::real(1.38)?), 100.0)?,
        Layer::new(Material::constant(Index::real(2.1)?), 130.0)?,
    ];
    let glass = Material::named("bk7").expect("a built-in glass");
    let stack = Stack::new(air, layers, glass);

    for degrees in [0.0, 60.0] {
        let incidence = Incidence::degrees(degrees)?;
        // R and T per wavelength, unpolarised (the mean of s and p). `Auto` treats a layer too
        // thick for the grid to resolve its fringes incoherently.
        let response = stack.response(
            &grid,
            &incidence,
            Polarization::Unpolarized,
            Coherence::Auto,
        )?;
        let r = Spectrum::new(grid, response.reflectance.clone())?;
        println!("2-layer film on BK7 at {degrees} degrees");
        for nm in [400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0] {
            let i = ((nm - grid.start_nm()) / grid.step_nm()).round() as usize;
            println!(
                "  {nm:.0} nm  R {:.4}  T {:.4}",
                response.reflectance[i], response.transmittance[i]
            );
        }
        // The reflected colour: the film's reflectance as a surface under each light (01).
        for light_name in ["D65", "A"] {
            let light = data::spectrum(light_name)?
                .data
                .resample(&grid, Interpolation::LIGHT);
            let xyz = cmfs.reflectance_xyz(&r, &light, Rule::Riemann)?;
            let [x, y] = xyz.xy();
            let rgb = RgbSpace::SRGB.rgb_from_xyz(xyz);
            println!(
                "  under {light_name:<3}  Y {:6.3}  xy ({x:.4}, {y:.4})  sRGB8 {:?}",
                xyz.y(),
                srgb8(rgb)
            );
        }
    }
    Ok(())
}
