//! Where a scene fit is: the stages of [`super::fit`] as values a caller can show while it
//! waits (a fit over a thickness ramp under a photograph takes minutes), and what each stage
//! cost ([`Timings`]).

use std::cell::RefCell;
use std::fmt;
use std::time::Instant;

/// A stage of the fit as it starts.
#[derive(Debug, Clone, PartialEq)]
pub enum Stage {
    /// The scene's spectra (its stimuli) are being gathered, for round `round`.
    Stimuli {
        /// The round, counting the first as 0.
        round: usize,
    },
    /// The uniform grids are being judged on `stimuli` stimuli.
    UniformGrids {
        /// Number of stimuli.
        stimuli: usize,
    },
    /// The greedy stage has `nodes` nodes, whose largest error is `max`.
    Greedy {
        /// Number of nodes so far.
        nodes: usize,
        /// Their largest CIEDE2000 over the stimuli.
        max: f64,
    },
    /// Pruning, at `nodes` nodes whose largest error is `max`.
    Pruning {
        /// Number of nodes left.
        nodes: usize,
        /// Their largest CIEDE2000 over the stimuli.
        max: f64,
    },
    /// Reseeding with `nodes` nodes (one fewer than the fit kept, or a budget's count): seed
    /// `seed` of `of` is being searched by `search` ("exchange" or "descent"); `kept` is the
    /// node count and largest error of the best set kept so far, if any.
    Reseeding {
        /// Number of nodes searched for.
        nodes: usize,
        /// The seed being searched, from 1.
        seed: usize,
        /// Number of seeds in all.
        of: usize,
        /// The search: "exchange" or "descent".
        search: &'static str,
        /// Node count and largest CIEDE2000 of the best set kept so far; None: none yet.
        kept: Option<(usize, f64)>,
    },
    /// The kept nodes' weights are solved once more.
    Reweighing {
        /// Number of nodes kept.
        nodes: usize,
    },
    /// Every texel of a spectral map checked: `nodes` nodes err `every` on them against
    /// `fitted` on the fit's own stimuli, so the worst join the fit for round `round`.
    Texels {
        /// The round, counting the first as 0.
        round: usize,
        /// Number of nodes.
        nodes: usize,
        /// Largest CIEDE2000 over the fit's own stimuli.
        fitted: f64,
        /// Largest CIEDE2000 over every texel.
        every: f64,
    },
    /// The image's `pixels` pixels are being rendered at 1 nm, to check the quadrature on.
    Image {
        /// Number of pixels rendered.
        pixels: usize,
    },
    /// `nodes` nodes err `image` on the image, beyond `tolerance`: the fit's margin narrows
    /// for round `round`.
    ImageMiss {
        /// The round, counting the first as 0.
        round: usize,
        /// Number of nodes.
        nodes: usize,
        /// Largest CIEDE2000 on the image.
        image: f64,
        /// The CIEDE2000 the image had to stay within.
        tolerance: f64,
    },
}

impl Stage {
    /// The stage's kind, as [`Timings`] adds it up: "stimuli", "uniform grids", "greedy",
    /// "pruning", "exchange", "descent", "reweighing", "texels", "image".
    pub fn kind(&self) -> &'static str {
        match self {
            Stage::Stimuli { .. } => "stimuli",
            Stage::UniformGrids { .. } => "uniform grids",
            Stage::Greedy { .. } => "greedy",
            Stage::Pruning { .. } => "pruning",
            Stage::Reseeding { search, .. } => search,
            Stage::Reweighing { .. } => "reweighing",
            Stage::Texels { .. } => "texels",
            Stage::Image { .. } | Stage::ImageMiss { .. } => "image",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stage::Stimuli { round: 0 } => write!(f, "gathering the scene's spectra"),
            Stage::Stimuli { round } => {
                write!(f, "gathering the scene's spectra, round {round}")
            }
            Stage::UniformGrids { stimuli } => {
                write!(f, "judging the uniform grids on {stimuli} spectra")
            }
            Stage::Greedy { nodes, max } => {
                write!(f, "adding nodes: {nodes} (largest error {max:.3})")
            }
            Stage::Pruning { nodes, max } => {
                write!(f, "pruning: {nodes} nodes ({max:.3})")
            }
            Stage::Reseeding {
                nodes,
                seed,
                of,
                search,
                kept,
            } => {
                write!(f, "{nodes} nodes: seed {seed}/{of}, {search}")?;
                match kept {
                    Some((n, e)) => write!(f, " (kept {n} nodes, {e:.3})"),
                    None => Ok(()),
                }
            }
            Stage::Reweighing { nodes } => write!(f, "final weights, {nodes} nodes"),
            Stage::Texels {
                round,
                nodes,
                fitted,
                every,
            } => write!(
                f,
                "every texel: {nodes} nodes err {every:.3} (the fit's stimuli {fitted:.3}); \
                 refitting, round {round}"
            ),
            Stage::Image { pixels } => {
                write!(f, "checking the image: {pixels} pixels at 1 nm")
            }
            Stage::ImageMiss {
                round,
                nodes,
                image,
                tolerance,
            } => write!(
                f,
                "the image: {nodes} nodes err {image:.3}, beyond {tolerance}; refitting, \
                 round {round}"
            ),
        }
    }
}

/// A caller's sink for stages; [`quiet`] ignores them.
pub type Report<'a> = &'a dyn Fn(&Stage);

/// A sink that ignores every stage.
pub fn quiet(_: &Stage) {}

/// Seconds spent in one kind of stage ([`Stage::kind`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageTime {
    /// The kind of stage ([`Stage::kind`]).
    pub stage: String,
    /// Seconds spent in it, added up.
    pub seconds: f64,
}

/// Where a fit's time went: each stage runs from its report to the next one's, and the time of
/// each kind of stage is added up, in the order the kinds first ran.
pub struct Timings {
    open: RefCell<Option<(&'static str, Instant)>>,
    spent: RefCell<Vec<StageTime>>,
}

impl Default for Timings {
    fn default() -> Self {
        Timings::new()
    }
}

impl Timings {
    /// No stage open, no time spent.
    pub fn new() -> Timings {
        Timings {
            open: RefCell::new(None),
            spent: RefCell::new(Vec::new()),
        }
    }

    /// `stage` starts now: the stage before it ends.
    pub fn mark(&self, stage: &Stage) {
        self.close();
        *self.open.borrow_mut() = Some((stage.kind(), Instant::now()));
    }

    fn close(&self) {
        if let Some((kind, t)) = self.open.borrow_mut().take() {
            let seconds = t.elapsed().as_secs_f64();
            let mut spent = self.spent.borrow_mut();
            match spent.iter_mut().find(|s| s.stage == kind) {
                Some(s) => s.seconds += seconds,
                None => spent.push(StageTime {
                    stage: kind.to_string(),
                    seconds,
                }),
            }
        }
    }

    /// The open stage ends now; the seconds of each kind.
    pub fn finish(&self) -> Vec<StageTime> {
        self.close();
        self.spent.borrow().clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timings_add_up_each_kind_of_stage() {
        let t = Timings::new();
        let greedy = Stage::Greedy { nodes: 4, max: 1.0 };
        t.mark(&Stage::Stimuli { round: 0 });
        std::thread::sleep(std::time::Duration::from_millis(20));
        t.mark(&greedy);
        std::thread::sleep(std::time::Duration::from_millis(10));
        t.mark(&Stage::Stimuli { round: 1 });
        t.mark(&greedy);
        let spent = t.finish();
        let kinds: Vec<&str> = spent.iter().map(|s| s.stage.as_str()).collect();
        assert_eq!(kinds, ["stimuli", "greedy"]);
        assert!(
            spent[0].seconds >= 0.02 && spent[1].seconds >= 0.01,
            "{spent:?}"
        );
        // Finished: nothing is open, and a second finish adds nothing.
        assert_eq!(t.finish(), spent);
    }

    #[test]
    fn a_stage_reads_as_what_the_fit_is_doing() {
        let s = Stage::Reseeding {
            nodes: 15,
            seed: 2,
            of: 3,
            search: "descent",
            kept: Some((16, 0.3314)),
        };
        assert_eq!(
            s.to_string(),
            "15 nodes: seed 2/3, descent (kept 16 nodes, 0.331)"
        );
        assert_eq!(
            Stage::Greedy { nodes: 4, max: 1.5 }.to_string(),
            "adding nodes: 4 (largest error 1.500)"
        );
        let t = Stage::Texels {
            round: 1,
            nodes: 12,
            fitted: 0.256,
            every: 0.567,
        };
        assert_eq!(
            t.to_string(),
            "every texel: 12 nodes err 0.567 (the fit's stimuli 0.256); refitting, round 1"
        );
    }
}
