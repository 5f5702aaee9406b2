//! `audit`: the planarity of panels made anywhere (ISO 1101 flatness, best fit, the corner
//! figure), each against its tolerance class, as a planarity report.
//!
//! ```
//! use glam::DVec3;
//! use lamina::rationalize::audit::{Panel, Panels};
//! use lamina::stage::audit;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let warped = Panel {
//!     corners: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.002), DVec3::Y],
//!     ..Default::default()
//! };
//! let panels = Panels { panels: vec![warped], notes: Vec::new() };
//! let done = audit::run(panels, &audit::Options { tolerance: Some(0.01), ..Default::default() })?;
//! assert!(done.report.summary.within_tolerance);
//! # Ok(()) }
//! ```

use glam::DVec3;

use crate::rationalize::audit::{audit, Panel, Panels};
use crate::rationalize::panels::MAX_FLATNESS_CORNERS;
use crate::rationalize::tolerance::{Allowance, Judged, Rule, Rules};
pub use crate::report::planarity::Metric;
use crate::report::planarity::{Context, PanelRow, Report};
use crate::stage::OptionError;

/// How panels are judged. Give `tolerance`, `tolerance_rules`, or both (then `tolerance` is the
/// rules' default and the rules must not give one).
#[derive(Clone, Debug)]
pub struct Options {
    /// Largest figure accepted, mm (with `tolerance_rules`: for the panels no rule matches). Default:
    /// none.
    pub tolerance: Option<f64>,
    /// Tolerance classes by layer, group and panel size; the first rule a panel matches gives
    /// its tolerance. Default: none.
    pub tolerance_rules: Option<Rules>,
    /// Where the rules came from, for the report's notes. Default "the rules".
    pub rules_name: String,
    /// The figure held to the tolerance. Default: ISO 1101 flatness.
    pub metric: Metric,
    /// The panels' name in the report's title. Default "panels".
    pub name: String,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            tolerance: None,
            tolerance_rules: None,
            rules_name: "the rules".into(),
            metric: Metric::Flatness,
            name: "panels".into(),
        }
    }
}

/// The audit: the planarity report, and what the caller should be told.
#[derive(Clone, Debug)]
pub struct Audited {
    /// The report, as the command writes it.
    pub report: Report,
    /// Things read or defaulted that the caller should hear (faces skipped, classes that match
    /// no panel), one line each.
    pub notes: Vec<String>,
}

/// Why panels could not be audited.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(
        "no face has 4 or more distinct corners: nothing to audit (a triangulated export, as \
         from STL or trimesh, has lost its panels: export quads or n-gons)"
    )]
    /// No face to audit.
    NoPanels,
    #[error(
        "{0} faces have more than {MAX_FLATNESS_CORNERS} corners, beyond the exact flatness \
         search: give metric= best-fit"
    )]
    /// Faces beyond the exact flatness search.
    TooManyCorners(usize),
    #[error(
        "panel {id} ({label}) matches no rule of {rules} and there is no default: add \
         \"default\" to the rules or give tolerance="
    )]
    /// A panel no tolerance rule matches.
    Unmatched {
        /// The panel's number in the input.
        id: usize,
        /// Its name, layer and group.
        label: String,
        /// Where the rules came from.
        rules: String,
    },
}

impl Options {
    /// The tolerance classes: the rules, with `tolerance` as their default.
    fn classes(&self) -> Result<Rules, OptionError> {
        if let Some(t) = self.tolerance {
            if !(t.is_finite() && t > 0.0) {
                return Err(OptionError::new(
                    "tolerance",
                    format!("must be a positive distance in mm, got {t}"),
                ));
            }
        }
        let mut rules = self.tolerance_rules.clone().unwrap_or_default();
        match (self.tolerance, rules.default) {
            (Some(_), Some(_)) => {
                return Err(OptionError::new(
                    "tolerance",
                    format!(
                        "is given and so is a default tolerance in {}: give it in one place",
                        self.rules_name
                    ),
                ))
            }
            (Some(t), None) => rules.default = Some(Allowance::absolute(t)),
            (None, None) if self.tolerance_rules.is_none() => {
                return Err(OptionError::new(
                    "tolerance",
                    "is needed: give tolerance= (mm) or tolerance_rules=",
                ))
            }
            _ => {}
        }
        Ok(rules)
    }
}

/// Audits `panels` (as read by `rationalize::audit::read_panels`, or made in memory). Faces of
/// fewer than four distinct corners are planar by construction: counted, not audited.
pub fn run(panels: Panels, opts: &Options) -> Result<Audited, Error> {
    let rules = opts.classes()?;
    let Panels {
        panels: read,
        notes: read_notes,
    } = panels;
    let mut notes = Vec::new();
    let total = read.len();
    let (ids, panels): (Vec<usize>, Vec<Panel>) = read
        .into_iter()
        .enumerate()
        .filter(|(_, p)| distinct_corners(&p.corners) >= 4)
        .unzip();
    let skipped = total - panels.len();
    if skipped > 0 {
        notes.push(format!(
            "{skipped} of {total} faces have fewer than 4 distinct corners (planar by construction): skipped"
        ));
    }
    if panels.is_empty() {
        return Err(Error::NoPanels);
    }
    let judged = judge(opts, &rules, &ids, &panels)?;
    let metrics = audit(&panels);
    let too_many = metrics.iter().filter(|m| m.flatness.is_nan()).count();
    if too_many > 0 {
        if opts.metric == Metric::Flatness {
            return Err(Error::TooManyCorners(too_many));
        }
        notes.push(format!(
            "{too_many} faces have more than {MAX_FLATNESS_CORNERS} corners: no flatness for them (NaN)"
        ));
    }
    let with_rules = opts.tolerance_rules.is_some();
    let (rows, corners): (Vec<PanelRow>, Vec<Vec<DVec3>>) = panels
        .into_iter()
        .zip(metrics)
        .zip(&ids)
        .zip(&judged)
        .map(|(((p, metrics), &index), j)| {
            let row = PanelRow {
                index,
                nodes: p.nodes,
                name: p.name,
                layer: p.layer,
                group: p.group,
                tolerance: j.tolerance,
                class: with_rules.then(|| j.rule.unwrap_or(rules.rules.len())),
                metrics,
                ..Default::default()
            };
            (row, p.corners)
        })
        .unzip();
    let classes: Vec<(String, String)> = if with_rules {
        rules
            .rules
            .iter()
            .map(|r| (r.name.clone(), describe_rule(r)))
            .chain(rules.default.map(|d| {
                (
                    "default".to_string(),
                    format!("any other panel: {}", d.describe()),
                )
            }))
            .collect()
    } else {
        Vec::new()
    };
    let report = Report::new(
        Context {
            title: format!("Planarity audit of {}", opts.name),
            source: opts.name.clone(),
            notes: read_notes
                .into_iter()
                .chain((skipped > 0).then(|| format!(
                    "{skipped} faces of fewer than 4 distinct corners skipped (planar by construction)."
                )))
                .chain((too_many > 0).then(|| format!(
                    "{too_many} faces of more than {MAX_FLATNESS_CORNERS} corners have no flatness; the largest flatness is of the others."
                )))
                .chain(with_rules.then(|| format!(
                    "Tolerances from {}: the first rule a panel matches gives its tolerance; size is the panel's largest corner-to-corner distance.",
                    opts.rules_name
                )))
                .collect(),
            ..Default::default()
        },
        rows,
        corners,
        rules.default.filter(|d| d.relative == 0.0).map(|d| d.mm),
        classes,
        opts.metric,
    );
    for c in &report.summary.classes {
        if c.panels == 0 {
            notes.push(format!(
                "tolerance class \"{}\" ({}) matches no panel",
                c.name, c.rule
            ));
        }
    }
    Ok(Audited { report, notes })
}

/// Each panel's tolerance; an error for a panel no rule matches when there is no default.
fn judge(
    opts: &Options,
    rules: &Rules,
    ids: &[usize],
    panels: &[Panel],
) -> Result<Vec<Judged>, Error> {
    panels
        .iter()
        .zip(ids)
        .map(|(p, &id)| {
            rules.judge(p).ok_or_else(|| {
                let label: Vec<String> =
                    [("name", &p.name), ("layer", &p.layer), ("group", &p.group)]
                        .into_iter()
                        .filter_map(|(k, v)| v.as_ref().map(|v| format!("{k} \"{v}\"")))
                        .collect();
                Error::Unmatched {
                    id,
                    label: if label.is_empty() {
                        "no name, layer or group".into()
                    } else {
                        label.join(", ")
                    },
                    rules: opts.rules_name.clone(),
                }
            })
        })
        .collect()
}

/// What a rule matches and allows, in words.
fn describe_rule(r: &Rule) -> String {
    let mut what = Vec::new();
    if let Some(l) = &r.layer {
        what.push(format!("layer {l}"));
    }
    if let Some(g) = &r.group {
        what.push(format!("group {g}"));
    }
    if let Some(s) = r.min_size {
        what.push(format!("size ≥ {s} mm"));
    }
    if let Some(s) = r.max_size {
        what.push(format!("size ≤ {s} mm"));
    }
    if what.is_empty() {
        what.push("every panel".into());
    }
    format!("{}: {}", what.join(", "), r.allowance().describe())
}

/// Corners more than 1e-9 of the polygon's size apart from every earlier one.
fn distinct_corners(p: &[DVec3]) -> usize {
    let size = p.iter().map(|q| q.distance(p[0])).fold(0.0, f64::max);
    let eps = 1e-9 * size.max(f64::MIN_POSITIVE);
    (0..p.len())
        .filter(|&i| p[..i].iter().all(|q| q.distance(p[i]) > eps))
        .count()
}

/// The report as CSV, one row per panel: id, labels, every figure, class, tolerance and
/// verdict (rows formatted in blocks on every core).
pub fn csv(report: &Report) -> String {
    use rayon::prelude::*;
    let metric = report.summary.metric;
    // Names are quoted as CSV asks when they hold a comma, quote or line break.
    let field = |v: &Option<String>| match v {
        None => String::new(),
        Some(v) if v.contains([',', '"', '\n', '\r']) => format!("\"{}\"", v.replace('"', "\"\"")),
        Some(v) => v.clone(),
    };
    let row = |(r, p): (&PanelRow, &Vec<DVec3>)| {
        let m = &r.metrics;
        format!(
            "{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{},{}\n",
            r.index,
            field(&r.name),
            field(&r.layer),
            field(&r.group),
            p.len(),
            m.flatness,
            m.best_fit,
            m.deviation,
            m.diagonal_distance,
            m.diagonal_rel_diagonal,
            m.torsion_deg,
            m.normal[0],
            m.normal[1],
            m.normal[2],
            metric.name(),
            field(&r.class_name),
            r.tolerance,
            if r.pass { "pass" } else { "fail" }
        )
    };
    let blocks: Vec<String> = report
        .panels
        .par_chunks(4096)
        .zip(report.quads.par_chunks(4096))
        .map(|(rows, quads)| rows.iter().zip(quads).map(row).collect())
        .collect();
    let mut out = String::from(
        "panel,name,layer,group,corners,flatness_mm,best_fit_mm,corner_mm,diagonal_distance_mm,warp,torsion_deg,normal_x,normal_y,normal_z,metric,class,tolerance_mm,pass\n",
    );
    for b in &blocks {
        out.push_str(b);
    }
    out
}
