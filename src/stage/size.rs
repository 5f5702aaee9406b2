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
use crate::analyze::sizing::{
    size, BuiltSteel, Limit, LoadSpec, Sizing, SizingError, SizingOptions,
};
pub use crate::analyze::sizing::{DeflectionLimit, GroupBy};
use crate::rationalize::axes::Axes;
use crate::rationalize::planarize::Selector;
use crate::rationalize::plates::{PlateError, PlateSet};
use crate::stage::plates::{self as plate_stage, Joints};
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
    /// How `plates` will join the plates (weld gap, node cores, bolts): the self-weight and
    /// the mass are the plates' as `plates` cuts them with these, and a seam whose bolts need
    /// thicker plies gets them. Default: plates' defaults.
    pub joints: Joints,
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
            joints: Joints::default(),
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
    #[error("{0}")]
    /// The joints cannot be made: an option of theirs, or a seam's bolts even on the thickest
    /// plies.
    Joints(#[source] plate_stage::Error),
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
            built: None,
            floor: Vec::new(),
        })
    }
}

/// Sizes the plate network of `axes`. `progress` may stop it before the analysis starts (one
/// analysis runs to its end: the rounds are not yet interruptible inside).
pub fn run(axes: &Axes, opts: &Options, progress: &dyn Progress) -> Result<Sized, Error> {
    let sizing_opts = opts.sizing()?;
    (opts.joints.check()).map_err(|e| Error::Joints(plate_stage::Error::Plates(e)))?;
    let mut notes = Vec::new();
    if opts.material.is_none() {
        notes.push(format!(
            "material 1.4404 (stainless 316L, f_y {} MPa), the default: give material= for another",
            sizing_opts.material.fy
        ));
    }
    progress.begin("sizing", None);
    checkpoint(progress)?;
    let (sizing, sizing_opts, weighed) = size_as_cut(axes, opts, sizing_opts, progress)?;
    notes.extend(weighed.note.clone());
    checkpoint(progress)?;
    let (max_u, max_w) = (sizing.max_utilisation(), sizing.max_weld_utilisation());
    let (_, max_d) = sizing.max_displacement();
    let deflection_ok = sizing.deflection_limit.is_none_or(|l| max_d <= l);
    let ok = max_u <= 1.0 && max_w <= 1.0 && deflection_ok;
    let report = report(&sizing, &sizing_opts, opts, &weighed);
    Ok(Sized {
        sizing,
        ok,
        report,
        notes,
    })
}

/// Rounds of sizing and cutting at most before the steel as cut is taken as it stands.
const CUT_ROUNDS: usize = 12;

/// The round from which the gauges only rise (see [`size_as_cut`]).
const SETTLE_FROM: usize = 4;

/// How the steel was weighed: the plates as cut, or why the uncut panels.
#[derive(Clone, Debug)]
pub struct Weighed {
    /// The plates as `plates` cuts them with the joints (false: the uncut panels).
    pub as_cut: bool,
    /// Rounds of sizing, each followed by a cut.
    pub rounds: usize,
    /// The plates cut from the final gauges, kg, against the analysis's (equal when settled).
    pub cut_kg: Option<f64>,
    /// A line for the user when the steel is not the plates as cut, or did not settle.
    pub note: Option<String>,
    /// Per edge, a seam's bolts as the last cut made them (what `plates` makes of this sizing).
    pub bolts: Vec<Option<BoltsRow>>,
}

/// Sizes, cuts the plates from the gauges as `plates` will, and sizes again on the steel as
/// cut (setbacks at the nodes, bolt holes, node cores) until the cut is the steel analysed;
/// a seam whose bolts do not hold (or fit) goes up to thicker plies.
fn size_as_cut(
    axes: &Axes,
    opts: &Options,
    mut sizing_opts: SizingOptions,
    progress: &dyn Progress,
) -> Result<(Sizing, SizingOptions, Weighed), Error> {
    let mut sizing = size(axes, &sizing_opts)?;
    let mut weighed = Weighed {
        as_cut: false,
        rounds: 1,
        cut_kg: None,
        note: None,
        bolts: Vec::new(),
    };
    let density = sizing_opts.material.density;
    loop {
        checkpoint(progress)?;
        match cut(axes, opts, &sizing_opts, &sizing) {
            Ok(set) => {
                let built = built_steel(&set, &sizing, density);
                weighed.bolts = seam_bolts(&set);
                weighed.cut_kg = Some(
                    set.mass_kg(density)
                        + built.nodes.iter().fold(0.0, |s, n| s + n.1)
                        + built.fasteners.iter().sum::<f64>(),
                );
                if sizing_opts
                    .built
                    .as_ref()
                    .is_some_and(|b| same_steel(b, &built))
                {
                    weighed.as_cut = true;
                    break;
                }
                if weighed.rounds >= CUT_ROUNDS {
                    weighed.as_cut = sizing_opts.built.is_some();
                    weighed.note = Some(format!(
                        "the steel as cut did not settle in {CUT_ROUNDS} rounds of sizing and \
                         cutting: the plates cut from these gauges weigh {:.3} kg, the analysis \
                         {:.3} kg",
                        weighed.cut_kg.unwrap_or(0.0),
                        sizing.mass_kg
                    ));
                    break;
                }
                sizing_opts.built = Some(built);
                if weighed.rounds >= SETTLE_FROM {
                    // Gauges that go back and forth between two cuts: from here they only
                    // rise, so the rounds settle.
                    let floor = &mut sizing_opts.floor;
                    floor.resize(sizing.gauges.len(), 0.0);
                    for (f, g) in floor.iter_mut().zip(&sizing.gauges) {
                        *f = f.max(*g);
                    }
                }
            }
            Err(plate_stage::Error::Plates(
                PlateError::BoltsOverloaded { edge, .. } | PlateError::NoRoomForBolt { edge, .. },
            )) if raise_floor(&mut sizing_opts, &sizing, edge) => {}
            Err(
                e @ plate_stage::Error::Plates(
                    PlateError::BoltsOverloaded { .. } | PlateError::NoRoomForBolt { .. },
                ),
            )
            | Err(e @ plate_stage::Error::Option(_)) => return Err(Error::Joints(e)),
            Err(e) => {
                // Axes `plates` cannot cut: the uncut panels, said.
                weighed.note = Some(format!(
                    "the self-weight is the uncut panels' (setbacks and bolt holes not taken \
                     off): the plates cannot be cut from these axes ({e})"
                ));
                weighed.bolts.clear();
                if sizing_opts.built.take().is_some() {
                    sizing = size(axes, &sizing_opts)?;
                }
                break;
            }
        }
        sizing = size(axes, &sizing_opts)?;
        weighed.rounds += 1;
    }
    Ok((sizing, sizing_opts, weighed))
}

/// Per edge of `set`, a seam's bolts: size, class, count and their Table 3.4 checks.
fn seam_bolts(set: &PlateSet) -> Vec<Option<BoltsRow>> {
    (set.by_edge.iter())
        .map(|list| match list.as_slice() {
            [a, _] => {
                let p = &set.plates[*a];
                let b = p.bolt?;
                let (utilisation, check) = b.checks.map(|c| c.governing()).unzip();
                Some(BoltsRow {
                    check,
                    class: b.grade.name,
                    count: p.holes.len(),
                    size: b.size.name,
                    utilisation,
                })
            }
            _ => None,
        })
        .collect()
}

/// Whether two weighings of the steel agree (to a millionth of a mm² per ply).
fn same_steel(a: &BuiltSteel, b: &BuiltSteel) -> bool {
    let near = |x: f64, y: f64| (x - y).abs() <= 1e-6 * x.abs().max(1.0);
    a.nodes.len() == b.nodes.len()
        && (a.nodes.iter().zip(&b.nodes)).all(|(x, y)| x.0 == y.0 && near(x.1, y.1))
        && (a.fasteners.iter().zip(&b.fasteners)).all(|(x, y)| near(*x, *y))
        && a.areas.len() == b.areas.len()
        && (a.areas.iter().zip(&b.areas)).all(|(x, y)| near(x[0], y[0]) && near(x[1], y[1]))
}

/// Puts a floor under member `edge` one stack above its gauge in `sizing` (its bolts need
/// thicker plies); false when it is on the thickest already.
fn raise_floor(sizing_opts: &mut SizingOptions, sizing: &Sizing, edge: usize) -> bool {
    let now = sizing.gauges[edge];
    let Some(next) = crate::analyze::sizing::stacks(&sizing_opts.gauges)
        .into_iter()
        .map(|c| c.0)
        .find(|&t| t > now + 1e-9)
    else {
        return false;
    };
    if sizing_opts.floor.is_empty() {
        sizing_opts.floor = vec![0.0; sizing.gauges.len()];
    }
    sizing_opts.floor[edge] = next;
    true
}

/// The plates `plates` cuts from `sizing` with the joints of `opts`.
fn cut(
    axes: &Axes,
    opts: &Options,
    sizing_opts: &SizingOptions,
    sizing: &Sizing,
) -> Result<PlateSet, plate_stage::Error> {
    let mut p = plate_stage::Options {
        sizing: Some(plate_stage::Gauges {
            per_edge: sizing.gauges.clone(),
            list: sizing_opts.gauges.clone(),
            material: Some(sizing_opts.material.clone()),
            seam_groups: sizing_opts.seam_groups,
            seam_forces: (0..sizing.gauges.len())
                .map(|k| sizing.seam_forces(k))
                .collect(),
            joints: None,
        }),
        groups: sizing_opts.seam_groups.unwrap_or(1),
        material: Some(sizing_opts.material.clone()),
        ..Default::default()
    };
    opts.joints.apply(&mut p);
    let (options, _, _) = plate_stage::plate_options(axes, &p)?;
    Ok(crate::rationalize::plates::plates(axes, &options)?)
}

/// The steel of `set`: each edge's plates' areas (a seam's by the sizing's plies) and the
/// node cores' masses.
fn built_steel(set: &PlateSet, sizing: &Sizing, density: f64) -> BuiltSteel {
    let areas = (set.by_edge.iter().enumerate())
        .map(|(k, list)| match list.as_slice() {
            [one] => [set.plates[*one].area(), 0.0],
            [a, b] => {
                let (pa, pb) = (&set.plates[*a], &set.plates[*b]);
                // The sizing's first ply is the one welded at the member's first node.
                let first = sizing.model.members[k]
                    .section
                    .plies
                    .map_or(pa.thickness, |p| p[0]);
                if (pa.thickness - first).abs() < 1e-9 {
                    [pa.area(), pb.area()]
                } else {
                    [pb.area(), pa.area()]
                }
            }
            _ => [0.0, 0.0],
        })
        .collect();
    // A seam's bolts: its first ply's holes, each a set of the length ordered.
    let fasteners = (set.by_edge.iter())
        .map(|list| match list.as_slice() {
            [a, _] => {
                let p = &set.plates[*a];
                p.bolt.map_or(0.0, |b| {
                    let each = crate::rationalize::bolts::set_volume(&b.size, b.length);
                    each * p.holes.len() as f64 * density * 1e-6
                })
            }
            _ => 0.0,
        })
        .collect();
    BuiltSteel {
        areas,
        fasteners,
        nodes: (set.cores.iter())
            .map(|c| (c.node as usize, c.mass_kg(density)))
            .collect(),
    }
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
    /// The joints the plates were weighed with as `plates` cuts them; None when the self-weight
    /// is the uncut panels' (`totals.self_weight` says why).
    pub joints: Option<JointsRow>,
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

/// The joints `plates` must be given to cut what was analysed.
#[derive(Clone, Debug, Serialize)]
pub struct JointsRow {
    /// The joints.
    #[serde(skip)]
    pub joints: Joints,
    /// The bolt size asked for; None: by the grip.
    pub bolt: Option<&'static str>,
    /// The socket asked for, mm; None: one for each size.
    pub bolt_clearance: Option<SocketRow>,
    /// The node core's tube, mm; None: none.
    pub node_core: Option<CoreRow>,
    /// Root gap at the nodes, mm.
    pub weld_gap: f64,
    /// How far a root gap may be from it, mm.
    pub weld_gap_tolerance: f64,
}

/// A socket, mm.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SocketRow {
    /// Its radius.
    pub radius: f64,
    /// How far it reaches from the washer.
    pub reach: f64,
}

/// A node core's tube, mm.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CoreRow {
    /// Outer diameter.
    pub diameter: f64,
    /// Wall.
    pub wall: f64,
}

impl JointsRow {
    fn of(j: &Joints) -> JointsRow {
        JointsRow {
            joints: *j,
            bolt: j.bolt.map(|b| b.name),
            bolt_clearance: j.bolt_clearance.map(|s| SocketRow {
                radius: s.radius,
                reach: s.height,
            }),
            node_core: j.node_core.map(|c| CoreRow {
                diameter: c.diameter,
                wall: c.wall,
            }),
            weld_gap: j.weld_gap,
            weld_gap_tolerance: j.weld_gap_tolerance,
        }
    }
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
    /// A seam's bolts as `plates` cuts them from this sizing, and their EN 1993-1-8 Table 3.4
    /// checks under `seam_forces`; None for a single plate (and when `joints` is None).
    pub bolts: Option<BoltsRow>,
    /// A seam's bolt sets (bolts, nuts, two washers each), kg, in its self-weight; None for a
    /// single plate (and when `joints` is None).
    pub bolts_kg: Option<f64>,
    /// Its steel in the analysis (self-weight and mass), kg: its plates as cut, a seam's two
    /// plies together (the uncut panel when `joints` is None).
    pub mass_kg: f64,
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

/// A seam's bolts.
#[derive(Clone, Debug, Serialize)]
pub struct BoltsRow {
    /// The Table 3.4 check that governs (None: not checked).
    pub check: Option<&'static str>,
    /// Property class (8.8 with carbon steel, A4-70 with stainless).
    pub class: &'static str,
    /// Bolts in the row.
    pub count: usize,
    /// M6 … M30.
    pub size: &'static str,
    /// The most loaded bolt's governing utilisation (shear, bearing, tension, punching, shear
    /// with tension).
    pub utilisation: Option<f64>,
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
    /// The node core's mass, kg, in the self-weight at this node; None without a core.
    pub core_kg: Option<f64>,
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
    /// The seams' bolt sets in `mass_kg`, kg.
    pub bolts_kg: f64,
    /// The node cores in `mass_kg`, kg.
    pub cores_kg: f64,
    /// The deflection limit, mm.
    pub deflection_limit: Option<f64>,
    /// The steel analysed, kg: the plates (as cut, unless `joints` is None), the seams' bolt
    /// sets and the node cores.
    pub mass_kg: f64,
    /// Largest displacement under the serviceability combinations, mm.
    pub max_displacement: f64,
    /// The serviceability combination giving the largest displacement.
    pub max_displacement_load: String,
    /// The node that moves most.
    pub max_displacement_node: usize,
    /// The largest bolt utilisation over the seams (EN 1993-1-8 Table 3.4); None without seams.
    pub max_bolt_utilisation: Option<f64>,
    /// Largest member utilisation.
    pub max_utilisation: f64,
    /// Largest weld utilisation.
    pub max_weld_utilisation: f64,
    /// Largest out-of-balance force over the largest load.
    pub residual: f64,
    /// What the self-weight is made of.
    pub self_weight: String,
    /// The structure's largest horizontal extent, mm.
    pub span: f64,
    /// Nodes whose weld throat is below 3 mm (EN 1993-1-8 §4.5.2(2)): welded by a
    /// thin-sheet procedure.
    pub thin_sheet_welds: Vec<usize>,
}

fn report(s: &Sizing, sizing: &SizingOptions, opts: &Options, weighed: &Weighed) -> Report {
    let core_kg = |i: usize| {
        (sizing.built.iter().flat_map(|b| &b.nodes))
            .find(|n| n.0 == i)
            .map(|n| n.1)
    };
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
                bolts: weighed.bolts.get(k).cloned().flatten(),
                bolts_kg: (sizing.built.as_ref())
                    .map(|b| b.fasteners[k])
                    .filter(|_| m.section.plies.is_some()),
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
                mass_kg: s.member_kg[k],
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
                core_kg: core_kg(i),
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
        joints: weighed.as_cut.then(|| JointsRow::of(&opts.joints)),
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
            max_bolt_utilisation: (weighed.bolts.iter().flatten())
                .filter_map(|b| b.utilisation)
                .reduce(f64::max),
            bolts_kg: (sizing.built.iter().flat_map(|b| &b.fasteners)).fold(0.0, |s, x| s + x),
            cores_kg: (sizing.built.iter().flat_map(|b| &b.nodes)).fold(0.0, |s, n| s + n.1),
            self_weight: match (weighed.as_cut, &weighed.note) {
                (true, None) => format!(
                    "the plates as `plates` cuts them from these gauges with the joints \
                     (setbacks at the nodes and bolt holes taken off), each seam's bolt sets \
                     (bolt, nut, two washers: nominal cylinders, hexagon prisms and rings) along \
                     it, each node core at its node: {} round(s) of sizing and cutting, the last \
                     cut's steel the steel analysed{}",
                    weighed.rounds,
                    if weighed.rounds > SETTLE_FROM {
                        format!(
                            " (from round {SETTLE_FROM} on each round's gauges were the next's \
                             least, so that the rounds settle: the figures of rounds and \
                             stiffening are the last round's)"
                        )
                    } else {
                        String::new()
                    }
                ),
                (_, Some(note)) => note.clone(),
                (false, None) => "the uncut panels".into(),
            },
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
