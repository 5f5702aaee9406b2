//! Fitting a flat tree to a façade (Hanafin et al. §4, Figs. 5 and 9): the tree is scaled about
//! its root and its root placed on the façade; branches are cut where they leave the boundary
//! polygon; only what stays connected to the root is kept; and the boundary itself becomes the
//! frame, split wherever a branch meets it. The result is the structure; its cells (the
//! infill panels) are the `cells` stage's to find.
//!
//! Guarantees: no member lies outside the boundary (cut points lie on it, within the
//! tolerance), the result is one connected network that holds the root, and no two nodes
//! coincide within the tolerance (1e-9 of the boundary's diagonal).

use std::collections::{BTreeMap, HashMap};

use glam::{DVec2, DVec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

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
    /// Pieces inside the boundary but no longer connected to the root (dropped).
    pub detached_pieces: usize,
    /// Points where a branch meets the frame.
    pub frame_joints: usize,
    /// Frame members (0 without a frame).
    pub frame_edges: usize,
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
    #[error("the root point ({0}, {1}) lies outside the boundary: give --root-at inside it")]
    RootOutside(f64, f64),
    #[error("--fit cover: from its root the tree never reaches the boundary's {0} side")]
    CannotCover(&'static str),
    #[error(
        "--fit contain: the tree reaches {0} of its root, where the root touches the \
         boundary; place the root with --root-at"
    )]
    CannotContain(&'static str),
    #[error("--fit: the scale must be a positive number, got {0}")]
    Scale(f64),
    #[error("the tree has no member inside the boundary from its root")]
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

    /// The side `p` lies on within `tol`, and where along it (0..1).
    fn on(&self, p: DVec2, tol: f64) -> Option<(u32, f64)> {
        self.near(p, p, tol)
            .filter_map(|i| {
                let (a, b) = self.side(i);
                let d = b - a;
                let u = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                let dist = (a + d * u).distance(p);
                (dist <= tol).then_some((dist, i, u))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
            .map(|(_, i, u)| (i, u))
    }

    fn distance(&self, p: DVec2) -> f64 {
        (0..self.points.len() as u32)
            .map(|i| {
                let (a, b) = self.side(i);
                let d = b - a;
                let u = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                (a + d * u).distance(p)
            })
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
    if !boundary.contains(at) && sides.on(at, tol).is_none() {
        return Err(FacadeError::RootOutside(at.x, at.y));
    }
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
    let place = |p: DVec3| at + (p.truncate() - r0) * scale;
    let placed: Vec<DVec2> = tree.nodes.iter().map(|n| place(n.p)).collect();

    let mut report = FacadeReport {
        scale,
        root_at: at.to_array(),
        tree_edges: tree.edges.len(),
        kept_whole: 0,
        cut: 0,
        outside: 0,
        detached_pieces: 0,
        frame_joints: 0,
        frame_edges: 0,
        shortest_member: 0.0,
        closest_to_frame: None,
    };
    let inside = |p: DVec2| boundary.contains(p) || sides.on(p, tol).is_some();

    // Pieces of every member inside the boundary, between old nodes and new points.
    let mut out = Builder::default();
    let mut ts = Vec::new();
    for e in &tree.edges {
        let (p, q) = (placed[e.a as usize], placed[e.b as usize]);
        if boundary.contains_segment(p, q) {
            let (a, b) = (out.old(e.a, p, &tree.nodes), out.old(e.b, q, &tree.nodes));
            out.edge(a, b, e.radius);
            report.kept_whole += 1;
            continue;
        }
        ts.clear();
        sides.crossings(p, q, tol, &mut ts);
        ts.push(0.0);
        ts.push(1.0);
        ts.sort_by(f64::total_cmp);
        ts.dedup_by(|b, a| (*b - *a) * p.distance(q) <= tol);
        let (mut pieces, mut whole) = (0, false);
        for w in ts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if !inside(p.lerp(q, 0.5 * (t0 + t1))) {
                continue;
            }
            let mut end = |t: f64| {
                if t == 0.0 {
                    out.old(e.a, p, &tree.nodes)
                } else if t == 1.0 {
                    out.old(e.b, q, &tree.nodes)
                } else {
                    out.new_point(p.lerp(q, t), e.radius)
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
    let Some(&root_node) = out.map.get(&root) else {
        return Err(FacadeError::Empty);
    };

    // Keep what the root reaches.
    let (kept, detached) = out.reachable(root_node);
    report.detached_pieces = detached;
    let (map, mut network) = out.compact(&kept);
    let root_new = map[root_node as usize].expect("the root is reachable from itself");

    // The frame: every side split where kept nodes lie on it.
    let frame_radius = opts
        .frame_radius
        .unwrap_or(tree.nodes[root as usize].radius);
    let mut on_frame = vec![false; network.nodes.len()];
    if opts.frame {
        let mut splits: Vec<Vec<(f64, u32)>> = vec![Vec::new(); boundary.points().len()];
        for (k, n) in network.nodes.iter().enumerate() {
            if let Some((i, u)) = sides.on(n.p.truncate(), tol) {
                splits[i as usize].push((u, k as u32));
                on_frame[k] = true;
                report.frame_joints += 1;
            }
        }
        // Corners: a node already there, or a new one.
        let corners: Vec<u32> = (0..boundary.points().len())
            .map(|i| {
                let c = boundary.points()[i];
                let prev = (i + boundary.points().len() - 1) % boundary.points().len();
                let found = splits[i]
                    .iter()
                    .chain(&splits[prev])
                    .find(|(_, k)| network.nodes[*k as usize].p.truncate().distance(c) <= tol)
                    .map(|&(_, k)| k);
                found.unwrap_or_else(|| {
                    network.nodes.push(Node {
                        p: c.extend(0.0),
                        normal: None,
                        radius: frame_radius,
                    });
                    on_frame.push(true);
                    network.nodes.len() as u32 - 1
                })
            })
            .collect();
        let n = corners.len();
        for (i, split) in splits.iter_mut().enumerate() {
            split.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut chain = vec![corners[i]];
            chain.extend(split.iter().map(|&(_, k)| k));
            chain.push(corners[(i + 1) % n]);
            chain.dedup();
            for w in chain.windows(2) {
                network.edges.push(Edge {
                    a: w[0],
                    b: w[1],
                    radius: frame_radius,
                });
                report.frame_edges += 1;
            }
        }
        // Nodes on the frame within the tolerance of each other are one joint.
        network = merge_close(network, tol);
    }
    report.shortest_member = network.lengths().map_or(0.0, |l| l.min);
    report.closest_to_frame = network
        .nodes
        .iter()
        .enumerate()
        .filter(|(k, _)| !on_frame.get(*k).copied().unwrap_or(false))
        .map(|(_, n)| sides.distance(n.p.truncate()))
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

/// The network under construction: old nodes mapped on first use, new points appended.
#[derive(Default)]
struct Builder {
    nodes: Vec<Node>,
    edges: Vec<Edge>,
    /// Old node → new node.
    map: HashMap<u32, u32>,
}

impl Builder {
    fn old(&mut self, k: u32, p: DVec2, old: &[Node]) -> u32 {
        let nodes = &mut self.nodes;
        *self.map.entry(k).or_insert_with(|| {
            nodes.push(Node {
                p: p.extend(0.0),
                ..old[k as usize]
            });
            nodes.len() as u32 - 1
        })
    }

    fn new_point(&mut self, p: DVec2, radius: f64) -> u32 {
        self.nodes.push(Node {
            p: p.extend(0.0),
            normal: None,
            radius,
        });
        self.nodes.len() as u32 - 1
    }

    fn edge(&mut self, a: u32, b: u32, radius: f64) {
        if a != b {
            self.edges.push(Edge { a, b, radius });
        }
    }

    /// Nodes the root reaches, and how many connected pieces it does not.
    fn reachable(&self, root: u32) -> (Vec<bool>, usize) {
        let n = self.nodes.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        for e in &self.edges {
            let (a, b) = (find(&mut parent, e.a), find(&mut parent, e.b));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let r = find(&mut parent, root);
        let labels: Vec<u32> = (0..n as u32).map(|v| find(&mut parent, v)).collect();
        let kept: Vec<bool> = labels.iter().map(|&l| l == r).collect();
        let mut others: Vec<u32> = labels.iter().copied().filter(|&l| l != r).collect();
        others.sort_unstable();
        others.dedup();
        (kept, others.len())
    }

    /// The kept part as a network (node order kept), with the old → new map.
    fn compact(self, kept: &[bool]) -> (Vec<Option<u32>>, Network) {
        let mut map = vec![None; self.nodes.len()];
        let mut net = Network::default();
        for (k, n) in self.nodes.into_iter().enumerate() {
            if kept[k] {
                map[k] = Some(net.nodes.len() as u32);
                net.nodes.push(n);
            }
        }
        for e in self.edges {
            if let (Some(a), Some(b)) = (map[e.a as usize], map[e.b as usize]) {
                net.edges.push(Edge { a, b, ..e });
            }
        }
        (map, net)
    }
}

/// Merges nodes closer than `tol` (the earlier one stays), and drops the edges that become
/// loops or repeats.
fn merge_close(net: Network, tol: f64) -> Network {
    let cell = tol.max(f64::MIN_POSITIVE) * 4.0;
    let key = |p: DVec3| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    let mut map = vec![0u32; net.nodes.len()];
    let mut nodes = Vec::with_capacity(net.nodes.len());
    for (k, n) in net.nodes.iter().enumerate() {
        let (cx, cy) = key(n.p);
        let hit = (-1..=1)
            .flat_map(|dx| (-1..=1).map(move |dy| (cx + dx, cy + dy)))
            .filter_map(|c| grid.get(&c))
            .flatten()
            .copied()
            .find(|&m| nodes_at(&nodes, m).distance(n.p) <= tol);
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
    let mut seen: BTreeMap<(u32, u32), ()> = BTreeMap::new();
    let edges = net
        .edges
        .iter()
        .filter_map(|e| {
            let (a, b) = (map[e.a as usize], map[e.b as usize]);
            (a != b && seen.insert((a.min(b), a.max(b)), ()).is_none()).then_some(Edge {
                a,
                b,
                ..*e
            })
        })
        .collect();
    Network {
        nodes,
        edges,
        meta: net.meta,
    }
}

fn nodes_at(nodes: &[Node], k: u32) -> DVec3 {
    nodes[k as usize].p
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
        let outside = FacadeOptions {
            root_at: Some(DVec2::new(0.0, -1.0)),
            ..Default::default()
        };
        assert!(matches!(
            fit(&y_tree().network, 0, &b, &outside),
            Err(FacadeError::RootOutside(..))
        ));
        Ok(())
    }
}
