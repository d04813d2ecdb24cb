//! Scene presets that reproduce the paper's figures 6-9.

use super::{Environment, Film, Lighting, Object, Ramp, Scene, Shape, Sun, Surface, View};
use crate::colorimetry::{Cmfs, Observer};
use crate::error::{Error, Result};
use crate::spectrum::{Interpolation, Tabulated, WavelengthGrid};
use crate::thinfilm::{Index, Layer, Material as Optical};

/// The paper's figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// Fig. 6: chrome-oxide film (n = 2.7, 270 nm) on black plastic (n = 1.45).
    Ball,
    /// Fig. 7: transparent plastic (1.45) with a TiO2 film (2.3), 150 nm (left) and 350 nm.
    TransparentBall,
    /// Fig. 8: chrome oxide on plastic, thickness rising from 100 nm (left) to 400 nm (right).
    Cylinders,
    /// Fig. 9: ColorChecker patches and plastic spheres under D65, A and low-pressure sodium
    /// (one row under the map with an environment).
    Chart,
    /// The 24 ColorChecker reflectances as Lambertian spheres, 6 x 4 (the Mitsuba 3 check).
    CheckerSpheres,
}

impl Preset {
    /// Every preset: the figures in order, then [`Preset::CheckerSpheres`].
    pub const ALL: [Preset; 5] = [
        Preset::Ball,
        Preset::TransparentBall,
        Preset::Cylinders,
        Preset::Chart,
        Preset::CheckerSpheres,
    ];

    /// Its name as `--scene` and file names spell it (`transparent-ball`).
    pub fn name(self) -> &'static str {
        match self {
            Preset::Ball => "ball",
            Preset::TransparentBall => "transparent-ball",
            Preset::Cylinders => "cylinders",
            Preset::Chart => "chart",
            Preset::CheckerSpheres => "checker-spheres",
        }
    }

    /// The image size the figure is framed for (width, height).
    pub fn default_size(self) -> (usize, usize) {
        match self {
            Preset::Ball | Preset::Cylinders => (512, 512),
            Preset::TransparentBall => (768, 384),
            Preset::Chart => (768, 512),
            Preset::CheckerSpheres => (384, 256),
        }
    }

    /// The lights of the chart's rows, top to bottom.
    pub const CHART_LIGHTS: [&'static str; 3] = ["D65", "A", "lps"];

    /// Builds the scene. `lighting` replaces the preset's light (`chart`: its three rows become
    /// one row under it); None: the uniform light `light` (D65 by default) with a key light of
    /// the same SPD (`chart` compares its three lights).
    ///
    /// ```
    /// use specmap::render::{cpu, prepare::Prepared, Preset, Spectral};
    ///
    /// // The paper's Fig. 6 (a chrome-oxide film on black plastic) under D65, 32 x 32 pixels.
    /// let scene = Preset::Ball.scene(32, 32, "D65", None)?;
    /// let image = cpu::render(&Prepared::new(&scene, &Spectral::default())?);
    /// assert_eq!((image.width, image.height), (32, 32));
    /// # Ok::<(), specmap::error::Error>(())
    /// ```
    pub fn scene(
        self,
        width: usize,
        height: usize,
        light: &str,
        lighting: Option<Lighting>,
    ) -> Result<Scene> {
        let main = MainLight {
            light,
            lighting: lighting.as_ref(),
        };
        let (objects, lightings, view) = match self {
            Preset::Ball => ball(&main)?,
            Preset::TransparentBall => transparent_ball(&main)?,
            Preset::Cylinders => cylinders(&main)?,
            Preset::Chart => match &lighting {
                None => chart()?,
                Some(l) => chart_under(l.clone(), width, height)?,
            },
            Preset::CheckerSpheres => checker_spheres(main.lighting(1.0)?)?,
        };
        Ok(Scene {
            name: self.name().into(),
            width,
            height,
            view,
            lightings,
            objects,
            background: 0,
            backdrop: super::Backdrop::DEFAULT,
            orientation: super::IDENTITY,
            any_orientation: false,
        })
    }
}

/// A preset's objects, lightings and view.
type Framed = (Vec<Object>, Vec<Lighting>, View);

/// The light a preset's main lighting is: the caller's lighting, else a uniform `light` with
/// the key light.
struct MainLight<'a> {
    light: &'a str,
    lighting: Option<&'a Lighting>,
}

impl MainLight<'_> {
    /// The caller's lighting, else the uniform light of `radiance` with the key light.
    fn lighting(&self, radiance: f64) -> Result<Lighting> {
        match self.lighting {
            Some(l) => Ok(l.clone()),
            None => Lighting::uniform(self.light, radiance, Some(key_light())),
        }
    }
}

/// A film of constant real indices: `layers` as (n, thickness nm) from air, on `substrate`.
fn film(layers: &[(f64, f64)], substrate: f64) -> Result<Film> {
    Ok(Film {
        ambient: Optical::constant(Index::real(1.0)?),
        layers: layers
            .iter()
            .map(|&(n, d)| Layer::new(Optical::constant(Index::real(n)?), d))
            .collect::<Result<_>>()?,
        substrate: Optical::constant(Index::real(substrate)?),
    })
}

/// A filmed surface of shininess 200: on black plastic (k_d = 1), or transparent.
fn filmed(label: &str, f: Film, transparent: bool) -> Result<Surface> {
    let black_plastic = Tabulated::new(vec![380.0, 780.0], vec![0.02, 0.02])?;
    Ok(Surface {
        label: label.into(),
        diffuse: (!transparent).then_some(black_plastic),
        kd: if transparent { 0.0 } else { 1.0 },
        ks: 0.0,
        shininess: 200.0,
        film: Some(f),
        transparent,
    })
}

/// A main object (one the tolerance fit looks at) of no ramp.
fn object(shape: Shape, surface: Surface, lighting: usize) -> Object {
    Object {
        shape,
        surface,
        lighting,
        ramp: None,
        main: true,
    }
}

/// A sphere at (x, y, 0).
fn sphere(x: f64, y: f64, radius: f64) -> Shape {
    Shape::Sphere {
        center: [x, y, 0.0],
        radius,
    }
}

/// Fig. 6: one filmed sphere.
fn ball(main: &MainLight) -> Result<Framed> {
    let surface = filmed(
        "chrome oxide 270 nm on black plastic",
        film(&[(2.7, 270.0)], 1.45)?,
        false,
    )?;
    Ok((
        vec![object(sphere(0.0, 0.0, 1.0), surface, 0)],
        vec![main.lighting(1.0)?],
        View {
            center: [0.0, 0.0],
            half_height: 1.15,
        },
    ))
}

/// Fig. 7: two transparent filmed spheres (under a sky over a dark floor of their own).
fn transparent_ball(main: &MainLight) -> Result<Framed> {
    let mut l = main.lighting(1.0)?;
    if main.lighting.is_none() {
        // A lossless film in a uniform light is invisible (R + T = 1): a bright sky over a
        // dark floor shows the film in reflection and in transmission.
        l.environment = Environment::SkyGround {
            sky: 1.0,
            ground: 0.05,
            blend_deg: 10.0,
        };
    }
    let clear = |x: f64, label: &str, nm: f64| -> Result<Object> {
        let surface = filmed(label, film(&[(2.3, nm)], 1.45)?, true)?;
        Ok(object(sphere(x, 0.0, 0.9), surface, 0))
    };
    Ok((
        vec![
            clear(-1.0, "TiO2 150 nm on clear plastic", 150.0)?,
            clear(1.0, "TiO2 350 nm on clear plastic", 350.0)?,
        ],
        vec![l],
        View {
            center: [0.0, 0.0],
            half_height: 1.0,
        },
    ))
}

/// Fig. 8: three filmed cylinders whose film thickens fourfold from left to right.
fn cylinders(main: &MainLight) -> Result<Framed> {
    let objects = [0.62, 0.0, -0.62]
        .iter()
        .map(|&y| -> Result<Object> {
            let mut o = object(
                Shape::CylinderX {
                    center: [0.0, y, 0.0],
                    radius: 0.28,
                    half_length: 0.95,
                },
                filmed(
                    "chrome oxide 100-400 nm on black plastic",
                    film(&[(2.7, 100.0)], 1.45)?,
                    false,
                )?,
                0,
            );
            o.ramp = Some(Ramp {
                x0: -0.95,
                x1: 0.95,
                s0: 1.0,
                s1: 4.0,
            });
            Ok(o)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((
        objects,
        vec![main.lighting(1.0)?],
        View {
            center: [0.0, 0.0],
            half_height: 1.0,
        },
    ))
}

/// The key light of the presets: from the upper left, in front.
pub fn key_light_direction() -> [f64; 3] {
    let d: [f64; 3] = [-0.5, 0.6, 0.62];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    d.map(|c| c / n)
}

fn key_light() -> Sun {
    Sun {
        direction: key_light_direction(),
        irradiance: 1.5,
    }
}

/// The centre of ColorChecker sphere `k` (0..24, the table's column order) of the
/// `checker-spheres` preset: 6 columns, 4 rows, one world unit apart, from the top left.
pub fn checker_sphere_center(k: usize) -> [f64; 3] {
    let (col, row) = ((k % 6) as f64, (k / 6) as f64);
    [col - 2.5, 1.5 - row, 0.0]
}

/// The radius of the `checker-spheres` preset's spheres.
pub const CHECKER_SPHERE_RADIUS: f64 = 0.4;

/// The 24 ColorChecker reflectances as Lambertian spheres (k_d = 1, no specular) under one
/// lighting, framed 4 world units high: what the Mitsuba 3 interop test renders sphere by
/// sphere.
fn checker_spheres(lighting: Lighting) -> Result<Framed> {
    let cc = crate::data::Table::builtin("colorchecker")?;
    let objects = cc
        .columns()
        .iter()
        .enumerate()
        .map(|(k, name)| -> Result<Object> {
            Ok(Object {
                shape: Shape::Sphere {
                    center: checker_sphere_center(k),
                    radius: CHECKER_SPHERE_RADIUS,
                },
                surface: Surface {
                    label: format!("colorchecker:{name}"),
                    diffuse: Some(cc.column(name)?),
                    kd: 1.0,
                    ks: 0.0,
                    shininess: 1.0,
                    film: None,
                    transparent: false,
                },
                lighting: 0,
                ramp: None,
                main: true,
            })
        })
        .collect::<Result<_>>()?;
    Ok((
        objects,
        vec![lighting],
        View {
            center: [0.0, 0.0],
            half_height: 2.0,
        },
    ))
}

/// One row of Fig. 9 (the patches, the plastic spheres) under `lighting`, framed to the width.
fn chart_under(lighting: Lighting, width: usize, height: usize) -> Result<Framed> {
    let (all, _, _) = chart()?;
    let objects = all
        .into_iter()
        .filter(|o| o.lighting == 0)
        .map(|mut o| {
            if let Shape::Quad { center, .. } | Shape::Sphere { center, .. } = &mut o.shape {
                center[1] -= 1.0;
            }
            o
        })
        .collect();
    // The row spans x from -1.9 to 1.9.
    let half_height = (2.0 * height as f64 / width.max(1) as f64).max(0.55);
    Ok((
        objects,
        vec![lighting],
        View {
            center: [0.0, 0.0],
            half_height,
        },
    ))
}

/// Fig. 9: per row (D65, A, LPS), the 24 ColorChecker patches and three plastic spheres: red,
/// neutral 5, and a metamer of neutral 5 under D65 (same colour under D65, not under the
/// others). A patch facing the camera gets exactly the light's radiance (uniform 0.5 plus a key
/// light adding 0.5 at the patches' normal), so its colour is `specmap color colorchecker:<patch>
/// --under <light>`.
fn chart() -> Result<Framed> {
    let cc = crate::data::Table::builtin("colorchecker")?;
    let grey = cc.column("neutral-5")?;
    let metamer = d65_metamer(&grey)?;
    let reflectances = ChartReflectances { cc, grey, metamer };
    let l = key_light_direction();
    let mut objects = Vec::new();
    let mut lightings = Vec::new();
    for (r, light) in Preset::CHART_LIGHTS.iter().enumerate() {
        let sun = Sun {
            direction: l,
            irradiance: 0.5 * std::f64::consts::PI / l[2],
        };
        lightings.push(Lighting::uniform(light, 0.5, Some(sun))?);
        objects.extend(reflectances.row(r)?);
    }
    Ok((
        objects,
        lightings,
        View {
            center: [0.0, 0.0],
            half_height: 1.5,
        },
    ))
}

/// The reflectances of the chart's rows: the ColorChecker's, its neutral 5 and a D65 metamer
/// of it.
struct ChartReflectances {
    cc: crate::data::Table,
    grey: Tabulated,
    metamer: Tabulated,
}

impl ChartReflectances {
    /// Row `r` (lit by lighting `r`, centred at y = 1 - r): its backdrop, the 24 patches and
    /// the three plastic spheres.
    fn row(&self, r: usize) -> Result<Vec<Object>> {
        let y = 1.0 - r as f64;
        let mut objects = vec![chart_object(
            Shape::Quad {
                center: [0.0, y, -1.0],
                half_size: [2.6, 0.5],
            },
            plain(
                "backdrop".into(),
                Tabulated::new(vec![380.0, 780.0], vec![0.08, 0.08])?,
                0.0,
            ),
            r,
            false,
        )];
        for (k, name) in self.cc.columns().iter().enumerate() {
            let (col, row) = (k % 6, k / 6);
            let pitch = 0.23;
            let center = [
                -1.2 + (col as f64 - 2.5) * pitch,
                y + (1.5 - row as f64) * pitch,
                0.0,
            ];
            objects.push(chart_object(
                Shape::Quad {
                    center,
                    half_size: [0.1, 0.1],
                },
                plain(format!("colorchecker:{name}"), self.cc.column(name)?, 0.0),
                r,
                false,
            ));
        }
        for (k, (label, rd)) in [
            ("plastic colorchecker:red", self.cc.column("red")?),
            ("plastic colorchecker:neutral-5", self.grey.clone()),
            ("plastic D65 metamer of neutral-5", self.metamer.clone()),
        ]
        .into_iter()
        .enumerate()
        {
            let shape = sphere(0.2 + 0.7 * k as f64, y, 0.3);
            objects.push(chart_object(shape, plain(label.into(), rd, 0.04), r, true));
        }
        Ok(objects)
    }
}

/// A chart object of no ramp under lighting `lighting`; `main`: one the tolerance fit looks at.
fn chart_object(shape: Shape, surface: Surface, lighting: usize, main: bool) -> Object {
    Object {
        shape,
        surface,
        lighting,
        ramp: None,
        main,
    }
}

/// A Lambertian surface (k_d = 1) of reflectance `rd`, with a specular `ks` of shininess 60.
fn plain(label: String, rd: Tabulated, ks: f64) -> Surface {
    Surface {
        label,
        diffuse: Some(rd),
        kd: 1.0,
        ks,
        shininess: 60.0,
        film: None,
        transparent: false,
    }
}

/// A reflectance with the same CIE 1931 XYZ as `r` under D65 (at 1 nm, Riemann) but a different
/// spectrum: `r` plus a metameric black (a smooth wave with its D65 x, y, z components removed),
/// scaled to stay within [0.01, 0.99].
pub fn d65_metamer(r: &Tabulated) -> Result<Tabulated> {
    let grid = WavelengthGrid::visible_1nm();
    let cmfs = Cmfs::new(Observer::Cie1931, &grid)?;
    let d65 = crate::data::spectrum("D65")?
        .data
        .resample(&grid, Interpolation::LIGHT);
    let base = r.resample(&grid, Interpolation::SMOOTH);
    let a: Vec<Vec<f64>> = [&cmfs.x, &cmfs.y, &cmfs.z]
        .iter()
        .map(|c| {
            c.values()
                .iter()
                .zip(d65.values())
                .map(|(c, s)| c * s)
                .collect()
        })
        .collect();
    let wave: Vec<f64> = grid
        .wavelengths_nm()
        .map(|w| (2.0 * std::f64::consts::PI * (w - 380.0) / 160.0).sin())
        .collect();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let g = nalgebra::Matrix3::from_fn(|i, j| dot(&a[i], &a[j]));
    let rhs = nalgebra::Vector3::from_fn(|i, _| dot(&a[i], &wave));
    let coef = g
        .try_inverse()
        .ok_or_else(|| Error::invalid("the D65 colour-matching vectors are dependent"))?
        * rhs;
    let black: Vec<f64> = (0..grid.len())
        .map(|i| wave[i] - (0..3).map(|c| coef[c] * a[c][i]).sum::<f64>())
        .collect();
    // The largest scale keeping base + s * black within [0.01, 0.99].
    let mut s = f64::INFINITY;
    for (b, k) in base.values().iter().zip(&black) {
        if *k > 0.0 {
            s = s.min((0.99 - b) / k);
        } else if *k < 0.0 {
            s = s.min((b - 0.01) / -k);
        }
    }
    let s = 0.9 * s.max(0.0);
    Tabulated::new(
        grid.wavelengths_nm().collect(),
        base.values()
            .iter()
            .zip(&black)
            .map(|(b, k)| b + s * k)
            .collect(),
    )
}
