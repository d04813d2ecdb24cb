//! `view --script FILE`: a JSON array of steps replayed in the window, then the window closes;
//! `--json` prints what happened (every frame's time and wavelengths, the probes, the commands).

use serde_json::Value;
use std::path::{Path, PathBuf};

/// One step of a script.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Step {
    /// Any `render` option by its long name (and `exposure`), a value or null to unset.
    Set(Vec<(String, Option<String>)>),
    /// Orbit the camera by (yaw, pitch) degrees.
    Orbit([f64; 2]),
    /// Multiply the zoom.
    Zoom(f64),
    /// Render this many more frames.
    Frames(usize),
    /// Wait until the fitted quadrature is in use (or the fit failed).
    WaitQuadrature,
    /// Probe image pixel (x, y).
    Probe([usize; 2]),
    /// The image as PNG (sRGB, exposed) or EXR (linear), by the extension.
    Screenshot(PathBuf),
    /// The whole window as PNG.
    ScreenshotWindow(PathBuf),
    /// Print the `specmap render` command of the view.
    Command,
}

/// Reads and checks a script: every step's problem named with its position.
pub(crate) fn load(path: &Path) -> anyhow::Result<Vec<Step>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("--script {}: {e}", path.display()))?;
    let v: Value = serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("--script {}: not JSON: {e}", path.display()))?;
    let Value::Array(steps) = v else {
        anyhow::bail!("--script {}: must be a JSON array of steps", path.display());
    };
    steps
        .iter()
        .enumerate()
        .map(|(i, s)| {
            step(s).map_err(|e| anyhow::anyhow!("--script {} step {}: {e}", path.display(), i + 1))
        })
        .collect()
}

fn step(v: &Value) -> anyhow::Result<Step> {
    let Value::Object(m) = v else {
        anyhow::bail!("a step is an object such as {{\"frames\": 2}}, not {v}");
    };
    if m.len() != 1 {
        anyhow::bail!("a step has one key, e.g. {{\"set\": {{...}}}} or {{\"frames\": 2}}");
    }
    let (k, v) = m.iter().next().expect("one key");
    let num = |v: &Value| {
        v.as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| anyhow::anyhow!("\"{k}\" needs a number, not {v}"))
    };
    let pair = |v: &Value| -> anyhow::Result<[f64; 2]> {
        match v.as_array().map(|a| a.as_slice()) {
            Some([a, b]) => Ok([num(a)?, num(b)?]),
            _ => anyhow::bail!("\"{k}\" needs two numbers, e.g. [30, -10], not {v}"),
        }
    };
    let path = |v: &Value| {
        v.as_str()
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
            .ok_or_else(|| anyhow::anyhow!("\"{k}\" needs a file name, not {v}"))
    };
    Ok(match k.as_str() {
        "set" => {
            let Value::Object(opts) = v else {
                anyhow::bail!("\"set\" needs an object of options, e.g. {{\"film\": \"2.7:300\"}}");
            };
            Step::Set(
                opts.iter()
                    .map(|(k, v)| {
                        let v = match v {
                            Value::Null => None,
                            Value::String(s) => Some(s.clone()),
                            Value::Number(n) => Some(n.to_string()),
                            Value::Bool(_) | Value::Array(_) | Value::Object(_) => {
                                anyhow::bail!("option \"{k}\": a string or a number, not {v}")
                            }
                        };
                        Ok((k.clone(), v))
                    })
                    .collect::<anyhow::Result<_>>()?,
            )
        }
        "orbit" => Step::Orbit(pair(v)?),
        "zoom" => {
            let z = num(v)?;
            if z <= 0.0 {
                anyhow::bail!("\"zoom\" must be positive, not {z}");
            }
            Step::Zoom(z)
        }
        "frames" => Step::Frames(
            v.as_u64()
                .filter(|n| (1..=100_000).contains(n))
                .ok_or_else(|| anyhow::anyhow!("\"frames\" needs a count from 1, not {v}"))?
                as usize,
        ),
        "wait" if v == "quadrature" => Step::WaitQuadrature,
        "wait" => anyhow::bail!("\"wait\" knows \"quadrature\", not {v}"),
        "probe" => {
            let [x, y] = pair(v)?;
            if x < 0.0 || y < 0.0 || x.fract() != 0.0 || y.fract() != 0.0 {
                anyhow::bail!("\"probe\" needs whole pixel numbers, not {v}");
            }
            Step::Probe([x as usize, y as usize])
        }
        "screenshot" => Step::Screenshot(path(v)?),
        "screenshot_window" => Step::ScreenshotWindow(path(v)?),
        "command" => Step::Command,
        other => anyhow::bail!(
            "unknown step \"{other}\" (set, orbit, zoom, frames, wait, probe, screenshot, \
             screenshot_window, command)"
        ),
    })
}

/// One frame, for the report.
#[derive(Debug, Clone, serde::Serialize)]
pub(crate) struct FrameRecord {
    pub(crate) ms: f64,
    pub(crate) prepare_ms: f64,
    pub(crate) nodes: usize,
    pub(crate) kind: String,
    /// Whether a fit was running while the frame was drawn.
    pub(crate) fitting: bool,
}

/// What `--json` prints at the end.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub(crate) struct Report {
    pub(crate) backend: String,
    pub(crate) first_frame_ms: Option<f64>,
    pub(crate) frames: Vec<FrameRecord>,
    pub(crate) fits: Vec<serde_json::Value>,
    pub(crate) probes: Vec<super::probe::Probe>,
    pub(crate) commands: Vec<String>,
    pub(crate) screenshots: Vec<String>,
    pub(crate) errors: Vec<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_parse_and_a_bad_one_is_named_with_its_position() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.json");
        std::fs::write(
            &p,
            r#"[{"set": {"film": "2.7:300", "exposure": -1, "env": null}}, {"orbit": [30, -10]},
               {"frames": 2}, {"wait": "quadrature"}, {"probe": [4, 5]},
               {"screenshot": "a.png"}, {"command": true}]"#,
        )
        .unwrap();
        let s = load(&p).unwrap();
        assert_eq!(
            s[0],
            Step::Set(vec![
                ("env".into(), None),
                ("exposure".into(), Some("-1".into())),
                ("film".into(), Some("2.7:300".into())),
            ])
        );
        assert_eq!(s[1], Step::Orbit([30.0, -10.0]));
        assert_eq!(s[4], Step::Probe([4, 5]));
        std::fs::write(&p, r#"[{"frames": 2}, {"probe": [1.5, 2]}]"#).unwrap();
        let e = load(&p).unwrap_err().to_string();
        assert!(e.contains("step 2") && e.contains("whole pixel"), "{e}");
        std::fs::write(&p, r#"[{"fly": 1}]"#).unwrap();
        assert!(load(&p)
            .unwrap_err()
            .to_string()
            .contains("unknown step \"fly\""));
    }
}
