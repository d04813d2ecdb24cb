//! 05: a preset scene rendered spectrally on the CPU, written as a PNG.
//!
//! Builds on 04 (a film's reflectance per wavelength): the renderer evaluates the paper's
//! spectral Phong model with thin films (Eq. 1-9) at every pixel and wavelength, then turns
//! each pixel's spectrum into a colour (01). The preset is the paper's Fig. 6, a sphere with a
//! chrome-oxide film (n 2.7, 270 nm) on black plastic, under a uniform D65 light and a key light;
//! it is rendered at 96 x 96 on a 10 nm grid, then once more on a 40 nm grid to show what a
//! coarse grid costs in CIEDE2000.
//!
//! `cargo run --example 05_render_a_preset`

use specmap::render::{compare, Preset, Spectral};

fn main() -> specmap::Result<()> {
    let dir = std::env::temp_dir().join("specmap-examples");
    std::fs::create_dir_all(&dir).map_err(|source| specmap::Error::Io {
        path: dir.clone(),
        source,
    })?;

    // The scene: the preset at a small size, lit by a uniform D65 (None: no environment map;
    // `specmap render --env MAP` passes a map's lighting there).
    let (width, height) = (96, 96);
    let scene = Preset::Ball.scene(width, height, "D65", None)?;

    // How spectra become colours: 380..780 nm at 10 nm, Riemann, CIE 1931, sRGB.
    let fine = Spectral::step(10.0)?;
    let image = scene.render_cpu(&fine)?;
    let png = dir.join("ball.png");
    image.write_png(&png, 0.0)?; // exposure 0 EV
    println!(
        "{}: {}x{} pixels, {} wavelengths, written to {}",
        Preset::Ball.name(),
        image.width,
        image.height,
        fine.grid.len(),
        png.display()
    );
    let centre = image.get(width / 2, height / 2);
    println!(
        "  centre pixel, linear sRGB: {:.4} {:.4} {:.4}",
        centre[0], centre[1], centre[2]
    );

    // The same scene on a coarse grid: fewer wavelengths are faster, at a colour error.
    let coarse = Spectral::step(40.0)?;
    let rough = scene.render_cpu(&coarse)?;
    let c = compare(&image, &rough, &fine.space)?;
    println!(
        "  at 40 nm ({} wavelengths): mean CIEDE2000 {:.3}, max {:.3} against 10 nm",
        coarse.grid.len(),
        c.mean,
        c.max
    );
    Ok(())
}
