//! Tolerance classes for the audit: each panel is judged against its own tolerance, given by
//! the first rule it matches (by layer, group or size) or by the default. A tolerance is
//! `mm + relative × size`, where size is the panel's largest corner-to-corner distance: an
//! absolute figure, a supplier's relative one (0.3 % of the size is `"relative": 0.003`), or
//! both added.
//!
//! ```json
//! { "default": { "mm": 0.5 },
//!   "rules": [
//!     { "name": "glass", "layer": "GLASS*", "relative": 0.003 },
//!     { "name": "large steel", "group": "3", "min_size": 2000, "mm": 1.0 } ] }
//! ```
//!
//! A rule matches a panel when every criterion it gives holds: `layer` (DXF layer) and `group`
//! (OBJ group or object, a plate's assembly group) are patterns where `*` stands for any run of
//! characters and `?` for one, compared without regard to ASCII case; `min_size` ≤ size ≤
//! `max_size`, mm. A rule with no criterion matches every panel.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::audit::Panel;
use crate::files::{read_nonempty, utf8_text, ReadError};

/// The most rules a file may hold.
pub const MAX_RULES: usize = 10_000;

/// What a class allows: `mm + relative × size`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Allowance {
    #[serde(default)]
    pub mm: f64,
    #[serde(default)]
    pub relative: f64,
}

impl Allowance {
    pub fn absolute(mm: f64) -> Allowance {
        Allowance { mm, relative: 0.0 }
    }

    pub fn at(&self, size: f64) -> f64 {
        self.mm + self.relative * size
    }

    fn check(&self) -> Result<(), String> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(self.mm) && ok(self.relative) && self.mm + self.relative > 0.0) {
            return Err(format!(
                "mm ({}) and relative ({}) must be finite and ≥ 0, and not both 0",
                self.mm, self.relative
            ));
        }
        Ok(())
    }

    /// "0.5 mm", "0.003 × size", "1 mm + 0.001 × size".
    pub fn describe(&self) -> String {
        match (self.mm > 0.0, self.relative > 0.0) {
            (true, false) => format!("{} mm", self.mm),
            (false, true) => format!("{} × size", self.relative),
            _ => format!("{} mm + {} × size", self.mm, self.relative),
        }
    }
}

/// One rule: what it matches and what it allows.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    #[serde(default)]
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_size: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_size: Option<f64>,
    #[serde(default)]
    pub mm: f64,
    #[serde(default)]
    pub relative: f64,
}

impl Rule {
    pub fn allowance(&self) -> Allowance {
        Allowance {
            mm: self.mm,
            relative: self.relative,
        }
    }

    fn matches(&self, panel: &Panel, size: f64) -> bool {
        let named = |pattern: &Option<String>, name: &Option<String>| match (pattern, name) {
            (None, _) => true,
            (Some(p), Some(n)) => glob(p, n),
            (Some(_), None) => false,
        };
        named(&self.layer, &panel.layer)
            && named(&self.group, &panel.group)
            && self.min_size.is_none_or(|s| size >= s)
            && self.max_size.is_none_or(|s| size <= s)
    }

    fn uses_size(&self) -> bool {
        self.relative > 0.0 || self.min_size.is_some() || self.max_size.is_some()
    }
}

/// The tolerance classes of an audit.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Rules {
    #[serde(default)]
    pub default: Option<Allowance>,
    #[serde(default)]
    pub rules: Vec<Rule>,
}

/// A panel's tolerance and the rule that gave it (None: the default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judged {
    pub rule: Option<usize>,
    pub tolerance: f64,
}

impl Rules {
    /// One tolerance for every panel.
    pub fn uniform(mm: f64) -> Rules {
        Rules {
            default: Some(Allowance::absolute(mm)),
            rules: Vec::new(),
        }
    }

    pub fn read(path: &Path) -> Result<Rules, ReadError> {
        let text = utf8_text(path, read_nonempty(path)?)?;
        let rules: Rules = serde_json::from_str(&text)
            .map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
        if rules.rules.len() > MAX_RULES {
            return Err(ReadError::file(
                path,
                format!("{} rules, more than {MAX_RULES}", rules.rules.len()),
            ));
        }
        if let Some(d) = &rules.default {
            d.check()
                .map_err(|m| ReadError::record(path, "default", m))?;
        }
        let mut rules = rules;
        let mut names = std::collections::HashSet::new();
        for (k, r) in rules.rules.iter_mut().enumerate() {
            if r.name.is_empty() {
                r.name = format!("rule {}", k + 1);
            }
            if r.name == "default" || !names.insert(r.name.clone()) {
                return Err(ReadError::record(
                    path,
                    format!("rule {}", k + 1),
                    format!("the name \"{}\" is taken: each class needs its own", r.name),
                ));
            }
            let bad =
                |m: String| ReadError::record(path, format!("rule {} ({})", k + 1, r.name), m);
            r.allowance().check().map_err(bad)?;
            for (what, v) in [("min_size", r.min_size), ("max_size", r.max_size)] {
                if v.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
                    return Err(bad(format!("{what} must be a finite size ≥ 0 in mm")));
                }
            }
            if let (Some(lo), Some(hi)) = (r.min_size, r.max_size) {
                if lo > hi {
                    return Err(bad(format!("min_size {lo} is above max_size {hi}")));
                }
            }
        }
        Ok(rules)
    }

    /// The tolerance of a panel, or None when no rule matches and there is no default.
    pub fn judge(&self, panel: &Panel) -> Option<Judged> {
        let sized = self.default.is_some_and(|d| d.relative > 0.0)
            || self.rules.iter().any(Rule::uses_size);
        let size = if sized { panel.size() } else { 0.0 };
        match self.rules.iter().position(|r| r.matches(panel, size)) {
            Some(k) => Some(Judged {
                rule: Some(k),
                tolerance: self.rules[k].allowance().at(size),
            }),
            None => self.default.map(|d| Judged {
                rule: None,
                tolerance: d.at(size),
            }),
        }
    }
}

/// Whether `name` matches `pattern` (`*` any run, `?` one character), ignoring ASCII case.
pub fn glob(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.chars().map(|c| c.to_ascii_lowercase()).collect();
    let n: Vec<char> = name.chars().map(|c| c.to_ascii_lowercase()).collect();
    // Greedy with backtracking to the last star: linear in practice, never exponential.
    let (mut i, mut j) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some((i, j));
            i += 1;
        } else if let Some((si, sj)) = star {
            i = si + 1;
            j = sj + 1;
            star = Some((si, sj + 1));
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn square(side: f64, layer: Option<&str>, group: Option<&str>) -> Panel {
        Panel {
            corners: vec![
                DVec3::ZERO,
                DVec3::new(side, 0.0, 0.0),
                DVec3::new(side, side, 0.0),
                DVec3::new(0.0, side, 0.0),
            ],
            layer: layer.map(str::to_string),
            group: group.map(str::to_string),
            ..Default::default()
        }
    }

    #[test]
    fn patterns() {
        assert!(glob("GLASS*", "glass-north"));
        assert!(glob("*", ""));
        assert!(glob("a?c", "abc"));
        assert!(!glob("a?c", "ac"));
        assert!(glob("*north*", "GLASS-NORTH-2"));
        assert!(!glob("steel", "steel2"));
        assert!(glob("s*l*2", "steel2"));
    }

    #[test]
    fn first_matching_rule_then_the_default() {
        let rules = Rules {
            default: Some(Allowance::absolute(0.5)),
            rules: vec![
                Rule {
                    name: "glass".into(),
                    layer: Some("GLASS*".into()),
                    group: None,
                    min_size: None,
                    max_size: None,
                    mm: 0.0,
                    relative: 0.003,
                },
                Rule {
                    name: "big".into(),
                    layer: None,
                    group: None,
                    min_size: Some(2000.0),
                    max_size: None,
                    mm: 1.0,
                    relative: 0.0,
                },
            ],
        };
        // A 1000 mm glass square: its diagonal is the size.
        let glass = rules.judge(&square(1000.0, Some("glass-n"), None)).unwrap();
        assert_eq!(glass.rule, Some(0));
        assert!((glass.tolerance - 0.003 * 1000.0 * 2f64.sqrt()).abs() < 1e-12);
        let big = rules.judge(&square(2000.0, Some("steel"), None)).unwrap();
        assert_eq!((big.rule, big.tolerance), (Some(1), 1.0));
        let small = rules.judge(&square(10.0, None, Some("3"))).unwrap();
        assert_eq!((small.rule, small.tolerance), (None, 0.5));
        let no_default = Rules {
            default: None,
            ..rules
        };
        assert_eq!(no_default.judge(&square(10.0, None, None)), None);
    }

    #[test]
    fn bad_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rules.json");
        for (text, needle) in [
            (r#"{"rules":[{"layer":"A","mm":-1}]}"#, "rule 1"),
            (r#"{"rules":[{"layer":"A"}]}"#, "not both 0"),
            (
                r#"{"rules":[{"mm":1,"min_size":5,"max_size":2}]}"#,
                "above max_size",
            ),
            (r#"{"rules":[{"mm":1,"colour":"red"}]}"#, "unknown field"),
            (r#"{"default":{"mm":"NaN"}}"#, "line 1"),
            (
                r#"{"rules":[{"name":"a","mm":1},{"name":"a","mm":2}]}"#,
                "rule 2",
            ),
        ] {
            std::fs::write(&path, text).unwrap();
            let err = Rules::read(&path).unwrap_err().to_string();
            assert!(err.contains(needle), "{text}: {err}");
        }
    }
}
