//! From node axes to steel plates: each network edge becomes one flat plate in its panel's
//! plane, centred on it, with a thickness from a gauge list, cut back at each node so that the
//! plates meeting there do not interpenetrate.
//!
//! The plates at a node all contain the node's axis line, so their cross-section in the plane
//! ⊥ the axis is the same at every height: half-strips leaving the axis in directions u_k, each
//! t_k thick. Two half-strips at angle θ are kept apart by the bisector of their directions
//! when each starts at least s_k = (t_k/2)·cot(θ/2) + g/(2·sin(θ/2)) from the axis, g being the
//! weld gap left between them at the bisector. A plate's setback at a node is the largest such
//! s_k over the other plates there (g/2 for a straight continuation, nothing at a tip). The cut
//! is a line parallel to the axis in the plate's plane.
//!
//! Each plate is stored as a 2D outline in its own frame (origin at the first node, x along the
//! edge, y toward the axis, z the plate normal) and the rigid transform placing it; the
//! panel's fourth corner is projected into the plane of the other three (its distance is the
//! panel deviation planarize reported, and is recorded as `flattening`).

use glam::{DVec2, DVec3};

use super::axes::Axes;
use super::planarize::Selector;

#[derive(Clone, Debug, PartialEq)]
pub enum Thickness {
    /// Every plate this thick, mm.
    Constant(f64),
    /// The gauge at the edge radius's place between 0 and the largest radius (thicker veins,
    /// thicker plates); edges without a radius get the thinnest gauge.
    FromRadius,
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
    /// Gap left between plates meeting at a node, mm.
    pub weld_gap: f64,
    /// Assembly groups (see `groups.rs`); seam plates are split in two of half thickness.
    pub groups: usize,
}

impl Default for PlateOptions {
    fn default() -> Self {
        PlateOptions {
            gauges: vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0],
            thickness: Thickness::FromRadius,
            overrides: Vec::new(),
            weld_gap: 1.0,
            groups: 1,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlateError {
    #[error("the gauge list is empty")]
    NoGauges,
    #[error("gauges must be positive and ascending: {0:?}")]
    Gauges(Vec<f64>),
    #[error("--thickness must be a positive number of mm, got {0}")]
    Thickness(f64),
    #[error("a thickness override must be a positive number of mm, got {0}")]
    Override(f64),
    #[error("a thickness override names edge {0}, but there are {1} edges")]
    OverrideEdge(usize, usize),
    #[error("thickness override {0} (counting from 1) matches no edge")]
    OverrideUnused(usize),
    #[error("--weld-gap must be ≥ 0 mm, got {0}")]
    WeldGap(f64),
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
    #[error("edge {0}: its panel is twisted or self-crossing (the axes cross within the height)")]
    Twisted(usize),
    #[error(transparent)]
    Groups(#[from] super::groups::GroupError),
    #[error("the axes hold {0} nodes but {1} axes, {2} heights; {3} edges but {4} radii")]
    Lengths(usize, usize, usize, usize, usize),
    #[error("edge {0} refers to node {1}, which does not exist")]
    MissingNode(usize, u32),
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
    /// Plates (by index) welded to this one at each node: every other plate there except its
    /// own other half.
    pub partners: [Vec<usize>; 2],
    /// On a seam between groups: the other half-thickness plate, bolted face to face.
    pub bolted_to: Option<usize>,
    /// Distance of the panel's fourth corner from the plate's plane, mm.
    pub flattening: f64,
}

impl Plate {
    pub fn area(&self) -> f64 {
        polygon_area(&self.outline)
    }

    /// The plate as a closed prism: outline at z = ±t/2, fan-triangulated caps (the outline
    /// is convex), outward-facing triangles.
    pub fn prism(&self) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let n = self.outline.len() as u32;
        let h = self.thickness / 2.0;
        let mut v: Vec<DVec3> = self
            .outline
            .iter()
            .map(|p| self.placement.world(*p, -h))
            .collect();
        v.extend(self.outline.iter().map(|p| self.placement.world(*p, h)));
        let mut t = Vec::new();
        for k in 1..n - 1 {
            t.push([0, k + 1, k]); // bottom, facing −z
            t.push([n, n + k, n + k + 1]); // top, facing +z
        }
        for k in 0..n {
            let j = (k + 1) % n;
            t.push([k, j, n + j]);
            t.push([k, n + j, n + k]);
        }
        (v, t)
    }
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
    if !(opts.weld_gap.is_finite() && opts.weld_gap >= 0.0) {
        return Err(PlateError::WeldGap(opts.weld_gap));
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
    match opts.thickness {
        Thickness::Constant(t) => vec![t; axes.edges.len()],
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

pub fn plates(axes: &Axes, opts: &PlateOptions) -> Result<Vec<Plate>, PlateError> {
    check(axes, opts)?;
    let n = axes.positions.len();
    let t = thicknesses(axes, opts)?;
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
    let mut out = Vec::with_capacity(axes.edges.len());
    for (k, &[a, b]) in axes.edges.iter().enumerate() {
        let mut setback = [0.0; 2];
        for (end, v) in [a, b].into_iter().enumerate() {
            for &(m, m_end) in &at[v as usize] {
                if m == k {
                    continue;
                }
                let cos = dir[k][end].dot(dir[m][m_end]).clamp(-1.0, 1.0);
                let theta = cos.acos();
                let half = 0.5 * theta;
                if half.sin() < 1e-6 {
                    return Err(PlateError::TooClose {
                        edge: k,
                        node: v,
                        angle_deg: theta.to_degrees(),
                    });
                }
                let s = 0.5 * t[k] / half.tan() + opts.weld_gap / (2.0 * half.sin());
                setback[end] = f64::max(setback[end], s);
            }
        }
        out.push(plate(axes, k, t[k], setback)?);
    }
    let group = super::groups::partition(&axes.positions, &axes.edges, opts.groups)?;
    Ok(split_and_tag(out, &group))
}

/// Seam plates into two halves, one per group, offset ±t/4 across the plate so that they lie
/// face to face within the original thickness; then partners by plate and tags.
fn split_and_tag(per_edge: Vec<Plate>, group: &[u32]) -> Vec<Plate> {
    let mut out: Vec<Plate> = Vec::with_capacity(per_edge.len());
    for mut p in per_edge {
        let [ga, gb] = p.nodes.map(|v| group[v as usize]);
        if ga == gb {
            p.group = ga;
            out.push(p);
            continue;
        }
        let quarter = p.thickness / 4.0;
        let first = out.len();
        for (g, side) in [(ga, -1.0), (gb, 1.0)] {
            let mut half = p.clone();
            half.thickness = p.thickness / 2.0;
            half.placement.origin += p.placement.z * (side * quarter);
            half.group = g;
            half.bolted_to = Some(if side < 0.0 { first + 1 } else { first });
            out.push(half);
        }
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
            let partners = p.nodes.map(|v| {
                at[&v]
                    .iter()
                    .copied()
                    .filter(|&j| j != i && Some(j) != p.bolted_to)
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
    out
}

fn plate(axes: &Axes, k: usize, thickness: f64, setback: [f64; 2]) -> Result<Plate, PlateError> {
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
        clip(&poly, p + normal * s, normal)
    };
    let poly = cut(quad.to_vec(), quad[0], quad[3], quad[1], setback[0]);
    let poly = cut(poly, quad[1], quad[2], quad[0], setback[1]);
    if poly.len() < 3 || polygon_area(&poly) < 1e-9 {
        return Err(PlateError::TooShort(k, setback[0], setback[1]));
    }
    Ok(Plate {
        id: String::new(),
        group: 0,
        bolted_to: None,
        edge: k,
        nodes: [a as u32, b as u32],
        thickness,
        outline: poly,
        placement,
        setback,
        partners: [Vec::new(), Vec::new()],
        flattening,
    })
}

fn convex_ccw(p: &[DVec2]) -> bool {
    (0..p.len()).all(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % p.len()], p[(k + 2) % p.len()]);
        (b - a).perp_dot(c - b) > 0.0
    })
}

/// The part of a convex polygon on the side of the line through `p` that `normal` points to.
fn clip(poly: &[DVec2], p: DVec2, normal: DVec2) -> Vec<DVec2> {
    let side = |q: DVec2| (q - p).dot(normal);
    let mut out = Vec::new();
    for (k, &q) in poly.iter().enumerate() {
        let r = poly[(k + 1) % poly.len()];
        let (sq, sr) = (side(q), side(r));
        if sq >= 0.0 {
            out.push(q);
        }
        if (sq >= 0.0) != (sr >= 0.0) {
            out.push(q + (r - q) * (sq / (sq - sr)));
        }
    }
    // Drop repeated points a cut exactly through a corner leaves.
    out.dedup_by(|a, b| a.distance(*b) < 1e-12);
    if out.len() > 1 && out[0].distance(out[out.len() - 1]) < 1e-12 {
        out.pop();
    }
    out
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
        let p = plates(&y_joint(), &opts).expect("valid");
        let want = 3.0 / 60f64.to_radians().tan() + 2.0 / (2.0 * 60f64.to_radians().sin());
        for plate in &p {
            assert!((plate.setback[0] - want).abs() < 1e-12);
            assert_eq!(plate.setback[1], 0.0, "a tip is not cut");
            // A rectangle (100 − setback) × 50.
            assert!((plate.area() - (100.0 - want) * 50.0).abs() < 1e-9);
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
        let p = plates(&y_joint(), &PlateOptions::default()).expect("valid");
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
