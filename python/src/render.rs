//! The spectral renderer: `render`, `specmap render`'s one image returned instead of written.

use crate::cli::render_args::{BackendArg, RenderArgs};
use crate::errors::OrPy;
use clap::Parser;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)?;
    Ok(())
}

/// The image `argv` (the flags of `specmap render`, without `-o`) describes, rendered by the
/// CLI's own stages on the backend it would choose: `(image, report)`, the image `(H, W, 3)`
/// float32 linear RGB as an .exr output holds it (times 2^`--exposure`), the report the JSON
/// text `--json` prints, without "output" (nothing is written). A sweep or a sequence is a
/// ValueError.
#[pyfunction]
fn render<'py>(
    py: Python<'py>,
    argv: Vec<String>,
) -> PyResult<(Bound<'py, PyArray3<f32>>, String)> {
    let args = crate::parse_flags::<RenderCommand>("render", argv)?.args;
    if args.backend != BackendArg::Cpu {
        provide_runtime_dir();
    }
    let (image, report) = py
        .detach(move || {
            let exposure = args.exposure;
            let rendered = crate::cli::render::render_image(args)?;
            let report = serde_json::to_string(&rendered.json)?;
            Ok::<_, anyhow::Error>((linear_rgb(&rendered.image, exposure), report))
        })
        .or_py()?;
    Ok((image.into_pyarray(py), report))
}

/// `(H, W, 3)`: the pixels times 2^`exposure_ev` in f32, as `Image::write_exr` writes them.
fn linear_rgb(image: &specmap::render::Image, exposure_ev: f64) -> Array3<f32> {
    let k = exposure_ev.exp2() as f32;
    let flat: Vec<f32> = image
        .pixels
        .iter()
        .flat_map(|p| [p[0] * k, p[1] * k, p[2] * k])
        .collect();
    Array3::from_shape_vec((image.height, image.width, 3), flat).expect("width x height pixels")
}

/// What the CLI's `main` does before a command that may open a GPU: a private
/// `XDG_RUNTIME_DIR` where the session has none (see `cli::runtime_dir`), so that Mesa's Vulkan
/// layer probes quietly. Once per process, with the GIL held (no other Python code runs).
fn provide_runtime_dir() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        crate::cli::runtime_dir::provide();
    });
}

#[derive(Parser)]
struct RenderCommand {
    #[command(flatten)]
    args: RenderArgs,
}
