//! specmap: spectral data toolkit and RGB -> spectral environment-map converter.
//!
//! The library knows nothing of the command line. Modules, from the ground up:
//! - [`spectrum`]: wavelength grids, sampled spectra, resampling, integration rules;
//! - [`data`]: built-in spectral tables and user CSV files;
//! - [`colorimetry`]: SPD -> XYZ (the paper's Eq. 10/11), RGB spaces, CIELAB, CIEDE2000, CCT;
//! - [`fit`]: the paper's per-light basis weights, exact and non-negative modes, the round trip;
//! - [`thinfilm`]: multilayer thin-film interference (paper Eq. 2-9 for N layers);
//! - [`render`]: spectral preview renderer (Eq. 1 Phong + thin films), wgpu compute and CPU;
//! - [`rendition`]: colour rendition of a spectral map against its truth (patches, CAT02, CIEDE2000);
//! - [`tradeoff`]: colour error against time for wavelength grids and rules; `--tolerance`;
//! - [`quadrature`]: nodes and weight triples (uniform, Meyer's, fitted to a scene's spectra);
//! - [`plot`], [`io`]: PNG/SVG plots and safe (temporary file + rename) output.

// Every public item says what it is (the library's API; Cargo.toml's [lints] keep the rest).
#![warn(missing_docs)]

pub mod batch;
pub mod colorimetry;
pub mod data;
pub mod envmap;
pub mod error;
pub mod fit;
pub mod illuminant;
pub mod io;
pub mod plot;
pub mod quadrature;
pub mod render;
pub mod rendition;
pub mod spectrum;
pub mod thinfilm;
pub mod tradeoff;

pub use error::{Error, Result};
