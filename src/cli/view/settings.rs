//! The view's settings: `specmap render`'s options as its command line spells them. Every
//! change goes through `render`'s own parser, so the window accepts exactly what `render`
//! accepts and what it shows is one `specmap render` command away.

use crate::cli::demo::sh;
use crate::cli::render_args::RenderArgs;

/// Options that only `render`'s still output or report use: never part of what is shown.
const STILL_ONLY: [&str; 3] = ["output", "turntable", "frames"];

/// `render`'s options, in `--help`'s order, each set away from its default.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Settings {
    pairs: Vec<(String, String)>,
}

impl Settings {
    pub(crate) fn from_args(a: &RenderArgs) -> Settings {
        Settings {
            pairs: a
                .to_pairs()
                .into_iter()
                .filter(|(k, _)| !STILL_ONLY.contains(k))
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
        }
    }

    pub(crate) fn get(&self, key: &str) -> Option<&str> {
        self.pairs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Sets (or, with None, removes) options at once, checked by `render`'s parser: on an
    /// error nothing changes. Returns whether anything did.
    pub(crate) fn set_many(&mut self, changes: &[(&str, Option<String>)]) -> anyhow::Result<bool> {
        let mut next = self.clone();
        for (key, value) in changes {
            let key = key.trim_start_matches('-');
            if STILL_ONLY.contains(&key) || key == "json" || key.starts_with("sweep") {
                anyhow::bail!("--{key} does not apply to the view");
            }
            match (next.pairs.iter().position(|(k, _)| k == key), value) {
                (Some(i), Some(v)) => next.pairs[i].1 = v.clone(),
                (Some(i), None) => {
                    next.pairs.remove(i);
                }
                (None, Some(v)) => next.pairs.push((key.to_string(), v.clone())),
                (None, None) => {}
            }
        }
        let parsed = next.parse()?;
        // Back through to_pairs: the canonical order, defaults dropped.
        let next = Settings::from_args(&parsed);
        let changed = next != *self;
        *self = next;
        Ok(changed)
    }

    #[cfg(test)]
    pub(crate) fn set(&mut self, key: &str, value: Option<String>) -> anyhow::Result<bool> {
        self.set_many(&[(key, value)])
    }

    /// The options parsed as `render` parses them.
    pub(crate) fn parse(&self) -> anyhow::Result<RenderArgs> {
        RenderArgs::parse_pairs(self.pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())))
    }

    /// The pairs but `skip`'s, for keys of what a result depends on.
    pub(crate) fn without(&self, skip: &[&str]) -> Vec<(String, String)> {
        self.pairs
            .iter()
            .filter(|(k, _)| !skip.contains(&k.as_str()))
            .cloned()
            .collect()
    }

    /// The `specmap render` command that renders what the view shows, to `output`, with
    /// `fit_range` (the range the view's fit covers) in place of the settings' own, and a
    /// fit forced (`--quadrature scene`) where the view fits.
    pub(crate) fn command(&self, output: &str, fit_range: Option<String>) -> String {
        let mut words = vec!["specmap".to_string(), "render".to_string()];
        for (k, v) in &self.pairs {
            if k == "fit-range" && fit_range.is_some() {
                continue;
            }
            words.push(format!("--{k}"));
            if !crate::cli::render_args::FLAGS.contains(&k.as_str()) {
                words.push(sh(v));
            }
        }
        // The view fits as long as it takes; a still's plan would weigh the fit against one
        // frame and might take the uniform grid instead. The command fits as the view did.
        let fits = self.get("tolerance").is_some() && self.get("quadrature").is_none();
        if let Some(r) = fit_range {
            words.push("--fit-range".into());
            words.push(r);
            if fits {
                words.push("--quadrature".into());
                words.push("scene".into());
            }
        }
        words.push("-o".into());
        words.push(sh(output));
        words.join(" ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(argv: &[(&str, &str)]) -> Settings {
        Settings::from_args(&RenderArgs::parse_pairs(argv.iter().copied()).unwrap())
    }

    #[test]
    fn a_change_is_checked_by_renders_parser_and_a_bad_one_changes_nothing() {
        let mut s = settings(&[("scene", "cylinders"), ("light", "A")]);
        assert!(s.set("film", Some("2.7:300".into())).unwrap());
        assert_eq!(s.get("film"), Some("2.7:300"));
        let before = s.clone();
        let e = s.set("scene", Some("teapot".into())).unwrap_err();
        assert!(e.to_string().contains("teapot"), "{e}");
        assert_eq!(s, before);
        // Conflicting options are refused as render refuses them.
        assert!(s
            .set_many(&[("step", Some("5".into())), ("samples", Some("9".into()))])
            .is_err());
        // Back to a default: the option leaves the command.
        assert!(s.set("light", Some("D65".into())).unwrap());
        assert_eq!(s.get("light"), None);
    }

    #[test]
    fn the_command_parses_back_to_the_same_settings() {
        let s = settings(&[
            ("scene", "ball"),
            ("film", "2.7:250,1.38:100"),
            ("exposure", "-1.5"),
            ("orbit", "30,-10"),
            ("diffuse", "my lamp.csv"),
        ]);
        let cmd = s.command("view.png", None);
        assert!(
            cmd.starts_with("specmap render --film 2.7:250,1.38:100"),
            "{cmd}"
        );
        assert!(cmd.contains("--diffuse 'my lamp.csv'"), "{cmd}");
        assert!(cmd.ends_with("-o view.png"), "{cmd}");
        assert_eq!(s.parse().unwrap().to_pairs().len(), 4); // --scene ball is the default
    }
}
