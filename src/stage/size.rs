//! `size`: a linear frame (or shell) analysis of the plate network and the gauges it needs,
//! with the sizing file's contents as a typed report.
//!
//! ```
//! use lamina::stage::{planarize, size, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let solved = planarize::run(&net, None, &planarize::Options::default(), &Quiet)?;
//! let opts = size::Options {
//!     support: vec![size::support("z<1")?],
//!     load: vec!["self-weight".into()],
//!     ..Default::default()
//! };
//! let sized = size::run(&solved.axes, &opts, &Quiet)?;
//! assert!(sized.report.totals.max_utilisation <= 1.0);
//! # Ok(()) }
//! ```

use std::collections::BTreeMap;

use glam::DVec3;
use serde::Serialize;

use crate::analyze::frame::local_frame;
pub use crate::analyze::frame::Support;
pub use crate::analyze::material::Material;
use crate::analyze::sizing::{size, Limit, LoadSpec, Sizing, SizingError, SizingOptions};
pub use crate::analyze::sizing::{DeflectionLimit, GroupBy};
use crate::rationalize::axes::Axes;
use crate::rationalize::planarize::Selector;
use crate::stage::{checkpoint, Cancelled, OptionError, Progress};

/// What to analyse and how. `Default` is the command's defaults; give at least one support
/// and one load.
#[derive(Clone, Debug)]
pub struct Options {
    /// The steel. Default: 1.4404 (stainless 316L), with a note saying so.
    pub material: Option<Material>,
    /// Sheet thicknesses to choose from, mm, ascending. Default 1.5, 2, 3, 4, 5, 6, 8, 10.
    pub gauges: Vec<f64>,
    /// Supported nodes and how they are held.
    pub support: Vec<(Selector, Support)>,
    /// Loads, each a case (their sum another): `self-weight[:FACTOR]`,
    /// `point:NODES:FX,FY,FZ` (N), `wind:KPA:DX,DY,DZ`.
    pub load: Vec<String>,
    /// Largest displacement under the sum of the loads. Default: none.
    pub deflection_limit: Option<DeflectionLimit>,
    /// Members sized together. Default: each member.
    pub group_by: GroupBy,
    /// The assembly groups `plates` will cut (its groups=): members between two groups are
    /// bolted seams, sized as their two plies from the sums of two gauges; and the groups of
    /// `GroupBy::Assembly`. Default: none (one group, no seams).
    pub groups: Option<usize>,
    /// Neighbouring members within one gauge step. Default false.
    pub smooth: bool,
    /// Fillet weld throat over the thinner plate. Default 0.7.
    pub throat: f64,
    /// Rounds of analysis and gauge choice at most. Default 20.
    pub max_rounds: usize,
    /// Analyse the panels as shells, this many elements up each (even, 4 to 32). Default:
    /// the frame.
    pub shells: Option<usize>,
    /// The axes' name in the report. Default "axes.json".
    pub name: String,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            material: None,
            gauges: vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0],
            support: Vec::new(),
            load: Vec::new(),
            deflection_limit: None,
            group_by: GroupBy::Member,
            groups: None,
            smooth: false,
            throat: 0.7,
            max_rounds: 20,
            shells: None,
            name: "axes.json".into(),
        }
    }
}

/// A support as the command line writes it: `SELECTOR[:fixed|:pinned]` (fixed by default).
pub fn support(s: &str) -> Result<(Selector, Support), String> {
    let (sel, kind) = match s.rsplit_once(':') {
        Some((a, "fixed")) => (a, Support::Fixed),
        Some((a, "pinned")) => (a, Support::Pinned),
        Some((_, k)) if !k.contains(['<', '>', '=']) => {
            return Err(format!("`{s}`: `{k}` is not fixed or pinned"))
        }
        _ => (s, Support::Fixed),
    };
    Ok((Selector::parse(sel)?, kind))
}

/// `member`, `chain` or `assembly` (its count from `groups`).
pub fn group_by(s: &str) -> Result<GroupBy, String> {
    match s {
        "member" => Ok(GroupBy::Member),
        "chain" => Ok(GroupBy::Chain),
        "assembly" => Ok(GroupBy::Assembly(0)),
        _ => Err(format!("`{s}`: give member, chain or assembly")),
    }
}

/// The sizing: the analysis, whether everything holds, and the sizing file's contents.
#[derive(Clone, Debug)]
pub struct Sized {
    /// The analysis.
    pub sizing: Sizing,
    /// Utilisation and weld utilisation at most 1, and the deflection limit held.
    pub ok: bool,
    /// The report, as the command writes it.
    pub report: Report,
    /// Defaults taken that change the result (the material), one line each.
    pub notes: Vec<String>,
}

/// Why no sizing was made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// The analysis failed.
    Sizing(#[from] SizingError),
    #[error(transparent)]
    /// The caller stopped the stage.
    Cancelled(#[from] Cancelled),
}

impl Options {
    /// The analysis's options, every option checked.
    fn sizing(&self) -> Result<SizingOptions, OptionError> {
        if self.gauges.is_empty()
            || self
                .gauges
                .iter()
                .any(|g| !(g.is_finite() && *g > 0.0 && *g <= 200.0))
            || self.gauges.windows(2).any(|w| w[0] >= w[1])
        {
            return Err(OptionError::new(
                "gauges",
                "must be thicknesses from 0 to 200 mm in ascending order",
            ));
        }
        super::positive("throat", self.throat, 2.0, "")?;
        if !(1..=200).contains(&self.max_rounds) {
            return Err(OptionError::new(
                "max_rounds",
                format!("must be from 1 to 200, got {}", self.max_rounds),
            ));
        }
        if let Some(n) = self.shells {
            // Two elements up a panel are far from converged (a deep network's deflection
            // 49 % under what 4 and 6 give): 4 is the least.
            if !(4..=32).contains(&n) || n % 2 == 1 {
                return Err(OptionError::new(
                    "shells",
                    format!(
                        "must be an even number of elements from 4 to 32 (2 is not converged), \
                         got {n}"
                    ),
                ));
            }
        }
        if self.support.is_empty() {
            return Err(OptionError::new(
                "support",
                "is needed: give a selector and fixed or pinned, e.g. support= 'z<1'",
            ));
        }
        if self.load.is_empty() {
            return Err(OptionError::new(
                "load",
                "is needed: self-weight, point:NODES:FX,FY,FZ or wind:KPA:DX,DY,DZ",
            ));
        }
        let loads = self
            .load
            .iter()
            .map(|s| {
                LoadSpec::parse_action(s)
                    .map(|(l, action)| (s.clone(), l, action))
                    .map_err(|e| OptionError::new("load", e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(SizingOptions {
            material: match &self.material {
                Some(m) => m.clone(),
                None => Material::get("1.4404").expect("a built-in material"),
            },
            gauges: self.gauges.clone(),
            supports: self.support.clone(),
            loads,
            deflection_limit: self.deflection_limit,
            group_by: match (self.group_by, self.groups) {
                (GroupBy::Assembly(_), Some(k)) if k >= 1 => GroupBy::Assembly(k),
                (GroupBy::Assembly(k), None) if k >= 1 => GroupBy::Assembly(k),
                (GroupBy::Assembly(_), _) => {
                    return Err(OptionError::new(
                        "group_by",
                        "assembly needs groups= K (at least 1), the count plates' groups= is given",
                    ))
                }
                (by, _) => by,
            },
            seam_groups: match (self.groups, self.group_by) {
                (Some(0), _) => {
                    return Err(OptionError::new(
                        "groups",
                        "must be at least 1 (the assembly groups plates will cut)",
                    ))
                }
                (Some(k), _) => Some(k),
                (None, GroupBy::Assembly(k)) if k >= 1 => Some(k),
                (None, _) => None,
            },
            smooth: self.smooth,
            throat_factor: self.throat,
            max_rounds: self.max_rounds,
            shells: self.shells,
        })
    }
}

/// Sizes the plate network of `axes`. `progress` may stop it before the analysis starts (one
/// analysis runs to its end: the rounds are not yet interruptible inside).
pub fn run(axes: &Axes, opts: &Options, progress: &dyn Progress) -> Result<Sized, Error> {
    let sizing_opts = opts.sizing()?;
    let mut notes = Vec::new();
    if opts.material.is_none() {
        notes.push(format!(
            "material 1.4404 (stainless 316L, f_y {} MPa), the default: give material= for another",
            sizing_opts.material.fy
        ));
    }
    progress.begin("sizing", None);
    checkpoint(progress)?;
    let sizing = size(axes, &sizing_opts)?;
    checkpoint(progress)?;
    let (max_u, max_w) = (sizing.max_utilisation(), sizing.max_weld_utilisation());
    let (_, max_d) = sizing.max_displacement();
    let deflection_ok = sizing.deflection_limit.is_none_or(|l| max_d <= l);
    let ok = max_u <= 1.0 && max_w <= 1.0 && deflection_ok;
    let report = report(&sizing, &sizing_opts, opts);
    Ok(Sized {
        sizing,
        ok,
        report,
        notes,
    })
}

/// The sizing file (`lamina-sizing`): every member's gauge and check, every node's
/// displacement and weld, the reactions and the totals. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Frame or shells.
    pub analysis: serde_json::Value,
    /// Load cases at their characteristic values, the sum of them last (when there are several).
    pub cases: Vec<String>,
    /// The combinations of EN 1990 the checks use.
    pub combinations: Vec<CombinationRow>,
    /// Whether the rounds settled before the cap.
    pub converged: bool,
    /// What the figures mean.
    pub definitions: Definitions,
    /// Rounds of stiffening for the deflection limit.
    pub deflection_rounds: usize,
    /// Edges (members).
    pub edges: Vec<EdgeRow>,
    /// The file format's name.
    pub format: &'static str,
    /// Gauges to choose from, mm.
    pub gauges: Vec<f64>,
    /// How members are sized together.
    pub group_by: serde_json::Value,
    /// The steel.
    pub material: Material,
    /// Nodes.
    pub nodes: Vec<NodeRow>,
    /// Support reactions under the sum of the loads.
    pub reactions: Vec<Reaction>,
    /// Rounds of analysis and gauge choice.
    pub rounds: usize,
    /// The assembly groups the seams were sized for (`plates --groups`), when given.
    pub seam_groups: Option<usize>,
    /// Whether neighbouring members keep within a gauge step.
    pub smooth: bool,
    /// Where the input came from.
    pub source: String,
    /// The supports added.
    pub supports: Vec<String>,
    /// The whole structure's figures.
    pub totals: Totals,
    /// The unit of lengths.
    pub units: BTreeMap<&'static str, &'static str>,
    /// The format's version.
    pub version: u32,
}

/// One combination of the loads.
#[derive(Clone, Debug, Serialize)]
pub struct CombinationRow {
    /// The factor on each load, by its name.
    pub factors: BTreeMap<String, f64>,
    /// `ULS` (EN 1990 6.10: members and welds) or `SLS` (6.14b, characteristic: deflection).
    pub limit: &'static str,
    /// Its name, as edges' and nodes' `load` give it.
    pub name: String,
}

/// What the figures mean.
#[derive(Clone, Debug, Serialize)]
pub struct Definitions {
    /// How the loads are combined.
    pub combinations: &'static str,
    /// Displacement, mm.
    pub displacement: &'static str,
    /// End forces in the member's local axes under the sum of the loads [a: Fx Fy Fz Mx My Mz, b: …].
    pub end_forces: &'static str,
    /// The model sliced.
    pub model: String,
    /// Support reactions under the sum of the loads.
    pub reactions: &'static str,
    /// Utilisation: the governing check's figure over its limit.
    pub utilisation: &'static str,
    /// Weld utilisation (EN 1993-1-8 §4.5.3.3).
    pub weld_utilisation: &'static str,
}

/// One member.
#[derive(Clone, Debug, Serialize)]
pub struct EdgeRow {
    /// The member's first node.
    pub a: usize,
    /// Local axes.
    pub axes: LocalAxes,
    /// The member's second node.
    pub b: usize,
    /// The check that governs.
    pub check: &'static str,
    /// Every check's largest utilisation and the combination giving it.
    pub checks: BTreeMap<&'static str, CheckRow>,
    /// Section depth (the panel height across the member), mm.
    pub depth: f64,
    /// End forces in the member's local axes under the sum of the loads [a: Fx Fy Fz Mx My Mz, b: …].
    pub end_forces: [f64; 12],
    /// Gauge, mm.
    pub gauge: f64,
    /// Length, mm.
    pub length: f64,
    /// The load case governing it.
    pub load: String,
    /// A bolted seam's two plies, mm (the first welded at node a, the second at node b;
    /// adding up to the gauge); None for a single plate.
    pub plies: Option<[f64; 2]>,
    /// What a seam's bolts carry (`plates --sizing` checks them): in the local axes [N, V_y,
    /// V_z, T, M_y, M_z] (N, N·mm), each the largest magnitude at either end over the ultimate
    /// combinations; None for a single plate.
    pub seam_forces: Option<[f64; 6]>,
    /// Utilisation: the governing check's figure over its limit.
    pub utilisation: f64,
}

/// One check of a member.
#[derive(Clone, Debug, Serialize)]
pub struct CheckRow {
    /// The combination giving the largest utilisation.
    pub load: String,
    /// The largest utilisation over the ultimate combinations.
    pub utilisation: f64,
}

/// A member's local axes.
#[derive(Clone, Debug, Serialize)]
pub struct LocalAxes {
    /// Local x (along the member).
    pub x: [f64; 3],
    /// Local y (in the panel plane, across the member).
    pub y: [f64; 3],
    /// Local z (the panel normal).
    pub z: [f64; 3],
}

/// One node.
#[derive(Clone, Debug, Serialize)]
pub struct NodeRow {
    /// Displacement, mm.
    pub displacement: [f64; 3],
    /// Position, mm.
    pub position: [f64; 3],
    /// Rotation, rad.
    pub rotation: [f64; 3],
    /// The throat is below EN 1993-1-8 §4.5.2(2)'s 3 mm: a thin-sheet weld procedure.
    pub thin_sheet: bool,
    /// Fillet weld throat, mm.
    pub throat: f64,
    /// The load case governing the weld.
    pub weld_load: Option<String>,
    /// Weld utilisation (EN 1993-1-8 §4.5.3.3).
    pub weld_utilisation: Option<f64>,
}

/// A support's reaction under the sum of the loads.
#[derive(Clone, Debug, Serialize)]
pub struct Reaction {
    /// Force, N.
    pub force: [f64; 3],
    /// Moment, N·mm.
    pub moment: [f64; 3],
    /// The node.
    pub node: usize,
}

/// The whole structure's figures.
#[derive(Clone, Debug, Serialize)]
pub struct Totals {
    /// The deflection limit, mm.
    pub deflection_limit: Option<f64>,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Largest displacement under the serviceability combinations, mm.
    pub max_displacement: f64,
    /// The serviceability combination giving the largest displacement.
    pub max_displacement_load: String,
    /// The node that moves most.
    pub max_displacement_node: usize,
    /// Largest member utilisation.
    pub max_utilisation: f64,
    /// Largest weld utilisation.
    pub max_weld_utilisation: f64,
    /// Largest out-of-balance force over the largest load.
    pub residual: f64,
    /// The structure's largest horizontal extent, mm.
    pub span: f64,
    /// Nodes whose weld throat is below 3 mm (EN 1993-1-8 §4.5.2(2)): welded by a
    /// thin-sheet procedure.
    pub thin_sheet_welds: Vec<usize>,
}

fn report(s: &Sizing, sizing: &SizingOptions, opts: &Options) -> Report {
    use crate::analyze::report as words;
    let total = s.total();
    let (dnode, dmax) = s.max_displacement();
    let v3 = |v: DVec3| v.to_array();
    let edges = s
        .model
        .members
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let (x, y, z, l) = local_frame(&s.model, m);
            let c = &s.checks[k];
            EdgeRow {
                a: m.a,
                axes: LocalAxes {
                    x: v3(x),
                    y: v3(y),
                    z: v3(z),
                },
                b: m.b,
                check: c.check,
                checks: crate::analyze::sizing::CHECK_NAMES
                    .into_iter()
                    .zip(s.by_check[k])
                    .map(|(name, (u, case))| {
                        (
                            name,
                            CheckRow {
                                load: s.cases[case].name.clone(),
                                utilisation: u,
                            },
                        )
                    })
                    .collect(),
                depth: m.section.depth,
                end_forces: total.end_forces[k],
                gauge: s.gauges[k],
                length: l,
                load: s.cases[c.case].name.clone(),
                plies: m.section.plies,
                seam_forces: s.seam_forces(k),
                utilisation: c.utilisation,
            }
        })
        .collect();
    let nodes = s
        .model
        .nodes
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = total.displacements[i];
            let weld = s.welds[i].as_ref();
            NodeRow {
                displacement: [d[0], d[1], d[2]],
                position: v3(*p),
                rotation: [d[3], d[4], d[5]],
                thin_sheet: weld.is_some() && s.throats[i] < words::MIN_THROAT,
                throat: s.throats[i],
                weld_load: weld.map(|w| s.cases[w.case].name.clone()),
                weld_utilisation: weld.map(|w| w.utilisation),
            }
        })
        .collect();
    let reactions = total
        .reactions
        .iter()
        .map(|(node, r)| Reaction {
            force: [r[0], r[1], r[2]],
            moment: [r[3], r[4], r[5]],
            node: *node,
        })
        .collect();
    Report {
        analysis: match sizing.shells {
            None => serde_json::json!("frame"),
            Some(n) => serde_json::json!({ "shells": n }),
        },
        cases: s.cases[..s.first_combination]
            .iter()
            .map(|c| c.name.clone())
            .collect(),
        combinations: s
            .combinations
            .iter()
            .map(|c| CombinationRow {
                factors: sizing
                    .loads
                    .iter()
                    .zip(&c.factors)
                    .map(|((name, _, _), f)| (name.clone(), *f))
                    .collect(),
                limit: match c.limit {
                    Limit::Ultimate => "ULS",
                    Limit::Serviceability => "SLS",
                },
                name: c.name.clone(),
            })
            .collect(),
        converged: s.converged,
        definitions: Definitions {
            combinations: words::COMBINATIONS,
            displacement: words::DISPLACEMENT,
            end_forces: "under the sum of the loads, in the member's local axes: forces and moments the joints apply to its ends, [a: Fx Fy Fz Mx My Mz, b: ...]",
            model: match sizing.shells {
                None => "a node at mid-height of each node axis (the panels' centroid line), a member per edge with a solid rectangle: depth the panel height across the member (local y, in the panel plane), thickness the gauge (local z, the panel normal); rigid joints; linear elastic, Timoshenko beams".to_string(),
                Some(n) => format!("the panels as flat shells (four-node: incompatible-mode membrane, MITC4 bending), {n} elements up each panel and square along it, the gauge as thickness, welded along the node axes they share; a node's displacement is its axis' mid-height point's, a member's end forces the resultant its panel takes along that end's axis, about the mid-height point; fixed supports hold the whole axis, pinned ones its mid-height point"),
            },
            reactions: "under the sum of the loads: force and moment each support applies",
            utilisation: words::UTILISATION,
            weld_utilisation: words::WELD_UTILISATION,
        },
        deflection_rounds: s.deflection_rounds,
        edges,
        format: crate::analyze::sizing::FORMAT,
        gauges: sizing.gauges.clone(),
        group_by: match sizing.group_by {
            GroupBy::Member => serde_json::json!("member"),
            GroupBy::Chain => serde_json::json!("chain"),
            GroupBy::Assembly(k) => serde_json::json!({ "assembly": k }),
        },
        material: sizing.material.clone(),
        nodes,
        reactions,
        rounds: s.rounds,
        seam_groups: sizing.seam_groups,
        smooth: sizing.smooth,
        source: opts.name.clone(),
        supports: sizing
            .supports
            .iter()
            .map(|(sel, k)| format!("{sel}: {k:?}"))
            .collect(),
        totals: Totals {
            deflection_limit: s.deflection_limit,
            mass_kg: s.mass_kg,
            max_displacement: dmax,
            max_displacement_load: s.cases[s.deflection_case()].name.clone(),
            max_displacement_node: dnode,
            max_utilisation: s.max_utilisation(),
            max_weld_utilisation: s.max_weld_utilisation(),
            residual: total.residual,
            span: s.span,
            thin_sheet_welds: (0..s.throats.len())
                .filter(|&i| s.welds[i].is_some() && s.throats[i] < words::MIN_THROAT)
                .collect(),
        },
        units: [
            ("force", "N"),
            ("length", "mm"),
            ("mass", "kg"),
            ("moment", "N·mm"),
            ("stress", "MPa"),
        ]
        .into_iter()
        .collect(),
        version: crate::analyze::sizing::VERSION,
    }
}

impl Report {
    /// The sizing file's text (pretty JSON, one final newline).
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("reports serialise") + "\n"
    }
}
