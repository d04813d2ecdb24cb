//! 02: the paper's basis weights for a light, the exact mode, and a colour's round trip.
//!
//! Builds on 01 (spectra on a grid, XYZ and sRGB). The paper turns RGB into a spectrum as
//! `SPD(R,G,B) = (R wR MCC_R + G wG MCC_G + B wB MCC_B) SPD_light`, with the ColorChecker's red,
//! green and blue patches as the basis and weights chosen so that RGB (1,1,1) is the light's
//! own colour. This example fits those weights for illuminant A, then the exact mode (a full
//! 3x3 matrix that returns every colour), and sends one colour through RGB -> spectrum -> RGB.
//!
//! `cargo run --example 02_fit_a_light`

use specmap::colorimetry::{Observer, RgbSpace};
use specmap::fit::{fit, round_trip, FitInput, Mode, Upsampler, PAPER_BASIS};
use specmap::spectrum::{Rule, WavelengthGrid};

fn main() -> specmap::Result<()> {
    let grid = WavelengthGrid::visible_1nm();
    let space = RgbSpace::SRGB;

    // The light and the three basis reflectances, by name, on one grid (as in 01: any table,
    // TABLE:COLUMN or CSV path).
    let input = FitInput::from_names(
        "A",
        PAPER_BASIS,
        &grid,
        Observer::Cie1931,
        Rule::Riemann,
        space,
    )?;

    // 1. The paper's mode: three weights, exact for white only.
    let paper = fit(&input, Mode::Paper)?;
    let [wr, wg, wb] = paper.weights;
    println!("illuminant A, ColorChecker red/green/blue basis, sRGB");
    println!("  paper weights   wR {wr:.4}  wG {wg:.4}  wB {wb:.4}");
    println!(
        "  (closed form; argmin agrees to {:.1e} after {} iterations)",
        paper.argmin.max_abs_difference, paper.argmin.iterations
    );
    println!(
        "  condition number of the basis colours: {:.2}",
        paper.condition_number
    );

    // 2. The exact mode: coefficients a = W rgb with a full matrix W.
    let exact = fit(&input, Mode::Exact)?;
    println!("  exact matrix W (coefficients = W rgb):");
    for row in exact.matrix {
        println!("    {:9.4} {:9.4} {:9.4}", row[0], row[1], row[2]);
    }

    // 3. One colour's round trip. The Upsampler is the per-pixel engine `convert` uses.
    let rgb = [0.8, 0.4, 0.1]; // linear sRGB, an orange
    for (name, f) in [("paper", &paper), ("exact", &exact)] {
        let up = Upsampler::new(f, &space);
        let a = up.coefficients(rgb);
        let spd = up.spd(rgb); // one value per grid wavelength
        let back = up.rendered_rgb(a);
        println!(
            "  {name}: rgb {rgb:?} -> spectrum of {} samples (peak {:.3}) -> rgb [{:.4}, {:.4}, {:.4}], \
             CIEDE2000 {:.4}",
            spd.len(),
            spd.iter().copied().fold(f64::MIN, f64::max),
            back[0],
            back[1],
            back[2],
            up.round_trip_error(rgb, a)
        );
    }

    // 4. The round trip over a grid of colours (9 x 9 x 9 without black), as `specmap fit`
    //    reports it: the paper's mode errs away from white; the exact mode does not.
    for (name, f) in [("paper", &paper), ("exact", &exact)] {
        let rt = round_trip(f, 9, &space);
        println!(
            "  {name} round trip over {} colours: mean {:.3}, max {:.3} CIEDE2000; {:.0}% go negative",
            rt.colours,
            rt.mean_de2000,
            rt.max_de2000,
            100.0 * rt.negative_fraction
        );
    }
    Ok(())
}
