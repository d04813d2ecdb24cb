//! Helpers shared by the integration tests (each test file uses a subset).
#![allow(dead_code)]

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
    WritableImage,
};
use std::path::Path;
use std::process::{Command, Output};

/// Runs the `specmap` binary built for the tests.
pub(crate) fn specmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .output()
        .expect("the specmap binary runs")
}

/// A bundled sample map in envmaps/, as a path string.
pub(crate) fn sample(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("envmaps")
        .join(name)
        .display()
        .to_string()
}

/// Writes a single-part scan-line EXR of f32 channels (sorted by name, as OpenEXR stores them)
/// with the exr crate: an independent writer, which also lets a test put NaN or huge values in.
pub(crate) fn write_channels(path: &Path, w: usize, h: usize, channels: Vec<(&str, Vec<f32>)>) {
    write_channels_with(path, w, h, channels, LayerAttributes::default());
}

/// [`write_channels`] with the layer's attributes.
pub(crate) fn write_channels_with(
    path: &Path,
    w: usize,
    h: usize,
    channels: Vec<(&str, Vec<f32>)>,
    attributes: LayerAttributes,
) {
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(n, v)| AnyChannel::new(n, FlatSamples::F32(v)))
        .collect();
    let layer = Layer::new(
        (w, h),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// Runs `specmap ARGS --json`, which must succeed, and parses its output.
pub(crate) fn specmap_json(args: &[&str]) -> serde_json::Value {
    let mut all = args.to_vec();
    all.push("--json");
    let out = specmap(&all);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// The GPU renderer, once per test binary; None without an adapter, unless
/// `SPECMAP_REQUIRE_GPU=1` (set by tools/test.sh, which installs Mesa's lavapipe), where a
/// missing adapter fails.
pub(crate) fn gpu() -> Option<&'static specmap::render::gpu::Gpu> {
    use specmap::render::gpu::Gpu;
    static GPU: std::sync::OnceLock<Option<Gpu>> = std::sync::OnceLock::new();
    GPU.get_or_init(|| match Gpu::new() {
        Ok(g) => {
            eprintln!("GPU tests on {:?}", g.adapter());
            Some(g)
        }
        Err(e) => {
            if std::env::var("SPECMAP_REQUIRE_GPU").as_deref() == Ok("1") {
                panic!("SPECMAP_REQUIRE_GPU=1 but {e}");
            }
            eprintln!("notice: skipping GPU checks: {e}");
            None
        }
    })
    .as_ref()
}
