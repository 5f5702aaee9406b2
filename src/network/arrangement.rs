//! Flat drawings as planar arrangements: where edges cross without a shared node, or end on
//! another edge (T-junctions), and noding them so that each such point becomes a node.
//!
//! A network is flat when every node lies within the tolerance of one plane; only then do
//! crossings mean anything (3D members pass each other). Candidates come from an R-tree of the
//! edges' boxes, so the cost is O(E log E + crossings).

use std::collections::HashSet;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use super::{Edge, Network, Node};
use crate::geom::merge::merge_points;

/// A place where a flat drawing is not noded.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Defect {
    /// Two edges cross at a point that is neither's end.
    Crossing { edges: [u32; 2], at: [f64; 3] },
    /// A node lies on an edge that does not end there.
    TJunction { node: u32, edge: u32, at: [f64; 3] },
}

impl std::fmt::Display for Defect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = |a: &[f64; 3]| format!("({:.4}, {:.4}, {:.4})", a[0], a[1], a[2]);
        match self {
            Defect::Crossing { edges, at } => write!(
                f,
                "edges {} and {} cross at {} without a node",
                edges[0],
                edges[1],
                p(at)
            ),
            Defect::TJunction { node, edge, at } => write!(
                f,
                "node {node} lies on edge {edge} at {} (a T-junction without a node)",
                p(at)
            ),
        }
    }
}

/// What noding did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SplitStats {
    pub crossings: usize,
    pub t_junctions: usize,
    /// Nodes added (crossings through one point share one).
    pub nodes_added: usize,
    /// Edges after noding, less edges before.
    pub edges_added: usize,
    /// Edges that became repeats of another once noded (overlapping collinear lines), dropped.
    pub overlaps_dropped: usize,
}

/// The plane a network lies in, as an origin and two axes, if every node is within `tol` of it.
fn plane(net: &Network, tol: f64) -> Option<(DVec3, DVec3, DVec3)> {
    let p: Vec<DVec3> = net.nodes.iter().map(|n| n.p).collect();
    let o = *p.first()?;
    let far = *p
        .iter()
        .max_by(|a, b| a.distance_squared(o).total_cmp(&b.distance_squared(o)))?;
    let u = (far - o).try_normalize()?;
    let off = |q: &DVec3| (*q - o) - u * (*q - o).dot(u);
    let third = p
        .iter()
        .max_by(|a, b| off(a).length_squared().total_cmp(&off(b).length_squared()))?;
    let n = match u.cross(off(third)).try_normalize() {
        Some(n) if off(third).length() > tol => n,
        _ => {
            // On one line: any plane through it.
            let n = u.any_orthonormal_vector();
            return Some((o, u, n.cross(u)));
        }
    };
    if p.iter().any(|q| (*q - o).dot(n).abs() > tol) {
        return None;
    }
    Some((o, u, n.cross(u)))
}

type Boxed = GeomWithData<Rectangle<[f64; 2]>, u32>;

struct Flat {
    pts: Vec<DVec2>,
}

impl Flat {
    fn seg(&self, e: &Edge) -> (DVec2, DVec2) {
        (self.pts[e.a as usize], self.pts[e.b as usize])
    }
}

/// Every crossing and T-junction of a flat network (none for a network that is not flat), in
/// edge order. `tol` in mm: points closer than this are one point.
pub fn defects(net: &Network, tol: f64) -> Vec<Defect> {
    find(net, tol).map(|(d, _)| d).unwrap_or_default()
}

/// A crossing or T-junction with its parameter along each edge it splits.
struct Cut {
    edge: u32,
    t: f64,
    /// An existing node, or a new point.
    node: Option<u32>,
    at: DVec3,
}

/// Edges per parallel task in the crossing search.
const EDGE_CHUNK: usize = 4096;

/// A node on an edge's interior: (edge, node, parameter along the edge).
type OnEdge = (u32, u32, f64);
/// A proper crossing: (edge, later edge, parameter on each, the point).
type Crossing = (u32, u32, f64, f64, DVec3);

fn find(net: &Network, tol: f64) -> Option<(Vec<Defect>, Vec<Cut>)> {
    let (o, u, v) = plane(net, tol)?;
    let flat = Flat {
        pts: net
            .nodes
            .iter()
            .map(|n| DVec2::new((n.p - o).dot(u), (n.p - o).dot(v)))
            .collect(),
    };
    let to3 = |q: DVec2| o + u * q.x + v * q.y;
    let boxes: Vec<Boxed> = net
        .edges
        .iter()
        .enumerate()
        .filter(|(_, e)| e.a != e.b)
        .map(|(k, e)| {
            let (a, b) = flat.seg(e);
            let (lo, hi) = (a.min(b) - tol, a.max(b) + tol);
            GeomWithData::new(
                Rectangle::from_corners([lo.x, lo.y], [hi.x, hi.y]),
                k as u32,
            )
        })
        .collect();
    // Nodes no edge ends at can still lie on an edge: they get an index of their own (most
    // drawings have none). Every other node on an edge is the end of an edge whose box meets it.
    let mut ends = vec![false; net.nodes.len()];
    for e in net.edges.iter().filter(|e| e.a != e.b) {
        ends[e.a as usize] = true;
        ends[e.b as usize] = true;
    }
    let lonely: Vec<GeomWithData<[f64; 2], u32>> = (0..net.nodes.len())
        .filter(|&i| !ends[i])
        .map(|i| GeomWithData::new(flat.pts[i].to_array(), i as u32))
        .collect();
    let lonely = RTree::bulk_load(lonely);
    let tree = RTree::bulk_load(boxes);
    // Each edge against the later edges whose boxes meet its own, in parallel a chunk of edges
    // at a time: both edges' ends on the other (T-junctions) and proper crossings.
    let per_chunk: Vec<(Vec<OnEdge>, Vec<Crossing>)> = net
        .edges
        .par_chunks(EDGE_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut on = Vec::new();
            let mut crossings = Vec::new();
            let mut others: Vec<u32> = Vec::new();
            for (i, e) in chunk.iter().enumerate() {
                if e.a == e.b {
                    continue;
                }
                let k = (c * EDGE_CHUNK + i) as u32;
                let (a, b) = flat.seg(e);
                let (lo, hi) = (a.min(b) - tol, a.max(b) + tol);
                let env = AABB::from_corners([lo.x, lo.y], [hi.x, hi.y]);
                for p in lonely.locate_in_envelope(&env) {
                    if let Some(t) = interior_param(a, b, flat.pts[p.data as usize], tol) {
                        on.push((k, p.data, t));
                    }
                }
                others.clear();
                others.extend(
                    tree.locate_in_envelope_intersecting(&env)
                        .map(|g| g.data)
                        .filter(|&j| j > k),
                );
                others.sort_unstable();
                for &j in &others {
                    let f = &net.edges[j as usize];
                    let (c, d) = flat.seg(f);
                    for n in [f.a, f.b] {
                        if n != e.a && n != e.b {
                            if let Some(t) = interior_param(a, b, flat.pts[n as usize], tol) {
                                on.push((k, n, t));
                            }
                        }
                    }
                    for n in [e.a, e.b] {
                        if n != f.a && n != f.b {
                            if let Some(t) = interior_param(c, d, flat.pts[n as usize], tol) {
                                on.push((j, n, t));
                            }
                        }
                    }
                    if [f.a, f.b].iter().any(|x| *x == e.a || *x == e.b) {
                        continue;
                    }
                    if let Some((t, s)) = crossing(a, b, c, d, tol) {
                        crossings.push((k, j, t, s, to3(a + (b - a) * t)));
                    }
                }
            }
            (on, crossings)
        })
        .collect();
    let mut on: Vec<OnEdge> = Vec::new();
    let mut crossings: Vec<Crossing> = Vec::new();
    for (o, c) in per_chunk {
        on.extend(o);
        crossings.extend(c);
    }
    // A node on an edge is found once per edge ending at it: once is enough.
    on.sort_unstable_by_key(|&(edge, node, _)| (edge, node));
    on.dedup_by_key(|&mut (edge, node, _)| (edge, node));
    // In edge order: each edge's T-junctions (by node), then its crossings with later edges.
    let mut defects = Vec::new();
    let mut cuts = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < on.len() || j < crossings.len() {
        let take_on = j == crossings.len() || (i < on.len() && on[i].0 <= crossings[j].0);
        if take_on {
            let (edge, node, t) = on[i];
            let at = net.nodes[node as usize].p;
            defects.push(Defect::TJunction {
                node,
                edge,
                at: at.to_array(),
            });
            cuts.push(Cut {
                edge,
                t,
                node: Some(node),
                at,
            });
            i += 1;
        } else {
            let (k, other, t, s, at) = crossings[j];
            defects.push(Defect::Crossing {
                edges: [k, other],
                at: at.to_array(),
            });
            cuts.push(Cut {
                edge: k,
                t,
                node: None,
                at,
            });
            cuts.push(Cut {
                edge: other,
                t: s,
                node: None,
                at,
            });
            j += 1;
        }
    }
    Some((defects, cuts))
}

/// Where along a-b (0..1, away from both ends by more than `tol`) the point q lies, if within
/// `tol` of the segment.
fn interior_param(a: DVec2, b: DVec2, q: DVec2, tol: f64) -> Option<f64> {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return None;
    }
    let t = (q - a).dot(ab) / len2;
    let foot = a + ab * t;
    let inside = q.distance(a) > tol && q.distance(b) > tol && (0.0..=1.0).contains(&t);
    (inside && q.distance(foot) <= tol).then_some(t)
}

/// Parameters (t on a-b, s on c-d) of a proper crossing, away from every end by more than
/// `tol` (a crossing near an end is a T-junction, found as a node on the other edge).
fn crossing(a: DVec2, b: DVec2, c: DVec2, d: DVec2, tol: f64) -> Option<(f64, f64)> {
    let (r, s) = (b - a, d - c);
    let denom = r.perp_dot(s);
    if denom == 0.0 {
        return None;
    }
    let t = (c - a).perp_dot(s) / denom;
    let u = (c - a).perp_dot(r) / denom;
    if !(0.0..=1.0).contains(&t) || !(0.0..=1.0).contains(&u) {
        return None;
    }
    let x = a + r * t;
    let near_end = [a, b, c, d].iter().any(|p| p.distance(x) <= tol);
    (!near_end).then_some((t, u))
}

/// The network with every crossing and T-junction made a node, edges split there; `None` when
/// the network is not flat. New nodes take the radius of the edge they split; sub-edges keep
/// their edge's radius. Crossings within `tol` of each other share a node.
pub fn split_crossings(net: &Network, tol: f64) -> Option<(Network, SplitStats)> {
    let (defects, cuts) = find(net, tol)?;
    let mut stats = SplitStats {
        crossings: defects
            .iter()
            .filter(|d| matches!(d, Defect::Crossing { .. }))
            .count(),
        t_junctions: defects
            .iter()
            .filter(|d| matches!(d, Defect::TJunction { .. }))
            .count(),
        ..Default::default()
    };
    if cuts.is_empty() {
        return Some((net.clone(), stats));
    }
    // New points welded among themselves and onto existing nodes.
    let fresh: Vec<DVec3> = cuts
        .iter()
        .filter(|c| c.node.is_none())
        .map(|c| c.at)
        .collect();
    let mut all: Vec<DVec3> = net.nodes.iter().map(|n| n.p).collect();
    all.extend(&fresh);
    let (map, merged) = merge_points(&all, tol);
    let mut nodes = net.nodes.clone();
    let old = net.nodes.len();
    // Each merged id that is not an old node becomes a new node (first appearance order).
    let mut id_of = vec![u32::MAX; merged.len()];
    for (i, &m) in map.iter().take(old).enumerate() {
        if id_of[m as usize] == u32::MAX {
            id_of[m as usize] = i as u32;
        }
    }
    let mut fresh_ids = Vec::with_capacity(fresh.len());
    let mut f = 0usize;
    for c in &cuts {
        let id = match c.node {
            Some(n) => n,
            None => {
                let m = map[old + f] as usize;
                f += 1;
                if id_of[m] == u32::MAX {
                    id_of[m] = nodes.len() as u32;
                    let radius = net.edges[c.edge as usize].radius;
                    nodes.push(Node {
                        p: merged[m],
                        normal: None,
                        radius,
                    });
                }
                id_of[m]
            }
        };
        fresh_ids.push(id);
    }
    stats.nodes_added = nodes.len() - old;
    let mut per_edge: Vec<Vec<(f64, u32)>> = vec![Vec::new(); net.edges.len()];
    for (c, &id) in cuts.iter().zip(&fresh_ids) {
        per_edge[c.edge as usize].push((c.t, id));
    }
    let mut edges = Vec::with_capacity(net.edges.len() + cuts.len());
    let mut seen: HashSet<(u32, u32)> = HashSet::new();
    for (k, e) in net.edges.iter().enumerate() {
        let mut chain = std::mem::take(&mut per_edge[k]);
        chain.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut ids = vec![e.a];
        ids.extend(chain.iter().map(|&(_, id)| id));
        ids.push(e.b);
        ids.dedup();
        for w in ids.windows(2) {
            let key = (w[0].min(w[1]), w[0].max(w[1]));
            if w[0] != w[1] && !seen.insert(key) {
                stats.overlaps_dropped += 1;
                continue;
            }
            edges.push(Edge {
                a: w[0],
                b: w[1],
                radius: e.radius,
            });
        }
    }
    stats.edges_added = edges.len().saturating_sub(net.edges.len());
    Some((
        Network {
            nodes,
            edges,
            meta: net.meta.clone(),
        },
        stats,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net(points: &[[f64; 2]], edges: &[[u32; 2]]) -> Network {
        Network {
            nodes: points
                .iter()
                .map(|p| Node::at(DVec3::new(p[0], p[1], 0.0)))
                .collect(),
            edges: edges.iter().map(|e| Edge::new(e[0], e[1])).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn a_plus_sign_is_one_crossing_and_four_edges_once_noded() {
        let n = net(
            &[[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]],
            &[[0, 1], [2, 3]],
        );
        let d = defects(&n, 1e-9);
        assert_eq!(d.len(), 1);
        assert!(matches!(d[0], Defect::Crossing { edges: [0, 1], .. }));
        let (s, stats) = split_crossings(&n, 1e-9).expect("flat");
        assert_eq!((s.nodes.len(), s.edges.len()), (5, 4));
        assert_eq!(stats.nodes_added, 1);
        assert!(defects(&s, 1e-9).is_empty());
    }

    #[test]
    fn a_t_junction_splits_the_edge_it_ends_on() {
        let n = net(
            &[[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            &[[0, 1], [2, 3]],
        );
        let d = defects(&n, 1e-9);
        assert!(matches!(
            d[..],
            [Defect::TJunction {
                node: 2,
                edge: 0,
                ..
            }]
        ));
        let (s, _) = split_crossings(&n, 1e-9).expect("flat");
        assert_eq!((s.nodes.len(), s.edges.len()), (4, 3));
        assert_eq!(s.validate().degree_histogram, vec![0, 3, 0, 1]);
    }

    #[test]
    fn three_lines_through_one_point_share_one_node() {
        let n = net(
            &[
                [-1.0, 0.0],
                [1.0, 0.0],
                [0.0, -1.0],
                [0.0, 1.0],
                [-1.0, -1.0],
                [1.0, 1.0],
            ],
            &[[0, 1], [2, 3], [4, 5]],
        );
        let (s, stats) = split_crossings(&n, 1e-9).expect("flat");
        assert_eq!(stats.nodes_added, 1);
        assert_eq!(s.edges.len(), 6);
        assert_eq!(s.validate().degree_histogram[6], 1);
    }

    #[test]
    fn overlapping_collinear_lines_keep_one_copy() {
        let n = net(
            &[[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [3.0, 0.0]],
            &[[0, 1], [2, 3]],
        );
        let (s, stats) = split_crossings(&n, 1e-9).expect("flat");
        assert_eq!(s.edges.len(), 3, "{:?}", s.edges);
        assert_eq!(stats.overlaps_dropped, 1);
    }

    #[test]
    fn networks_off_a_plane_have_no_crossings() {
        let mut n = net(
            &[[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]],
            &[[0, 1], [2, 3]],
        );
        n.nodes[3].p.z = 1.0;
        assert!(defects(&n, 1e-9).is_empty());
        assert!(split_crossings(&n, 1e-9).is_none());
    }
}
