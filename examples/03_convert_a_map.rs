//! 03: an RGB environment map to a spectral OpenEXR.
//!
//! Builds on 02 (RGB -> spectrum for one light): `convert` does it for every pixel of a map,
//! after finding the map's lights (sun, sky, lamps) and giving each pixel a spectrum of the
//! light it comes from. This example writes a tiny lat-long RGB map (a blue sky, a warm sun and
//! brown ground) into a temporary folder, converts it the way `specmap convert` does by default
//! and prints the report's main facts. For a real map, pass its path instead (the repository
//! bundles envmaps/sunrise.exr).
//!
//! `cargo run --example 03_convert_a_map`

use specmap::envmap::convert::{convert, ConvertOptions};
use std::path::{Path, PathBuf};

/// Width and height of the lat-long map (2:1).
const SIZE: (usize, usize) = (128, 64);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::temp_dir().join("specmap-examples");
    std::fs::create_dir_all(&dir)?;
    let input = write_tiny_map(&dir.join("tiny_sky.exr"))?;
    let output = dir.join("tiny_sky_spectral.exr");

    // The command line's defaults: the scene's own lights (daylight for sun and sky), 380..780 nm
    // at 5 nm, half floats, ZIP. Every field of ConvertOptions is a flag of `specmap convert`.
    let opts = ConvertOptions::faithful();
    let input_name = input.to_str().ok_or("a temporary path that is not UTF-8")?;
    let report = convert(input_name, &output, &opts, &|_done, _total| {})?;

    println!("{} -> {}", report.input, report.output);
    println!(
        "  {}x{} {:?} in, {}x{} {:?} out",
        report.input_size[0],
        report.input_size[1],
        report.input_layout,
        report.output_size[0],
        report.output_size[1],
        report.output_layout
    );
    let w = &report.wavelengths_nm;
    println!(
        "  {} bands, {}..{} nm; {} channels, {} bytes",
        w.len(),
        w[0],
        w[w.len() - 1],
        report.channels,
        report.bytes
    );
    println!("  mode {}, main light {}", report.mode, report.light);
    println!("  sun found: {} ({})", report.sun.found, report.sun.reason);
    for light in &report.lights {
        println!(
            "  light {:?}: {} ({:.0}% of the energy)",
            light.kind,
            light.spd,
            100.0 * light.energy_share
        );
    }
    let rt = &report.roundtrip;
    println!(
        "  round trip over {} pixels: mean {:.4}, max {:.4} CIEDE2000",
        rt.pixels, rt.weighted_mean_de2000, rt.max_de2000
    );
    for note in &report.notes {
        println!("  note: {note}");
    }
    Ok(())
}

/// Writes a lat-long RGB OpenEXR with the `exr` crate: sky above the horizon (bluer at the
/// zenith), a small bright sun, ground below. Returns its path.
fn write_tiny_map(path: &Path) -> Result<PathBuf, exr::error::Error> {
    let (w, h) = SIZE;
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let up = 1.0 - (y as f32 + 0.5) / (h as f32 / 2.0); // 1 at the zenith, 0 at the horizon
        if (x, y) == (w / 2, h / 4) {
            (20000.0, 19000.0, 17000.0) // the sun: one pixel, very bright
        } else if up > 0.0 {
            (0.35 + 0.2 * (1.0 - up), 0.55 + 0.1 * (1.0 - up), 0.9f32) // sky
        } else {
            (0.12, 0.09, 0.06) // ground
        }
    })?;
    Ok(path.to_path_buf())
}
