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
//! Checks per member, at five points along it, for every load case and their sum:
//! - `stress`: von Mises from the largest normal stress at a corner of the section (axial force
//!   and both bending moments) and the largest shear stress (torsion, Roark's modulus, plus
//!   1.5 V/A of the resultant shear; the two are added although their peaks are at different
//!   points, which is safe), over f_y/γ_M0;
//! - `buckling`: the compression over the weak-axis flexural buckling resistance of the member
//!   as a pin-ended strut (EN 1993-1-1 §6.3.1.2, curve c for solid sections, L_cr = L), over
//!   χ A f_y/γ_M1. Interaction with bending (§6.3.3) is not checked.
//!
//! Welds (EN 1993-1-8 §4.5.3.3, the simplified method): each member end is held by two fillet
//! welds of throat a (0.7 × the thinner of the plates meeting at the node) along its depth, one
//! on each face; the force per length is the sum of the parts from every end force (axial,
//! shears, in-plane moment as a line's bending, out-of-plane moment as a couple across the
//! thickness, torsion as the two lines' polar moment), over f_vw,d · a with
//! f_vw,d = f_u / (√3 β_w γ_M2).

use glam::DVec3;
use thiserror::Error;

use super::frame::{self, CaseResult, Elastic, FrameError, LoadCase, Member, Model, Section};
use super::material::Material;
use super::shell;
use crate::rationalize::axes::Axes;
use crate::rationalize::groups::{partition, GroupError};
use crate::rationalize::planarize::Selector;

pub use super::frame::Support;

pub const GRAVITY: f64 = 9.80665;
/// Stations along a member where it is checked, as fractions of its length.
const STATIONS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

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
    pub loads: Vec<(String, LoadSpec)>,
    pub deflection_limit: Option<DeflectionLimit>,
    pub group_by: GroupBy,
    pub smooth: bool,
    /// Fillet throat over the thinner plate.
    pub throat_factor: f64,
    /// Rounds of analysis and choice at most.
    pub max_rounds: usize,
    /// Analyse the panels as flat shells, this many elements up each (even), not as beams.
    pub shells: Option<usize>,
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
    #[error(transparent)]
    Frame(#[from] FrameError),
    #[error("group_by= assembly: {0}")]
    Groups(#[from] GroupError),
}

/// Per member and case, what governs.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    pub utilisation: f64,
    /// `stress` or `buckling`.
    pub check: &'static str,
    /// Index of the load case (`cases()` order).
    pub case: usize,
}

#[derive(Clone, Debug)]
pub struct Sizing {
    pub model: Model,
    pub cases: Vec<LoadCase>,
    pub results: Vec<CaseResult>,
    pub gauges: Vec<f64>,
    pub checks: Vec<Check>,
    /// Per node: the largest weld utilisation and its case.
    pub welds: Vec<Option<Check>>,
    pub throats: Vec<f64>,
    pub rounds: usize,
    pub converged: bool,
    pub deflection_rounds: usize,
    /// The limit in mm, when one is set.
    pub deflection_limit: Option<f64>,
    pub span: f64,
    pub mass_kg: f64,
    /// Elements up each panel when the panels were analysed as shells; None for the frame.
    pub shells: Option<usize>,
}

impl Sizing {
    /// The case that sums every load (the last one).
    pub fn total(&self) -> &CaseResult {
        self.results.last().expect("at least one case")
    }

    /// The node moving most under the sum of the loads, and how far, mm.
    pub fn max_displacement(&self) -> (usize, f64) {
        max_displacement(self.total())
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
            section: Section {
                depth,
                thickness: gauges[k],
            },
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

/// The load cases: one per load, and their sum last (alone when there is one load).
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
    for (name, spec) in &opts.loads {
        let mut case = LoadCase {
            name: name.clone(),
            ..Default::default()
        };
        match spec {
            LoadSpec::SelfWeight { factor } => {
                for (k, m) in model.members.iter().enumerate() {
                    let l = model.nodes[m.a].distance(model.nodes[m.b]);
                    let newtons = areas[k]
                        * m.section.thickness
                        * opts.material.density
                        * 1e-6
                        * GRAVITY
                        * factor;
                    case.member.push((k, DVec3::new(0.0, 0.0, -newtons / l)));
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
    if out.len() > 1 {
        let mut all = LoadCase {
            name: "all loads".into(),
            ..Default::default()
        };
        for c in &out {
            all.nodal.extend(c.nodal.iter().copied());
            all.member.extend(c.member.iter().copied());
        }
        out.push(all);
    }
    Ok(out)
}

/// Utilisation of a member's section for one case, and what governs.
pub fn member_check(
    model: &Model,
    k: usize,
    section: Section,
    end: &[f64; 12],
    w_global: DVec3,
    material: &Material,
) -> (f64, &'static str) {
    let m = &model.members[k];
    let (x, y, z, l) = frame::local_frame(model, m);
    let w = DVec3::new(x.dot(w_global), y.dot(w_global), z.dot(w_global));
    let s = section;
    let (a, wy, wz) = (
        s.area(),
        s.depth * s.thickness * s.thickness / 6.0,
        s.thickness * s.depth * s.depth / 6.0,
    );
    let fyd = material.fy / material.gamma_m0;
    let mut stress = 0.0f64;
    let mut compression = 0.0f64;
    for f in STATIONS {
        let [n, vy, vz, t, my, mz] = frame::internal_forces(end, w, f * l);
        let sigma = n.abs() / a + my.abs() / wy + mz.abs() / wz;
        let tau = t.abs() / s.torsion_modulus() + 1.5 * vy.hypot(vz) / a;
        stress = stress.max((sigma * sigma + 3.0 * tau * tau).sqrt() / fyd);
        compression = compression.max(-n);
    }
    let buckling = if compression > 0.0 {
        let i = s.thickness / 12f64.sqrt();
        let lambda1 = std::f64::consts::PI * (material.e / material.fy).sqrt();
        let lambda = l / i / lambda1;
        let phi = 0.5 * (1.0 + 0.49 * (lambda - 0.2) + lambda * lambda);
        let chi = (1.0 / (phi + (phi * phi - lambda * lambda).max(0.0).sqrt())).min(1.0);
        compression / (chi * a * material.fy / material.gamma_m1)
    } else {
        0.0
    };
    if buckling > stress {
        (buckling, "buckling")
    } else {
        (stress, "stress")
    }
}

/// Weld utilisation at each node (see the module notes), with the throats used.
fn weld_checks(
    model: &Model,
    results: &[CaseResult],
    material: &Material,
    throat_factor: f64,
) -> (Vec<Option<Check>>, Vec<f64>) {
    let n = model.nodes.len();
    let mut thinnest = vec![f64::INFINITY; n];
    for m in &model.members {
        for v in [m.a, m.b] {
            thinnest[v] = thinnest[v].min(m.section.thickness);
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
    for (c, r) in results.iter().enumerate() {
        for (k, m) in model.members.iter().enumerate() {
            let s = m.section;
            let (h, t) = (s.depth, s.thickness);
            for (e, node) in [m.a, m.b].into_iter().enumerate() {
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
            let mesh = shell::mesh(
                model,
                &axes.positions,
                &axes.axes,
                &axes.heights,
                per_height,
            );
            shell::solve(model, &mesh, opts.material.nu, cases)?
        }
    })
}

/// Analyses with the given gauges and checks every member in every case.
/// A model, its load cases, their results and each member's check.
type Analysis = (Model, Vec<LoadCase>, Vec<CaseResult>, Vec<Check>);

fn analyse(axes: &Axes, gauges: &[f64], opts: &SizingOptions) -> Result<Analysis, SizingError> {
    let model = build(axes, gauges, &opts.supports, &opts.material)?;
    let cases = cases(axes, &model, opts)?;
    let results = solve(axes, &model, &cases, opts)?;
    let checks = checks_of(&model, &cases, &results, &opts.material);
    Ok((model, cases, results, checks))
}

fn checks_of(
    model: &Model,
    cases: &[LoadCase],
    results: &[CaseResult],
    material: &Material,
) -> Vec<Check> {
    let w: Vec<Vec<DVec3>> = cases
        .iter()
        .map(|c| c.member_loads(model.members.len()))
        .collect();
    (0..model.members.len())
        .map(|k| {
            let mut best = Check {
                utilisation: 0.0,
                check: "stress",
                case: 0,
            };
            for (c, r) in results.iter().enumerate() {
                let section = model.members[k].section;
                let (u, what) =
                    member_check(model, k, section, &r.end_forces[k], w[c][k], material);
                if u > best.utilisation {
                    best = Check {
                        utilisation: u,
                        check: what,
                        case: c,
                    };
                }
            }
            best
        })
        .collect()
}

/// The utilisation a member would have with another gauge under the same end forces (its own
/// weight scaled with it): the choice of each round.
fn utilisation_with(
    model: &Model,
    k: usize,
    results: &[CaseResult],
    w: &[Vec<DVec3>],
    gauge: f64,
    material: &Material,
) -> f64 {
    let section = Section {
        thickness: gauge,
        ..model.members[k].section
    };
    results
        .iter()
        .enumerate()
        .map(|(c, r)| member_check(model, k, section, &r.end_forces[k], w[c][k], material).0)
        .fold(0.0, f64::max)
}

/// The whole sizing (see the module notes).
pub fn size(axes: &Axes, opts: &SizingOptions) -> Result<Sizing, SizingError> {
    if opts.loads.is_empty() {
        return Err(SizingError::NoLoad);
    }
    let g = &opts.gauges;
    let top = g.len() - 1;
    let mut level = vec![0usize; axes.edges.len()];
    let gauges_of = |level: &[usize]| level.iter().map(|&i| g[i]).collect::<Vec<f64>>();
    let (mut model, mut cases, mut results, _) = analyse(axes, &gauges_of(&level), opts)?;
    let group = groups(axes, &model, opts.group_by)?;
    let n_groups = group.iter().copied().max().map_or(0, |m| m + 1);
    let mut rounds = 1;
    let mut converged = false;
    // Stress rounds: each group the thinnest gauge that holds its members' current forces.
    while rounds <= opts.max_rounds {
        let w: Vec<Vec<DVec3>> = cases
            .iter()
            .map(|c| c.member_loads(model.members.len()))
            .collect();
        let mut want = vec![0usize; n_groups];
        for (k, &gk) in group.iter().enumerate() {
            let need = (0..=top)
                .find(|&i| utilisation_with(&model, k, &results, &w, g[i], &opts.material) <= 1.0)
                .unwrap_or(top);
            want[gk] = want[gk].max(need);
        }
        let next: Vec<usize> = group.iter().map(|&gk| want[gk]).collect();
        if next == level {
            converged = true;
            break;
        }
        level = next;
        (model, cases, results, _) = analyse(axes, &gauges_of(&level), opts)?;
        rounds += 1;
    }
    // Deflection: raise the groups that stiffen the worst displacement most per added mass.
    let span = span_of(&axes.positions);
    let limit = opts.deflection_limit.map(|d| match d {
        DeflectionLimit::Ratio(r) => span / r,
        DeflectionLimit::Millimetres(v) => v,
    });
    let mut deflection_rounds = 0;
    if let Some(limit) = limit {
        while deflection_rounds < 200 {
            let (node, worst) = max_displacement(results.last().expect("a case"));
            if worst <= limit {
                break;
            }
            let shares = stiffening(
                axes,
                opts,
                &model,
                cases.last().expect("a case"),
                results.last().expect("a case"),
                node,
            )?;
            let mut per_group = vec![0.0; n_groups];
            for (k, s) in shares.iter().enumerate() {
                per_group[group[k]] += s;
            }
            let mut order: Vec<usize> = (0..n_groups)
                .filter(|&gk| per_group[gk] > 0.0 && group_level(&group, &level, gk) < top)
                .collect();
            if order.is_empty() {
                break;
            }
            order.sort_by(|&a, &b| per_group[b].total_cmp(&per_group[a]).then(a.cmp(&b)));
            let take = (order.len() / 10).max(1);
            for &gk in &order[..take] {
                for (k, lv) in level.iter_mut().enumerate() {
                    if group[k] == gk {
                        *lv = (*lv + 1).min(top);
                    }
                }
            }
            let checks;
            (model, cases, results, checks) = analyse(axes, &gauges_of(&level), opts)?;
            deflection_rounds += 1;
            // A raise adds weight: keep the stresses within the gauges too.
            for (k, c) in checks.iter().enumerate() {
                if c.utilisation > 1.0 && level[k] < top {
                    let gk = group[k];
                    for (j, lv) in level.iter_mut().enumerate() {
                        if group[j] == gk {
                            *lv = (*lv + 1).min(top);
                        }
                    }
                }
            }
        }
    }
    if opts.smooth {
        // Neighbours within one step: raise the thinner until it holds everywhere.
        let mut at: Vec<Vec<usize>> = vec![Vec::new(); model.nodes.len()];
        for (k, m) in model.members.iter().enumerate() {
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
    let checks;
    (model, cases, results, checks) = analyse(axes, &gauges_of(&level), opts)?;
    let (welds, throats) = weld_checks(&model, &results, &opts.material, opts.throat_factor);
    let areas = panel_areas(axes);
    let mass_kg = model
        .members
        .iter()
        .zip(&areas)
        .map(|(m, a)| a * m.section.thickness * opts.material.density * 1e-6)
        .sum();
    Ok(Sizing {
        gauges: gauges_of(&level),
        model,
        cases,
        results,
        checks,
        welds,
        throats,
        rounds,
        converged,
        deflection_rounds,
        deflection_limit: limit,
        span,
        mass_kg,
        shells: opts.shells,
    })
}

fn group_level(group: &[usize], level: &[usize], gk: usize) -> usize {
    group
        .iter()
        .zip(level)
        .filter(|(g, _)| **g == gk)
        .map(|(_, l)| *l)
        .min()
        .unwrap_or(0)
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
}

#[derive(serde::Deserialize)]
struct GaugeEdge {
    gauge: f64,
}

/// A sizing file's gauge per edge and its gauge list, for `plates --sizing`.
pub fn read_gauges(
    path: &std::path::Path,
) -> Result<(Vec<f64>, Vec<f64>), crate::files::ReadError> {
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
    }
    Ok((file.edges.iter().map(|e| e.gauge).collect(), file.gauges))
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
