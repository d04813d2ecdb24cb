//! Spectral quadrature: the wavelengths (nodes) a renderer samples and a weight triple per node,
//! so that the colour of a spectrum `S` is `XYZ = sum_i w_i S(lambda_i)`.
//!
//! A uniform grid with an integration rule is one quadrature (`w_i = h_i cmf(lambda_i)`, `h_i`
//! the rule's weight); so is Meyer's four-wavelength Gaussian rule ([`meyer`]); and so is the
//! quadrature fitted to a scene ([`fit`]): nodes where its lights have lines and as few as its
//! materials' smoothness allows between them, weights solved by least squares over the spectra
//! the scene can produce, checked on spectra not used to fit ([`estimate`]).
//!
//! The weights are in the colour-matching functions' units times nm: `sum_i w_i S(lambda_i)`
//! stands for `integral S(lambda) cmf(lambda) d lambda`. A colour relative to a light (Eq. 10/11)
//! divides by the light's own `sum_i w_y,i L(lambda_i)`, so a perfect white has Y = 100 on every
//! quadrature.

pub mod cache;
pub mod choose;
pub mod estimate;
pub mod fit;
mod lsq;
pub(crate) mod meyer;
mod pnorm;
pub mod progress;
pub(crate) mod stored;

use crate::colorimetry::{Cmfs, Observer, Xyz};
use crate::error::{Error, Result};
use crate::spectrum::{Rule, WavelengthGrid};
use std::fmt;

/// Where a quadrature came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A uniform grid and an integration rule.
    Uniform,
    /// Meyer's (1988) Gaussian quadrature.
    Meyer,
    /// Fitted to a scene's spectra.
    Scene,
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Kind::Uniform => "uniform",
            Kind::Meyer => "meyer",
            Kind::Scene => "scene",
        })
    }
}

/// Nodes in nm (strictly increasing) and a weight triple per node. Stored (in a cache entry,
/// say) as a [`Record`]; read back, it is checked as [`Quadrature::new`] checks, and a uniform
/// one is made again from its grid and rule.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "Record", into = "Record")]
pub struct Quadrature {
    kind: Kind,
    observer: Observer,
    nodes_nm: Vec<f64>,
    weights: Vec<[f64; 3]>,
    /// The grid and rule of a uniform quadrature.
    uniform: Option<(WavelengthGrid, Rule)>,
}

impl Quadrature {
    /// Nodes and weights as given. Errors: no node, a node that is not a positive finite
    /// wavelength or not above the one before it, a weight that is not finite, or weights under
    /// which the observer sees nothing (`sum w_y <= 0`).
    pub fn new(
        kind: Kind,
        observer: Observer,
        nodes_nm: Vec<f64>,
        weights: Vec<[f64; 3]>,
    ) -> Result<Quadrature> {
        if nodes_nm.is_empty() {
            return Err(Error::invalid("a quadrature needs at least one wavelength"));
        }
        if nodes_nm.len() != weights.len() {
            return Err(Error::invalid(format!(
                "{} wavelengths but {} weight triples",
                nodes_nm.len(),
                weights.len()
            )));
        }
        if let Some(bad) = nodes_nm.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
            return Err(Error::invalid(format!(
                "quadrature node {bad} nm is not a positive wavelength"
            )));
        }
        if let Some(i) = nodes_nm.windows(2).position(|p| p[1] <= p[0]) {
            return Err(Error::invalid(format!(
                "quadrature nodes must increase strictly: {} nm follows {} nm",
                nodes_nm[i + 1],
                nodes_nm[i]
            )));
        }
        if let Some(i) = weights
            .iter()
            .position(|w| !w.iter().all(|v| v.is_finite()))
        {
            return Err(Error::invalid(format!(
                "the weights of the node at {} nm are not finite: {:?}",
                nodes_nm[i], weights[i]
            )));
        }
        let q = Quadrature {
            kind,
            observer,
            nodes_nm,
            weights,
            uniform: None,
        };
        if q.sum()[1].is_nan() || q.sum()[1] <= 0.0 {
            return Err(Error::invalid(
                "the quadrature's Y weights sum to nothing: the observer would see no light",
            ));
        }
        Ok(q)
    }

    /// A uniform grid and an integration rule: `w_i = h_i cmf(lambda_i)`.
    ///
    /// A perfect white under any light has Y = 100; the Y weights sum to the integral of ybar
    /// (about 106.86 nm):
    ///
    /// ```
    /// use specmap::colorimetry::Observer;
    /// use specmap::quadrature::{Kind, Quadrature};
    /// use specmap::spectrum::{Rule, WavelengthGrid};
    ///
    /// let grid = WavelengthGrid::new(380.0, 780.0, 5.0)?;
    /// let q = Quadrature::uniform(grid, Rule::Riemann, Observer::Cie1931)?;
    /// assert_eq!((q.kind(), q.len()), (Kind::Uniform, 81));
    /// assert!((q.sum()[1] - 106.86).abs() < 0.05, "{:?}", q.sum());
    ///
    /// let light = vec![1.0; q.len()]; // equal energy, at the nodes
    /// let white = q.relative_xyz(&light, &light).unwrap();
    /// assert!((white.y() - 100.0).abs() < 1e-12);
    /// # Ok::<(), specmap::Error>(())
    /// ```
    pub fn uniform(grid: WavelengthGrid, rule: Rule, observer: Observer) -> Result<Quadrature> {
        let cmfs = Cmfs::new(observer, &grid)?;
        let h = rule.weights(grid.len(), grid.step_nm());
        let weights = (0..grid.len())
            .map(|i| {
                [
                    h[i] * cmfs.x.values()[i],
                    h[i] * cmfs.y.values()[i],
                    h[i] * cmfs.z.values()[i],
                ]
            })
            .collect();
        let mut q = Quadrature::new(
            Kind::Uniform,
            observer,
            grid.wavelengths_nm().collect(),
            weights,
        )
        .map_err(|e| Error::invalid(format!("the grid {grid}: {e}")))?;
        q.uniform = Some((grid, rule));
        Ok(q)
    }

    /// Meyer's four-wavelength Gaussian quadrature ([`meyer`]).
    pub fn meyer(observer: Observer) -> Result<Quadrature> {
        meyer::meyer(observer)
    }

    /// Where the quadrature came from.
    pub fn kind(&self) -> Kind {
        self.kind
    }
    /// The observer whose colour-matching functions the weights integrate.
    pub fn observer(&self) -> Observer {
        self.observer
    }
    /// The nodes in nm, strictly increasing.
    pub fn nodes_nm(&self) -> &[f64] {
        &self.nodes_nm
    }
    /// Per node: the x, y, z weights (CMF units times nm).
    pub fn weights(&self) -> &[[f64; 3]] {
        &self.weights
    }
    /// The grid and rule of a uniform quadrature.
    pub fn uniform_grid(&self) -> Option<(WavelengthGrid, Rule)> {
        self.uniform
    }
    /// Number of nodes (never zero).
    pub fn len(&self) -> usize {
        self.nodes_nm.len()
    }
    /// Always false: a quadrature has at least one node.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The sums of the weights: the integrals of the colour-matching functions themselves.
    pub fn sum(&self) -> [f64; 3] {
        self.integrate(&vec![1.0; self.len()])
    }

    /// `sum_i w_i v_i` for values at the nodes.
    pub fn integrate(&self, values: &[f64]) -> [f64; 3] {
        let mut s = [0.0; 3];
        for (w, v) in self.weights.iter().zip(values) {
            for c in 0..3 {
                s[c] += w[c] * v;
            }
        }
        s
    }

    /// XYZ of `stimulus` (values at the nodes) relative to `light` (the same): Y = 100 for a
    /// perfect white under the light. None when the light has no luminance on the nodes.
    pub fn relative_xyz(&self, stimulus: &[f64], light: &[f64]) -> Option<Xyz> {
        let y = self.integrate(light)[1];
        if !(y.is_finite() && y > 0.0) {
            return None;
        }
        let [x, yy, z] = self.integrate(stimulus);
        Some(Xyz::new(100.0 * x / y, 100.0 * yy / y, 100.0 * z / y))
    }

    /// A short description: `380:780:5 riemann` for a uniform grid, else the node count and
    /// the wavelengths.
    pub fn describe(&self) -> String {
        match self.uniform {
            Some((grid, rule)) => format!("{grid} {rule}"),
            None => format!(
                "{} {} nodes at {} nm",
                self.kind,
                self.len(),
                self.nodes_nm
                    .iter()
                    .map(|w| crate::spectrum::fmt_num((w * 100.0).round() / 100.0))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }

    /// The summary `--json` reports.
    pub fn summary(&self, estimate_de2000: Option<f64>) -> Summary {
        Summary {
            kind: self.kind,
            nodes: self.len(),
            nodes_nm: self.nodes_nm.clone(),
            weights: self.weights.clone(),
            grid: self.uniform.map(|(g, _)| g.to_string()),
            rule: self.uniform.map(|(_, r)| r),
            estimate_de2000,
        }
    }
}

impl fmt::Display for Quadrature {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe())
    }
}

/// A quadrature as it is stored.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// Where the quadrature came from.
    pub kind: Kind,
    /// The observer the weights are for.
    pub observer: Observer,
    /// The nodes in nm, strictly increasing.
    pub nodes_nm: Vec<f64>,
    /// Per node: the x, y, z weights (CMF units times nm).
    pub weights: Vec<[f64; 3]>,
    /// The grid and rule of a uniform quadrature.
    pub grid: Option<String>,
    /// The integration rule of a uniform quadrature.
    pub rule: Option<Rule>,
}

impl From<Quadrature> for Record {
    fn from(q: Quadrature) -> Record {
        Record {
            kind: q.kind,
            observer: q.observer,
            grid: q.uniform.map(|(g, _)| g.to_string()),
            rule: q.uniform.map(|(_, r)| r),
            nodes_nm: q.nodes_nm,
            weights: q.weights,
        }
    }
}

impl TryFrom<Record> for Quadrature {
    type Error = Error;
    fn try_from(r: Record) -> Result<Quadrature> {
        match (r.kind, &r.grid, r.rule) {
            (Kind::Uniform, Some(g), Some(rule)) => {
                let q = Quadrature::uniform(g.parse()?, rule, r.observer)?;
                if q.nodes_nm != r.nodes_nm {
                    return Err(Error::invalid(format!(
                        "a stored uniform quadrature on {g} lists other wavelengths"
                    )));
                }
                Ok(q)
            }
            (Kind::Uniform, _, _) => Err(Error::invalid(
                "a stored uniform quadrature needs its grid and rule",
            )),
            (kind, _, _) => Quadrature::new(kind, r.observer, r.nodes_nm, r.weights),
        }
    }
}

/// A quadrature as `--json` reports it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Summary {
    /// Where the quadrature came from.
    pub kind: Kind,
    /// Number of nodes.
    pub nodes: usize,
    /// The nodes in nm, strictly increasing.
    pub nodes_nm: Vec<f64>,
    /// Per node: the x, y, z weights (`XYZ = sum_i w_i S(lambda_i)`, CMF units times nm).
    pub weights: Vec<[f64; 3]>,
    /// The grid and rule of a uniform quadrature.
    pub grid: Option<String>,
    /// The integration rule of a uniform quadrature.
    pub rule: Option<Rule>,
    /// The largest CIEDE2000 over the stimuli it was checked on, when it was.
    pub estimate_de2000: Option<f64>,
}

/// "1 node meets", "9 nodes meet": `n` nodes and a verb (given as after "nodes") that agrees.
pub(crate) fn nodes_verb(n: usize, verb: &str) -> String {
    if n == 1 {
        let s = if verb.ends_with('s') { "es" } else { "s" };
        format!("1 node {verb}{s}")
    } else {
        format!("{n} nodes {verb}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_count_agrees_with_its_verb() {
        assert_eq!(nodes_verb(1, "meet"), "1 node meets");
        assert_eq!(nodes_verb(1, "miss"), "1 node misses");
        assert_eq!(nodes_verb(9, "err"), "9 nodes err");
    }

    #[test]
    fn a_uniform_grid_is_its_rule_times_the_cmfs() {
        let grid = WavelengthGrid::new(380.0, 780.0, 5.0).unwrap();
        let q = Quadrature::uniform(grid, Rule::Trapezoid, Observer::Cie1931).unwrap();
        let cmfs = Cmfs::new(Observer::Cie1931, &grid).unwrap();
        assert_eq!(q.len(), 81);
        assert_eq!(q.nodes_nm()[1], 385.0);
        // The sum of the y weights is the trapezoid integral of ybar (106.86 for CIE 1931).
        let want = cmfs.y.integrate(Rule::Trapezoid);
        assert!((q.sum()[1] - want).abs() < 1e-12 * want);
        assert!((q.sum()[1] - 106.86).abs() < 0.05, "{}", q.sum()[1]);
        assert_eq!(q.weights()[0][1], 2.5 * cmfs.y.values()[0]);
        assert_eq!(q.describe(), "380:780:5 trapezoid");
    }

    #[test]
    fn a_quadrature_reads_back_as_it_was_stored_and_is_checked() {
        let grid = WavelengthGrid::new(380.0, 780.0, 10.0).unwrap();
        let u = Quadrature::uniform(grid, Rule::Simpson, Observer::Cie1964).unwrap();
        let m = Quadrature::meyer(Observer::Cie1931).unwrap();
        for q in [u, m] {
            let text = serde_json::to_string(&q).unwrap();
            let back: Quadrature = serde_json::from_str(&text).unwrap();
            assert_eq!(back, q);
        }
        // A stored quadrature that Quadrature::new would refuse is refused.
        let bad = r#"{"kind":"scene","observer":"cie1931","nodes_nm":[600.0,500.0],
            "weights":[[1,1,1],[1,1,1]],"grid":null,"rule":null}"#;
        let e = serde_json::from_str::<Quadrature>(bad).unwrap_err();
        assert!(e.to_string().contains("increase strictly"), "{e}");
    }

    #[test]
    fn a_white_is_y_100_on_any_quadrature() {
        let q = Quadrature::new(
            Kind::Scene,
            Observer::Cie1931,
            vec![450.0, 550.0, 600.0],
            vec![[1.0, 0.5, 3.0], [0.5, 2.0, 0.1], [2.0, 1.0, 0.0]],
        )
        .unwrap();
        let light = [1.0, 2.0, 3.0];
        let xyz = q.relative_xyz(&light, &light).unwrap();
        assert!((xyz.y() - 100.0).abs() < 1e-12);
        assert!(q.relative_xyz(&[1.0; 3], &[0.0; 3]).is_none());
    }

    #[test]
    fn malformed_quadratures_are_errors() {
        let o = Observer::Cie1931;
        let w = vec![[1.0; 3]; 2];
        for (nodes, weights) in [
            (vec![], vec![]),
            (vec![500.0, 500.0], w.clone()),
            (vec![600.0, 500.0], w.clone()),
            (vec![-5.0, 500.0], w.clone()),
            (vec![f64::NAN, 500.0], w.clone()),
            (vec![500.0], w.clone()),
            (
                vec![500.0, 600.0],
                vec![[1.0, f64::INFINITY, 1.0], [1.0; 3]],
            ),
            (vec![500.0, 600.0], vec![[1.0, 0.0, 1.0]; 2]),
        ] {
            assert!(
                Quadrature::new(Kind::Scene, o, nodes.clone(), weights).is_err(),
                "{nodes:?}"
            );
        }
    }
}
