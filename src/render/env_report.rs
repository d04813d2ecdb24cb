//! What loading an environment file found, for the render's report.

/// What loading an environment file found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EnvReport {
    /// The file's path, as given.
    pub file: String,
    /// `rgb`, `basis` (version 1: three ColorChecker coefficients and a sun), `basis-k` (the
    /// K-spectrum form) or `spectral`.
    pub kind: &'static str,
    /// The file's image size in pixels (width, height).
    pub input_size: [usize; 2],
    /// The light the map's spectra were made with: `--light` for an RGB map (converted here),
    /// the header's for a file from `specmap convert`.
    pub light: String,
    /// Whether `--light` changed the lighting (only an RGB map's).
    pub light_used: bool,
    /// Label of the sun's SPD ("none" for a map of its own spectra without a sun).
    pub sun_spd: String,
    /// The sun taken out as a directional light (None: no sun found).
    pub sun_direction: Option<[f64; 3]>,
    /// The sun's irradiance at normal incidence, in units of its SPD at Y = 1 (None: no sun).
    pub sun_irradiance: Option<f64>,
    /// How many spectra the map's coefficients expand with.
    pub spectra: usize,
    /// A spectral map: how well its own spectra hold it.
    pub projection: Option<crate::envmap::convert::own_basis::Projection>,
}

/// The sun SPD given to sun pixels of an RGB map converted here: CIE D65, as in the paper.
pub const SUN_SPD: &str = "D65";
