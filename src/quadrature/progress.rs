//! Where a scene fit is: the stages of [`super::fit`] as values a caller can show while it
//! waits (a fit over a thickness ramp under a photograph takes minutes).

use std::fmt;

/// A stage of the fit as it starts.
#[derive(Debug, Clone, PartialEq)]
pub enum Stage {
    /// The greedy stage has `nodes` nodes, whose largest error is `max`.
    Greedy { nodes: usize, max: f64 },
    /// Pruning, at `nodes` nodes whose largest error is `max`.
    Pruning { nodes: usize, max: f64 },
    /// Reseeding with `nodes` nodes (one fewer than the fit kept, or a budget's count): seed
    /// `seed` of `of` is being searched by `search` ("exchange" or "descent"); `kept` is the
    /// node count and largest error of the best set kept so far, if any.
    Reseeding {
        nodes: usize,
        seed: usize,
        of: usize,
        search: &'static str,
        kept: Option<(usize, f64)>,
    },
    /// The kept nodes' weights are solved once more.
    Reweighing { nodes: usize },
    /// Every texel of a spectral map checked: `nodes` nodes err `every` on them against
    /// `fitted` on the fit's own stimuli, so the worst join the fit for round `round`.
    Texels {
        round: usize,
        nodes: usize,
        fitted: f64,
        every: f64,
    },
    /// The image's `pixels` pixels are being rendered at 1 nm, to check the quadrature on.
    Image { pixels: usize },
    /// `nodes` nodes err `image` on the image, beyond `tolerance`: the fit's margin narrows
    /// for round `round`.
    ImageMiss {
        round: usize,
        nodes: usize,
        image: f64,
        tolerance: f64,
    },
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
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

#[cfg(test)]
mod tests {
    use super::*;

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
