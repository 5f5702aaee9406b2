//! From node axes to steel plates: each network edge becomes one flat plate in its panel's
//! plane, centred on it, with a thickness from a gauge list, cut back at each node so that the
//! plates meeting there do not interpenetrate.
//!
//! The plates at a node all contain the node's axis line, so their cross-section in the plane
//! ⊥ the axis is the same at every height: half-strips leaving the axis in directions u_k, each
//! t_k thick. Each plate is cut back from the axis by a setback chosen so that every pair of
//! angularly adjacent plates has the weld gap between them within its tolerance (see
//! `welds.rs`); a node where no setbacks can do that is reported, or given a node core (a tube
//! on the axis the plates butt against) when asked. The cut is a line parallel to the axis in
//! the plate's plane.
//!
//! Seam plates (between assembly groups) are two plates from the gauge list, the thinnest pair
//! that adds up to the plate's thickness, bolted face to face (the stack centred on the panel
//! plane) through a row of holes that keeps EN 1993-1-8's end, edge and pitch distances
//! (`bolts.rs`). Each ply is its node's group's: at that node it is the strip the others are
//! set back to, and it welds only to that group's plates; at the other node it passes unwelded,
//! set back until it is the weld gap plus its partner ply's thickness clear of everything
//! welded there (the fillet on the face it lies on has a leg of 0.7 √2 t of the thinner plate,
//! under that). The holes go where both plies are, the same in
//! both plies' frames, so they coincide in 3D.
//!
//! Each plate is stored as a 2D outline in its own frame (origin at the first node, x along the
//! edge, y toward the axis, z the plate normal) and the rigid transform placing it; the
//! panel's fourth corner is projected into the plane of the other three (its distance is the
//! panel deviation planarize reported, and is recorded as `flattening`).

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::axes::Axes;
use super::bolts::{self, BoltChecks, BoltGrade, BoltSize, PlySteel, SeamForces};
use super::clearance::{self, Room, Socket};
use super::planarize::Selector;
use super::welds::{self, Strip};
use crate::geom::clip_convex;

#[derive(Clone, Debug, PartialEq)]
pub enum Thickness {
    /// Every plate this thick, mm.
    Constant(f64),
    /// The gauge at the edge radius's place between 0 and the largest radius (thicker veins,
    /// thicker plates); edges without a radius get the thinnest gauge.
    FromRadius,
    /// One per edge, in edge order (from a sizing), mm: on the gauge list, or for a seam
    /// between groups the sum of two gauges (its plies, as the sizing analysed them).
    PerEdge(Vec<f64>),
}

/// Which edges a thickness override applies to.
#[derive(Clone, Debug, PartialEq)]
pub enum EdgeSelector {
    /// One edge, by index.
    Edge(usize),
    /// Every edge whose two nodes both match.
    Nodes(Selector),
}

impl EdgeSelector {
    /// `edge=K`, or a node selector (`all`, `node=N`, `z<1`, ...) both ends must match.
    pub fn parse(s: &str) -> Result<EdgeSelector, String> {
        match s.trim().strip_prefix("edge=") {
            Some(k) => k
                .trim()
                .parse()
                .map(EdgeSelector::Edge)
                .map_err(|_| format!("\"{k}\" is not an edge number")),
            None => Selector::parse(s).map(EdgeSelector::Nodes),
        }
    }

    fn matches(&self, axes: &Axes, k: usize) -> bool {
        match self {
            EdgeSelector::Edge(e) => *e == k,
            EdgeSelector::Nodes(sel) => axes.edges[k]
                .iter()
                .all(|&v| sel.matches(v, axes.positions[v as usize])),
        }
    }
}

#[derive(Clone, Debug)]
pub struct PlateOptions {
    /// Sheet thicknesses available, mm, ascending.
    pub gauges: Vec<f64>,
    pub thickness: Thickness,
    /// Per-edge thicknesses over the rule, in order (a later match wins).
    pub overrides: Vec<(EdgeSelector, f64)>,
    /// Root gap between plates meeting at a node, mm.
    pub weld_gap: f64,
    /// How far a root gap may be from `weld_gap`, mm.
    pub weld_gap_tolerance: f64,
    /// Assembly groups (see `groups.rs`); seam plates are split in two, bolted face to face.
    pub groups: usize,
    /// Bolt size through the seam plates [default: by the grip, smaller where the plate is
    /// small].
    pub bolt: Option<BoltSize>,
    /// A tube at every node whose gaps cannot be evened by setbacks alone.
    pub node_core: Option<CoreSize>,
    /// The bolts' class and the plies' steel, for the checks of EN 1993-1-8 Table 3.4.
    pub bolt_grade: BoltGrade,
    pub ply_steel: PlySteel,
    /// Per edge, what a seam's bolts carry (from a sizing): the size is the first that holds.
    /// None: the bolts are not checked.
    pub seam_forces: Option<Vec<Option<SeamForces>>>,
    /// The socket that tightens the bolts (None: one for each size).
    pub socket: Option<Socket>,
}

/// How the plates are joined, which decides how much steel is cut away at the nodes and for
/// the bolts: `size` weighs the plates as `plates` cuts them with these, and `plates` refuses
/// a sizing made with others.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joints {
    /// Root gap between plates at a node, mm.
    pub weld_gap: f64,
    /// How far a root gap may be from `weld_gap`, mm.
    pub weld_gap_tolerance: f64,
    /// A tube at nodes whose gaps setbacks cannot even.
    pub node_core: Option<CoreSize>,
    /// Bolts through the seams (None: by the grip).
    pub bolt: Option<BoltSize>,
    /// The socket that tightens the bolts (None: one for each size).
    pub bolt_clearance: Option<Socket>,
}

impl Joints {
    /// The weld gap and its tolerance in range: a gap above 0 (0 only with a node core), a
    /// tolerance at most the gap.
    pub fn check(&self) -> Result<(), PlateError> {
        if !(self.weld_gap >= 0.0 && self.weld_gap <= 100.0) {
            return Err(PlateError::WeldGap(self.weld_gap));
        }
        if self.weld_gap == 0.0 && self.node_core.is_none() {
            return Err(PlateError::WeldGapZero);
        }
        if !(self.weld_gap_tolerance >= 0.0 && self.weld_gap_tolerance <= 100.0) {
            return Err(PlateError::WeldGapTolerance(self.weld_gap_tolerance));
        }
        if self.weld_gap_tolerance > self.weld_gap {
            return Err(PlateError::ToleranceOverGap {
                gap: self.weld_gap,
                tolerance: self.weld_gap_tolerance,
            });
        }
        Ok(())
    }
}

/// A node core's tube, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoreSize {
    pub diameter: f64,
    pub wall: f64,
}

impl CoreSize {
    /// `tube:D,T` (outer diameter and wall, mm).
    pub fn parse(s: &str) -> Result<CoreSize, String> {
        let body = s
            .trim()
            .strip_prefix("tube:")
            .ok_or_else(|| format!("`{s}`: give the node core as tube:DIAMETER,WALL in mm"))?;
        let (d, t) = body
            .split_once(',')
            .ok_or_else(|| format!("`{s}`: give the node core as tube:DIAMETER,WALL in mm"))?;
        let num = |v: &str| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x > 0.0 && *x <= 1000.0)
                .ok_or_else(|| format!("`{s}`: `{v}` is not a size in mm from 0 to 1000"))
        };
        let (diameter, wall) = (num(d)?, num(t)?);
        if 2.0 * wall >= diameter {
            return Err(format!(
                "`{s}`: the wall must be less than half the diameter"
            ));
        }
        Ok(CoreSize { diameter, wall })
    }
}

impl Default for PlateOptions {
    fn default() -> Self {
        PlateOptions {
            gauges: vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0],
            thickness: Thickness::FromRadius,
            overrides: Vec::new(),
            weld_gap: 1.0,
            weld_gap_tolerance: 0.5,
            groups: 1,
            bolt: None,
            node_core: None,
            bolt_grade: bolts::grade(true),
            ply_steel: PlySteel::of(
                &crate::analyze::material::Material::get("1.4404").expect("a built-in steel"),
            ),
            seam_forces: None,
            socket: None,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlateError {
    #[error("the gauge list is empty")]
    NoGauges,
    #[error("the sizing has {0} edges, the axes {1}: size these axes again")]
    PerEdge(usize, usize),
    #[error("gauges must be positive and ascending: {0:?}")]
    Gauges(Vec<f64>),
    #[error("thickness= must be a positive number of mm, got {0}")]
    Thickness(f64),
    #[error("a thickness override must be a positive number of mm, got {0}")]
    Override(f64),
    #[error("a thickness override names edge {0}, but there are {1} edges")]
    OverrideEdge(usize, usize),
    #[error("thickness override {0} (counting from 1) matches no edge")]
    OverrideUnused(usize),
    #[error("weld_gap= must be from 0 to 100 mm, got {}", crate::text::num(*.0))]
    WeldGap(f64),
    #[error("weld_gap_tolerance= must be from 0 to 100 mm, got {}", crate::text::num(*.0))]
    WeldGapTolerance(f64),
    #[error(
        "weld_gap_tolerance= {} mm is more than weld_gap= {} mm: root gaps down to {} mm would \
         let plates overlap; keep the tolerance at most the gap",
        crate::text::num(*tolerance), crate::text::num(*gap), crate::text::num(*gap - *tolerance)
    )]
    ToleranceOverGap { gap: f64, tolerance: f64 },
    #[error(
        "node {node}: the plates on edges {} and {} overlap (root gap {} mm): give a larger \
         weld_gap= or a node_core=",
        edges[0], edges[1], crate::text::num(*gap)
    )]
    Overlap {
        node: usize,
        edges: [usize; 2],
        gap: f64,
    },
    #[error(
        "weld_gap= 0: the plates at a node would meet with no root gap (and overlap where the \
         gaps cannot be evened); give a gap above 0, or node_core= for a tube they weld to"
    )]
    WeldGapZero,
    #[error("{what} {t} mm is not on the gauge list {gauges:?}: add it with gauges=")]
    OffGauge {
        what: &'static str,
        t: f64,
        gauges: Vec<f64>,
    },
    #[error("edge {edge} (nodes {} and {}): the seam takes no row of {bolt} bolts by EN 1993-1-8 Table 3.3 (at least two, {:.1} mm from every edge, pitch {:.1} to {:.1} mm on its {thinner} mm ply) where its plies overlap, {:.1} mm along the member between their setbacks: {}", .nodes[0], .nodes[1], .edge_distance, .min_pitch, .max_pitch, .overlap, if *.chosen { "give a smaller bolt= or thicker gauges" } else { "the smallest size is too big for it: give another groups= (the seams fall elsewhere), a smaller node_core= (its radius sets the setbacks there) or thicker gauges" })]
    NoRoomForBolt {
        /// Length of the plies' overlap along the member's mid-height line, mm.
        overlap: f64,
        /// Whether the size was the caller's (bolt=) rather than the smallest tried.
        chosen: bool,
        edge: usize,
        nodes: [u32; 2],
        bolt: &'static str,
        edge_distance: f64,
        min_pitch: f64,
        max_pitch: f64,
        thinner: f64,
    },
    #[error(
        "edge {edge} (nodes {} and {}): the seam's bolts do not hold its forces from the sizing: \
         {bolt} at best, utilisation {} ({check}, EN 1993-1-8 Table 3.4): {}",
        .nodes[0], .nodes[1], crate::text::num((*utilisation * 1000.0).round() / 1000.0),
        if *chosen { "give another bolt= or thicker gauges" } else { "give thicker gauges (size with a thicker list) or another groups=" }
    )]
    BoltsOverloaded {
        chosen: bool,
        edge: usize,
        nodes: [u32; 2],
        bolt: &'static str,
        utilisation: f64,
        check: &'static str,
    },
    #[error("node {0} has no usable axis or height")]
    Axis(u32),
    #[error("edge {0} has zero length or lies along its node's axis: it has no plate")]
    Degenerate(usize),
    #[error("edge {edge}: the plates meeting at node {node} are {angle_deg:.2}° apart, too close to cut apart")]
    TooClose {
        edge: usize,
        node: u32,
        angle_deg: f64,
    },
    #[error("edge {0}: its setbacks ({1:.1} and {2:.1} mm) leave nothing of the plate")]
    TooShort(usize, f64, f64),
    #[error(
        "edge {edge}: the seam's ply that passes node {node} cannot stop {} mm clear of the \
         plates welded there within its length: give another groups= (the seams fall \
         elsewhere)",
        crate::text::num(*clearance)
    )]
    PlyTooShort {
        edge: usize,
        node: u32,
        clearance: f64,
    },
    #[error("edge {0}: its panel is twisted or self-crossing (the axes cross within the height)")]
    Twisted(usize),
    #[error(transparent)]
    Groups(#[from] super::groups::GroupError),
    #[error("the axes hold {0} nodes but {1} axes, {2} heights; {3} edges but {4} radii")]
    Lengths(usize, usize, usize, usize, usize),
    #[error("edge {0} refers to node {1}, which does not exist")]
    MissingNode(usize, u32),
}

/// How far two plates may cross at a node (rounding), mm: more is an overlap and an error.
const OVERLAP: f64 = 1e-9;

/// What names the per-edge gauges when they come from a sizing (`PlateError::OffGauge`).
pub const SIZING_GAUGE: &str = "the sizing's gauge";

impl PlateError {
    /// Whether the sizing's per-edge gauges are at fault (not the axes or the options): the
    /// command names the sizing file then.
    pub fn is_the_sizings(&self) -> bool {
        matches!(
            self,
            PlateError::PerEdge(..)
                | PlateError::OffGauge {
                    what: SIZING_GAUGE,
                    ..
                }
        )
    }
}

/// Where a plate sits: world = origin + x·X + y·Y + z·Z for plate coordinates (x, y, z), with z
/// across the thickness (the plate spans z ∈ [−t/2, t/2]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub origin: DVec3,
    pub x: DVec3,
    pub y: DVec3,
    pub z: DVec3,
}

impl Placement {
    pub fn world(&self, p: DVec2, z: f64) -> DVec3 {
        self.origin + self.x * p.x + self.y * p.y + self.z * z
    }

    /// Rows of the 4 × 4 matrix (OpenSCAD's `multmatrix`).
    pub fn matrix(&self) -> [[f64; 4]; 4] {
        let (o, x, y, z) = (self.origin, self.x, self.y, self.z);
        [
            [x.x, y.x, z.x, o.x],
            [x.y, y.y, z.y, o.y],
            [x.z, y.z, z.z, o.z],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }
}

#[derive(Clone, Debug)]
pub struct Plate {
    /// Tag `G-NNN`: assembly group (from 1) and number within it, in edge order.
    pub id: String,
    /// Assembly group, from 0.
    pub group: u32,
    pub edge: usize,
    pub nodes: [u32; 2],
    pub thickness: f64,
    /// Counter-clockwise, in the plate's frame, mm.
    pub outline: Vec<DVec2>,
    pub placement: Placement,
    /// Cut back from each node's axis, mm.
    pub setback: [f64; 2],
    /// Plates (by index) welded to this one at each node: every other plate of the node's
    /// group there (a seam's ply only at its own group's node, to that group's plates); none
    /// where the node has a core.
    pub partners: [Vec<usize>; 2],
    /// The core (index into `PlateSet::cores`) this plate welds to at each node, if any.
    pub core: [Option<usize>; 2],
    /// On a seam between groups: the other half, bolted face to face.
    pub bolted_to: Option<usize>,
    /// Bolt hole centres in the plate's frame (seam plates only); both halves share them.
    pub holes: Vec<DVec2>,
    pub bolt: Option<Bolting>,
    /// Distance of the panel's fourth corner from the plate's plane, mm.
    pub flattening: f64,
}

/// The bolts through a seam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bolting {
    pub size: BoltSize,
    pub grade: BoltGrade,
    /// Under the sizing's forces (None without them).
    pub checks: Option<BoltChecks>,
    /// Both halves together, mm.
    pub grip: f64,
    /// Standard length to order, mm.
    pub length: f64,
}

/// Sides of the polygon standing for a hole in meshes and plates.json's areas.
pub const HOLE_SEGMENTS: usize = 64;

/// A hole as a polygon: `HOLE_SEGMENTS` corners on the circle, counter-clockwise from +x.
pub fn hole_polygon(centre: DVec2, diameter: f64) -> Vec<DVec2> {
    (0..HOLE_SEGMENTS)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / HOLE_SEGMENTS as f64;
            centre + DVec2::from_angle(a) * (0.5 * diameter)
        })
        .collect()
}

impl Plate {
    /// Outline less the holes (as their polygons), mm².
    pub fn area(&self) -> f64 {
        let holes: f64 = self
            .holes
            .iter()
            .map(|c| polygon_area(&hole_polygon(*c, self.hole_diameter())))
            .sum();
        polygon_area(&self.outline) - holes
    }

    /// d0 of the bolt holes, or 0 without bolts.
    pub fn hole_diameter(&self) -> f64 {
        self.bolt.map(|b| b.size.hole).unwrap_or(0.0)
    }

    /// The plate as a closed prism: outline at z = ±t/2, holes as `HOLE_SEGMENTS`-gons through
    /// it, caps by constrained Delaunay, outward-facing triangles.
    pub fn prism(&self) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        prism(
            &self.outline,
            &self.holes,
            self.hole_diameter(),
            self.thickness,
            |p, z| self.placement.world(p, z),
        )
    }
}

/// A plate as a closed prism: `outline` (counter-clockwise, in the plate's frame) at z = ±t/2,
/// holes of `hole_diameter` at `holes` as `HOLE_SEGMENTS`-gons through it, caps by constrained
/// Delaunay, outward-facing triangles; `world` places a frame point at a height. The first
/// `outline.len()` points are the outline at −t/2, the same number from `n` (the loops' point
/// count) at +t/2.
pub fn prism(
    outline: &[DVec2],
    holes: &[DVec2],
    hole_diameter: f64,
    thickness: f64,
    world: impl Fn(DVec2, f64) -> DVec3,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut loops = vec![outline.to_vec()];
    loops.extend(holes.iter().map(|c| hole_polygon(*c, hole_diameter)));
    let flat: Vec<DVec2> = loops.iter().flatten().copied().collect();
    let n = flat.len() as u32;
    let h = thickness / 2.0;
    let mut v: Vec<DVec3> = flat.iter().map(|p| world(*p, -h)).collect();
    v.extend(flat.iter().map(|p| world(*p, h)));
    let mut t = Vec::new();
    for [a, b, c] in cap_triangles(&loops) {
        t.push([a, c, b]); // bottom, facing −z
        t.push([n + a, n + b, n + c]); // top, facing +z
    }
    let mut base = 0u32;
    for (k, l) in loops.iter().enumerate() {
        let m = l.len() as u32;
        for i in 0..m {
            let (p, q) = (base + i, base + (i + 1) % m);
            // The outline runs counter-clockwise, the holes too: their walls face inward.
            if k == 0 {
                t.push([p, q, n + q]);
                t.push([p, n + q, n + p]);
            } else {
                t.push([q, p, n + p]);
                t.push([q, n + p, n + q]);
            }
        }
        base += m;
    }
    (v, t)
}

/// Counter-clockwise triangles covering the first loop less the others (holes inside it), as
/// indices into the loops' points laid end to end. A convex loop without holes is a fan.
fn cap_triangles(loops: &[Vec<DVec2>]) -> Vec<[u32; 3]> {
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
    if loops.len() == 1 {
        let n = loops[0].len() as u32;
        return (1..n.saturating_sub(1)).map(|k| [0, k, k + 1]).collect();
    }
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut index = std::collections::HashMap::new();
    let mut handles = Vec::new();
    let mut next = 0u32;
    for l in loops {
        let mut hs = Vec::with_capacity(l.len());
        for p in l {
            let h = cdt
                .insert(Point2::new(p.x, p.y))
                .expect("plate coordinates are finite");
            index.entry(h).or_insert(next);
            next += 1;
            hs.push(h);
        }
        handles.push(hs);
    }
    for hs in &handles {
        for k in 0..hs.len() {
            let (a, b) = (hs[k], hs[(k + 1) % hs.len()]);
            if a != b && !cdt.exists_constraint(a, b) {
                cdt.add_constraint(a, b);
            }
        }
    }
    let mut out = Vec::new();
    for f in cdt.inner_faces() {
        let vs = f.vertices();
        let p = vs.map(|v| DVec2::new(v.position().x, v.position().y));
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let inside = |l: &[DVec2]| {
            (0..l.len()).all(|k| (l[(k + 1) % l.len()] - l[k]).perp_dot(c - l[k]) > 0.0)
        };
        if !inside(&loops[0]) || loops[1..].iter().any(|h| inside(h)) {
            continue;
        }
        let tri = vs.map(|v| index[&v.fix()]);
        if (p[1] - p[0]).perp_dot(p[2] - p[0]) > 0.0 {
            out.push(tri);
        } else {
            out.push([tri[0], tri[2], tri[1]]);
        }
    }
    out
}

pub fn polygon_area(p: &[DVec2]) -> f64 {
    let mut a = 0.0;
    for (k, q) in p.iter().enumerate() {
        let r = p[(k + 1) % p.len()];
        a += q.perp_dot(r);
    }
    0.5 * a
}

fn check(axes: &Axes, opts: &PlateOptions) -> Result<(), PlateError> {
    if opts.gauges.is_empty() {
        return Err(PlateError::NoGauges);
    }
    let ascending = opts.gauges.windows(2).all(|w| w[0] < w[1]);
    if !ascending || opts.gauges.iter().any(|g| !(g.is_finite() && *g > 0.0)) {
        return Err(PlateError::Gauges(opts.gauges.clone()));
    }
    if let Thickness::Constant(t) = opts.thickness {
        if !(t.is_finite() && t > 0.0) {
            return Err(PlateError::Thickness(t));
        }
    }
    if let Thickness::PerEdge(list) = &opts.thickness {
        if list.len() != axes.edges.len() {
            return Err(PlateError::PerEdge(list.len(), axes.edges.len()));
        }
        if let Some(t) = list.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
            return Err(PlateError::Thickness(*t));
        }
    }
    for (sel, t) in &opts.overrides {
        if !(t.is_finite() && *t > 0.0) {
            return Err(PlateError::Override(*t));
        }
        if let EdgeSelector::Edge(k) = sel {
            if *k >= axes.edges.len() {
                return Err(PlateError::OverrideEdge(*k, axes.edges.len()));
            }
        }
    }
    Joints {
        weld_gap: opts.weld_gap,
        weld_gap_tolerance: opts.weld_gap_tolerance,
        node_core: opts.node_core,
        bolt: opts.bolt,
        bolt_clearance: opts.socket,
    }
    .check()?;
    let on_list = |t: f64| opts.gauges.iter().any(|g| (g - t).abs() < 1e-9);
    let off = |what: &'static str, t: f64| PlateError::OffGauge {
        what,
        t,
        gauges: opts.gauges.clone(),
    };
    if let Thickness::Constant(t) = opts.thickness {
        if !on_list(t) {
            return Err(off("thickness=", t));
        }
    }
    if let Thickness::PerEdge(list) = &opts.thickness {
        // A seam's stack may be two gauges; `plates` checks single plates are on the list.
        let stack =
            |t: f64| seam_gauges(t, &opts.gauges).is_some_and(|(a, b)| (a + b - t).abs() < 1e-9);
        if let Some(t) = list.iter().find(|t| !on_list(**t) && !stack(**t)) {
            return Err(off(SIZING_GAUGE, *t));
        }
    }
    if let Some((_, t)) = opts.overrides.iter().find(|(_, t)| !on_list(*t)) {
        return Err(off("the thickness override", *t));
    }
    let n = axes.positions.len();
    if axes.axes.len() != n || axes.heights.len() != n || axes.edge_radii.len() != axes.edges.len()
    {
        return Err(PlateError::Lengths(
            n,
            axes.axes.len(),
            axes.heights.len(),
            axes.edges.len(),
            axes.edge_radii.len(),
        ));
    }
    for (k, e) in axes.edges.iter().enumerate() {
        if let Some(&v) = e.iter().find(|&&v| v as usize >= n) {
            return Err(PlateError::MissingNode(k, v));
        }
    }
    for i in 0..axes.positions.len() {
        let ok = axes.positions[i].is_finite()
            && axes.axes[i].is_finite()
            && (axes.axes[i].length() - 1.0).abs() < 1e-6
            && axes.heights[i].is_finite()
            && axes.heights[i] > 0.0;
        if !ok {
            return Err(PlateError::Axis(i as u32));
        }
    }
    Ok(())
}

/// Thickness of each edge's plate: the rule, then the overrides.
pub fn thicknesses(axes: &Axes, opts: &PlateOptions) -> Result<Vec<f64>, PlateError> {
    let mut t = by_rule(axes, opts);
    for (n, (sel, value)) in opts.overrides.iter().enumerate() {
        let mut used = false;
        for (k, t) in t.iter_mut().enumerate() {
            if sel.matches(axes, k) {
                *t = *value;
                used = true;
            }
        }
        if !used {
            return Err(PlateError::OverrideUnused(n + 1));
        }
    }
    Ok(t)
}

fn by_rule(axes: &Axes, opts: &PlateOptions) -> Vec<f64> {
    match &opts.thickness {
        Thickness::Constant(t) => vec![*t; axes.edges.len()],
        Thickness::PerEdge(list) => list.clone(),
        Thickness::FromRadius => {
            let top = axes.edge_radii.iter().copied().fold(0.0, f64::max);
            let last = opts.gauges.len() - 1;
            axes.edge_radii
                .iter()
                .map(|&r| {
                    let k = if top > 0.0 {
                        ((r / top) * last as f64).round() as usize
                    } else {
                        0
                    };
                    opts.gauges[k.min(last)]
                })
                .collect()
        }
    }
}

/// The two gauges a seam plate of thickness `t` is split into: the thinnest pair adding up to
/// at least `t`, the most even of those; thinner first.
pub fn seam_gauges(t: f64, gauges: &[f64]) -> Option<(f64, f64)> {
    let mut best: Option<(f64, f64)> = None;
    for (i, &a) in gauges.iter().enumerate() {
        for &b in &gauges[i..] {
            if a + b < t - 1e-9 {
                continue;
            }
            let better = best.is_none_or(|(x, y)| {
                let (sum, old) = (a + b, x + y);
                sum < old - 1e-9 || ((sum - old).abs() <= 1e-9 && b - a < y - x)
            });
            if better {
                best = Some((a, b));
            }
        }
    }
    best
}

/// A tube at a node the plates weld to, mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Core {
    pub id: String,
    pub node: u32,
    pub group: u32,
    pub size: CoreSize,
    /// From the node along its axis, `length` long.
    pub base: DVec3,
    pub axis: DVec3,
    pub length: f64,
}

impl Core {
    /// The tube's mass, kg, for a steel of `density` kg/dm³.
    pub fn mass_kg(&self, density: f64) -> f64 {
        let (d, w) = (self.size.diameter, self.size.wall);
        let inner = d - 2.0 * w;
        std::f64::consts::FRAC_PI_4 * (d * d - inner * inner) * self.length * density * 1e-6
    }
}

/// Two plates side by side at a node and the wedge between them (see `welds::Wedge`).
#[derive(Clone, Debug, PartialEq)]
pub struct WeldPair {
    /// Edges (the plates on them).
    pub edges: [usize; 2],
    /// The angle between the two plates about the node axis, degrees in (0, 180].
    pub angle_deg: f64,
    /// Root gap between the two plates (a seam counts as its stack), mm.
    pub gap: f64,
}

/// The welds at one node.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeWelds {
    pub node: u32,
    /// The node's assembly group: its plates, and of a seam the ply in this group, weld here.
    pub group: u32,
    /// Edges meeting here.
    pub edges: Vec<usize>,
    /// Setback here of the plate each of those edges welds with (a seam's ply of this group),
    /// mm.
    pub setbacks: Vec<f64>,
    /// The seams' other plies (by edge), which pass this node unwelded: their setback here and
    /// their least distance from every plate welded here (and from the core), mm.
    pub passing: Vec<Passing>,
    pub pairs: Vec<WeldPair>,
    /// Every adjacent pair's root gap within the tolerance.
    pub even: bool,
    /// Index into `PlateSet::cores`, when the node has one.
    pub core: Option<usize>,
}

/// A seam's ply at the node of the other group: set back until it clears every plate welded
/// there (and the core) by the weld gap plus the thickness of its partner ply, which welds
/// there (room for that fillet's leg, 0.7 √2 t of the thinner plate, under t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Passing {
    pub edge: usize,
    pub setback: f64,
    /// Its least distance from the plates welded at the node and the core, mm.
    pub clearance: f64,
}

/// Everything `plates` makes.
#[derive(Clone, Debug)]
pub struct PlateSet {
    pub plates: Vec<Plate>,
    /// Per edge: its plate, or a seam's two halves.
    pub by_edge: Vec<Vec<usize>>,
    /// Nodes where two or more plates meet.
    pub welds: Vec<NodeWelds>,
    pub cores: Vec<Core>,
    /// Bolts moved along their rows for room to fit and tighten them, and those without.
    pub room: Room,
}

impl PlateSet {
    /// The plates' mass, kg, for a steel of `density` kg/dm³ (plates only: no bolts or cores).
    pub fn mass_kg(&self, density: f64) -> f64 {
        self.plates
            .iter()
            .map(|q| q.area() * q.thickness * density * 1e-6)
            .sum()
    }
}

pub fn plates(axes: &Axes, opts: &PlateOptions) -> Result<PlateSet, PlateError> {
    check(axes, opts)?;
    let n = axes.positions.len();
    let t = thicknesses(axes, opts)?;
    let group = super::groups::partition(&axes.positions, &axes.edges, opts.groups)?;
    // A sized stack of two gauges is a seam's; a single plate is on the list.
    if let Thickness::PerEdge(_) = opts.thickness {
        for (k, &[a, b]) in axes.edges.iter().enumerate() {
            let single = group[a as usize] == group[b as usize];
            if single && !opts.gauges.iter().any(|g| (g - t[k]).abs() < 1e-9) {
                return Err(PlateError::OffGauge {
                    what: SIZING_GAUGE,
                    t: t[k],
                    gauges: opts.gauges.clone(),
                });
            }
        }
    }
    // A seam's two plies, and the stack every plate's cut allows for.
    let plies: Vec<Option<(f64, f64)>> = axes
        .edges
        .iter()
        .zip(&t)
        .map(|(&[a, b], &tk)| {
            (group[a as usize] != group[b as usize])
                .then(|| seam_gauges(tk, &opts.gauges).expect("two of the largest gauge hold it"))
        })
        .collect();
    let stack: Vec<f64> = t
        .iter()
        .zip(&plies)
        .map(|(&tk, p)| p.map(|(a, b)| a + b).unwrap_or(tk))
        .collect();
    // Incident edges per node, and each edge's in-section direction u at each end.
    let mut at: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n]; // (edge, end)
    let mut dir = vec![[DVec3::ZERO; 2]; axes.edges.len()];
    for (k, &[a, b]) in axes.edges.iter().enumerate() {
        for (end, (v, w)) in [(a, b), (b, a)].into_iter().enumerate() {
            let d = axes.axes[v as usize];
            let e = axes.positions[w as usize] - axes.positions[v as usize];
            dir[k][end] = (e - d * e.dot(d))
                .try_normalize()
                .ok_or(PlateError::Degenerate(k))?;
            at[v as usize].push((k, end));
        }
    }
    // Per edge and end: the setback of the plate welded there (a seam's ply of that node's
    // group) and of a seam's other ply.
    let mut welded = vec![[0.0f64; 2]; axes.edges.len()];
    let mut passing = vec![[0.0f64; 2]; axes.edges.len()];
    let mut welds = Vec::new();
    let mut cores = Vec::new();
    let sides = Sides {
        t: &t,
        plies: &plies,

        dir: &dir,
        group: &group,
    };
    // The nodes side by side (each solves its own setbacks), then in order: the first error
    // and the cores' numbering as one after another would give.
    let solved: Vec<_> = (at.par_iter().enumerate())
        .filter(|(_, here)| here.len() >= 2)
        .map(|(v, here)| (v, here, node_welds(axes, opts, v, here, &sides)))
        .collect();
    for (v, here, solved) in solved {
        let (mut node, core) = solved?;
        if let Some(c) = core {
            node.core = Some(cores.len());
            cores.push(c);
        }
        // Plates that overlap cannot be built, whatever the report says about the node.
        if let Some(pair) = node.pairs.iter().find(|p| p.gap < -OVERLAP) {
            return Err(PlateError::Overlap {
                node: v,
                edges: pair.edges,
                gap: pair.gap,
            });
        }
        for (&(k, end), s) in here.iter().zip(&node.setbacks) {
            welded[k][end] = *s;
            passing[k][end] = *s;
        }
        for p in &node.passing {
            let end = usize::from(axes.edges[p.edge][0] as usize != v);
            passing[p.edge][end] = p.setback;
        }
        welds.push(node);
    }
    let mut per_edge = Vec::with_capacity(axes.edges.len());
    for (k, ply) in plies.iter().enumerate() {
        let Some((ta, tb)) = *ply else {
            per_edge.push(vec![plate(axes, k, t[k], welded[k])?.0]);
            continue;
        };
        // Each ply reaches its own group's node and stops short of the other's; the bolts go
        // where both are.
        let [w, p] = [welded[k], passing[k]];
        let (mut both, mid) = plate(axes, k, stack[k], [w[0].max(p[0]), w[1].max(p[1])])?;
        bolt_seam(&mut both, mid, opts, ta.min(tb))?;
        let mut halves = Vec::with_capacity(2);
        // Ply a (node a's group) on the −z side of the stack, ply b on the +z side.
        for (thickness, setback, centre) in
            [(ta, [w[0], p[1]], -0.5 * tb), (tb, [p[0], w[1]], 0.5 * ta)]
        {
            let (mut half, _) = plate(axes, k, thickness, setback)?;
            half.placement.origin += half.placement.z * centre;
            half.holes = both.holes.clone();
            half.bolt = both.bolt;
            halves.push(half);
        }
        per_edge.push(halves);
    }
    let (plates, by_edge) = tag(per_edge, &group);
    let mut set = PlateSet {
        plates,
        by_edge,
        welds,
        cores,
        room: Room::default(),
    };
    core_partners(&mut set);
    set.room = clearance::make_room(&mut set, opts.socket);
    // A moved bolt changes the row's checks.
    let moved: std::collections::BTreeSet<[usize; 2]> = (set.room.moved.iter().map(|m| m.0))
        .chain(set.room.dropped.iter().map(|d| d.0))
        .collect();
    for [a, b] in moved {
        let (pa, pb) = (&set.plates[a], &set.plates[b]);
        let Some(bolting) = pa.bolt else { continue };
        let overlap = clearance::overlap_outline(&pa.outline, &pb.outline);
        let thinner = pa.thickness.min(pb.thickness);
        let Some(checks) = opts.bolt_checks(pa.edge, &bolting.size, &pa.holes, &overlap, thinner)
        else {
            continue;
        };
        if checks.governing().0 > 1.0 {
            return Err(overloaded(pa, &bolting.size, &checks, opts));
        }
        for i in [a, b] {
            if let Some(bt) = set.plates[i].bolt.as_mut() {
                bt.checks = Some(checks);
            }
        }
    }
    Ok(set)
}

impl PlateOptions {
    /// What the seam on `edge` carries, from the sizing (None without one).
    fn seam_forces(&self, edge: usize) -> Option<SeamForces> {
        self.seam_forces
            .as_ref()
            .and_then(|f| f.get(edge).copied().flatten())
    }

    /// The Table 3.4 checks of `bolt`s at `holes` through the seam on `edge`, its plies
    /// overlapping over `overlap`, under the sizing's forces (None without them).
    fn bolt_checks(
        &self,
        edge: usize,
        bolt: &BoltSize,
        holes: &[DVec2],
        overlap: &[DVec2],
        thinner: f64,
    ) -> Option<BoltChecks> {
        let forces = self.seam_forces(edge)?;
        Some(bolts::check(
            bolt,
            &self.bolt_grade,
            holes,
            overlap,
            thinner,
            &self.ply_steel,
            &forces,
        ))
    }
}

/// The error for a seam of `p`'s whose `bolt`s do not hold.
fn overloaded(p: &Plate, bolt: &BoltSize, checks: &BoltChecks, opts: &PlateOptions) -> PlateError {
    let (utilisation, check) = checks.governing();
    PlateError::BoltsOverloaded {
        chosen: opts.bolt.is_some(),
        edge: p.edge,
        nodes: p.nodes,
        bolt: bolt.name,
        utilisation,
        check,
    }
}

/// Per edge: what its plates are (for the strips at a node).
struct Sides<'a> {
    t: &'a [f64],
    plies: &'a [Option<(f64, f64)>],
    dir: &'a [[DVec3; 2]],
    group: &'a [u32],
}

/// The setbacks, wedges and gaps at node `v`, with a core when it needs one and one is asked
/// for (the caller numbers it: `NodeWelds::core` is left None). A seam's ply of this node's
/// group is the strip that welds here; its other ply then stops clear of every plate welded
/// here.
fn node_welds(
    axes: &Axes,
    opts: &PlateOptions,
    v: usize,
    here: &[(usize, usize)],
    sides: &Sides,
) -> Result<(NodeWelds, Option<Core>), PlateError> {
    let d = axes.axes[v];
    let e1 = sides.dir[here[0].0][here[0].1];
    let e2 = d.cross(e1);
    // In the section, +u.perp() is the plate's −z at its first node and +z at its second: the
    // ply of the first node's group is on −z, so either end's own ply sits half the other ply
    // to +u.perp() of the plane.
    let strip = |k: usize, end: usize, own: bool| {
        let u = sides.dir[k][end];
        let [a, b] = axes.edges[k];
        let mut s = Strip::centred(
            DVec2::new(u.dot(e1), u.dot(e2)),
            sides.t[k],
            axes.positions[a as usize].distance(axes.positions[b as usize]),
        );
        if let Some((ta, tb)) = sides.plies[k] {
            let (mine, other) = if end == 0 { (ta, tb) } else { (tb, ta) };
            let (t, offset) = if own {
                (mine, 0.5 * other)
            } else {
                (other, -0.5 * mine)
            };
            s.thickness = t;
            s.offset = offset;
        }
        s
    };
    let strips: Vec<Strip> = here.iter().map(|&(k, end)| strip(k, end, true)).collect();
    let cut =
        welds::even_gaps(&strips, opts.weld_gap, opts.weld_gap_tolerance).ok_or_else(|| {
            // Two plates leave the axis in the same direction: name the pair.
            let (k, angle) = closest_pair(&strips);
            PlateError::TooClose {
                edge: here[k].0,
                node: v as u32,
                angle_deg: angle.to_degrees(),
            }
        })?;
    let mut setbacks = cut.setbacks;
    let mut core = None;
    if let (false, Some(size)) = (cut.even, opts.node_core) {
        setbacks = welds::core_setbacks(&strips, 0.5 * size.diameter, opts.weld_gap);
        core = Some(Core {
            id: format!("{}-C{v}", sides.group[v] + 1),
            node: v as u32,
            group: sides.group[v],
            size,
            base: axes.positions[v],
            axis: d,
            length: axes.heights[v],
        });
    }
    // One record per pair of neighbours (a two-plate node's pair is neighbours on both sides),
    // with the angle between the two plates, 0–180°: a wedge opening more than 180° is the
    // outside of a corner, whose plates meet at the other side's angle.
    let mut pairs: Vec<WeldPair> = Vec::new();
    for w in welds::wedges(&strips) {
        let edges = [here[w.a].0, here[w.b].0];
        if pairs
            .iter()
            .any(|p| p.edges == edges || p.edges == [edges[1], edges[0]])
        {
            continue;
        }
        let angle = w.angle.min(std::f64::consts::TAU - w.angle);
        pairs.push(WeldPair {
            edges,
            angle_deg: angle.to_degrees(),
            gap: welds::root_gap(&strips[w.a], setbacks[w.a], &strips[w.b], setbacks[w.b]),
        });
    }
    // The other plies, one after another, each clear of the welded plates and those before it
    // by the gap and its own ply's thickness (the ply it lies on welds here with a fillet
    // whose leg, 0.7 √2 t of the thinner plate, is under that).
    let radius = core.as_ref().map(|c| 0.5 * c.size.diameter);
    let mut placed: Vec<(Strip, f64)> = Vec::new();
    let mut passing = Vec::new();
    for (i, &(k, end)) in here.iter().enumerate() {
        if sides.plies[k].is_none() {
            continue;
        }
        let other = strip(k, end, false);
        let clearance = opts.weld_gap + strips[i].thickness;
        let others: Vec<(Strip, f64)> = (0..here.len())
            .filter(|&j| j != i)
            .map(|j| (strips[j], setbacks[j]))
            .chain(placed.iter().copied())
            .collect();
        let setback = welds::clearing_setback(&other, setbacks[i], &others, radius, clearance)
            .ok_or(PlateError::PlyTooShort {
                edge: k,
                node: v as u32,
                clearance,
            })?;
        let gap = others
            .iter()
            .map(|(o, so)| welds::root_gap(&other, setback, o, *so))
            .chain(radius.map(|r| setback - r))
            .fold(f64::INFINITY, f64::min);
        placed.push((other, setback));
        passing.push(Passing {
            edge: k,
            setback,
            clearance: gap,
        });
    }
    let welds = NodeWelds {
        node: v as u32,
        group: sides.group[v],
        edges: here.iter().map(|h| h.0).collect(),
        setbacks,
        passing,
        pairs,
        even: cut.even,
        core: None,
    };
    Ok((welds, core))
}

/// A strip of the two whose directions are closest, and their angle.
fn closest_pair(strips: &[Strip]) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for a in 0..strips.len() {
        for b in a + 1..strips.len() {
            let angle = strips[a].u.angle_to(strips[b].u).abs();
            if angle < best.1 {
                best = (a, angle);
            }
        }
    }
    best
}

/// Holes along the seam plate's mid-height line `mid`, of the given size or from the grip's
/// default down (then up) the first whose row fits and, with the seam's forces, holds.
fn bolt_seam(
    p: &mut Plate,
    mid: [DVec2; 2],
    opts: &PlateOptions,
    thinner: f64,
) -> Result<(), PlateError> {
    let grip = p.thickness;
    let forces = opts.seam_forces(p.edge);
    let tried: Vec<BoltSize> = match opts.bolt {
        Some(b) => vec![b],
        None => {
            let top = bolts::for_grip(grip);
            let down = bolts::SIZES.iter().rev().filter(|b| b.d <= top.d);
            // Larger ones only when the forces ask for them.
            let up = bolts::SIZES
                .iter()
                .filter(|b| b.d > top.d && forces.is_some());
            down.chain(up).copied().collect()
        }
    };
    let mut weakest: Option<(BoltSize, BoltChecks)> = None;
    for b in &tried {
        // Along the mid-height line; on a plate too short for that, up its middle across the
        // member (p2 ≥ 2.4 d0), which holds the plies against turning as well.
        // Through the middle of the plies' overlap, which a setback may have moved off the
        // panel's middle.
        let centre = bolts::chord(&p.outline, mid[0], mid[1], 0.0)
            .map_or(0.5 * (mid[0] + mid[1]), |(a, b, _)| 0.5 * (a + b));
        let up = (mid[1] - mid[0]).perp().normalize_or_zero() * 1e4;
        let mut rows: Vec<Vec<DVec2>> =
            bolts::denser_rows(&p.outline, mid[0], mid[1], b, thinner, bolts::min_pitch(b))
                .collect();
        if rows.is_empty() {
            rows = bolts::denser_rows(
                &p.outline,
                centre - up,
                centre + up,
                b,
                thinner,
                bolts::min_pitch_across(b),
            )
            .collect();
        }
        // The fewest bolts that hold (without forces, the fewest the pitch allows).
        let mut chosen = None;
        for holes in rows {
            let checks = opts.bolt_checks(p.edge, b, &holes, &p.outline, thinner);
            match checks {
                Some(c) if c.governing().0 > 1.0 => {
                    if weakest.is_none_or(|(_, w)| c.governing().0 < w.governing().0) {
                        weakest = Some((*b, c));
                    }
                }
                _ => {
                    chosen = Some((holes, checks));
                    break;
                }
            }
        }
        let Some((holes, checks)) = chosen else {
            continue;
        };
        p.holes = holes;
        p.bolt = Some(Bolting {
            size: *b,
            grade: opts.bolt_grade,
            checks,
            grip,
            length: bolts::length(b, grip).unwrap_or(f64::NAN),
        });
        return Ok(());
    }
    if let Some((b, c)) = weakest {
        return Err(overloaded(p, &b, &c, opts));
    }
    let last = tried.last().expect("at least one size");
    Err(PlateError::NoRoomForBolt {
        overlap: bolts::chord(&p.outline, mid[0], mid[1], 0.0).map_or(0.0, |c| c.2),
        chosen: opts.bolt.is_some(),
        edge: p.edge,
        nodes: p.nodes,
        bolt: last.name,
        edge_distance: bolts::edge_distance(last),
        min_pitch: bolts::min_pitch(last),
        max_pitch: bolts::max_pitch(thinner),
        thinner,
    })
}

/// Groups, pairs and partners of the plates per edge (one, or a seam's two plies: node a's
/// group's first), and tags `G-NNN` in edge order within each group.
fn tag(per_edge: Vec<Vec<Plate>>, group: &[u32]) -> (Vec<Plate>, Vec<Vec<usize>>) {
    let mut out: Vec<Plate> = Vec::with_capacity(per_edge.len());
    let mut by_edge = Vec::with_capacity(per_edge.len());
    for plates in per_edge {
        let first = out.len();
        let seam = plates.len() == 2;
        for (i, mut p) in plates.into_iter().enumerate() {
            p.group = group[p.nodes[i] as usize];
            p.bolted_to = seam.then_some(first + 1 - i);
            out.push(p);
        }
        by_edge.push((first..out.len()).collect());
    }
    let mut at: std::collections::HashMap<u32, Vec<usize>> = Default::default();
    for (i, p) in out.iter().enumerate() {
        for v in p.nodes {
            at.entry(v).or_default().push(i);
        }
    }
    let mut count: std::collections::BTreeMap<u32, usize> = Default::default();
    let tagged: Vec<([Vec<usize>; 2], String)> = out
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // Welded at a node only within its group: a ply passes the other group's node.
            let partners = p.nodes.map(|v| {
                let g = group[v as usize];
                if p.group != g {
                    return Vec::new();
                }
                at[&v]
                    .iter()
                    .copied()
                    .filter(|&j| j != i && out[j].group == g)
                    .collect::<Vec<_>>()
            });
            let n = count.entry(p.group).or_default();
            *n += 1;
            (partners, format!("{}-{:03}", p.group + 1, n))
        })
        .collect();
    for (p, (partners, id)) in out.iter_mut().zip(tagged) {
        p.partners = partners;
        p.id = id;
    }
    (out, by_edge)
}

/// At a node with a core, every plate of its group welds to the core rather than to the other
/// plates.
fn core_partners(set: &mut PlateSet) {
    for w in &set.welds {
        if w.core.is_none() {
            continue;
        }
        for &k in &w.edges {
            for &i in &set.by_edge[k] {
                let p = &mut set.plates[i];
                for end in 0..2 {
                    if p.nodes[end] == w.node && p.group == w.group {
                        p.partners[end].clear();
                        p.core[end] = w.core;
                    }
                }
            }
        }
    }
}

/// The plate on edge `k`, and its mid-height line (from the middle of its side at the first
/// node to the middle of the side at the second), where bolts go.
fn plate(
    axes: &Axes,
    k: usize,
    thickness: f64,
    setback: [f64; 2],
) -> Result<(Plate, [DVec2; 2]), PlateError> {
    let [a, b] = axes.edges[k];
    let (a, b) = (a as usize, b as usize);
    let (va, vb) = (axes.positions[a], axes.positions[b]);
    let (da, db) = (axes.axes[a], axes.axes[b]);
    let (ha, hb) = (axes.heights[a], axes.heights[b]);
    let x = (vb - va).try_normalize().ok_or(PlateError::Degenerate(k))?;
    let z = x
        .cross(da)
        .try_normalize()
        .ok_or(PlateError::Degenerate(k))?;
    let y = z.cross(x);
    let placement = Placement {
        origin: va,
        x,
        y,
        z,
    };
    let local = |p: DVec3| {
        let d = p - va;
        DVec2::new(d.dot(x), d.dot(y))
    };
    let fourth = vb + db * hb;
    let flattening = (fourth - va).dot(z).abs();
    let quad = [local(va), local(vb), local(fourth), local(va + da * ha)];
    if !convex_ccw(&quad) {
        return Err(PlateError::Twisted(k));
    }
    // Cut back at a along the line through quad[0], quad[3]; at b along quad[1], quad[2].
    let cut = |poly: Vec<DVec2>, p: DVec2, q: DVec2, toward: DVec2, s: f64| {
        let along = (q - p).normalize();
        let mut normal = along.perp();
        if (toward - p).dot(normal) < 0.0 {
            normal = -normal;
        }
        clip_convex(&poly, p + normal * s, normal)
    };
    let poly = cut(quad.to_vec(), quad[0], quad[3], quad[1], setback[0]);
    let poly = cut(poly, quad[1], quad[2], quad[0], setback[1]);
    if poly.len() < 3 || polygon_area(&poly) < 1e-9 {
        return Err(PlateError::TooShort(k, setback[0], setback[1]));
    }
    let mid = [0.5 * (quad[0] + quad[3]), 0.5 * (quad[1] + quad[2])];
    let plate = Plate {
        id: String::new(),
        group: 0,
        bolted_to: None,
        holes: Vec::new(),
        bolt: None,
        edge: k,
        nodes: [a as u32, b as u32],
        thickness,
        outline: poly,
        placement,
        setback,
        partners: [Vec::new(), Vec::new()],
        core: [None, None],
        flattening,
    };
    Ok((plate, mid))
}

fn convex_ccw(p: &[DVec2]) -> bool {
    (0..p.len()).all(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % p.len()], p[(k + 2) % p.len()]);
        (b - a).perp_dot(c - b) > 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat Y joint at the origin: three edges 120° apart, axes +Z, height 50.
    fn y_joint() -> Axes {
        let mut positions = vec![DVec3::ZERO];
        for k in 0..3 {
            let a = (k as f64) * 120f64.to_radians();
            positions.push(DVec3::new(a.cos(), a.sin(), 0.0) * 100.0);
        }
        Axes {
            positions,
            edges: vec![[0, 1], [0, 2], [0, 3]],
            axes: vec![DVec3::Z; 4],
            heights: vec![50.0; 4],
            reference: vec![DVec3::Z; 4],
            fixed_normals: vec![None; 3],
            edge_radii: vec![0.0; 3],
        }
    }

    #[test]
    fn a_y_joint_is_cut_back_by_the_bisector_rule() {
        let opts = PlateOptions {
            thickness: Thickness::Constant(6.0),
            weld_gap: 2.0,
            ..Default::default()
        };
        let p = plates(&y_joint(), &opts).expect("valid").plates;
        let want = 3.0 / 60f64.to_radians().tan() + 2.0 / (2.0 * 60f64.to_radians().sin());
        for plate in &p {
            // The gap solve starts from the bisector rule, which is exact here; it may move by
            // its bisection's step.
            assert!((plate.setback[0] - want).abs() < 1e-6);
            assert_eq!(plate.setback[1], 0.0, "a tip is not cut");
            // A rectangle (100 − setback) × 50.
            assert!((plate.area() - (100.0 - plate.setback[0]) * 50.0).abs() < 1e-9);
            assert_eq!(plate.partners[0].len(), 2);
        }
        // The plates' corners nearest the node are at least the weld gap apart at the
        // bisector: the corner of plate 0 at (s, ±t/2) lies g/2 from the bisector at 60°.
        let corner = DVec2::new(want, 3.0);
        let bisector_normal = DVec2::new(-(60f64.to_radians().sin()), 60f64.to_radians().cos());
        assert!((corner.dot(bisector_normal).abs() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn prisms_are_closed_with_the_plate_volume() {
        let p = plates(&y_joint(), &PlateOptions::default())
            .expect("valid")
            .plates;
        let (v, t) = p[0].prism();
        let mesh = crate::mesh::TriMesh {
            positions: v,
            triangles: t,
            colors: None,
        };
        let topo = mesh.check_manifold();
        assert!(topo.closed, "{topo:?}");
        let vol = topo.volume.expect("closed");
        assert!((vol - p[0].area() * p[0].thickness).abs() < 1e-6, "{vol}");
    }

    /// A straight run of four 300 mm edges along x, axes +Z, 100 mm high.
    fn run() -> Axes {
        let positions: Vec<DVec3> = (0..5).map(|k| DVec3::X * (300.0 * k as f64)).collect();
        Axes {
            positions,
            edges: vec![[0, 1], [1, 2], [2, 3], [3, 4]],
            axes: vec![DVec3::Z; 5],
            heights: vec![100.0; 5],
            reference: vec![DVec3::Z; 5],
            fixed_normals: vec![None; 4],
            edge_radii: vec![0.0; 4],
        }
    }

    #[test]
    fn seams_are_two_gauges_bolted_through_the_same_holes() {
        let opts = PlateOptions {
            thickness: Thickness::Constant(5.0),
            groups: 2,
            ..Default::default()
        };
        let set = plates(&run(), &opts).expect("valid");
        let seam: Vec<&Plate> = set
            .plates
            .iter()
            .filter(|p| p.bolted_to.is_some())
            .collect();
        assert_eq!(seam.len(), 2, "one seam in two plies");
        let (a, b) = (seam[0], seam[1]);
        // 5 mm: 2 + 3 from the default gauges, stacked face to face about the panel plane.
        assert_eq!((a.thickness, b.thickness), (2.0, 3.0));
        let gap = (b.placement.origin - a.placement.origin).dot(a.placement.z);
        assert!((gap - 2.5).abs() < 1e-12, "{gap}");
        let bolt = a.bolt.expect("bolted");
        // Unwin: 10 (√2.5 − 0.2) = 13.8 mm, nearest M12; but on the 2 mm ply 14 t = 28 mm is
        // under M12's least pitch 2.2 × 13 = 28.6 mm (Table 3.3): M10.
        assert_eq!(bolt.size.name, "M10");
        assert!(a.holes.len() >= 2);
        for w in a.holes.windows(2) {
            assert!(w[0].distance(w[1]) <= 14.0 * 2.0 + 1e-9);
        }
        assert!(!a.holes.is_empty() && a.holes == b.holes);
        // Every hole 1.2 d0 inside every edge of both plies, neighbours 2.2 d0 apart.
        let e = 1.2 * bolt.size.hole;
        for ply in [a, b] {
            for h in &ply.holes {
                for k in 0..ply.outline.len() {
                    let (p, q) = (ply.outline[k], ply.outline[(k + 1) % ply.outline.len()]);
                    assert!((q - p).normalize().perp_dot(*h - p) >= e - 1e-9);
                }
            }
        }
        // Each ply welds at its own group's node, to that group's plates only, with the setback
        // the weld report gives; at the other node it has no partners and stops clear.
        assert_ne!(a.group, b.group);
        for (end, (mine, other)) in [(a, b), (b, a)].into_iter().enumerate() {
            let v = mine.nodes[end];
            let node = set.welds.iter().find(|w| w.node == v).expect("a joint");
            assert_eq!(node.group, mine.group);
            assert!(!mine.partners[end].is_empty());
            for &j in &mine.partners[end] {
                assert_eq!(set.plates[j].group, mine.group);
            }
            assert!(other.partners[end].is_empty());
            let i = node
                .edges
                .iter()
                .position(|&k| k == mine.edge)
                .expect("there");
            assert!((node.setbacks[i] - mine.setback[end]).abs() < 1e-12);
            let pass = node
                .passing
                .iter()
                .find(|p| p.edge == mine.edge)
                .expect("passes");
            assert!((pass.setback - other.setback[end]).abs() < 1e-12);
            assert!(pass.setback > mine.setback[end]);
            assert!(
                pass.clearance >= opts.weld_gap + mine.thickness - 1e-6,
                "{pass:?}"
            );
            // The plates of the node's group meet the ply, not the stack: each plate's partners
            // at v hold the ply and not its partner.
            for &j in &mine.partners[end] {
                let q = &set.plates[j];
                let at = usize::from(q.nodes[0] != v);
                assert!(q.partners[at].contains(
                    &set.plates
                        .iter()
                        .position(|p| std::ptr::eq(p, mine))
                        .expect("in the set")
                ));
            }
        }
        for w in a.holes.windows(2) {
            assert!(w[0].distance(w[1]) >= 2.2 * bolt.size.hole - 1e-9);
        }
        // The prism has its holes: closed, with the holes' volume taken out.
        let (v, t) = a.prism();
        let mesh = crate::mesh::TriMesh {
            positions: v,
            triangles: t,
            colors: None,
        };
        let topo = mesh.check_manifold();
        assert!(topo.closed, "{topo:?}");
        assert_eq!(topo.genus, Some(a.holes.len() as i64));
        let vol = topo.volume.expect("closed");
        assert!((vol - a.area() * a.thickness).abs() < 1e-6, "{vol}");
        // A bolt too big for the plate is an error naming the edge.
        let huge = PlateOptions {
            bolt: Some(crate::rationalize::bolts::parse("M30").expect("listed")),
            ..opts.clone()
        };
        let mut low = run();
        low.heights = vec![60.0; 5];
        assert!(matches!(
            plates(&low, &huge),
            Err(PlateError::NoRoomForBolt { .. })
        ));
    }

    #[test]
    fn gauges_hold_every_thickness() {
        assert_eq!(
            seam_gauges(6.0, &[1.5, 2.0, 3.0, 4.0, 5.0, 6.0]),
            Some((3.0, 3.0))
        );
        assert_eq!(seam_gauges(1.5, &[1.5, 2.0, 3.0]), Some((1.5, 1.5)));
        assert_eq!(seam_gauges(4.0, &[1.5, 2.0, 3.0, 4.0]), Some((2.0, 2.0)));
        let off = PlateOptions {
            thickness: Thickness::Constant(2.5),
            ..Default::default()
        };
        assert!(matches!(
            plates(&y_joint(), &off),
            Err(PlateError::OffGauge { .. })
        ));
    }

    #[test]
    fn thickness_follows_the_radius_hierarchy() {
        let mut axes = y_joint();
        axes.edge_radii = vec![1.0, 0.5, 0.0];
        let t = thicknesses(&axes, &PlateOptions::default()).expect("valid");
        assert_eq!(t, vec![6.0, 4.0, 1.5]);
        // Overrides by edge and by nodes (edges 1 and 2 end at nodes 2 and 3, both at y ≠ 0).
        let opts = PlateOptions {
            overrides: vec![
                (EdgeSelector::parse("y>1").expect("selector"), 5.0),
                (EdgeSelector::parse("edge=2").expect("selector"), 2.0),
            ],
            ..Default::default()
        };
        // y>1 needs both ends: node 0 is at the origin, so no edge matches.
        assert!(matches!(
            thicknesses(&axes, &opts),
            Err(PlateError::OverrideUnused(_))
        ));
        let opts = PlateOptions {
            overrides: vec![
                (EdgeSelector::parse("x<=0").expect("selector"), 5.0),
                (EdgeSelector::parse("edge=2").expect("selector"), 2.0),
            ],
            ..Default::default()
        };
        assert_eq!(thicknesses(&axes, &opts), Ok(vec![6.0, 5.0, 2.0]));
    }

    #[test]
    fn bad_options_and_crossing_axes_are_errors() {
        let axes = y_joint();
        let bad = |opts: PlateOptions| plates(&axes, &opts).err();
        assert_eq!(
            bad(PlateOptions {
                gauges: vec![],
                ..Default::default()
            }),
            Some(PlateError::NoGauges)
        );
        assert!(matches!(
            bad(PlateOptions {
                gauges: vec![3.0, 2.0],
                ..Default::default()
            }),
            Some(PlateError::Gauges(_))
        ));
        let mut missing = y_joint();
        missing.edges[2] = [0, 9];
        assert_eq!(
            plates(&missing, &PlateOptions::default()).err(),
            Some(PlateError::MissingNode(2, 9))
        );
        let mut twisted = y_joint();
        // Node 1's axis leans back over node 0 so far that the panel's sides cross.
        twisted.axes[1] = DVec3::new(-0.99, 0.0, 0.141).normalize();
        twisted.heights[1] = 500.0;
        assert_eq!(
            plates(&twisted, &PlateOptions::default()).err(),
            Some(PlateError::Twisted(0))
        );
    }
}
