//! What the controls hold between edits: text fields and sliders, applied on Enter or release,
//! first filled from the view's settings.

/// Text fields and sliders between edits (applied on Enter or release).
pub(crate) struct UiState {
    pub(super) env: String,
    pub(super) light: String,
    pub(super) substrate: String,
    pub(super) diffuse: String,
    /// The film's layers: index text and thickness in nm.
    pub(super) layers: Vec<(String, f64)>,
    pub(super) orbit: [f64; 2],
    pub(super) size: String,
    pub(super) samples: usize,
    pub(super) tolerance: f64,
    pub(super) budget: usize,
}

impl UiState {
    pub(crate) fn new(s: &super::settings::Settings) -> UiState {
        let text = |k: &str| s.get(k).unwrap_or_default().to_string();
        let args = s.parse().ok();
        let films = args.as_ref().and_then(|a| super::fit::films(a).ok());
        let layers = match s.get("film") {
            Some(f) => f
                .split(',')
                .filter_map(|p| p.rsplit_once(':'))
                .map(|(n, d)| (n.trim().to_string(), d.trim().parse().unwrap_or(0.0)))
                .collect(),
            None => films
                .iter()
                .flatten()
                .flatten()
                .next()
                .map(|f| {
                    f.layers
                        .iter()
                        .map(|l| {
                            let n = l.material().index_at(550.0).map_or(1.5, |i| i.n());
                            (format!("{n}"), l.thickness_nm())
                        })
                        .collect()
                })
                .unwrap_or_default(),
        };
        let orbit = s
            .get("orbit")
            .and_then(|o| crate::cli::render_args::orbit(o).ok())
            .map_or([0.0, 0.0], |o| [o.yaw_deg, o.pitch_deg]);
        UiState {
            env: text("env"),
            light: s.get("light").unwrap_or("D65").to_string(),
            substrate: text("substrate"),
            diffuse: text("diffuse"),
            layers,
            orbit,
            size: args
                .as_ref()
                .and_then(|a| a.image_size().ok())
                .map_or(String::new(), |(w, h)| format!("{w}x{h}")),
            samples: args.as_ref().and_then(|a| a.samples).unwrap_or(81),
            tolerance: args.as_ref().and_then(|a| a.tolerance).unwrap_or(0.5),
            budget: args.as_ref().and_then(|a| a.max_nodes).unwrap_or(8),
        }
    }
}
