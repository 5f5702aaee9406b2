//! Sizing the plates of a network from a frame analysis, as Karamba's cross-section
//! optimisation does: every member (or group) gets the thinnest gauge whose utilisation is at
//! most 1, the analysis is repeated with the new sections (and their weight) until nothing
//! changes; then gauges are raised where they stiffen most until the deflection limit holds;
//! optionally neighbours are kept within one gauge step.
//!
//! The model ([`build`]): a node at the middle of each node axis' panel height (the centroid line
//! of every panel meeting there), a member per edge with a solid rectangular section, depth the
//! panel's height across the member and thickness its gauge, the depth in the panel plane.
//!
//! Loads are permanent (self-weight, or a load marked `:G`) or variable (point loads and wind)
//! and combined as EN 1990 says ([`combinations`]): members and welds are checked under the
//! ultimate combinations (6.10, with both γ_G = 1.35 and 1.0), the deflection under the
//! characteristic serviceability ones (6.14b). The loads one by one and their sum are analysed
//! too: sizing.json's displacements, end forces and reactions are the sum's.
//!
//! Checks per member, at five points along it, in every ultimate combination:
//! - `stress`: von Mises from the largest normal stress at a corner of the section (axial force
//!   and both bending moments) and the largest shear stress (torsion, Roark's modulus, plus
//!   1.5 V/A of the resultant shear; the two are added although their peaks are at different
//!   points, which is safe), over f_y/γ_M0;
//! - `buckling`: the compression over the weak-axis flexural buckling resistance of the member
//!   as a pin-ended strut (EN 1993-1-1 §6.3.1.2, curve c for solid sections, L_cr = L), over
//!   χ A f_y/γ_M1;
//! - `lateral-torsional`: the largest in-plane moment over χ_LT W_el f_y/γ_M1 (§6.3.2.2, curve
//!   d for "other sections"), M_cr of the rectangle restrained against twist at its nodes only
//!   (C1 π/L √(E I_weak G I_t), no warping stiffness), C1 from the moment diagram;
//! - `interaction`: compression with bending about both axes, (6.61) and (6.62), with Annex B's
//!   factors for elastic sections and the largest C_m, C_mLT and k_zy (1).
//!
//! Welds (EN 1993-1-8 §4.5.3.3, the simplified method): each member end is held by two fillet
//! welds of throat a (0.7 × the thinner of the plates meeting at the node) along its depth, one
//! on each face; the force per length is the sum of the parts from every end force (axial,
//! shears, in-plane moment as a line's bending, out-of-plane moment as a couple across the
//! thickness, torsion as the two lines' polar moment), over f_vw,d · a with
//! f_vw,d = f_u / (√3 β_w γ_M2). The welds are part of the sizing: where one does not hold,
//! the plates at its node thinner than it needs go up the gauge list; where even the thickest
//! gauge is not enough the sizing stops ([`SizingError::WeldsExhausted`]). A throat below 3 mm
//! (§4.5.2(2)) is named in the report: such a joint needs a thin-sheet procedure.

use glam::DVec3;
use thiserror::Error;

use super::frame::{self, CaseResult, Elastic, FrameError, LoadCase, Member, Model, Section};
use super::material::Material;
use super::shell;
use crate::rationalize::axes::Axes;
use crate::rationalize::clearance::Socket;
use crate::rationalize::groups::{partition, GroupError};
use crate::rationalize::planarize::Selector;
use crate::rationalize::plates::{seam_gauges, CoreSize, Joints};

pub use super::frame::Support;

pub const GRAVITY: f64 = 9.80665;
/// Stations along a member where it is checked, as fractions of its length.
const STATIONS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// Permanent (G) or variable (Q), as EN 1990 §4.1.1 classes an action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    Permanent,
    Variable,
}

/// A load as given on the command line.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadSpec {
    /// The plates' weight, times a factor.
    SelfWeight { factor: f64 },
    /// A force (N) on every node the selector picks.
    Point { nodes: Selector, force: DVec3 },
    /// Pressure (kPa) on each panel's area projected across the direction, acting along it.
    Wind { pressure: f64, direction: DVec3 },
}

impl LoadSpec {
    /// A load and its action: self-weight is permanent; a point load or wind is variable
    /// unless it ends in `:G` (`:Q` says variable).
    pub fn parse_action(s: &str) -> Result<(LoadSpec, Action), String> {
        let t = s.trim();
        let (body, marked) = match t.rsplit_once(':') {
            Some((b, "G")) => (b, Some(Action::Permanent)),
            Some((b, "Q")) => (b, Some(Action::Variable)),
            _ => (t, None),
        };
        let spec = LoadSpec::parse(body)?;
        let action = match (&spec, marked) {
            (LoadSpec::SelfWeight { .. }, Some(Action::Variable)) => {
                return Err(format!("`{t}`: self-weight is permanent (G), not variable"))
            }
            (LoadSpec::SelfWeight { .. }, _) => Action::Permanent,
            (_, Some(a)) => a,
            (_, None) => Action::Variable,
        };
        Ok((spec, action))
    }

    /// The combination value factor ψ0 of a variable load (EN 1990 Table A1.1): wind 0.6,
    /// a point load as an imposed load of categories A to D, 0.7.
    pub fn psi0(&self) -> f64 {
        match self {
            LoadSpec::Wind { .. } => 0.6,
            _ => 0.7,
        }
    }

    /// `self-weight[:FACTOR]`, `point:SELECTOR:FX,FY,FZ` (N), `wind:KPA:DX,DY,DZ`.
    pub fn parse(s: &str) -> Result<LoadSpec, String> {
        let s = s.trim();
        let vector = |t: &str| -> Result<DVec3, String> {
            let v: Vec<f64> = t
                .split(',')
                .map(|c| c.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("`{s}`: `{t}` is not three numbers x,y,z"))?;
            match v[..] {
                [x, y, z] if v.iter().all(|c| c.is_finite() && c.abs() <= 1e12) => {
                    Ok(DVec3::new(x, y, z))
                }
                _ => Err(format!("`{s}`: `{t}` is not three finite numbers x,y,z")),
            }
        };
        if let Some(rest) = s.strip_prefix("self-weight") {
            let factor = match rest.strip_prefix(':') {
                None if rest.is_empty() => 1.0,
                Some(f) => f
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0 && *v <= 100.0)
                    .ok_or_else(|| format!("`{s}`: the factor must be from 0 to 100"))?,
                None => return Err(format!("`{s}`: give self-weight or self-weight:FACTOR")),
            };
            return Ok(LoadSpec::SelfWeight { factor });
        }
        if let Some(rest) = s.strip_prefix("point:") {
            let (sel, force) = rest
                .rsplit_once(':')
                .ok_or_else(|| format!("`{s}`: give point:NODES:FX,FY,FZ (N)"))?;
            let nodes = Selector::parse(sel).map_err(|e| format!("`{s}`: {e}"))?;
            return Ok(LoadSpec::Point {
                nodes,
                force: vector(force)?,
            });
        }
        if let Some(rest) = s.strip_prefix("wind:") {
            let (q, dir) = rest
                .split_once(':')
                .ok_or_else(|| format!("`{s}`: give wind:KPA:DX,DY,DZ"))?;
            let pressure = q
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0 && *v <= 100.0)
                .ok_or_else(|| format!("`{s}`: the pressure must be from 0 to 100 kPa"))?;
            let direction = vector(dir)?
                .try_normalize()
                .ok_or_else(|| format!("`{s}`: the direction is zero"))?;
            return Ok(LoadSpec::Wind {
                pressure,
                direction,
            });
        }
        Err(format!(
            "`{s}`: a load is self-weight[:FACTOR], point:NODES:FX,FY,FZ or wind:KPA:DX,DY,DZ"
        ))
    }
}

/// Members sized together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GroupBy {
    Member,
    /// Runs of members through nodes with two members.
    Chain,
    /// The assembly groups `plates --groups K` makes (the same partition of the nodes): the
    /// members inside each group together, and the seam members between each pair of groups.
    Assembly(usize),
}

/// A limit on the largest displacement under the sum of the loads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeflectionLimit {
    /// The span over this (the span: the network's largest horizontal extent).
    Ratio(f64),
    Millimetres(f64),
}

impl DeflectionLimit {
    /// `L/300` or a length in mm.
    pub fn parse(s: &str) -> Result<DeflectionLimit, String> {
        let t = s.trim();
        let num = |v: &str| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x > 0.0 && *x <= 1e9)
        };
        if let Some(r) = t.strip_prefix("L/") {
            return num(r)
                .map(DeflectionLimit::Ratio)
                .ok_or_else(|| format!("`{s}`: give L/N with N a positive number"));
        }
        num(t)
            .map(DeflectionLimit::Millimetres)
            .ok_or_else(|| format!("`{s}`: give L/N or a length in mm"))
    }
}

#[derive(Clone, Debug)]
pub struct SizingOptions {
    pub material: Material,
    /// Ascending, mm.
    pub gauges: Vec<f64>,
    pub supports: Vec<(Selector, Support)>,
    /// Each load as written, what it is and its action.
    pub loads: Vec<(String, LoadSpec, Action)>,
    pub deflection_limit: Option<DeflectionLimit>,
    pub group_by: GroupBy,
    pub smooth: bool,
    /// Fillet throat over the thinner plate.
    pub throat_factor: f64,
    /// Rounds of analysis and choice at most.
    pub max_rounds: usize,
    /// Analyse the panels as flat shells, this many elements up each (even), not as beams.
    pub shells: Option<usize>,
    /// The assembly groups `plates` will cut (`plates --groups K`): a member between two
    /// groups is a bolted seam of two plies, sized as such from the sums of two gauges.
    pub seam_groups: Option<usize>,
    /// The steel as cut (from `plates`): what the self-weight and the mass are made of. None:
    /// the uncut panels.
    pub built: Option<BuiltSteel>,
    /// Per member, the least gauge (a seam's stack) it may take, mm: what the joints ask of it
    /// (a seam whose bolts need thicker plies). Empty: none.
    pub floor: Vec<f64>,
}

/// The steel of the plates as cut: per edge the area of each ply left after the setbacks at
/// the nodes and the bolt holes (a single plate's in the first), and the steel at the nodes
/// (node cores), kg.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltSteel {
    /// Per edge, mm²: `[ply a, ply b]` of a seam, `[plate, 0]` of a single plate.
    pub areas: Vec<[f64; 2]>,
    /// Per node with a core, its mass, kg.
    pub nodes: Vec<(usize, f64)>,
    /// Per edge, the mass of a seam's bolt sets (bolts, nuts, washers), kg; 0 elsewhere.
    pub fasteners: Vec<f64>,
}

#[derive(Debug, Error)]
pub enum SizingError {
    #[error("load= is needed: give at least one")]
    NoLoad,
    #[error(
        "the panels make {0} shell elements, more than {max}: give shells= fewer elements up each panel, or analyse the frame",
        max = shell::MAX_ELEMENTS
    )]
    TooManyShells(usize),
    #[error("no support: no node matches {0}")]
    SupportUnused(String),
    #[error("load {0}: no node matches it")]
    LoadUnused(String),
    #[error(
        "node {0}: its axis or height cannot make a section (zero height or an axis along an edge)"
    )]
    BadNode(usize),
    #[error(
        "gauges= is too thin for the welds: at node {node} the weld is utilised {utilisation:.3} \
         with a throat of {throat:.2} mm on the thickest gauge ({thickest} mm); it needs \
         {needed:.2} mm: add a thicker gauge or give a larger throat="
    )]
    WeldsExhausted {
        node: usize,
        utilisation: f64,
        throat: f64,
        needed: f64,
        thickest: f64,
    },
    #[error(transparent)]
    Frame(#[from] FrameError),
    #[error("{0}")]
    Groups(#[from] GroupError),
}

/// Per member and case, what governs.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    pub utilisation: f64,
    /// One of [`CHECK_NAMES`], or `weld`.
    pub check: &'static str,
    /// Index of the load case (`cases()` order).
    pub case: usize,
}

/// Which limit state a combination serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// EN 1990 6.10: strength and stability.
    Ultimate,
    /// EN 1990 6.14b, characteristic: deflection.
    Serviceability,
}

/// Partial factors of EN 1990 Table A1.2(B) (set B, STR/GEO): permanent actions unfavourable and
/// favourable, variable ones.
pub const GAMMA_G_SUP: f64 = 1.35;
pub const GAMMA_G_INF: f64 = 1.0;
pub const GAMMA_Q: f64 = 1.5;

/// A combination of the loads: a factor per load (in the loads' order).
#[derive(Clone, Debug, PartialEq)]
pub struct Combination {
    pub name: String,
    pub limit: Limit,
    pub factors: Vec<f64>,
}

/// The combinations of EN 1990 for the loads given: for ultimate limit states (6.10) the
/// permanent loads at γ_G,sup = 1.35 with each variable load leading at γ_Q = 1.5 and the others
/// at γ_Q ψ0, and the same with the permanent loads at γ_G,inf = 1.0 (favourable, as under wind
/// uplift); for serviceability (6.14b, characteristic) the permanent loads at 1 with each
/// variable load leading at 1 and the others at ψ0. Without variable loads: 1.35 G and G.
pub fn combinations(loads: &[(String, LoadSpec, Action)]) -> Vec<Combination> {
    let variable: Vec<usize> = (0..loads.len())
        .filter(|&i| loads[i].2 == Action::Variable)
        .collect();
    let leads: Vec<Option<usize>> = if variable.is_empty() {
        vec![None]
    } else {
        variable.iter().map(|&i| Some(i)).collect()
    };
    let make = |limit: Limit, g: f64, q: f64, lead: Option<usize>| {
        let factors: Vec<f64> = loads
            .iter()
            .enumerate()
            .map(|(i, (_, spec, action))| match action {
                Action::Permanent => g,
                Action::Variable if Some(i) == lead => q,
                Action::Variable => q * spec.psi0(),
            })
            .collect();
        let terms: Vec<String> = loads
            .iter()
            .zip(&factors)
            .map(|((name, _, _), f)| {
                if *f == 1.0 {
                    name.clone()
                } else {
                    format!("{} × {name}", fmt_factor(*f))
                }
            })
            .collect();
        let tag = match limit {
            Limit::Ultimate => "ULS",
            Limit::Serviceability => "SLS",
        };
        Combination {
            name: format!("{tag}: {}", terms.join(" + ")),
            limit,
            factors,
        }
    };
    let mut out = Vec::new();
    let has_g = loads.iter().any(|l| l.2 == Action::Permanent);
    for &lead in &leads {
        out.push(make(Limit::Ultimate, GAMMA_G_SUP, GAMMA_Q, lead));
    }
    if has_g && !variable.is_empty() {
        for &lead in &leads {
            out.push(make(Limit::Ultimate, GAMMA_G_INF, GAMMA_Q, lead));
        }
    }
    for &lead in &leads {
        out.push(make(Limit::Serviceability, 1.0, 1.0, lead));
    }
    out
}

/// A factor as few digits as it needs (1.05, not 1.0500000000000003).
fn fmt_factor(f: f64) -> String {
    let r = (f * 1e6).round() / 1e6;
    format!("{r}")
}

#[derive(Clone, Debug)]
pub struct Sizing {
    pub model: Model,
    /// The loads one by one (characteristic), their sum when there are several, then the
    /// combinations (see [`Sizing::combinations`]).
    pub cases: Vec<LoadCase>,
    pub results: Vec<CaseResult>,
    /// The combinations, the case of the first at `first_combination`.
    pub combinations: Vec<Combination>,
    pub first_combination: usize,
    pub gauges: Vec<f64>,
    pub checks: Vec<Check>,
    /// Per member, by check ([`CHECK_NAMES`]): the largest utilisation and its case.
    pub by_check: Vec<[(f64, usize); 4]>,
    /// Per node: the largest weld utilisation and its case.
    pub welds: Vec<Option<Check>>,
    pub throats: Vec<f64>,
    pub rounds: usize,
    pub converged: bool,
    pub deflection_rounds: usize,
    /// The limit in mm, when one is set.
    pub deflection_limit: Option<f64>,
    pub span: f64,
    /// The steel analysed, kg: the members', the seams' bolt sets and the node cores'.
    pub mass_kg: f64,
    /// Per member, its steel, kg (a seam's two plies together).
    pub member_kg: Vec<f64>,
    /// Elements up each panel when the panels were analysed as shells; None for the frame.
    pub shells: Option<usize>,
}

impl Sizing {
    /// The case that sums every load at its characteristic value (the only load when there is
    /// one): the state sizing.json's displacements, end forces and reactions describe.
    pub fn total(&self) -> &CaseResult {
        &self.results[self.first_combination - 1]
    }

    /// The loads of [`Sizing::total`].
    pub fn total_case(&self) -> &LoadCase {
        &self.cases[self.first_combination - 1]
    }

    /// What a seam's bolts carry: member `k`'s section forces in its local axes [N, V_y, V_z,
    /// T, M_y, M_z], each the largest magnitude at either end over the ultimate combinations
    /// (None for a member that is no seam).
    pub fn seam_forces(&self, k: usize) -> Option<[f64; 6]> {
        self.model.members[k].section.plies?;
        let mut out = [0.0f64; 6];
        for c in self.limit_cases(Limit::Ultimate) {
            let f = &self.results[c].end_forces[k];
            for (i, o) in out.iter_mut().enumerate() {
                *o = o.max(f[i].abs()).max(f[i + 6].abs());
            }
        }
        Some(out)
    }

    /// The case index of each combination for `limit`.
    pub fn limit_cases(&self, limit: Limit) -> Vec<usize> {
        limit_cases(&self.combinations, self.first_combination, limit)
    }

    /// The serviceability combination whose largest displacement is largest, that node and
    /// how far, mm: what the deflection limit is checked against.
    pub fn max_displacement(&self) -> (usize, f64) {
        let c = self.deflection_case();
        max_displacement(&self.results[c])
    }

    /// The case of the serviceability combination that moves a node most.
    pub fn deflection_case(&self) -> usize {
        deflection_case(&self.results, &self.limit_cases(Limit::Serviceability))
    }

    /// The largest member utilisation.
    pub fn max_utilisation(&self) -> f64 {
        self.checks
            .iter()
            .map(|c| c.utilisation)
            .fold(0.0, f64::max)
    }

    /// The largest weld utilisation.
    pub fn max_weld_utilisation(&self) -> f64 {
        self.welds
            .iter()
            .flatten()
            .map(|c| c.utilisation)
            .fold(0.0, f64::max)
    }

    /// The mean gauge of the lowest third of the members (by the height of their midpoints)
    /// and of the highest third, mm: a structure standing on its base should be thicker low.
    pub fn mean_gauges_low_high(&self) -> (f64, f64) {
        let m = &self.model;
        let mid: Vec<f64> = m
            .members
            .iter()
            .map(|e| 0.5 * (m.nodes[e.a].z + m.nodes[e.b].z))
            .collect();
        let mut order: Vec<usize> = (0..mid.len()).collect();
        order.sort_by(|&a, &b| mid[a].total_cmp(&mid[b]));
        let third = order.len() / 3;
        let mean = |ks: &[usize]| ks.iter().map(|&k| self.gauges[k]).sum::<f64>() / ks.len() as f64;
        (mean(&order[..third]), mean(&order[order.len() - third..]))
    }
}

/// The frame of a network with a gauge per edge (see the module notes).
pub fn build(
    axes: &Axes,
    gauges: &[f64],
    supports: &[(Selector, Support)],
    material: &Material,
) -> Result<Model, SizingError> {
    let nodes: Vec<DVec3> = (0..axes.positions.len())
        .map(|i| axes.positions[i] + axes.axes[i] * (0.5 * axes.heights[i]))
        .collect();
    let mut members = Vec::with_capacity(axes.edges.len());
    for (k, &[a, b]) in axes.edges.iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        let x = (nodes[b] - nodes[a]).normalize_or_zero();
        let across = |i: usize| {
            let d = axes.axes[i] - x * axes.axes[i].dot(x);
            (d * axes.heights[i], d.length() * axes.heights[i])
        };
        let ((ya, da), (yb, db)) = (across(a), across(b));
        let depth = 0.5 * (da + db);
        let y = (ya + yb).try_normalize().ok_or(SizingError::BadNode(a))?;
        if depth.is_nan() || depth <= 0.0 {
            return Err(SizingError::BadNode(a));
        }
        members.push(Member {
            a,
            b,
            y,
            section: Section::solid(depth, gauges[k]),
        });
    }
    let mut held = vec![None; nodes.len()];
    for (sel, kind) in supports {
        let mut used = false;
        for (i, p) in axes.positions.iter().enumerate() {
            if sel.matches(i as u32, *p) {
                held[i] = Some(*kind);
                used = true;
            }
        }
        if !used {
            return Err(SizingError::SupportUnused(sel.to_string()));
        }
    }
    Ok(Model {
        nodes,
        members,
        supports: held,
        elastic: Elastic {
            e: material.e,
            g: material.shear_modulus(),
        },
    })
}

/// Each panel's area (its quad from the node axes), mm².
fn panel_areas(axes: &Axes) -> Vec<f64> {
    axes.quads()
        .iter()
        .map(|q| 0.5 * ((q[2] - q[0]).cross(q[3] - q[1])).length())
        .collect()
}

/// The steel of member `k` with `section`, kg: its plates as cut when they are known (a seam's
/// plies each by its own area), else its uncut panel (`areas`, mm²).
fn steel_kg(areas: &[f64], opts: &SizingOptions, k: usize, section: &Section) -> f64 {
    let volume = match (&opts.built, section.plies) {
        (Some(b), Some([ta, tb])) => b.areas[k][0] * ta + b.areas[k][1] * tb,
        (Some(b), None) => b.areas[k][0] * section.thickness,
        (None, _) => areas[k] * section.thickness,
    };
    volume * opts.material.density * 1e-6
}

/// The bolt sets through member `k`, kg (0 when the plates are not known).
fn fastener_kg(opts: &SizingOptions, k: usize) -> f64 {
    opts.built.as_ref().map_or(0.0, |b| b.fasteners[k])
}

/// The steel at the nodes (cores), kg.
fn node_steel_kg(opts: &SizingOptions) -> f64 {
    opts.built
        .iter()
        .flat_map(|b| &b.nodes)
        .fold(0.0, |s, n| s + n.1)
}

/// The load cases: one per load, their sum (when there are several), then the combinations of
/// [`combinations`] in their order.
pub fn cases(
    axes: &Axes,
    model: &Model,
    opts: &SizingOptions,
) -> Result<Vec<LoadCase>, SizingError> {
    if opts.loads.is_empty() {
        return Err(SizingError::NoLoad);
    }
    let areas = panel_areas(axes);
    let mut out = Vec::new();
    for (name, spec, _) in &opts.loads {
        let mut case = LoadCase {
            name: name.clone(),
            ..Default::default()
        };
        match spec {
            LoadSpec::SelfWeight { factor } => {
                for (k, m) in model.members.iter().enumerate() {
                    let l = model.nodes[m.a].distance(model.nodes[m.b]);
                    let kg = steel_kg(&areas, opts, k, &m.section) + fastener_kg(opts, k);
                    let newtons = kg * GRAVITY * factor;
                    case.member.push((k, DVec3::new(0.0, 0.0, -newtons / l)));
                }
                for &(i, kg) in opts.built.iter().flat_map(|b| &b.nodes) {
                    let newtons = kg * GRAVITY * factor;
                    case.nodal.push((i, [0.0, 0.0, -newtons, 0.0, 0.0, 0.0]));
                }
            }
            LoadSpec::Point { nodes, force } => {
                for (i, p) in axes.positions.iter().enumerate() {
                    if nodes.matches(i as u32, *p) {
                        case.nodal
                            .push((i, [force.x, force.y, force.z, 0.0, 0.0, 0.0]));
                    }
                }
                if case.nodal.is_empty() {
                    return Err(SizingError::LoadUnused(name.clone()));
                }
            }
            LoadSpec::Wind {
                pressure,
                direction,
            } => {
                for (k, m) in model.members.iter().enumerate() {
                    let (_, _, z, l) = frame::local_frame(model, m);
                    let newtons = pressure * 1e-3 * areas[k] * z.dot(*direction).abs();
                    case.member.push((k, *direction * (newtons / l)));
                }
            }
        }
        out.push(case);
    }
    let singles = out.len();
    if singles > 1 {
        let all = weighted(&out, "all loads".into(), &vec![1.0; singles]);
        out.push(all);
    }
    for c in combinations(&opts.loads) {
        let case = weighted(&out[..singles], c.name, &c.factors);
        out.push(case);
    }
    Ok(out)
}

/// The loads of `cases`, each times its factor, as one case.
fn weighted(cases: &[LoadCase], name: String, factors: &[f64]) -> LoadCase {
    let mut sum = LoadCase {
        name,
        ..Default::default()
    };
    for (c, &f) in cases.iter().zip(factors) {
        sum.nodal
            .extend(c.nodal.iter().map(|&(i, v)| (i, v.map(|x| x * f))));
        sum.member.extend(c.member.iter().map(|&(k, w)| (k, w * f)));
    }
    sum
}

/// A member's utilisation by each check, for one case.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MemberChecks {
    /// Von Mises at the worst corner over f_y/γ_M0.
    pub stress: f64,
    /// Compression over the flexural buckling resistance about the weak axis (§6.3.1).
    pub buckling: f64,
    /// In-plane bending over the lateral-torsional buckling resistance (§6.3.2.2).
    pub lateral_torsional: f64,
    /// Compression with bending about both axes (§6.3.3, (6.61) and (6.62)).
    pub interaction: f64,
}

/// The checks' names, in [`MemberChecks::values`]' order, as sizing.json writes them.
pub const CHECK_NAMES: [&str; 4] = ["stress", "buckling", "lateral-torsional", "interaction"];

impl MemberChecks {
    pub fn values(&self) -> [f64; 4] {
        [
            self.stress,
            self.buckling,
            self.lateral_torsional,
            self.interaction,
        ]
    }

    /// The largest and its name (the first on a tie).
    pub fn governing(&self) -> (f64, &'static str) {
        self.values()
            .into_iter()
            .zip(CHECK_NAMES)
            .fold((0.0, CHECK_NAMES[0]), |a, b| if b.0 > a.0 { b } else { a })
    }
}

/// The reduction factor χ of EN 1993-1-1 (6.49) for a relative slenderness, imperfection
/// factor α and plateau λ0.
fn chi(lambda: f64, alpha: f64, plateau: f64) -> f64 {
    if lambda <= plateau {
        return 1.0;
    }
    let phi = 0.5 * (1.0 + alpha * (lambda - plateau) + lambda * lambda);
    (1.0 / (phi + (phi * phi - lambda * lambda).max(0.0).sqrt())).min(1.0)
}

/// C1 of a moment diagram from its absolute values at the member's ends, quarter points and
/// middle (Kirby and Nethercot's quarter-point formula, as AISC 360 (F1-1) writes C_b), at
/// most 2.5; 1 for a uniform moment.
pub fn c1_of(moments: &[f64; 5]) -> f64 {
    let max = moments.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return 1.0;
    }
    let (qa, mid, qb) = (moments[1], moments[2], moments[3]);
    (12.5 * max / (2.5 * max + 3.0 * qa + 4.0 * mid + 3.0 * qb)).clamp(1.0, 2.5)
}

/// Utilisation of a member's section for one case by each check (see the module notes).
pub fn member_check(
    model: &Model,
    k: usize,
    section: Section,
    end: &[f64; 12],
    w_global: DVec3,
    material: &Material,
) -> MemberChecks {
    let m = &model.members[k];
    let (x, y, z, l) = frame::local_frame(model, m);
    let w = DVec3::new(x.dot(w_global), y.dot(w_global), z.dot(w_global));
    let s = section;
    let (a, wy, wz) = (s.area(), s.w_weak(), s.w_strong());
    let (fy, e) = (material.fy, material.e);
    let fyd = fy / material.gamma_m0;
    let mut stress = 0.0f64;
    let mut compression = 0.0f64;
    // |M| about the strong (local z: in the panel plane) and weak axes along the member.
    let mut strong = [0.0f64; 5];
    let mut weak = 0.0f64;
    for (j, f) in STATIONS.into_iter().enumerate() {
        let [n, vy, vz, t, my, mz] = frame::internal_forces(end, w, f * l);
        let sigma = n.abs() / a + my.abs() / wy + mz.abs() / wz;
        let tau = t.abs() / s.torsion_modulus() + 1.5 * vy.hypot(vz) / a;
        stress = stress.max((sigma * sigma + 3.0 * tau * tau).sqrt() / fyd);
        compression = compression.max(-n);
        strong[j] = mz.abs();
        weak = weak.max(my.abs());
    }
    // Flexural buckling about each axis as a pin-ended strut, L_cr = L, curve c (α = 0.49).
    let lambda1 = std::f64::consts::PI * (e / fy).sqrt();
    // Radii of gyration: out of the plane (a seam's plies each on its own), and in it.
    let slenderness = |i: f64| l / (i / a).sqrt() / lambda1;
    let (lambda_z, lambda_y) = (slenderness(s.iy()), slenderness(s.iz()));
    let (chi_z, chi_y) = (chi(lambda_z, 0.49, 0.2), chi(lambda_y, 0.49, 0.2));
    let n_rd = a * fy / material.gamma_m1;
    let n_z = compression / (chi_z * n_rd);
    let n_y = compression / (chi_y * n_rd);
    // Lateral-torsional buckling of the rectangle bent in its plane, restrained at the nodes
    // only: M_cr = C1 π/L √(E I_weak G I_t) (no warping stiffness), curve d (α_LT = 0.76,
    // λ_LT,0 = 0.2, §6.3.2.2); a section thicker than deep does not buckle so.
    let m_max = strong.iter().copied().fold(0.0, f64::max);
    let m_rk = wz * fy;
    let chi_lt = if s.depth > s.thickness {
        let mcr = c1_of(&strong) * std::f64::consts::PI / l
            * (e * s.iy() * material.shear_modulus() * s.torsion_constant()).sqrt();
        chi(((m_rk / mcr).sqrt()).min(1e6), 0.76, 0.2)
    } else {
        1.0
    };
    let lateral_torsional = m_max / (chi_lt * m_rk / material.gamma_m1);
    // §6.3.3 with Annex B's factors for elastic (class 3) sections, C_m = C_mLT = 1 (a
    // uniform moment: the largest they take) and k_zy = 1 (its largest).
    let k_yy = 1.0 + 0.6 * lambda_y.min(1.0) * n_y;
    let k_zz = 1.0 + 0.6 * lambda_z.min(1.0) * n_z;
    let bend_strong = lateral_torsional;
    let bend_weak = weak / (wy * fy / material.gamma_m1);
    let interaction =
        (n_y + k_yy * bend_strong + k_zz * bend_weak).max(n_z + bend_strong + k_zz * bend_weak);
    MemberChecks {
        stress,
        buckling: n_z,
        lateral_torsional,
        interaction,
    }
}

/// Weld utilisation at each node (see the module notes), with the throats used.
fn weld_checks(
    model: &Model,
    results: &[CaseResult],
    uls: &[usize],
    material: &Material,
    throat_factor: f64,
) -> (Vec<Option<Check>>, Vec<f64>) {
    let n = model.nodes.len();
    let mut thinnest = vec![f64::INFINITY; n];
    for m in &model.members {
        for (e, v) in [m.a, m.b].into_iter().enumerate() {
            thinnest[v] = thinnest[v].min(welded(&m.section, e));
        }
    }
    let throats: Vec<f64> = thinnest
        .iter()
        .map(|t| {
            if t.is_finite() {
                throat_factor * t
            } else {
                0.0
            }
        })
        .collect();
    let fvw = material.fu / (3f64.sqrt() * material.beta_w * material.gamma_m2);
    let mut out: Vec<Option<Check>> = vec![None; n];
    for &c in uls {
        let r = &results[c];
        for (k, m) in model.members.iter().enumerate() {
            let s = m.section;
            for (e, node) in [m.a, m.b].into_iter().enumerate() {
                let (h, t) = (s.depth, welded(&s, e));
                let f = &r.end_forces[k][e * 6..e * 6 + 6];
                let (nx, vy, vz, tx, my, mz) = (
                    f[0].abs(),
                    f[1].abs(),
                    f[2].abs(),
                    f[3].abs(),
                    f[4].abs(),
                    f[5].abs(),
                );
                let polar = 2.0 * (h.powi(3) / 12.0 + h * t * t / 4.0);
                let f_t = tx * (0.25 * (h * h + t * t)).sqrt() / polar;
                let along = nx / (2.0 * h) + 3.0 * mz / (h * h) + my / (t * h);
                let across_y = vy / (2.0 * h) + f_t;
                let across_z = vz / (2.0 * h) + f_t;
                let per_length = (along * along + across_y * across_y + across_z * across_z).sqrt();
                let u = per_length / (fvw * throats[node]);
                if out[node].as_ref().is_none_or(|o| u > o.utilisation) {
                    out[node] = Some(Check {
                        utilisation: u,
                        check: "weld",
                        case: c,
                    });
                }
            }
        }
    }
    (out, throats)
}

/// Groups of members sized together: a group number per member.
pub fn groups(axes: &Axes, model: &Model, by: GroupBy) -> Result<Vec<usize>, SizingError> {
    let m = model.members.len();
    Ok(match by {
        GroupBy::Member => (0..m).collect(),
        GroupBy::Assembly(k) => {
            let node_group = partition(&axes.positions, &axes.edges, k)?;
            let mut number = std::collections::BTreeMap::new();
            model
                .members
                .iter()
                .map(|mm| {
                    let (ga, gb) = (node_group[mm.a], node_group[mm.b]);
                    let key = (ga.min(gb), ga.max(gb));
                    let next = number.len();
                    *number.entry(key).or_insert(next)
                })
                .collect()
        }
        GroupBy::Chain => {
            let mut degree = vec![0usize; model.nodes.len()];
            for mm in &model.members {
                degree[mm.a] += 1;
                degree[mm.b] += 1;
            }
            let mut at: Vec<Vec<usize>> = vec![Vec::new(); model.nodes.len()];
            for (k, mm) in model.members.iter().enumerate() {
                at[mm.a].push(k);
                at[mm.b].push(k);
            }
            let mut group = vec![usize::MAX; m];
            let mut next = 0;
            for start in 0..m {
                if group[start] != usize::MAX {
                    continue;
                }
                let mut stack = vec![start];
                group[start] = next;
                while let Some(k) = stack.pop() {
                    let mm = &model.members[k];
                    for v in [mm.a, mm.b] {
                        if degree[v] != 2 {
                            continue;
                        }
                        for &o in &at[v] {
                            if group[o] == usize::MAX {
                                group[o] = next;
                                stack.push(o);
                            }
                        }
                    }
                }
                next += 1;
            }
            group
        }
    })
}

/// The shell mesh of the panels of `axes` (the frame `model` built from them), `per_height`
/// elements up each: what `shells=` analyses, and what its CalculiX deck holds.
pub fn shell_mesh(axes: &Axes, model: &Model, per_height: usize) -> shell::Mesh {
    shell::mesh(
        model,
        &axes.positions,
        &axes.axes,
        &axes.heights,
        per_height,
    )
}

/// The frame's solve, or the shells' when asked: the same results either way.
fn solve(
    axes: &Axes,
    model: &Model,
    cases: &[LoadCase],
    opts: &SizingOptions,
) -> Result<Vec<CaseResult>, SizingError> {
    Ok(match opts.shells {
        None => frame::solve(model, cases)?,
        Some(per_height) => {
            let count = shell::element_count(model, &axes.positions, &axes.heights, per_height);
            if count > shell::MAX_ELEMENTS {
                return Err(SizingError::TooManyShells(count));
            }
            let mesh = shell_mesh(axes, model, per_height);
            shell::solve(model, &mesh, opts.material.nu, cases)?
        }
    })
}

/// A model, its load cases (see [`cases`]), their results, each member's governing check and
/// its largest utilisation by each check with the case.
struct Analysis {
    model: Model,
    cases: Vec<LoadCase>,
    results: Vec<CaseResult>,
    checks: Vec<Check>,
    by_check: Vec<[(f64, usize); 4]>,
    welds: Vec<Option<Check>>,
    throats: Vec<f64>,
}

/// The case of the first combination: after the loads and their sum (when there are several).
fn first_combination(loads: usize) -> usize {
    if loads > 1 {
        loads + 1
    } else {
        1
    }
}

/// One choice of a member's plate: a gauge, or a seam's stack and its two plies (thinner
/// first: the ply at the member's first node).
pub type Choice = (f64, Option<[f64; 2]>);

/// Every thickness two gauges add up to, thinnest first, each with the pair `plates` cuts it
/// from (the most even).
pub fn stacks(gauges: &[f64]) -> Vec<Choice> {
    let mut sums: Vec<f64> = gauges
        .iter()
        .enumerate()
        .flat_map(|(i, a)| gauges[i..].iter().map(move |b| a + b))
        .collect();
    sums.sort_by(f64::total_cmp);
    sums.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    sums.into_iter()
        .filter_map(|s| seam_gauges(s, gauges).map(|(a, b)| (s, Some([a, b]))))
        .collect()
}

/// What each member may be: the gauges, or for a seam between the assembly groups of
/// `seam_groups`, the stacks of two gauges.
pub fn choices(axes: &Axes, opts: &SizingOptions) -> Result<Vec<Vec<Choice>>, SizingError> {
    let single: Vec<Choice> = opts.gauges.iter().map(|&g| (g, None)).collect();
    let Some(k) = opts.seam_groups else {
        return Ok(vec![single; axes.edges.len()]);
    };
    let group = partition(&axes.positions, &axes.edges, k)?;
    let stacked = stacks(&opts.gauges);
    Ok(axes
        .edges
        .iter()
        .map(|&[a, b]| {
            if group[a as usize] != group[b as usize] {
                stacked.clone()
            } else {
                single.clone()
            }
        })
        .collect())
}

/// The plate welded at a member's end `e` (0 at its first node): a seam's ply there.
fn welded(section: &Section, e: usize) -> f64 {
    section.plies.map_or(section.thickness, |p| p[e])
}

/// Analyses with the given sections and checks every member in every ultimate combination.
fn analyse(
    axes: &Axes,
    sections: &[Choice],
    opts: &SizingOptions,
) -> Result<Analysis, SizingError> {
    let gauges: Vec<f64> = sections.iter().map(|c| c.0).collect();
    let mut model = build(axes, &gauges, &opts.supports, &opts.material)?;
    for (m, c) in model.members.iter_mut().zip(sections) {
        m.section.plies = c.1;
    }
    let cases = cases(axes, &model, opts)?;
    let results = solve(axes, &model, &cases, opts)?;
    let uls = uls_cases(opts);
    let (checks, by_check) = checks_of(&model, &cases, &results, &uls, &opts.material);
    let (welds, throats) = weld_checks(&model, &results, &uls, &opts.material, opts.throat_factor);
    Ok(Analysis {
        model,
        cases,
        results,
        checks,
        by_check,
        welds,
        throats,
    })
}

fn uls_cases(opts: &SizingOptions) -> Vec<usize> {
    limit_cases(
        &combinations(&opts.loads),
        first_combination(opts.loads.len()),
        Limit::Ultimate,
    )
}

/// Each member's governing check over the ultimate combinations `uls`, and its largest
/// utilisation by each check with its case.
fn checks_of(
    model: &Model,
    cases: &[LoadCase],
    results: &[CaseResult],
    uls: &[usize],
    material: &Material,
) -> (Vec<Check>, Vec<[(f64, usize); 4]>) {
    let w: Vec<Vec<DVec3>> = cases
        .iter()
        .map(|c| c.member_loads(model.members.len()))
        .collect();
    (0..model.members.len())
        .map(|k| {
            let mut best = Check {
                utilisation: 0.0,
                check: CHECK_NAMES[0],
                case: uls[0],
            };
            let mut each = [(0.0, uls[0]); 4];
            for &c in uls {
                let section = model.members[k].section;
                let all = member_check(
                    model,
                    k,
                    section,
                    &results[c].end_forces[k],
                    w[c][k],
                    material,
                );
                for (slot, u) in each.iter_mut().zip(all.values()) {
                    if u > slot.0 {
                        *slot = (u, c);
                    }
                }
                let (u, what) = all.governing();
                if u > best.utilisation {
                    best = Check {
                        utilisation: u,
                        check: what,
                        case: c,
                    };
                }
            }
            (best, each)
        })
        .unzip()
}

/// The utilisation a member would have with another gauge under the same end forces (its own
/// weight scaled with it) in the ultimate combinations `uls`: the choice of each round.
fn utilisation_with(
    model: &Model,
    k: usize,
    results: &[CaseResult],
    w: &[Vec<DVec3>],
    uls: &[usize],
    choice: Choice,
    material: &Material,
) -> f64 {
    let section = Section {
        thickness: choice.0,
        plies: choice.1,
        ..model.members[k].section
    };
    uls.iter()
        .map(|&c| {
            member_check(
                model,
                k,
                section,
                &results[c].end_forces[k],
                w[c][k],
                material,
            )
            .governing()
            .0
        })
        .fold(0.0, f64::max)
}

/// The least gauge level each member needs for the welds at its nodes to hold under the
/// current forces: at an over-utilised node, the members thinner than the utilisation times
/// the thinnest plate there (the throat scales with that plate).
fn weld_levels(
    model: &Model,
    welds: &[Option<Check>],
    throats: &[f64],
    choices: &[Vec<Choice>],
    opts: &SizingOptions,
) -> Vec<usize> {
    model
        .members
        .iter()
        .zip(choices)
        .map(|(m, list)| {
            [m.a, m.b]
                .into_iter()
                .enumerate()
                .filter_map(|(e, v)| {
                    let w = welds[v].as_ref()?;
                    if w.utilisation <= 1.0 {
                        return None;
                    }
                    let need = throats[v] / opts.throat_factor * w.utilisation;
                    let at_end = |c: &Choice| c.1.map_or(c.0, |p| p[e]);
                    Some(
                        list.iter()
                            .position(|c| at_end(c) >= need * (1.0 - 1e-12))
                            .unwrap_or(list.len() - 1),
                    )
                })
                .max()
                .unwrap_or(0)
        })
        .collect()
}

/// The whole sizing (see the module notes).
pub fn size(axes: &Axes, opts: &SizingOptions) -> Result<Sizing, SizingError> {
    if opts.loads.is_empty() {
        return Err(SizingError::NoLoad);
    }
    let g = &opts.gauges;
    let choices = choices(axes, opts)?;
    let tops: Vec<usize> = choices.iter().map(|c| c.len() - 1).collect();
    let uls = uls_cases(opts);
    // What the joints ask of each member (a seam's bolts): the first choice that thick.
    let floor: Vec<usize> = (0..axes.edges.len())
        .map(|k| match opts.floor.get(k) {
            Some(&t) => (choices[k].iter())
                .position(|c| c.0 >= t - 1e-9)
                .unwrap_or(tops[k]),
            None => 0,
        })
        .collect();
    let mut level = vec![0usize; axes.edges.len()];
    let sections_of = |level: &[usize]| {
        level
            .iter()
            .zip(&choices)
            .map(|(&i, c)| c[i])
            .collect::<Vec<Choice>>()
    };
    let mut now = analyse(axes, &sections_of(&level), opts)?;
    let group = groups(axes, &now.model, opts.group_by)?;
    let n_groups = group.iter().copied().max().map_or(0, |m| m + 1);
    let mut rounds = 1;
    let mut converged = false;
    // What the welds have asked of each member: it only rises, so the rounds settle.
    let mut weld_floor = vec![0usize; level.len()];
    // Stress rounds: each group the thinnest gauge that holds its members' current forces,
    // and the welds at their nodes.
    while rounds <= opts.max_rounds {
        let w: Vec<Vec<DVec3>> = now
            .cases
            .iter()
            .map(|c| c.member_loads(now.model.members.len()))
            .collect();
        for (f, n) in weld_floor.iter_mut().zip(weld_levels(
            &now.model,
            &now.welds,
            &now.throats,
            &choices,
            opts,
        )) {
            *f = (*f).max(n);
        }
        let mut want = vec![0usize; n_groups];
        for (k, &gk) in group.iter().enumerate() {
            let need = (0..=tops[k])
                .find(|&i| {
                    utilisation_with(
                        &now.model,
                        k,
                        &now.results,
                        &w,
                        &uls,
                        choices[k][i],
                        &opts.material,
                    ) <= 1.0
                })
                .unwrap_or(tops[k]);
            want[gk] = want[gk].max(need).max(weld_floor[k]).max(floor[k]);
        }
        let next: Vec<usize> = group.iter().map(|&gk| want[gk]).collect();
        if next == level {
            converged = true;
            break;
        }
        level = next;
        now = analyse(axes, &sections_of(&level), opts)?;
        rounds += 1;
    }
    // Deflection: raise the groups that stiffen the worst displacement most per added mass.
    let span = span_of(&axes.positions);
    let limit = opts.deflection_limit.map(|d| match d {
        DeflectionLimit::Ratio(r) => span / r,
        DeflectionLimit::Millimetres(v) => v,
    });
    let sls = limit_cases(
        &combinations(&opts.loads),
        first_combination(opts.loads.len()),
        Limit::Serviceability,
    );
    let mut deflection_rounds = 0;
    // Stiffen, smooth and hold again until the deflection holds after all three (smoothing
    // and holding add weight), or nothing can be raised.
    loop {
        let before = level.clone();
        if let Some(limit) = limit {
            while deflection_rounds < 200 {
                let c = deflection_case(&now.results, &sls);
                let (node, worst) = max_displacement(&now.results[c]);
                if worst <= limit {
                    break;
                }
                let shares =
                    stiffening(axes, opts, &now.model, &now.cases[c], &now.results[c], node)?;
                let mut per_group = vec![0.0; n_groups];
                for (k, s) in shares.iter().enumerate() {
                    per_group[group[k]] += s;
                }
                let mut order: Vec<usize> = (0..n_groups)
                    .filter(|&gk| per_group[gk] > 0.0 && has_room(&group, &level, &tops, gk))
                    .collect();
                if order.is_empty() {
                    break;
                }
                order.sort_by(|&a, &b| per_group[b].total_cmp(&per_group[a]).then(a.cmp(&b)));
                let take = (order.len() / 10).max(1);
                for &gk in &order[..take] {
                    for (k, lv) in level.iter_mut().enumerate() {
                        if group[k] == gk {
                            *lv = (*lv + 1).min(tops[k]);
                        }
                    }
                }
                now = analyse(axes, &sections_of(&level), opts)?;
                deflection_rounds += 1;
                // A raise adds weight: keep the stresses within the gauges too.
                for (k, c) in now.checks.iter().enumerate() {
                    if c.utilisation > 1.0 && level[k] < tops[k] {
                        let gk = group[k];
                        for (j, lv) in level.iter_mut().enumerate() {
                            if group[j] == gk {
                                *lv = (*lv + 1).min(tops[j]);
                            }
                        }
                    }
                }
            }
        }
        if opts.smooth {
            // Neighbours within one step: raise the thinner until it holds everywhere.
            let mut at: Vec<Vec<usize>> = vec![Vec::new(); now.model.nodes.len()];
            for (k, m) in now.model.members.iter().enumerate() {
                at[m.a].push(k);
                at[m.b].push(k);
            }
            let mut changed = true;
            while changed {
                changed = false;
                for list in &at {
                    let high = list.iter().map(|&k| level[k]).max().unwrap_or(0);
                    for &k in list {
                        if level[k] + 1 < high {
                            level[k] = high - 1;
                            changed = true;
                        }
                    }
                }
            }
        }
        // The raises for deflection and smoothness move forces: hold members and welds again,
        // raising only.
        let mut holding_rounds = 0;
        loop {
            now = analyse(axes, &sections_of(&level), opts)?;
            let for_welds = weld_levels(&now.model, &now.welds, &now.throats, &choices, opts);
            let mut want = vec![0usize; n_groups];
            for (k, &gk) in group.iter().enumerate() {
                let member = if now.checks[k].utilisation > 1.0 {
                    level[k] + 1
                } else {
                    level[k]
                };
                want[gk] = want[gk].max(member.max(for_welds[k]).max(floor[k]).min(tops[k]));
            }
            let next: Vec<usize> = group.iter().map(|&gk| want[gk]).collect();
            if next == level || holding_rounds >= opts.max_rounds {
                break;
            }
            level = next;
            holding_rounds += 1;
        }
        rounds += holding_rounds;
        let met = limit.is_none_or(|l| {
            max_displacement(&now.results[deflection_case(&now.results, &sls)]).1 <= l
        });
        if met || level == before || deflection_rounds >= 200 {
            break;
        }
    }
    let Analysis {
        model,
        cases,
        results,
        checks,
        by_check,
        welds,
        throats,
    } = now;
    if let Some((node, w)) = welds
        .iter()
        .enumerate()
        .filter_map(|(i, w)| Some((i, w.as_ref()?)))
        .filter(|(_, w)| w.utilisation > 1.0)
        .max_by(|a, b| a.1.utilisation.total_cmp(&b.1.utilisation))
    {
        let thickest = g[g.len() - 1];
        let thinnest_here = throats[node] / opts.throat_factor;
        if thinnest_here >= thickest {
            return Err(SizingError::WeldsExhausted {
                node,
                utilisation: w.utilisation,
                throat: throats[node],
                needed: throats[node] * w.utilisation,
                thickest,
            });
        }
    }
    let areas = panel_areas(axes);
    let member_kg: Vec<f64> = (model.members.iter().enumerate())
        .map(|(k, m)| steel_kg(&areas, opts, k, &m.section))
        .collect();
    let fasteners: f64 = (0..member_kg.len()).map(|k| fastener_kg(opts, k)).sum();
    let mass_kg = member_kg.iter().sum::<f64>() + fasteners + node_steel_kg(opts);
    let combinations = combinations(&opts.loads);
    Ok(Sizing {
        gauges: sections_of(&level).iter().map(|c| c.0).collect(),
        model,
        cases,
        results,
        combinations,
        first_combination: first_combination(opts.loads.len()),
        checks,
        by_check,
        welds,
        throats,
        rounds,
        converged,
        deflection_rounds,
        deflection_limit: limit,
        span,
        mass_kg,
        member_kg,
        shells: opts.shells,
    })
}

/// Whether a member of group `gk` can still go up its list.
fn has_room(group: &[usize], level: &[usize], tops: &[usize], gk: usize) -> bool {
    (0..group.len()).any(|k| group[k] == gk && level[k] < tops[k])
}

fn limit_cases(combinations: &[Combination], first: usize, limit: Limit) -> Vec<usize> {
    combinations
        .iter()
        .enumerate()
        .filter(|(_, c)| c.limit == limit)
        .map(|(j, _)| first + j)
        .collect()
}

/// Of `among`, the case whose largest displacement is largest (the first on a tie).
fn deflection_case(results: &[CaseResult], among: &[usize]) -> usize {
    among
        .iter()
        .copied()
        .fold(None, |best: Option<(usize, f64)>, c| {
            let d = max_displacement(&results[c]).1;
            match best {
                Some((_, b)) if b >= d => best,
                _ => Some((c, d)),
            }
        })
        .map_or(0, |(c, _)| c)
}

/// The node moving most in a case, and how far, mm.
pub fn max_displacement(r: &CaseResult) -> (usize, f64) {
    r.displacements
        .iter()
        .enumerate()
        .map(|(i, d)| (i, DVec3::new(d[0], d[1], d[2]).length()))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
}

/// The largest horizontal extent of the nodes, mm.
pub fn span_of(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
    (hi - lo).x.max((hi - lo).y).max(0.0)
}

/// Each member's share of the displacement of `node` along its direction (unit load method:
/// the member's strain energy product of the real and the virtual state), N·mm.
fn stiffening(
    axes: &Axes,
    opts: &SizingOptions,
    model: &Model,
    case: &LoadCase,
    real: &CaseResult,
    node: usize,
) -> Result<Vec<f64>, SizingError> {
    let d = real.displacements[node];
    let dir = DVec3::new(d[0], d[1], d[2]).normalize_or_zero();
    let unit = LoadCase {
        name: "unit".into(),
        nodal: vec![(node, [dir.x, dir.y, dir.z, 0.0, 0.0, 0.0])],
        member: vec![],
    };
    let virt = &solve(axes, model, &[unit], opts)?[0];
    let w = case.member_loads(model.members.len());
    // Virtual work of the real end forces (k u: what the ends take, the member's own load's
    // equivalent added back) over the virtual end displacements: the sum is δ.
    Ok(model
        .members
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let (x, y, z, l) = frame::local_frame(model, m);
            let fixed =
                frame::equivalent_loads(DVec3::new(x.dot(w[k]), y.dot(w[k]), z.dot(w[k])), l);
            let mut s = 0.0;
            for (e, v) in [m.a, m.b].into_iter().enumerate() {
                for part in 0..2 {
                    let o = e * 6 + part * 3;
                    let u = DVec3::new(
                        virt.displacements[v][part * 3],
                        virt.displacements[v][part * 3 + 1],
                        virt.displacements[v][part * 3 + 2],
                    );
                    let ul = DVec3::new(x.dot(u), y.dot(u), z.dot(u));
                    let f = &real.end_forces[k];
                    s += (f[o] + fixed[o]) * ul.x
                        + (f[o + 1] + fixed[o + 1]) * ul.y
                        + (f[o + 2] + fixed[o + 2]) * ul.z;
                }
            }
            s.max(0.0)
        })
        .collect())
}

pub const FORMAT: &str = "lamina-sizing";
pub const VERSION: u32 = 1;

#[derive(serde::Deserialize)]
struct GaugeFile {
    gauges: Vec<f64>,
    edges: Vec<GaugeEdge>,
    material: Option<Material>,
    seam_groups: Option<usize>,
    #[serde(default)]
    joints: Option<JointsFile>,
}

/// The joints a sizing weighed the plates with (`stage::size::JointsRow` writes them).
#[derive(serde::Deserialize)]
struct JointsFile {
    weld_gap: f64,
    weld_gap_tolerance: f64,
    node_core: Option<CoreFile>,
    bolt: Option<String>,
    bolt_clearance: Option<SocketFile>,
}

#[derive(serde::Deserialize)]
struct CoreFile {
    diameter: f64,
    wall: f64,
}

#[derive(serde::Deserialize)]
struct SocketFile {
    radius: f64,
    reach: f64,
}

impl JointsFile {
    /// The joints, each figure in the range its option allows.
    fn joints(&self) -> Result<Joints, String> {
        let length = |what: &str, v: f64| {
            (v.is_finite() && (0.0..=1000.0).contains(&v))
                .then_some(v)
                .ok_or_else(|| format!("joints: {what} {v} is not a length from 0 to 1000 mm"))
        };
        let node_core = match &self.node_core {
            Some(c) => Some(
                CoreSize::parse(&format!("tube:{},{}", c.diameter, c.wall))
                    .map_err(|e| format!("joints: node_core {e}"))?,
            ),
            None => None,
        };
        let bolt_clearance = match &self.bolt_clearance {
            Some(b) => Some(
                Socket::parse(&format!("{}:{}", b.radius, b.reach))
                    .map_err(|e| format!("joints: bolt_clearance {e}"))?,
            ),
            None => None,
        };
        Ok(Joints {
            weld_gap: length("weld_gap", self.weld_gap)?,
            weld_gap_tolerance: length("weld_gap_tolerance", self.weld_gap_tolerance)?,
            node_core,
            bolt: match &self.bolt {
                Some(b) => Some(
                    crate::rationalize::bolts::parse(b).map_err(|e| format!("joints: bolt {e}"))?,
                ),
                None => None,
            },
            bolt_clearance,
        })
    }
}

/// The joints of a sizing file's `joints` as JSON text (`null`: none).
pub fn joints_from_json(text: &str) -> Result<Option<Joints>, String> {
    let file: Option<JointsFile> = serde_json::from_str(text).map_err(|e| e.to_string())?;
    file.map(|j| j.joints()).transpose()
}

#[derive(serde::Deserialize)]
struct GaugeEdge {
    gauge: f64,
    #[serde(default)]
    seam_forces: Option<[f64; 6]>,
}

/// A sizing file's gauges and steel.
#[derive(Clone, Debug, PartialEq)]
pub struct SizedGauges {
    /// The gauge of each edge (a seam's stack of two plies), mm.
    pub per_edge: Vec<f64>,
    /// The list they were chosen from, mm.
    pub list: Vec<f64>,
    /// The steel (None in files from before it was written).
    pub material: Option<Material>,
    /// The assembly groups its seams were sized for (None: no seams).
    pub seam_groups: Option<usize>,
    /// Per edge, what a seam's bolts carry (None for other edges, and in files from before).
    pub seam_forces: Vec<Option<[f64; 6]>>,
    /// The joints the plates were weighed with as cut (None in files from before, and when
    /// the sizing weighed the uncut panels).
    pub joints: Option<Joints>,
}

/// A sizing file's gauges and steel, for `plates --sizing`.
pub fn read_gauges(path: &std::path::Path) -> Result<SizedGauges, crate::files::ReadError> {
    use crate::files::{read_lamina_json, ReadError};
    let file: GaugeFile = read_lamina_json(
        path,
        FORMAT,
        VERSION,
        "the sizing file `lamina size` writes",
    )?;
    let bad = |t: f64| !(t.is_finite() && t > 0.0 && t <= 200.0);
    if let Some(t) = file.gauges.iter().find(|t| bad(**t)) {
        return Err(ReadError::file(
            path,
            format!("gauge {t} is not a thickness"),
        ));
    }
    for (k, e) in file.edges.iter().enumerate() {
        if bad(e.gauge) {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                format!("gauge {} is not a thickness", e.gauge),
            ));
        }
        if e.seam_forces
            .is_some_and(|f| f.iter().any(|v| !(v.is_finite() && v.abs() < 1e15)))
        {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                "seam_forces must be six finite numbers (N, N·mm)",
            ));
        }
    }
    if let Some(m) = &file.material {
        if !(m.density > 0.1 && m.density <= 30.0) || m.name.trim().is_empty() || m.name.len() > 64
        {
            return Err(ReadError::file(
                path,
                "material: the name must be at most 64 characters and the density from 0.1 to 30 g/cm³",
            ));
        }
    }
    let joints = match &file.joints {
        Some(j) => Some(j.joints().map_err(|e| ReadError::file(path, e))?),
        None => None,
    };
    Ok(SizedGauges {
        joints,
        per_edge: file.edges.iter().map(|e| e.gauge).collect(),
        list: file.gauges,
        material: file.material,
        seam_groups: file.seam_groups,
        seam_forces: file.edges.iter().map(|e| e.seam_forces).collect(),
    })
}

#[derive(serde::Deserialize)]
struct CheckFile {
    edges: Vec<CheckEdge>,
}

/// One member's result in a sizing file.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
pub struct CheckEdge {
    pub gauge: f64,
    pub utilisation: f64,
    /// What governs it (stress, buckling, ...).
    pub check: String,
    /// The load case that governs it.
    pub load: String,
}

/// A sizing file's result per edge, for the viewer.
pub fn read_checks(path: &std::path::Path) -> Result<Vec<CheckEdge>, crate::files::ReadError> {
    use crate::files::{read_lamina_json, ReadError};
    let file: CheckFile = read_lamina_json(
        path,
        FORMAT,
        VERSION,
        "the sizing file `lamina size` writes",
    )?;
    if let Some(k) = file
        .edges
        .iter()
        .position(|e| !(e.gauge.is_finite() && e.utilisation.is_finite()))
    {
        return Err(ReadError::record(
            path,
            format!("edge {k}"),
            "its gauge or utilisation is not a finite number",
        ));
    }
    Ok(file.edges)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A horizontal plate `length` mm long, 200 mm deep (its axes vertical), clamped at node 0.
    fn cantilever(length: f64) -> Axes {
        Axes {
            positions: vec![DVec3::ZERO, DVec3::new(length, 0.0, 0.0)],
            edges: vec![[0, 1]],
            axes: vec![DVec3::Z; 2],
            heights: vec![200.0; 2],
            reference: vec![DVec3::Z; 2],
            fixed_normals: vec![None],
            edge_radii: vec![0.0],
        }
    }

    fn options(loads: &[&str], gauges: &[f64], throat: f64) -> SizingOptions {
        SizingOptions {
            material: Material::get("s355").unwrap(),
            gauges: gauges.to_vec(),
            supports: vec![(Selector::parse("node=0").unwrap(), Support::Fixed)],
            loads: loads
                .iter()
                .map(|s| {
                    let (spec, action) = LoadSpec::parse_action(s).unwrap();
                    (s.to_string(), spec, action)
                })
                .collect(),
            deflection_limit: None,
            group_by: GroupBy::Member,
            smooth: false,
            throat_factor: throat,
            max_rounds: 20,
            shells: None,
            seam_groups: None,
            built: None,
            floor: Vec::new(),
        }
    }

    #[test]
    fn actions_are_read_from_the_load_and_its_mark() {
        let action = |s: &str| LoadSpec::parse_action(s).map(|(_, a)| a);
        assert_eq!(action("self-weight"), Ok(Action::Permanent));
        assert_eq!(action("self-weight:1.2"), Ok(Action::Permanent));
        assert_eq!(action("point:node=1:0,0,-5"), Ok(Action::Variable));
        assert_eq!(action("point:node=1:0,0,-5:G"), Ok(Action::Permanent));
        assert_eq!(action("wind:0.5:1,0,0:Q"), Ok(Action::Variable));
        assert!(action("self-weight:Q").is_err());
    }

    #[test]
    fn combinations_follow_en_1990_6_10_and_6_14b() {
        let o = options(
            &["self-weight", "wind:0.5:1,0,0", "point:node=1:0,0,-5"],
            &[2.0],
            0.7,
        );
        let c = combinations(&o.loads);
        let factors: Vec<(Limit, Vec<f64>)> =
            c.iter().map(|c| (c.limit, c.factors.clone())).collect();
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        let expect = [
            (Limit::Ultimate, [1.35, 1.5, 1.5 * 0.7]),
            (Limit::Ultimate, [1.35, 1.5 * 0.6, 1.5]),
            (Limit::Ultimate, [1.0, 1.5, 1.5 * 0.7]),
            (Limit::Ultimate, [1.0, 1.5 * 0.6, 1.5]),
            (Limit::Serviceability, [1.0, 1.0, 0.7]),
            (Limit::Serviceability, [1.0, 0.6, 1.0]),
        ];
        assert_eq!(factors.len(), expect.len());
        for ((limit, f), (l, e)) in factors.iter().zip(&expect) {
            assert_eq!(limit, l);
            assert!(close(f, e), "{f:?} against {e:?}");
        }
        assert_eq!(
            c[0].name,
            "ULS: 1.35 × self-weight + 1.5 × wind:0.5:1,0,0 + 1.05 × point:node=1:0,0,-5"
        );
        let g_only = combinations(&options(&["self-weight"], &[2.0], 0.7).loads);
        assert_eq!(g_only.len(), 2);
        assert_eq!(g_only[0].factors, vec![1.35]);
        assert_eq!(g_only[1].factors, vec![1.0]);
    }

    #[test]
    fn c1_is_one_for_a_uniform_moment_and_more_for_a_peak() {
        assert_eq!(c1_of(&[5.0; 5]), 1.0);
        // Linear from M to -M: 12.5 / (2.5 + 1.5 + 0 + 1.5).
        assert!((c1_of(&[1.0, 0.5, 0.0, 0.5, 1.0]) - 12.5 / 5.5).abs() < 1e-12);
        // A cantilever's triangle: 12.5 / (2.5 + 2.25 + 2 + 0.75).
        assert!((c1_of(&[1.0, 0.75, 0.5, 0.25, 0.0]) - 12.5 / 7.5).abs() < 1e-12);
        assert_eq!(c1_of(&[0.0; 5]), 1.0);
    }

    #[test]
    fn lateral_torsional_buckling_of_a_plate_bent_in_its_plane() {
        // A uniform in-plane moment on a 1 m, 200 × 3 mm plate: M_cr = π/L √(E I_z G I_t).
        let axes = cantilever(1000.0);
        let m = Material::get("s355").unwrap();
        let model = build(&axes, &[3.0], &[], &m).unwrap();
        let moment = 1.0e6;
        let mut end = [0.0; 12];
        end[5] = -moment;
        end[11] = moment;
        let got = member_check(&model, 0, model.members[0].section, &end, DVec3::ZERO, &m);
        let (d, t, l) = (200.0, 3.0, 1000.0);
        let i_weak = d * t * t * t / 12.0;
        let r = t / d;
        let i_t =
            (d / 2.0) * (t / 2.0f64).powi(3) * (16.0 / 3.0 - 3.36 * r * (1.0 - r.powi(4) / 12.0));
        let g = 210_000.0 / 2.6;
        let mcr = std::f64::consts::PI / l * (210_000.0 * i_weak * g * i_t).sqrt();
        let w_el = t * d * d / 6.0;
        let lambda = (w_el * 355.0 / mcr).sqrt();
        let phi = 0.5 * (1.0 + 0.76 * (lambda - 0.2) + lambda * lambda);
        let chi = 1.0 / (phi + (phi * phi - lambda * lambda).sqrt());
        let expect = moment / (chi * w_el * 355.0);
        assert!(
            (got.lateral_torsional - expect).abs() < 1e-9 * expect,
            "{got:?} {expect}"
        );
        assert!(chi < 0.5, "a slender plate: χ_LT {chi}");
        // No compression: the interaction is the bending alone, more than the stress check.
        assert!((got.interaction - expect).abs() < 1e-9 * expect);
        assert!(got.interaction > got.stress);
        assert_eq!(got.governing().1, "lateral-torsional");
    }

    #[test]
    fn the_self_weight_is_the_steel_as_cut_with_its_bolts_and_cores() {
        // The 1000 × 200 panel uncut, then a third of it cut away, bolts on the member and a
        // core at the free end: the reaction carries exactly what is left.
        let axes = cantilever(1000.0);
        let uncut = size(&axes, &options(&["self-weight"], &[2.0], 0.7)).unwrap();
        let kg = |a: f64| a * 2.0 * 7.85e-6;
        assert!((uncut.mass_kg - kg(200_000.0)).abs() < 1e-12);
        let mut opts = options(&["self-weight"], &[2.0], 0.7);
        opts.built = Some(BuiltSteel {
            areas: vec![[133_000.0, 0.0]],
            nodes: vec![(1, 0.25)],
            fasteners: vec![0.5],
        });
        let cut = size(&axes, &opts).unwrap();
        let mass = kg(133_000.0) + 0.25 + 0.5;
        assert!((cut.mass_kg - mass).abs() < 1e-12, "{}", cut.mass_kg);
        assert!((cut.member_kg[0] - kg(133_000.0)).abs() < 1e-12);
        let up: f64 = cut.total().reactions.iter().map(|(_, r)| r[2]).sum();
        assert!((up - mass * GRAVITY).abs() < 1e-9 * up, "{up}");
        // The core hangs at the tip: the moment at the support grows by its whole lever.
        let moment = |s: &Sizing| s.total().reactions[0].1[4].abs();
        let spread = (mass - 0.25) * GRAVITY * 500.0;
        let tip = 0.25 * GRAVITY * 1000.0;
        assert!(
            (moment(&cut) - spread - tip).abs() < 1e-6 * moment(&cut),
            "{}",
            moment(&cut)
        );
    }

    #[test]
    fn a_floor_under_a_member_keeps_it_at_least_that_thick() {
        let axes = cantilever(150.0);
        let mut opts = options(&["self-weight"], &[1.5, 2.0, 3.0, 4.0], 0.7);
        assert_eq!(size(&axes, &opts).unwrap().gauges, vec![1.5]);
        opts.floor = vec![2.5];
        assert_eq!(size(&axes, &opts).unwrap().gauges, vec![3.0]);
    }

    #[test]
    fn welds_raise_the_gauges_until_they_hold() {
        // A stub (no lateral-torsional buckling to speak of) with small throats: the welds
        // govern and the sizing raises the gauge for them.
        let axes = cantilever(150.0);
        let gauges = [1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0];
        let load = ["point:node=1:0,0,-20000"];
        let plain = size(&axes, &options(&load, &gauges, 0.7)).unwrap();
        let weak = size(&axes, &options(&load, &gauges, 0.2)).unwrap();
        assert!(
            weak.gauges[0] > plain.gauges[0],
            "{:?} {:?}",
            weak.gauges,
            plain.gauges
        );
        assert!(weak.max_weld_utilisation() <= 1.0);
        assert!(weak.max_utilisation() <= 1.0);
        // One gauge thinner and the weld does not hold.
        let below = gauges[gauges.iter().position(|g| *g == weak.gauges[0]).unwrap() - 1];
        let one = size(&axes, &options(&load, &[below], 0.2));
        assert!(
            matches!(one, Err(SizingError::WeldsExhausted { .. })),
            "{one:?}"
        );
    }

    #[test]
    fn seams_choose_from_stacks_of_two_gauges_and_bend_as_two_plies() {
        let got = stacks(&[1.5, 2.0, 3.0]);
        let want = [
            (3.0, [1.5, 1.5]),
            (3.5, [1.5, 2.0]),
            (4.0, [2.0, 2.0]),
            (4.5, [1.5, 3.0]),
            (5.0, [2.0, 3.0]),
            (6.0, [3.0, 3.0]),
        ];
        assert_eq!(got.len(), want.len());
        for ((s, p), (ws, wp)) in got.iter().zip(want) {
            assert!((s - ws).abs() < 1e-12);
            assert_eq!(p.expect("plies"), wp);
        }
        // Two 2 mm plies: in-plane as a 4 mm plate, out of it as two 2 mm ones (a quarter).
        let seam = Section {
            depth: 100.0,
            thickness: 4.0,
            plies: Some([2.0, 2.0]),
        };
        let solid = Section::solid(100.0, 4.0);
        assert!((seam.iz() - solid.iz()).abs() < 1e-9);
        assert!((seam.iy() / solid.iy() - 0.25).abs() < 1e-12);
        assert!((seam.w_weak() / solid.w_weak() - 0.5).abs() < 1e-12);
        assert!((seam.bending_thickness() - 16f64.cbrt()).abs() < 1e-12);
        assert!(seam.torsion_constant() < 0.3 * solid.torsion_constant());
    }

    #[test]
    fn a_member_between_groups_is_sized_as_two_plies() {
        // Two plates in a row, the middle node's group not the ends': with seam_groups the
        // members are seams, their gauges stacks of two on the list.
        let mut axes = cantilever(600.0);
        axes.positions.push(DVec3::new(1200.0, 0.0, 0.0));
        axes.axes.push(DVec3::Z);
        axes.heights.push(200.0);
        axes.reference.push(DVec3::Z);
        axes.edges.push([1, 2]);
        axes.fixed_normals.push(None);
        axes.edge_radii.push(0.0);
        let mut o = options(&["point:node=2:0,0,-300"], &[1.5, 2.0, 3.0, 4.0, 5.0], 0.7);
        o.seam_groups = Some(2);
        let sized = size(&axes, &o).unwrap();
        let seams: Vec<_> = sized
            .model
            .members
            .iter()
            .filter_map(|m| m.section.plies.map(|p| (m.section.thickness, p)))
            .collect();
        assert_eq!(seams.len(), 1, "one member between the two groups");
        let (t, [a, b]) = seams[0];
        assert!((a + b - t).abs() < 1e-12 && o.gauges.contains(&a) && o.gauges.contains(&b));
        assert!(sized.max_utilisation() <= 1.0);
    }
}
