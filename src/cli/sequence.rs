//! `render --turntable N` and `render --film N:A..B --frames N`: a sequence of frames drawn on
//! one quadrature, chosen once for every frame (the turntable's every orientation, the sweep's
//! every thickness), and written as numbered images (`out.png` -> `out-000.png`, ...).

use super::outln;
use super::render_args::RenderArgs;
use specmap::colorimetry::RgbSpace;
use specmap::quadrature::choose::Selection;
use specmap::quadrature::Quadrature;
use specmap::render::gpu::{AdapterReport, Gpu};
use specmap::render::plan::Plan;
use specmap::render::prepare::Prepared;
use specmap::render::{cpu, Backend, Orbit, Scene};
use specmap::thinfilm::Layer;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What changes from frame to frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sequence {
    /// The camera orbits once around the scene, from `start`'s yaw, at its pitch.
    Turntable { frames: usize, start: Orbit },
    /// Every main film's thickness scales from 1 to `ratio` (its layers' ranges).
    Thickness { frames: usize, ratio: f64 },
}

/// One frame drawn.
#[derive(Debug, Clone, serde::Serialize)]
pub(crate) struct Frame {
    pub(crate) file: String,
    /// The orbit's yaw, or the thickness scale.
    pub(crate) at: f64,
    pub(crate) prepare_s: f64,
    pub(crate) render_s: f64,
}

impl Sequence {
    /// The sequence `--turntable` or `--frames` asks for, with the film's range; None for a
    /// still.
    pub(crate) fn of(a: &RenderArgs, ratio: Option<f64>) -> anyhow::Result<Option<Sequence>> {
        let orbit = a
            .orbit
            .as_deref()
            .map(super::render_args::orbit)
            .transpose()?;
        Ok(match (a.turntable, a.frames, ratio) {
            (Some(0), ..) | (_, Some(0), _) => {
                anyhow::bail!("a sequence needs at least one frame")
            }
            (Some(_), _, Some(_)) => anyhow::bail!(
                "--turntable turns the camera; a thickness range sweeps the film over --frames N \
                 (one at a time)"
            ),
            (Some(frames), None, None) => Some(Sequence::Turntable {
                frames,
                start: orbit.unwrap_or_default(),
            }),
            (None, Some(frames), Some(ratio)) => Some(Sequence::Thickness { frames, ratio }),
            (None, Some(_), None) => anyhow::bail!(
                "--frames sweeps a film's thickness: give each layer a range, e.g. --film \
                 2.7:100..400"
            ),
            (None, None, Some(_)) => anyhow::bail!(
                "a thickness range (--film N:A..B) is swept over --frames N, e.g. --frames 30"
            ),
            (Some(_), Some(_), None) => unreachable!("clap keeps --turntable and --frames apart"),
            (None, None, None) => None,
        })
    }

    pub(crate) fn frames(&self) -> usize {
        match *self {
            Sequence::Turntable { frames, .. } | Sequence::Thickness { frames, .. } => frames,
        }
    }

    /// The scene every frame's quadrature must hold for: `base` seen from every orientation,
    /// or with its films over the whole range.
    pub(crate) fn fit_scene(&self, base: &Scene) -> Scene {
        let mut s = base.clone();
        match *self {
            Sequence::Turntable { .. } => s.any_orientation = true,
            Sequence::Thickness { ratio, .. } => s.for_thicknesses((1.0, ratio)),
        }
        s
    }

    /// Where frame `k` is: the yaw (degrees) or the thickness scale.
    fn at(&self, k: usize) -> f64 {
        match *self {
            Sequence::Turntable { frames, start } => {
                start.yaw_deg + 360.0 * k as f64 / frames as f64
            }
            Sequence::Thickness { frames: 1, .. } => 1.0,
            Sequence::Thickness { frames, ratio } => {
                1.0 + (ratio - 1.0) * k as f64 / (frames - 1) as f64
            }
        }
    }

    /// Frame `k`'s scene, from `base` (as built: not orbited, films at their ranges' starts).
    pub(crate) fn frame(&self, base: &Scene, k: usize) -> anyhow::Result<Scene> {
        let mut s = base.clone();
        match *self {
            Sequence::Turntable { start, .. } => s.orbit(Orbit {
                yaw_deg: self.at(k),
                pitch_deg: start.pitch_deg,
            }),
            Sequence::Thickness { .. } => {
                let scale = self.at(k);
                for o in s.objects.iter_mut().filter(|o| o.main) {
                    if let Some(f) = &mut o.surface.film {
                        f.layers = f
                            .layers
                            .iter()
                            .map(|l| Layer::new(l.material().clone(), l.thickness_nm() * scale))
                            .collect::<Result<_, _>>()?;
                    }
                }
            }
        }
        Ok(s)
    }

    /// Frame `k`'s file: `out.png` -> `out-007.png` (digits for the last frame, at least 3).
    pub(crate) fn file(&self, output: &Path, k: usize) -> PathBuf {
        let digits = (self.frames() - 1).to_string().len().max(3);
        let stem = output
            .file_stem()
            .map_or("frame".into(), |s| s.to_string_lossy().into_owned());
        let ext = output
            .extension()
            .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
        output.with_file_name(format!("{stem}-{k:0digits$}{ext}"))
    }

    /// Draws every frame of `base` on `q` (on `gpu`, else the CPU) and writes it next to
    /// `output`, with a progress bar on a terminal; `first` is frame 0 prepared already, if it
    /// was.
    pub(crate) fn render(
        &self,
        (base, mut first): (&Scene, Option<Prepared>),
        q: &Quadrature,
        space: RgbSpace,
        gpu: Option<&Gpu>,
        (output, exposure): (&Path, f64),
    ) -> anyhow::Result<Vec<Frame>> {
        let n = self.frames();
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = indicatif::ProgressBar::new(n as u64);
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "frames {bar:30} {pos}/{len} [{elapsed} < {eta}]",
            ) {
                b.set_style(style);
            }
            b
        });
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let scene = self.frame(base, k)?;
            let t0 = Instant::now();
            let p = match first.take() {
                Some(p) => p,
                None => Prepared::with_quadrature(&scene, q, space)?,
            };
            let prepare_s = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            let image = match gpu {
                Some(g) => g.render(&p)?.0,
                None => cpu::render(&p),
            };
            let render_s = t1.elapsed().as_secs_f64();
            let file = self.file(output, k);
            image
                .write(&file, exposure)
                .map_err(|e| anyhow::anyhow!("writing frame {k} to {}: {e}", file.display()))?;
            out.push(Frame {
                file: file.display().to_string(),
                at: self.at(k),
                prepare_s,
                render_s,
            });
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        Ok(out)
    }
}

/// What a sequence drew, and on what.
pub(crate) struct SequenceReport<'a> {
    pub(crate) frames: Vec<Frame>,
    pub(crate) seconds: f64,
    pub(crate) quadrature: &'a Quadrature,
    pub(crate) selection: Option<&'a Selection>,
    pub(crate) plan: Option<&'a Plan>,
}

impl SequenceReport<'_> {
    /// Prints the report (`--json`: as JSON) of `scene`'s frames drawn on `backend`.
    pub(crate) fn emit(
        &self,
        scene: &Scene,
        json: bool,
        backend: Backend,
        adapter: Option<AdapterReport>,
    ) -> anyhow::Result<()> {
        let q = self.quadrature;
        let (prepare, render) = self
            .frames
            .iter()
            .fold((0.0, 0.0), |(p, r), f| (p + f.prepare_s, r + f.render_s));
        if json {
            let doc = serde_json::json!({
                "scene": scene.name,
                "size": [scene.width, scene.height],
                "backend": backend,
                "adapter": adapter,
                "wavelengths": q.len(),
                "quadrature": q.summary(self.selection.map(|s| s.estimate_de2000)),
                "quadrature_choice": self.selection,
                "quadrature_plan": self.plan,
                "frames": self.frames,
                "prepare_s": prepare,
                "render_s": render,
                "seconds": self.seconds,
            });
            super::emit(&(serde_json::to_string_pretty(&doc)? + "\n"));
            return Ok(());
        }
        let mut out = String::new();
        outln!(
            out,
            "rendered {} {}x{}, {} frames on {} wavelengths ({}) on the {backend}{}",
            scene.name,
            scene.width,
            scene.height,
            self.frames.len(),
            q.len(),
            q,
            adapter
                .as_ref()
                .map(|a| format!(" ({}, {})", a.name, a.backend))
                .unwrap_or_default()
        );
        if let Some(p) = self.plan {
            super::tolerance::write_plan(&mut out, p);
        }
        if let Some(s) = self.selection {
            super::tolerance::write_selection(&mut out, s);
        }
        let n = self.frames.len().max(1) as f64;
        outln!(
            out,
            "  frames {:.1} s: prepare {:.1} s, render {:.1} s ({:.2} s a frame)",
            self.seconds,
            prepare,
            render,
            (prepare + render) / n
        );
        if let (Some(first), Some(last)) = (self.frames.first(), self.frames.last()) {
            outln!(out, "wrote {} .. {}", first.file, last.file);
        }
        super::emit(&out);
        Ok(())
    }
}

/// `--film` with thickness ranges (`2.7:100..400`): the film at the ranges' starts, and the
/// ratio end/start every range shares (None where no layer has a range).
pub(crate) fn film_range(spec: &str) -> anyhow::Result<(String, Option<f64>)> {
    let mut start = Vec::new();
    let mut ranges = Vec::new();
    for (i, part) in spec.split(',').enumerate() {
        let Some((m, d)) = part.rsplit_once(':') else {
            start.push(part.to_string());
            continue;
        };
        match d.split_once("..") {
            None => start.push(part.to_string()),
            Some((a, b)) => {
                let bad = || {
                    anyhow::anyhow!(
                        "film layer {}: '{d}' must be a range A..B of thicknesses in nm with \
                         0 < A, e.g. 100..400",
                        i + 1
                    )
                };
                let a: f64 = a.trim().parse().map_err(|_| bad())?;
                let b: f64 = b.trim().parse().map_err(|_| bad())?;
                if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= 0.0) {
                    return Err(bad());
                }
                start.push(format!("{m}:{a}"));
                ranges.push((i + 1, b / a));
            }
        }
    }
    let Some(&(_, ratio)) = ranges.first() else {
        return Ok((spec.to_string(), None));
    };
    let layers = start.len();
    if ranges.len() != layers || ranges.iter().any(|r| (r.1 / ratio - 1.0).abs() > 1e-9) {
        anyhow::bail!(
            "--film '{spec}': a sweep scales every layer together, so every layer needs a range \
             of the same ratio (e.g. 1.38:100..200,2.1:130..260)"
        );
    }
    Ok((start.join(","), Some(ratio)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_film_range_is_its_start_and_one_ratio() {
        assert_eq!(
            film_range("2.7:100..400").unwrap(),
            ("2.7:100".to_string(), Some(4.0))
        );
        assert_eq!(
            film_range("1.38:100..200,2.1:130..260").unwrap(),
            ("1.38:100,2.1:130".to_string(), Some(2.0))
        );
        assert_eq!(film_range("2.7:270").unwrap(), ("2.7:270".into(), None));
        for bad in [
            "1.38:100..200,2.1:130",
            "1.38:100..200,2.1:130..300",
            "2.7:0..400",
        ] {
            assert!(film_range(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn frames_are_numbered_and_spread_over_the_sequence() {
        let t = Sequence::Turntable {
            frames: 36,
            start: Orbit {
                yaw_deg: 10.0,
                pitch_deg: 15.0,
            },
        };
        assert_eq!(t.at(0), 10.0);
        assert_eq!(t.at(9), 100.0);
        let f = t.file(Path::new("out/turn.png"), 7);
        assert_eq!(f, Path::new("out/turn-007.png"));
        let s = Sequence::Thickness {
            frames: 4,
            ratio: 4.0,
        };
        assert_eq!(
            (0..4).map(|k| s.at(k)).collect::<Vec<_>>(),
            [1.0, 2.0, 3.0, 4.0]
        );
        let many = Sequence::Thickness {
            frames: 1500,
            ratio: 2.0,
        };
        assert_eq!(many.file(Path::new("a.exr"), 3), Path::new("a-0003.exr"));
    }
}
