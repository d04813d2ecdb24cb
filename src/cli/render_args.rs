//! `specmap render`'s options (clap) and their parsing: the preset, the films and surfaces, the
//! size, the orbit, the fit's range; also read by `view` (its settings are render's options).

use super::{ObserverArg, RuleArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use specmap::render::Preset;
use specmap::spectrum::Tabulated;
use specmap::thinfilm::{Index, Layer, Material};
use std::path::PathBuf;

#[derive(Debug, Clone, Args)]
#[command(after_help = "\
Without --env the scene is lit by a uniform LIGHT and a key light of the same SPD
(transparent-ball: a bright sky over a dark floor). --film/--substrate/--diffuse/--kd/--ks/
--shininess change the scene's main objects (the chart's spheres).

Examples:
  specmap render --scene ball -o ball.png
  specmap render --scene ball --env envmaps/sunrise.exr --samples 81 -o ball.exr
  specmap render --scene cylinders --backend cpu --step 5 --json
  specmap render --scene cylinders --tolerance 0.5 --json   # the fewest wavelengths for CIEDE2000 0.5
  specmap render --scene cylinders --tolerance 0.5 --max-nodes 8   # at most 8: the best 8 if 8 miss
  specmap render --scene ball --light FL2 --quadrature meyer -o meyer.png
  specmap render --scene chart --size 768x512 --exposure -0.5 -o chart.png
  specmap render --scene ball --env envmaps/sunrise.exr --orbit 120,15 --zoom 1.5 -o turned.png
  specmap render --scene ball --film 1.38:100,2.1:130 --substrate bk7 -o coated.png
  specmap render --scene chart --size 384x256 --sweep 4,9,17,34,81,340 --sweep-out sweep/")]
pub(crate) struct RenderArgs {
    /// The scene preset (the paper's figures 6-9).
    #[arg(long, value_enum, default_value_t = SceneArg::Ball)]
    pub(crate) scene: SceneArg,
    /// Environment map: an RGB EXR/HDR (converted on the fly), or a basis or spectral EXR from
    /// `specmap convert`.
    #[arg(long, value_name = "MAP")]
    pub(crate) env: Option<PathBuf>,
    /// What rays that miss every object see: the environment through a 60 degree field of
    /// view (env), the environment straight behind the scene in one colour (flat), or black.
    #[arg(long, value_enum, value_name = "KIND", default_value_t = BackgroundArg::Env)]
    pub(crate) background: BackgroundArg,
    /// Main light: the uniform light without --env, the conversion's light with an RGB map
    /// (a spectral or basis map is lit by the spectra it holds; --light does not apply).
    #[arg(long, value_name = "LIGHT", default_value = "D65")]
    pub(crate) light: String,
    /// Film layers from the air side, INDEX:THICKNESS_NM[,...] (e.g. 2.7:270).
    #[arg(long, value_name = "N:D[,N:D...]")]
    pub(crate) film: Option<String>,
    /// Substrate index under the film (e.g. 1.45, bk7, 3.1+3.3i).
    #[arg(long, value_name = "N")]
    pub(crate) substrate: Option<String>,
    /// Pigment reflectance R_d: TABLE:COLUMN, a CSV, or a constant (e.g. 0.5).
    #[arg(long, value_name = "T:C|CSV")]
    pub(crate) diffuse: Option<String>,
    /// Diffuse coefficient k_d.
    #[arg(long)]
    pub(crate) kd: Option<f64>,
    /// Specular coefficient k_s (without a film).
    #[arg(long)]
    pub(crate) ks: Option<f64>,
    /// Phong exponent n.
    #[arg(long)]
    pub(crate) shininess: Option<f64>,
    /// Image size WxH (default: the preset's).
    #[arg(long, value_name = "WxH")]
    pub(crate) size: Option<String>,
    /// Wavelength step in nm over 380..780 (must divide 400).
    #[arg(long, value_name = "NM", conflicts_with = "samples")]
    pub(crate) step: Option<f64>,
    /// Number of wavelengths over 380..780 nm (default 81: 5 nm).
    #[arg(long, value_name = "N")]
    pub(crate) samples: Option<usize>,
    /// Choose the cheapest quadrature (fewest wavelengths) that keeps every spectrum the scene
    /// can produce (its lights, pigments and films over their angles and thicknesses) within
    /// this CIEDE2000 of the 1 nm render, and report it.
    #[arg(long, value_name = "DE", conflicts_with_all = ["step", "samples"])]
    pub(crate) tolerance: Option<f64>,
    /// With --tolerance: use at most N wavelengths (a renderer's fixed budget, e.g. 4 or 8
    /// SIMD lanes). Where no quadrature that small meets the tolerance, the scene's best N
    /// (searched from fresh starts), reported with how far it misses, on the image too.
    #[arg(long, value_name = "N", requires = "tolerance")]
    pub(crate) max_nodes: Option<usize>,
    /// With --tolerance: fit the wavelengths as `specmap view` does, for every orientation of
    /// the camera and each film's thickness scaled by 1 ± F, or from S0 to S1 times its
    /// thickness (the view's command carries its fit's range, so that `render` fits the same
    /// wavelengths; the view's default is 0.15).
    #[arg(long, value_name = "F|S0:S1", requires = "tolerance")]
    pub(crate) fit_range: Option<String>,
    /// With --tolerance: the most seconds the scene's fit may search (it returns the best
    /// wavelengths found by then). By default a tenth of the time the uniform grid that meets
    /// the tolerance would take for every frame, so that a fit which does not pay costs at most
    /// 10% more; where even that cannot pay, no fit runs. --quadrature scene: no limit.
    #[arg(long, value_name = "SECONDS", requires = "tolerance")]
    pub(crate) fit_budget: Option<f64>,
    /// Neither read nor store the chosen wavelengths in the cache
    /// ($XDG_CACHE_HOME/specmap/quadrature, else ~/.cache/specmap/quadrature).
    #[arg(long)]
    pub(crate) no_cache: bool,
    /// Which wavelengths and weights: `scene` fits them to the scene (needs --tolerance, and is
    /// its default), `uniform` is the --step/--samples grid (or, with --tolerance, the coarsest
    /// step at its best rule), `meyer` is Meyer's four-wavelength Gaussian quadrature.
    #[arg(long, value_enum, value_name = "KIND", conflicts_with = "sweep")]
    pub(crate) quadrature: Option<QuadratureArg>,
    /// Integration rule of the colour integrals.
    #[arg(long, value_enum, default_value_t = RuleArg::Riemann)]
    pub(crate) rule: RuleArg,
    /// Standard observer.
    #[arg(long, value_enum, default_value_t = ObserverArg::Cie1931)]
    pub(crate) observer: ObserverArg,
    /// Which renderer: the GPU if an adapter exists (auto), or one of them.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    pub(crate) backend: BackendArg,
    /// The camera orbits the scene by YAW and PITCH degrees, the objects turning with it (a
    /// turntable): the map and the sun stay with the world. For a sphere, exactly the camera
    /// orbiting.
    #[arg(long, value_name = "YAW,PITCH", allow_hyphen_values = true)]
    pub(crate) orbit: Option<String>,
    /// Zoom: the view's height divided by F (2 shows half as much, twice as large).
    #[arg(long, value_name = "F")]
    pub(crate) zoom: Option<f64>,
    /// A turntable: N frames orbiting the scene once (from --orbit's yaw, at its pitch), drawn
    /// on one quadrature and written as numbered images (-o turn.png: turn-000.png, ...).
    #[arg(long, value_name = "N", conflicts_with_all = ["sweep", "frames"])]
    pub(crate) turntable: Option<usize>,
    /// A thickness sweep: N frames with the film from its ranges' starts to their ends
    /// (--film 2.7:100..400), on one quadrature, written as numbered images.
    #[arg(long, value_name = "N", conflicts_with = "sweep")]
    pub(crate) frames: Option<usize>,
    /// Exposure in stops applied to the written image.
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub(crate) exposure: f64,
    /// Output image: .png (8-bit sRGB) or .exr (linear float).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Machine-readable report on stdout.
    #[arg(long)]
    pub(crate) json: bool,
    /// Instead of one image: the speed-for-accuracy curve at these wavelength counts.
    #[arg(long, value_name = "N,N,...", value_delimiter = ',')]
    pub(crate) sweep: Option<Vec<usize>>,
    /// Folder for the sweep's sweep.md, sweep.json and sweep.png.
    #[arg(long, value_name = "DIR", requires = "sweep")]
    pub(crate) sweep_out: Option<PathBuf>,
    /// Frames per wavelength count in the sweep (the fastest is kept).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub(crate) repeats: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackgroundArg {
    Env,
    Flat,
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SceneArg {
    /// Fig. 6: chrome-oxide film 270 nm (n 2.7) on black plastic (1.45)
    Ball,
    /// Fig. 7: TiO2 (2.3) on clear plastic (1.45), 150 nm and 350 nm
    TransparentBall,
    /// Fig. 8: chrome oxide, thickness rising from 100 nm (left) to 400 nm (right)
    Cylinders,
    /// Fig. 9: ColorChecker and plastic spheres under D65, A and low-pressure sodium (one row
    /// under --env)
    Chart,
    /// The 24 ColorChecker reflectances as Lambertian spheres, 6 x 4
    CheckerSpheres,
}

impl From<SceneArg> for Preset {
    fn from(s: SceneArg) -> Self {
        match s {
            SceneArg::Ball => Preset::Ball,
            SceneArg::TransparentBall => Preset::TransparentBall,
            SceneArg::Cylinders => Preset::Cylinders,
            SceneArg::Chart => Preset::Chart,
            SceneArg::CheckerSpheres => Preset::CheckerSpheres,
        }
    }
}

/// `--quadrature`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum QuadratureArg {
    /// fitted to the scene's spectra (with --tolerance)
    Scene,
    /// a uniform grid and integration rule
    Uniform,
    /// Meyer's (1988) four-wavelength Gaussian quadrature
    Meyer,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendArg {
    /// the GPU when an adapter exists, else the CPU (with a one-line notice)
    Auto,
    /// wgpu compute; an error without an adapter
    Gpu,
    /// the rayon reference renderer
    Cpu,
}

pub(crate) fn index(spec: &str, what: &str) -> anyhow::Result<Material> {
    let s = spec.trim();
    if let Some(m) = Material::named(s) {
        return Ok(m);
    }
    let i: Index = s.parse().with_context(|| {
        format!("{what} '{spec}' is not an index (2.7, 3.1+3.3i) or a named material (bk7)")
    })?;
    Ok(Material::constant(i))
}

pub(crate) fn film_layers(spec: &str) -> anyhow::Result<Vec<Layer>> {
    spec.split(',')
        .filter(|p| !p.trim().is_empty())
        .enumerate()
        .map(|(i, part)| {
            let n = i + 1;
            let (m, d) = part.trim().rsplit_once(':').with_context(|| {
                format!("film layer {n}: '{part}' must be INDEX:THICKNESS_NM, e.g. 2.7:270")
            })?;
            let d: f64 = d.trim().parse().map_err(|_| {
                anyhow::anyhow!("film layer {n}: thickness '{d}' is not a number (nm)")
            })?;
            Ok(Layer::new(index(m, &format!("film layer {n}"))?, d)?)
        })
        .collect()
}

fn size(spec: &str) -> anyhow::Result<(usize, usize)> {
    let (w, h) = spec
        .split_once(['x', 'X'])
        .with_context(|| format!("--size '{spec}' must be WxH, e.g. 512x512"))?;
    let p = |v: &str| -> anyhow::Result<usize> {
        v.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--size '{spec}': '{v}' is not a whole number"))
    };
    Ok((p(w)?, p(h)?))
}

pub(crate) fn diffuse(spec: &str) -> anyhow::Result<Tabulated> {
    if let Ok(v) = spec.trim().parse::<f64>() {
        if !(0.0..=1.0).contains(&v) {
            anyhow::bail!("--diffuse {v}: a constant reflectance must be between 0 and 1");
        }
        return Ok(Tabulated::new(vec![380.0, 780.0], vec![v, v])?);
    }
    Ok(specmap::data::spectrum(spec)?.data)
}

/// The options that take no value ([`RenderArgs::to_pairs`] gives them an empty one).
pub(crate) const FLAGS: [&str; 2] = ["no-cache", "json"];

/// `RenderArgs` parsed alone (for [`RenderArgs::parse_pairs`]).
#[derive(Debug, clap::Parser)]
#[command(name = "specmap render")]
struct RenderOnly {
    #[command(flatten)]
    args: RenderArgs,
}

impl RenderArgs {
    /// The options as `specmap render` spells them, `(long name, value)`, each one set away
    /// from its default (a flag's value is empty), in the order `--help` lists them.
    pub(crate) fn to_pairs(&self) -> Vec<(&'static str, String)> {
        fn name<T: ValueEnum>(v: &T) -> String {
            v.to_possible_value()
                .map_or(String::new(), |p| p.get_name().to_string())
        }
        let mut out: Vec<(&'static str, String)> = Vec::new();
        let mut opt = |k: &'static str, v: Option<String>| {
            if let Some(v) = v {
                out.push((k, v));
            }
        };
        let path = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
        let num = |v: Option<f64>| v.map(|v| v.to_string());
        opt(
            "scene",
            (self.scene != SceneArg::Ball).then(|| name(&self.scene)),
        );
        opt("env", path(&self.env));
        opt(
            "background",
            (self.background != BackgroundArg::Env).then(|| name(&self.background)),
        );
        opt("light", (self.light != "D65").then(|| self.light.clone()));
        opt("film", self.film.clone());
        opt("substrate", self.substrate.clone());
        opt("diffuse", self.diffuse.clone());
        opt("kd", num(self.kd));
        opt("ks", num(self.ks));
        opt("shininess", num(self.shininess));
        opt("size", self.size.clone());
        opt("step", num(self.step));
        opt("samples", self.samples.map(|v| v.to_string()));
        opt("tolerance", num(self.tolerance));
        opt("max-nodes", self.max_nodes.map(|v| v.to_string()));
        opt("fit-range", self.fit_range.clone());
        opt("fit-budget", num(self.fit_budget));
        opt("no-cache", self.no_cache.then(String::new));
        opt("quadrature", self.quadrature.map(|q| name(&q)));
        opt(
            "rule",
            (self.rule != RuleArg::Riemann).then(|| name(&self.rule)),
        );
        opt(
            "observer",
            (self.observer != ObserverArg::Cie1931).then(|| name(&self.observer)),
        );
        opt(
            "backend",
            (self.backend != BackendArg::Auto).then(|| name(&self.backend)),
        );
        opt("turntable", self.turntable.map(|v| v.to_string()));
        opt("frames", self.frames.map(|v| v.to_string()));
        opt("orbit", self.orbit.clone());
        opt("zoom", num(self.zoom));
        opt(
            "exposure",
            (self.exposure != 0.0).then(|| self.exposure.to_string()),
        );
        opt("output", path(&self.output));
        out
    }

    /// The options `pairs` give (as [`RenderArgs::to_pairs`] writes them), parsed and checked
    /// as `specmap render` parses its command line.
    pub(crate) fn parse_pairs<'a>(
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> anyhow::Result<RenderArgs> {
        let mut argv = vec!["specmap render".to_string()];
        for (k, v) in pairs {
            argv.push(match FLAGS.contains(&k) {
                true => format!("--{k}"),
                false => format!("--{k}={v}"),
            });
        }
        let r = <RenderOnly as clap::Parser>::try_parse_from(&argv).map_err(|e| {
            let text = e.to_string();
            anyhow::anyhow!(
                "{}",
                text.lines()
                    .next()
                    .unwrap_or("invalid option")
                    .trim_start_matches("error: ")
            )
        })?;
        Ok(r.args)
    }

    pub(crate) fn preset(&self) -> Preset {
        Preset::from(self.scene)
    }

    /// The image size: `--size` or the preset's.
    pub(crate) fn image_size(&self) -> anyhow::Result<(usize, usize)> {
        match &self.size {
            Some(s) => size(s),
            None => Ok(self.preset().default_size()),
        }
    }
}

/// `--fit-range F` (1 ± F) or `S0:S1`: the thickness scales a view's fit covers.
pub(crate) fn fit_range(spec: &str) -> anyhow::Result<(f64, f64)> {
    let bad = || {
        anyhow::anyhow!(
            "--fit-range '{spec}' must be a spread F between 0 and 1 (0.15: 15% either way) or \
             scales S0:S1 with 0 <= S0 <= S1"
        )
    };
    let (s0, s1) = match spec.split_once(':') {
        Some((a, b)) => (
            a.trim().parse::<f64>().map_err(|_| bad())?,
            b.trim().parse::<f64>().map_err(|_| bad())?,
        ),
        None => {
            let f: f64 = spec.trim().parse().map_err(|_| bad())?;
            if !(0.0..1.0).contains(&f) {
                return Err(bad());
            }
            (1.0 - f, 1.0 + f)
        }
    };
    if !(s0.is_finite() && s1.is_finite() && 0.0 <= s0 && s0 <= s1) {
        return Err(bad());
    }
    Ok((s0, s1))
}

/// `--orbit YAW,PITCH`.
pub(crate) fn orbit(spec: &str) -> anyhow::Result<specmap::render::Orbit> {
    let bad = || anyhow::anyhow!("--orbit '{spec}' must be YAW,PITCH in degrees, e.g. 30,-10");
    let (y, p) = spec.split_once(',').ok_or_else(bad)?;
    let yaw: f64 = y.trim().parse().map_err(|_| bad())?;
    let pitch: f64 = p.trim().parse().map_err(|_| bad())?;
    if !(yaw.is_finite() && pitch.is_finite() && pitch.abs() <= 90.0) {
        anyhow::bail!("--orbit '{spec}': the pitch must be between -90 and 90 degrees");
    }
    Ok(specmap::render::Orbit {
        yaw_deg: yaw,
        pitch_deg: pitch,
    })
}
