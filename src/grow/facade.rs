//! Fitting a flat tree to a façade (Hanafin et al. §4, Figs. 5 and 9): the tree is scaled about
//! its root and the root placed on the façade (on the boundary, inside it, or below it so that
//! the boundary frames a section of the crown); branches are cut where they leave the boundary
//! polygon; the boundary itself becomes the frame, split wherever a branch meets it; members
//! that cross are joined where they cross; and only what stays connected to the root is kept.
//! The façade's root is the tree's root when it lies inside, else the point where the tree
//! first enters (nearest the root along the tree). The result is the structure; its cells (the
//! infill panels) are the `cells` stage's to find.
//!
//! Guarantees: no member lies outside the boundary (cut points lie on it, within the
//! tolerance), the result is one connected network that holds the façade's root, members meet
//! only at nodes (collinear overlaps excepted), and no two nodes coincide within the tolerance
//! (1e-9 of the boundary's diagonal).

use std::collections::{BTreeMap, HashMap, HashSet};

use glam::{DVec2, DVec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use crate::geom::Ordered;

use super::outline::Outline;
use crate::network::{Edge, Network, Node};

/// How the tree is sized to the boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fit {
    /// This scale, 1 = as drawn.
    Scale(f64),
    /// The smallest scale whose bounding box, from the root, covers the boundary's.
    Cover,
    /// The largest scale whose bounding box, from the root, stays inside the boundary's.
    Contain,
}

#[derive(Clone, Debug, PartialEq)]
pub struct FacadeOptions {
    /// Where the root goes. Default: the middle of the boundary's lowest points.
    pub root_at: Option<DVec2>,
    /// Default `Cover`.
    pub fit: Fit,
    /// Add the boundary as members (the frame). Default true.
    pub frame: bool,
    /// Radius of the frame members, mm. Default: the root's radius.
    pub frame_radius: Option<f64>,
}

impl Default for FacadeOptions {
    fn default() -> Self {
        FacadeOptions {
            root_at: None,
            fit: Fit::Cover,
            frame: true,
            frame_radius: None,
        }
    }
}

/// What fitting did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FacadeReport {
    pub scale: f64,
    pub root_at: [f64; 2],
    /// Members of the tree before fitting.
    pub tree_edges: usize,
    /// Tree members kept whole.
    pub kept_whole: usize,
    /// Tree members cut at the boundary (pieces kept).
    pub cut: usize,
    /// Tree members wholly outside.
    pub outside: usize,
    /// Pieces inside the boundary but connected to the root neither through the tree nor the
    /// frame (dropped).
    pub detached_pieces: usize,
    /// Whether the façade's root lies on the boundary. When the tree's root is outside, the
    /// façade's root is the kept point nearest it along the tree: where the trunk enters.
    pub root_on_boundary: bool,
    /// Points where a branch meets the frame.
    pub frame_joints: usize,
    /// Frame members (0 without a frame).
    pub frame_edges: usize,
    /// Places where members crossed or touched and were joined.
    pub joints_at_crossings: usize,
    /// The shortest member of the result, mm: where a branch meets the frame close to a corner
    /// or to another branch, panels get small.
    pub shortest_member: f64,
    /// The smallest distance from a node inside to the frame, mm (None when every node is on it).
    pub closest_to_frame: Option<f64>,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FacadeError {
    #[error("the tree is not flat (node {0} is off the XY plane): a façade takes a 2D tree")]
    NotFlat(usize),
    #[error("fit= cover: from its root the tree never reaches the boundary's {0} side")]
    CannotCover(&'static str),
    #[error(
        "fit= contain: the tree reaches {0} of its root, where the root touches the \
         boundary; place the root with root_at="
    )]
    CannotContain(&'static str),
    #[error("fit=: the scale must be a positive number, got {0}")]
    Scale(f64),
    #[error("no member of the tree reaches inside the boundary")]
    Empty,
}

type SideBox = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// The boundary's sides in an rstar tree, for segment and point queries.
struct Sides<'a> {
    points: &'a [DVec2],
    tree: RTree<SideBox>,
}

impl<'a> Sides<'a> {
    fn new(outline: &'a Outline) -> Self {
        let points = outline.points();
        let n = points.len();
        let tree = RTree::bulk_load(
            (0..n)
                .map(|i| {
                    let (a, b) = (points[i], points[(i + 1) % n]);
                    SideBox::new(
                        Rectangle::from_corners(a.min(b).to_array(), a.max(b).to_array()),
                        i as u32,
                    )
                })
                .collect(),
        );
        Sides { points, tree }
    }

    fn side(&self, i: u32) -> (DVec2, DVec2) {
        let n = self.points.len();
        (self.points[i as usize], self.points[(i as usize + 1) % n])
    }

    fn near(&self, lo: DVec2, hi: DVec2, tol: f64) -> impl Iterator<Item = u32> + '_ {
        let env = AABB::from_corners((lo - tol).to_array(), (hi + tol).to_array());
        self.tree
            .locate_in_envelope_intersecting(&env)
            .map(|s| s.data)
    }

    /// The distance from `p` to side `i`, and where along the side (0..1) its foot lies.
    fn foot(&self, i: u32, p: DVec2) -> (f64, f64) {
        let (a, b) = self.side(i);
        let d = b - a;
        let u = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        ((a + d * u).distance(p), u)
    }

    /// The side `p` lies on within `tol`, and where along it (0..1).
    fn on(&self, p: DVec2, tol: f64) -> Option<(u32, f64)> {
        self.near(p, p, tol)
            .map(|i| (self.foot(i, p), i))
            .filter(|((dist, _), _)| *dist <= tol)
            .min_by(|x, y| x.0 .0.total_cmp(&y.0 .0).then(x.1.cmp(&y.1)))
            .map(|((_, u), i)| (i, u))
    }

    fn distance(&self, p: DVec2) -> f64 {
        (0..self.points.len() as u32)
            .map(|i| self.foot(i, p).0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Where segment pq meets the sides, as parameters along pq in (0, 1).
    fn crossings(&self, p: DVec2, q: DVec2, tol: f64, out: &mut Vec<f64>) {
        let r = q - p;
        let len2 = r.length_squared();
        for i in self.near(p.min(q), p.max(q), tol) {
            let (a, b) = self.side(i);
            let s = b - a;
            let denom = r.perp_dot(s);
            if denom.abs() > 1e-12 * r.length() * s.length() {
                let t = (a - p).perp_dot(s) / denom;
                let u = (a - p).perp_dot(r) / denom;
                if (0.0..=1.0).contains(&u) && t > 0.0 && t < 1.0 {
                    out.push(t);
                }
            } else if (a - p).perp_dot(r).abs() <= tol * r.length() {
                // Collinear: where the side's ends fall along pq.
                for e in [a, b] {
                    let t = (e - p).dot(r) / len2;
                    if t > 0.0 && t < 1.0 {
                        out.push(t);
                    }
                }
            }
        }
    }
}

/// The default root point: the middle of the boundary's lowest points.
pub fn default_root(boundary: &Outline) -> DVec2 {
    let tol = 1e-9 * boundary.size().length();
    let low = boundary.bounds().0.y;
    let xs: Vec<f64> = boundary
        .points()
        .iter()
        .filter(|p| p.y - low <= tol)
        .map(|p| p.x)
        .collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    DVec2::new(0.5 * (lo + hi), low)
}

/// The scale the fit asks for, given the tree's extents from its root (left, right, down, up)
/// and the boundary's from the root point.
fn scale_for(fit: Fit, tree: [f64; 4], boundary: [f64; 4], tol: f64) -> Result<f64, FacadeError> {
    const SIDES: [&str; 4] = ["left", "right", "lower", "upper"];
    const WAYS: [&str; 4] = ["left", "right", "below", "above"];
    match fit {
        Fit::Scale(s) if s.is_finite() && s > 0.0 => Ok(s),
        Fit::Scale(s) => Err(FacadeError::Scale(s)),
        Fit::Cover => {
            let mut s: f64 = 0.0;
            for k in 0..4 {
                if boundary[k] > tol {
                    if tree[k] <= 0.0 {
                        return Err(FacadeError::CannotCover(SIDES[k]));
                    }
                    s = s.max(boundary[k] / tree[k]);
                }
            }
            if s > 0.0 {
                Ok(s)
            } else {
                Err(FacadeError::CannotCover(SIDES[0]))
            }
        }
        Fit::Contain => {
            let mut s = f64::INFINITY;
            for k in 0..4 {
                if tree[k] > tol * 1e-3 {
                    if boundary[k] <= tol {
                        return Err(FacadeError::CannotContain(WAYS[k]));
                    }
                    s = s.min(boundary[k] / tree[k]);
                }
            }
            if s.is_finite() {
                Ok(s)
            } else {
                Err(FacadeError::Empty)
            }
        }
    }
}

/// Fits `tree` (flat, in XY) to `boundary`; `root` is the tree's root node.
pub fn fit(
    tree: &Network,
    root: u32,
    boundary: &Outline,
    opts: &FacadeOptions,
) -> Result<(Network, FacadeReport), FacadeError> {
    let diag = boundary.size().length();
    let tol = 1e-9 * diag;
    let tree_size = tree.bbox().diagonal().max(f64::MIN_POSITIVE);
    if let Some(k) = tree
        .nodes
        .iter()
        .position(|n| n.p.z.abs() > 1e-9 * tree_size)
    {
        return Err(FacadeError::NotFlat(k));
    }
    let sides = Sides::new(boundary);
    let at = opts.root_at.unwrap_or_else(|| default_root(boundary));
    let r0 = tree
        .nodes
        .get(root as usize)
        .ok_or(FacadeError::Empty)?
        .p
        .truncate();
    let (tlo, thi) = tree.nodes.iter().fold((r0, r0), |(lo, hi), n| {
        (lo.min(n.p.truncate()), hi.max(n.p.truncate()))
    });
    let (blo, bhi) = boundary.bounds();
    let scale = scale_for(
        opts.fit,
        [r0.x - tlo.x, thi.x - r0.x, r0.y - tlo.y, thi.y - r0.y],
        [at.x - blo.x, bhi.x - at.x, at.y - blo.y, bhi.y - at.y],
        tol,
    )?;
    let placed: Vec<DVec2> = tree
        .nodes
        .iter()
        .map(|n| at + (n.p.truncate() - r0) * scale)
        .collect();
    let from_root = tree_distances(tree, root, &placed);

    let mut report = FacadeReport {
        scale,
        root_at: at.to_array(),
        tree_edges: tree.edges.len(),
        kept_whole: 0,
        cut: 0,
        outside: 0,
        detached_pieces: 0,
        root_on_boundary: false,
        frame_joints: 0,
        frame_edges: 0,
        joints_at_crossings: 0,
        shortest_member: 0.0,
        closest_to_frame: None,
    };
    let inside = |p: DVec2| boundary.contains(p) || sides.on(p, tol).is_some();

    // Pieces of every member inside the boundary, between old nodes and new points.
    let mut out = Builder::default();
    let mut ts = Vec::new();
    for e in &tree.edges {
        let (ka, kb) = (e.a as usize, e.b as usize);
        let (p, q) = (placed[ka], placed[kb]);
        let len = p.distance(q);
        let reach = |t: f64| (from_root[ka] + t * len).min(from_root[kb] + (1.0 - t) * len);
        if boundary.contains_segment(p, q) {
            let a = out.old(e.a, p, &tree.nodes, from_root[ka]);
            let b = out.old(e.b, q, &tree.nodes, from_root[kb]);
            out.edge(a, b, e.radius);
            report.kept_whole += 1;
            continue;
        }
        ts.clear();
        sides.crossings(p, q, tol, &mut ts);
        ts.push(0.0);
        ts.push(1.0);
        ts.sort_by(f64::total_cmp);
        ts.dedup_by(|b, a| (*b - *a) * len <= tol);
        let (mut pieces, mut whole) = (0, false);
        for w in ts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if !inside(p.lerp(q, 0.5 * (t0 + t1))) {
                continue;
            }
            let mut end = |t: f64| {
                if t == 0.0 {
                    out.old(e.a, p, &tree.nodes, from_root[ka])
                } else if t == 1.0 {
                    out.old(e.b, q, &tree.nodes, from_root[kb])
                } else {
                    out.new_point(p.lerp(q, t), e.radius, reach(t))
                }
            };
            let (a, b) = (end(t0), end(t1));
            out.edge(a, b, e.radius);
            pieces += 1;
            whole = t0 == 0.0 && t1 == 1.0;
        }
        if pieces == 0 {
            report.outside += 1;
        } else if whole {
            report.kept_whole += 1;
        } else {
            report.cut += 1;
        }
    }
    // The façade's root: the tree's root if kept, else where the tree first enters.
    let root_node = (0..out.nodes.len())
        .filter(|&k| out.reach[k].is_finite())
        .min_by(|&x, &y| out.reach[x].total_cmp(&out.reach[y]).then(x.cmp(&y)))
        .ok_or(FacadeError::Empty)? as u32;
    let mut network = Network {
        nodes: out.nodes,
        edges: out.edges,
        meta: Default::default(),
    };

    if opts.frame {
        let radius = opts
            .frame_radius
            .unwrap_or(tree.nodes[root as usize].radius);
        report.frame_joints = add_frame(&mut network, boundary, &sides, radius, tol);
        report.frame_edges = network.edges.len() - out.edge_count;
    }
    // Nodes within the tolerance of each other are one joint; crossing members are joined.
    let (merged, map) = merge_close(network, tol);
    network = merged;
    let root_node = map[root_node as usize];
    report.joints_at_crossings = split_crossings(&mut network, tol);

    // Keep what the root reaches (through the frame too).
    let (kept, detached) = reachable(&network, root_node);
    report.detached_pieces = detached;
    let (map, mut network) = compact(network, &kept);
    let root_new = map[root_node as usize].expect("the root is reachable from itself");
    report.root_on_boundary = sides
        .on(network.nodes[root_new as usize].p.truncate(), tol)
        .is_some();
    report.shortest_member = network.lengths().map_or(0.0, |l| l.min);
    report.closest_to_frame = network
        .nodes
        .iter()
        .map(|n| n.p.truncate())
        .filter(|p| sides.on(*p, tol).is_none())
        .map(|p| sides.distance(p))
        .min_by(f64::total_cmp);
    network.meta.parameters.insert(
        "boundary".into(),
        serde_json::json!(boundary
            .points()
            .iter()
            .map(|p| [p.x, p.y])
            .collect::<Vec<_>>()),
    );
    network
        .meta
        .parameters
        .insert("root_node".into(), serde_json::json!(root_new));
    Ok((network, report))
}

/// Length along the tree from `root` to every node (infinite where it does not reach).
fn tree_distances(tree: &Network, root: u32, placed: &[DVec2]) -> Vec<f64> {
    let adj = tree.adjacency();
    let mut dist = vec![f64::INFINITY; tree.nodes.len()];
    let mut heap = std::collections::BinaryHeap::new();
    dist[root as usize] = 0.0;
    heap.push(std::cmp::Reverse((Ordered(0.0), root)));
    while let Some(std::cmp::Reverse((Ordered(d), v))) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        for &(w, _) in adj.neighbours(v) {
            let nd = d + placed[v as usize].distance(placed[w as usize]);
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                heap.push(std::cmp::Reverse((Ordered(nd), w)));
            }
        }
    }
    dist
}

/// Adds the boundary as members, split at every node that lies on it; returns how many
/// nodes lie on it.
fn add_frame(net: &mut Network, boundary: &Outline, sides: &Sides, radius: f64, tol: f64) -> usize {
    let corners = boundary.points();
    let n = corners.len();
    let mut splits: Vec<Vec<(f64, u32)>> = vec![Vec::new(); n];
    for (k, node) in net.nodes.iter().enumerate() {
        if let Some((i, u)) = sides.on(node.p.truncate(), tol) {
            splits[i as usize].push((u, k as u32));
        }
    }
    let joints = splits.iter().map(Vec::len).sum();
    // Corners: a node already there, or a new one.
    let corner_nodes: Vec<u32> = (0..n)
        .map(|i| {
            let c = corners[i];
            let prev = (i + n - 1) % n;
            let found = splits[i]
                .iter()
                .chain(&splits[prev])
                .find(|(_, k)| net.nodes[*k as usize].p.truncate().distance(c) <= tol)
                .map(|&(_, k)| k);
            found.unwrap_or_else(|| {
                net.nodes.push(Node {
                    p: c.extend(0.0),
                    normal: None,
                    radius,
                });
                net.nodes.len() as u32 - 1
            })
        })
        .collect();
    for (i, split) in splits.iter_mut().enumerate() {
        split.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut chain = vec![corner_nodes[i]];
        chain.extend(split.iter().map(|&(_, k)| k));
        chain.push(corner_nodes[(i + 1) % n]);
        chain.dedup();
        for w in chain.windows(2) {
            net.edges.push(Edge {
                a: w[0],
                b: w[1],
                radius,
            });
        }
    }
    joints
}

/// Joins members that cross or touch away from their ends: a node where they meet, each split
/// there. Returns the number of joints made. Collinear overlaps are left as they are.
fn split_crossings(net: &mut Network, tol: f64) -> usize {
    type EdgeBox = GeomWithData<Rectangle<[f64; 2]>, u32>;
    let pos = |net: &Network, k: u32| net.nodes[k as usize].p.truncate();
    let tree = RTree::bulk_load(
        net.edges
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let (a, b) = (pos(net, e.a), pos(net, e.b));
                EdgeBox::new(
                    Rectangle::from_corners(
                        (a.min(b) - tol).to_array(),
                        (a.max(b) + tol).to_array(),
                    ),
                    i as u32,
                )
            })
            .collect(),
    );
    // Split points per edge: (parameter, node).
    let mut splits: BTreeMap<u32, Vec<(f64, u32)>> = BTreeMap::new();
    let mut joints = 0;
    for (i, e) in net.edges.clone().iter().enumerate() {
        let (p, q) = (pos(net, e.a), pos(net, e.b));
        let env = AABB::from_corners(p.min(q).to_array(), q.max(p).to_array());
        let mut hits: Vec<u32> = tree
            .locate_in_envelope_intersecting(&env)
            .map(|c| c.data)
            .filter(|&j| j > i as u32)
            .collect();
        hits.sort_unstable();
        for j in hits {
            let f = net.edges[j as usize];
            if [f.a, f.b].contains(&e.a) || [f.a, f.b].contains(&e.b) {
                continue;
            }
            let (a, b) = (pos(net, f.a), pos(net, f.b));
            let (r, s) = (q - p, b - a);
            let denom = r.perp_dot(s);
            if denom.abs() <= 1e-12 * r.length() * s.length() {
                continue;
            }
            let t = (a - p).perp_dot(s) / denom;
            let u = (a - p).perp_dot(r) / denom;
            let (et, eu) = (tol / r.length(), tol / s.length());
            if t < -et || t > 1.0 + et || u < -eu || u > 1.0 + eu {
                continue;
            }
            // An end lying on the other member joins it there; otherwise a new node.
            let node = if t <= et {
                e.a
            } else if t >= 1.0 - et {
                e.b
            } else if u <= eu {
                f.a
            } else if u >= 1.0 - eu {
                f.b
            } else {
                net.nodes.push(Node {
                    p: p.lerp(q, t).extend(0.0),
                    normal: None,
                    radius: e.radius.max(f.radius),
                });
                net.nodes.len() as u32 - 1
            };
            if node != e.a && node != e.b {
                splits.entry(i as u32).or_default().push((t, node));
            }
            if node != f.a && node != f.b {
                splits.entry(j).or_default().push((u, node));
            }
            joints += 1;
        }
    }
    if splits.is_empty() {
        return 0;
    }
    let old = std::mem::take(&mut net.edges);
    for (i, e) in old.into_iter().enumerate() {
        match splits.get_mut(&(i as u32)) {
            None => net.edges.push(e),
            Some(list) => {
                list.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                let mut chain = vec![e.a];
                chain.extend(list.iter().map(|&(_, k)| k));
                chain.push(e.b);
                chain.dedup();
                for w in chain.windows(2) {
                    net.edges.push(Edge {
                        a: w[0],
                        b: w[1],
                        ..e
                    });
                }
            }
        }
    }
    joints
}

/// Nodes connected to `root`, and how many other connected pieces there are.
fn reachable(net: &Network, root: u32) -> (Vec<bool>, usize) {
    let (labels, count) = net.component_labels();
    let r = labels[root as usize];
    (labels.iter().map(|&l| l == r).collect(), count - 1)
}

/// The kept part (node order kept), with the old → new node map.
fn compact(net: Network, kept: &[bool]) -> (Vec<Option<u32>>, Network) {
    let mut map = vec![None; net.nodes.len()];
    let mut out = Network {
        meta: net.meta,
        ..Default::default()
    };
    for (k, n) in net.nodes.into_iter().enumerate() {
        if kept[k] {
            map[k] = Some(out.nodes.len() as u32);
            out.nodes.push(n);
        }
    }
    for e in net.edges {
        if let (Some(a), Some(b)) = (map[e.a as usize], map[e.b as usize]) {
            out.edges.push(Edge { a, b, ..e });
        }
    }
    (map, out)
}

/// The pieces under construction: old nodes mapped on first use, cut points appended, each
/// node with its distance along the tree from the root.
#[derive(Default)]
struct Builder {
    nodes: Vec<Node>,
    reach: Vec<f64>,
    edges: Vec<Edge>,
    edge_count: usize,
    /// Old node → new node.
    map: HashMap<u32, u32>,
}

impl Builder {
    fn old(&mut self, k: u32, p: DVec2, old: &[Node], reach: f64) -> u32 {
        let (nodes, reaches) = (&mut self.nodes, &mut self.reach);
        *self.map.entry(k).or_insert_with(|| {
            nodes.push(Node {
                p: p.extend(0.0),
                ..old[k as usize]
            });
            reaches.push(reach);
            nodes.len() as u32 - 1
        })
    }

    fn new_point(&mut self, p: DVec2, radius: f64, reach: f64) -> u32 {
        self.nodes.push(Node {
            p: p.extend(0.0),
            normal: None,
            radius,
        });
        self.reach.push(reach);
        self.nodes.len() as u32 - 1
    }

    fn edge(&mut self, a: u32, b: u32, radius: f64) {
        if a != b {
            self.edges.push(Edge { a, b, radius });
            self.edge_count += 1;
        }
    }
}

/// Merges nodes closer than `tol` (the earlier one stays), and drops the edges that become
/// loops or repeats.
fn merge_close(net: Network, tol: f64) -> (Network, Vec<u32>) {
    let cell = tol.max(f64::MIN_POSITIVE) * 4.0;
    let key = |p: DVec3| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    let mut map = vec![0u32; net.nodes.len()];
    let mut nodes: Vec<Node> = Vec::with_capacity(net.nodes.len());
    for (k, n) in net.nodes.iter().enumerate() {
        let (cx, cy) = key(n.p);
        let hit = (-1..=1)
            .flat_map(|dx| (-1..=1).map(move |dy| (cx + dx, cy + dy)))
            .filter_map(|c| grid.get(&c))
            .flatten()
            .copied()
            .find(|&m| nodes[m as usize].p.distance(n.p) <= tol);
        map[k] = match hit {
            Some(m) => m,
            None => {
                nodes.push(*n);
                let m = nodes.len() as u32 - 1;
                grid.entry((cx, cy)).or_default().push(m);
                m
            }
        };
    }
    let mut seen: HashSet<(u32, u32)> = HashSet::new();
    let edges = net
        .edges
        .iter()
        .filter_map(|e| {
            let (a, b) = (map[e.a as usize], map[e.b as usize]);
            (a != b && seen.insert((a.min(b), a.max(b)))).then_some(Edge { a, b, ..*e })
        })
        .collect();
    (
        Network {
            nodes,
            edges,
            meta: net.meta,
        },
        map,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grow::tree::Tree;

    fn rect(w: f64, h: f64) -> Outline {
        Outline::new(vec![
            DVec2::new(-w / 2.0, 0.0),
            DVec2::new(w / 2.0, 0.0),
            DVec2::new(w / 2.0, h),
            DVec2::new(-w / 2.0, h),
        ])
        .expect("a rectangle is a valid outline")
    }

    /// A Y: trunk up from the origin, two arms.
    fn y_tree() -> Tree {
        let mut t = Tree::default();
        for p in [(0.0, 0.0), (0.0, 2.0), (-2.0, 4.0), (2.0, 4.0)] {
            t.network.nodes.push(Node::at(DVec3::new(p.0, p.1, 0.0)));
        }
        t.network.edges = vec![Edge::new(0, 1), Edge::new(1, 2), Edge::new(1, 3)];
        t.parent = vec![None, Some(0), Some(1), Some(1)];
        t
    }

    #[test]
    fn cover_scales_to_the_boundary_and_cuts_at_it() -> Result<(), FacadeError> {
        let b = rect(8.0, 6.0);
        let (net, rep) = fit(&y_tree().network, 0, &b, &FacadeOptions::default())?;
        // Cover: width 4 must span 8 → scale 2; the arms are cut at y = 6.
        assert_eq!(rep.scale, 2.0);
        assert_eq!((rep.kept_whole, rep.cut, rep.outside), (1, 2, 0));
        assert!(net.validate().is_ok());
        let (_, parts) = net.component_labels();
        assert_eq!(parts, 1);
        for n in &net.nodes {
            assert!(n.p.y >= -1e-9 && n.p.y <= 6.0 + 1e-9 && n.p.x.abs() <= 4.0 + 1e-9);
        }
        // Frame: 4 corners + the root and two cut points on it → 7 frame members.
        assert_eq!(rep.frame_joints, 3);
        assert_eq!(rep.frame_edges, 7);
        assert!(rep.root_on_boundary);
        assert_eq!(net.edges.len(), 3 + 7);
        Ok(())
    }

    #[test]
    fn pieces_cut_off_from_the_root_are_dropped() -> Result<(), FacadeError> {
        // A U-shaped boundary: the right arm leaves through the notch and re-enters.
        let p = |x: f64, y: f64| DVec2::new(x, y);
        let u = Outline::new(vec![
            p(-10.0, 0.0),
            p(10.0, 0.0),
            p(10.0, 10.0),
            p(6.0, 10.0),
            p(6.0, 3.0),
            p(3.0, 3.0),
            p(3.0, 10.0),
            p(-10.0, 10.0),
        ])
        .expect("valid");
        let mut t = Tree::default();
        for q in [(0.0, 0.0), (0.0, 2.0), (9.0, 6.0)] {
            t.network.nodes.push(Node::at(DVec3::new(q.0, q.1, 0.0)));
        }
        t.network.edges = vec![Edge::new(0, 1), Edge::new(1, 2)];
        let opts = FacadeOptions {
            fit: Fit::Scale(1.0),
            frame: false,
            ..Default::default()
        };
        let (net, rep) = fit(&t.network, 0, &u, &opts)?;
        assert_eq!(rep.detached_pieces, 1);
        assert_eq!(net.component_labels().1, 1);
        assert!(net.nodes.iter().all(|n| n.p.x < 3.0 + 1e-9));
        Ok(())
    }

    #[test]
    fn contain_keeps_everything_and_bad_fits_are_named() -> Result<(), FacadeError> {
        let b = rect(8.0, 3.0);
        let opts = FacadeOptions {
            fit: Fit::Contain,
            frame: false,
            ..Default::default()
        };
        let (net, rep) = fit(&y_tree().network, 0, &b, &opts)?;
        assert_eq!(rep.scale, 0.75);
        assert_eq!((rep.kept_whole, rep.cut), (3, 0));
        assert_eq!(net.edges.len(), 3);
        let mid = FacadeOptions {
            root_at: Some(DVec2::new(0.0, 1.0)),
            ..Default::default()
        };
        assert_eq!(
            fit(&y_tree().network, 0, &b, &mid).map(|_| ()),
            Err(FacadeError::CannotCover("lower"))
        );
        Ok(())
    }

    #[test]
    fn a_root_below_the_boundary_enters_through_it_and_crossings_join() -> Result<(), FacadeError> {
        // An X of two long members above a root: the window [-4, 4] × [2, 6] holds the crossing.
        let mut t = Tree::default();
        for q in [
            (0.0, 0.0),
            (0.0, 1.0),
            (-5.0, 7.0),
            (5.0, 7.0),
            (-5.0, 3.0),
            (5.0, 3.0),
        ] {
            t.network.nodes.push(Node::at(DVec3::new(q.0, q.1, 0.0)));
        }
        t.network.edges = vec![
            Edge::new(0, 1),
            Edge::new(1, 4),
            Edge::new(1, 5),
            Edge::new(4, 3),
            Edge::new(5, 2),
        ];
        let b = Outline::new(vec![
            DVec2::new(-4.0, 2.0),
            DVec2::new(4.0, 2.0),
            DVec2::new(4.0, 6.0),
            DVec2::new(-4.0, 6.0),
        ])
        .expect("valid");
        let opts = FacadeOptions {
            root_at: Some(DVec2::ZERO),
            fit: Fit::Scale(1.0),
            ..Default::default()
        };
        let (net, rep) = fit(&t.network, 0, &b, &opts)?;
        assert!(rep.root_on_boundary);
        assert!(rep.joints_at_crossings >= 1);
        assert_eq!(net.component_labels().1, 1);
        let root = net.meta.parameters["root_node"]
            .as_u64()
            .expect("the root is recorded") as usize;
        let r = net.nodes[root].p;
        assert!(
            r.y == 2.0 || r.x.abs() == 4.0,
            "the root is where the tree enters: {r}"
        );
        // The crossing at (0, 5) is a node of degree 4.
        let adj = net.adjacency();
        let x = net
            .nodes
            .iter()
            .position(|n| n.p.truncate().distance(DVec2::new(0.0, 5.0)) < 1e-9)
            .expect("a node at the crossing");
        assert_eq!(adj.degree(x as u32), 4);
        Ok(())
    }
}
