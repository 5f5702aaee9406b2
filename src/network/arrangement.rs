//! Flat drawings as planar arrangements: where edges cross without a shared node, or end on
//! another edge (T-junctions), and noding them so that each such point becomes a node.
//!
//! A network is flat when every node lies within the tolerance of one plane; only then do
//! crossings mean anything (3D members pass each other). Candidates come from an R-tree of the
//! edges' boxes, so the cost is O(E log E + crossings).

use std::collections::HashSet;
use std::hash::BuildHasherDefault;
use std::ops::ControlFlow;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rstar::primitives::GeomWithData;
use rstar::{RTree, AABB};
use static_aabb2d_index::StaticAABB2DIndexBuilder;

use super::{Edge, Network, Node};
use crate::geom::merge::merge_points;
use crate::geom::KeyHasher;

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
    /// Edges that repeat another once noded (overlapping collinear lines, or a line drawn
    /// twice), dropped.
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

struct Flat {
    pts: Vec<DVec2>,
}

impl Flat {
    fn seg(&self, e: &Edge) -> (DVec2, DVec2) {
        (self.pts[e.a as usize], self.pts[e.b as usize])
    }
}

/// The crossings and T-junctions of a flat drawing: how many, and the first ones in edge order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Defects {
    /// The first defects in edge order (each edge's T-junctions by node, then its crossings
    /// with later edges), at most as many as asked for.
    pub listed: Vec<Defect>,
    /// Proper crossings counted.
    pub crossings: usize,
    /// T-junctions counted.
    pub t_junctions: usize,
    /// False when the search stopped at [`COUNT_CEILING`]: the counts are then lower bounds.
    pub counted_all: bool,
    /// Edges left out of the search because they repeat an earlier edge's two nodes.
    pub repeated_edges: usize,
}

impl Defects {
    /// Crossings and T-junctions together.
    pub fn total(&self) -> usize {
        self.crossings + self.t_junctions
    }

    /// "1,234 crossings and 5 T-junctions", with "at least" when the count stopped early.
    pub fn counted(&self) -> String {
        format!(
            "{}{} crossings and {} T-junctions",
            if self.counted_all { "" } else { "at least " },
            self.crossings,
            self.t_junctions
        )
    }
}

/// The most crossings and T-junctions [`split_crossings`] makes nodes of.
pub const SPLIT_LIMIT: usize = 1_000_000;

/// The search stops counting once it has found this many crossings and T-junctions, one more
/// than [`split_crossings`] would node (a drawing with more is not one anyone will node); the
/// counts are then lower bounds. Counting on to ten million took a 50,000-segment scribble 5 s
/// of CPU instead of half a second, and told nothing more.
pub const COUNT_CEILING: usize = SPLIT_LIMIT + 1;

/// Why a drawing could not be noded.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SplitError {
    #[error(
        "the network does not lie in one plane (within {tol} mm), so its edges cannot cross",
        tol = crate::text::num(*tol)
    )]
    NotFlat { tol: f64 },
    #[error(
        "the drawing has {counted}, more than the {limit} lamina makes nodes of: its edges \
         cross almost everywhere (a scribble, or edges between random nodes)"
    )]
    TooMany { counted: String, limit: usize },
}

/// Every crossing and T-junction of a flat network (none for a network that is not flat), in
/// edge order, listing at most `keep`. `tol` in mm: points closer than this are one point.
/// Edges repeating an earlier edge's two nodes are searched once. Time is O(E log E) plus the
/// candidate pairs, and the count stops at [`COUNT_CEILING`].
pub fn defects(net: &Network, tol: f64, keep: usize) -> Defects {
    find(net, tol, keep).map(|f| f.defects).unwrap_or(Defects {
        counted_all: true,
        ..Default::default()
    })
}

/// A crossing or T-junction with its parameter along each edge it splits.
struct Cut {
    edge: u32,
    t: f64,
    /// An existing node, or a new point.
    node: Option<u32>,
    at: DVec3,
}

/// Children per node of the edge tree (8 queried fastest on a million-edge drawing, against
/// 4, 16 and 32).
const TREE_NODE: usize = 8;
/// Edges per parallel task in the crossing search.
const EDGE_CHUNK: usize = 4096;
/// Tasks searched before the count is checked against the ceiling (fixed, so every machine
/// stops at the same place; each task keeps at most the room left in the list).
const WAVE: usize = 4;
/// At most this many edges that follow one another share one query of the edge tree…
const RUN: usize = 16;
/// …and only while the box around them is at most this many times their own boxes' area.
const RUN_SPREAD: f64 = 4.0;

/// A defect as the search finds it: a node on an edge's interior (edge, node, parameter), or a
/// proper crossing (edge, later edge, parameter on each, the point).
enum Raw {
    On(u32, u32, f64),
    Cross(u32, u32, f64, f64, DVec3),
}

/// What one task found among its edges: defects in edge order (at most the room it was given)
/// and how many it counted.
struct ChunkFound {
    raw: Vec<Raw>,
    crossings: usize,
    t_junctions: usize,
}

struct Found {
    defects: Defects,
    cuts: Vec<Cut>,
    /// Per edge: whether it was searched (false for loops and repeats of an earlier edge).
    searched: Vec<bool>,
}

fn find(net: &Network, tol: f64, keep: usize) -> Option<Found> {
    let (o, u, v) = plane(net, tol)?;
    let flat = Flat {
        pts: net
            .nodes
            .iter()
            .map(|n| DVec2::new((n.p - o).dot(u), (n.p - o).dot(v)))
            .collect(),
    };
    let to3 = |q: DVec2| o + u * q.x + v * q.y;
    // Each pair of nodes is searched once: a drawing with 50,000 copies of 72 lines costs what
    // 72 lines cost.
    let mut searched = vec![true; net.edges.len()];
    let mut seen: HashSet<u64, BuildHasherDefault<KeyHasher>> =
        HashSet::with_capacity_and_hasher(net.edges.len(), Default::default());
    let mut repeated_edges = 0;
    for (k, e) in net.edges.iter().enumerate() {
        if e.a == e.b {
            searched[k] = false;
        } else if !seen.insert((e.a.min(e.b) as u64) << 32 | e.a.max(e.b) as u64) {
            searched[k] = false;
            repeated_edges += 1;
        }
    }
    drop(seen);
    // The searched edges' boxes in a packed Hilbert R-tree: on a million-edge drawing it is
    // built in a third of the time of rstar's bulk load and queried in a third of the time.
    let count = searched.iter().filter(|s| **s).count();
    // One more item, a point that squares the tree's bounds: the builder orders boxes along a
    // Hilbert curve over its bounds scaled to a square, and a drawing 1,000 times longer than
    // wide would otherwise be cut into nodes as long as the drawing and a hair wide, which
    // every query crosses (a 12 mm × 16 m MINSERT took 1.3 s of queries instead of 0.3 s).
    let mut built = StaticAABB2DIndexBuilder::new_with_node_size(count + 1, TREE_NODE);
    // What a query needs of each edge it meets, in one place (a hit reads one record, not the
    // edge, then its two nodes).
    let mut items: Vec<Item> = Vec::with_capacity(count);
    let (mut lo_all, mut hi_all) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for (k, e) in net.edges.iter().enumerate().filter(|(k, _)| searched[*k]) {
        // Boxes as drawn; each query widens its own by the tolerance.
        let (a, b) = flat.seg(e);
        let (lo, hi) = (a.min(b), a.max(b));
        built.add(lo.x, lo.y, hi.x, hi.y);
        items.push(Item {
            a,
            b,
            ends: [e.a, e.b],
            edge: k as u32,
        });
        (lo_all, hi_all) = (lo_all.min(lo), hi_all.max(hi));
    }
    let corner = if count > 0 {
        lo_all + DVec2::splat((hi_all - lo_all).max_element())
    } else {
        DVec2::ZERO
    };
    built.add(corner.x, corner.y, corner.x, corner.y);
    // The builder fails only when it is given fewer or more boxes than it was told.
    let tree = built.build().ok()?;
    // A node on an edge's interior is an end of some searched edge whose box meets that
    // edge's box, so the edge tree finds it; only nodes that end no searched edge (isolated
    // nodes, nodes of loops only) need a tree of their own.
    let mut ends_an_edge = vec![false; net.nodes.len()];
    for (e, _) in net.edges.iter().zip(&searched).filter(|(_, s)| **s) {
        ends_an_edge[e.a as usize] = true;
        ends_an_edge[e.b as usize] = true;
    }
    let loose: Vec<GeomWithData<[f64; 2], u32>> = (0..net.nodes.len())
        .filter(|&i| !ends_an_edge[i])
        .map(|i| GeomWithData::new(flat.pts[i].to_array(), i as u32))
        .collect();
    drop(ends_an_edge);
    let loose = RTree::bulk_load(loose);
    // Each edge finds the nodes on its interior (its T-junctions) and its proper crossings
    // with later edges whose boxes meet its own, so every defect is found once, by the task
    // holding the edge, in edge order. Tasks run in parallel a wave at a time; each keeps at
    // most the room left in the list and counts the rest.
    // One edge against the edges near it (a superset of those whose boxes meet its own): its
    // T-junctions by node, then its crossings with later edges, each counted and listed while
    // there is room.
    let search_edge = |k: u32,
                       near: &[Item],
                       on: &mut Vec<(u32, f64)>,
                       crossed: &mut Vec<(u32, f64, f64)>,
                       out: &mut ChunkFound,
                       room: usize| {
        let e = &net.edges[k as usize];
        let (a, b) = flat.seg(e);
        let (lo, hi) = (a.min(b) - tol, a.max(b) + tol);
        let line = Line::new(a, b, tol);
        on.clear();
        crossed.clear();
        let mut on_interior = |n: u32, q: DVec2| {
            let in_box = q.cmpge(lo).all() && q.cmple(hi).all();
            if in_box && n != e.a && n != e.b {
                if let Some(t) = line.interior_param(q) {
                    on.push((n, t));
                }
            }
        };
        // The edges whose boxes (as drawn) meet its own widened by the tolerance, the test the
        // tree makes: their ends on its interior are its T-junctions (each found once, here);
        // the later ones may cross it.
        for f in near {
            let (flo, fhi) = (f.a.min(f.b), f.a.max(f.b));
            if fhi.x < lo.x || fhi.y < lo.y || flo.x > hi.x || flo.y > hi.y || f.edge == k {
                continue;
            }
            on_interior(f.ends[0], f.a);
            on_interior(f.ends[1], f.b);
            if f.edge > k && !f.ends.iter().any(|x| *x == e.a || *x == e.b) {
                if let Some((t, s)) = crossing(a, b, f.a, f.b, tol) {
                    crossed.push((f.edge, t, s));
                }
            }
        }
        let env = AABB::from_corners([lo.x, lo.y], [hi.x, hi.y]);
        let _ = loose.locate_in_envelope_int(&env, |p| {
            on_interior(p.data, flat.pts[p.data as usize]);
            ControlFlow::<()>::Continue(())
        });
        // A node ending several edges near this one is found once per edge.
        on.sort_unstable_by_key(|&(n, _)| n);
        on.dedup_by_key(|&mut (n, _)| n);
        for &(node, t) in on.iter() {
            out.t_junctions += 1;
            if out.raw.len() < room {
                out.raw.push(Raw::On(k, node, t));
            }
        }
        crossed.sort_unstable_by_key(|&(j, _, _)| j);
        for &(j, t, s) in crossed.iter() {
            out.crossings += 1;
            if out.raw.len() < room {
                out.raw.push(Raw::Cross(k, j, t, s, to3(a + (b - a) * t)));
            }
        }
    };
    let search = |c: usize, room: usize| -> ChunkFound {
        let mut out = ChunkFound {
            raw: Vec::new(),
            crossings: 0,
            t_junctions: 0,
        };
        let first = c * EDGE_CHUNK;
        let last = (first + EDGE_CHUNK).min(net.edges.len());
        let mut on: Vec<(u32, f64)> = Vec::new();
        let mut crossed: Vec<(u32, f64, f64)> = Vec::new();
        let mut stack: Vec<usize> = Vec::new();
        let mut near: Vec<Item> = Vec::new();
        let widened = |e: &Edge| {
            let (a, b) = flat.seg(e);
            (a.min(b) - tol, a.max(b) + tol)
        };
        let ks: Vec<u32> = (first as u32..last as u32)
            .filter(|&k| searched[k as usize])
            .collect();
        let mut next = 0;
        while next < ks.len() {
            // Edges that follow one another in a file mostly lie side by side: a run of them
            // whose boxes together cover not much more than each on its own asks the tree once,
            // and each edge picks its own from what came back (the tree's walk, not the tests,
            // was most of the search's time on million-edge drawings).
            let (mut lo_run, mut hi_run) = widened(&net.edges[ks[next] as usize]);
            let mut own_area = (hi_run - lo_run).element_product();
            let mut end = next + 1;
            while end < ks.len() && end - next < RUN {
                let (lo, hi) = widened(&net.edges[ks[end] as usize]);
                let (lo_u, hi_u) = (lo_run.min(lo), hi_run.max(hi));
                let area = own_area + (hi - lo).element_product();
                if (hi_u - lo_u).element_product() > RUN_SPREAD * area {
                    break;
                }
                (lo_run, hi_run, own_area) = (lo_u, hi_u, area);
                end += 1;
            }
            near.clear();
            tree.visit_query_with_stack(
                lo_run.x,
                lo_run.y,
                hi_run.x,
                hi_run.y,
                &mut |item: usize| {
                    // The squaring point is no edge.
                    if let Some(f) = items.get(item) {
                        near.push(*f);
                    }
                },
                &mut stack,
            );
            for &k in &ks[next..end] {
                search_edge(k, &near, &mut on, &mut crossed, &mut out, room);
            }
            next = end;
        }
        out
    };
    let chunks = net.edges.len().div_ceil(EDGE_CHUNK);
    let mut found = Found {
        defects: Defects {
            counted_all: true,
            repeated_edges,
            ..Default::default()
        },
        cuts: Vec::new(),
        searched: Vec::new(),
    };
    let mut c = 0;
    while c < chunks {
        if found.defects.total() >= COUNT_CEILING {
            found.defects.counted_all = false;
            break;
        }
        let wave = c..(c + WAVE).min(chunks);
        c = wave.end;
        let room = keep.saturating_sub(found.defects.listed.len());
        let parts: Vec<ChunkFound> = wave.into_par_iter().map(|c| search(c, room)).collect();
        for part in parts {
            found.defects.crossings += part.crossings;
            found.defects.t_junctions += part.t_junctions;
            let room = keep - found.defects.listed.len();
            for raw in part.raw.into_iter().take(room) {
                match raw {
                    Raw::On(edge, node, t) => {
                        let at = net.nodes[node as usize].p;
                        found.defects.listed.push(Defect::TJunction {
                            node,
                            edge,
                            at: at.to_array(),
                        });
                        found.cuts.push(Cut {
                            edge,
                            t,
                            node: Some(node),
                            at,
                        });
                    }
                    Raw::Cross(k, j, t, s, at) => {
                        found.defects.listed.push(Defect::Crossing {
                            edges: [k, j],
                            at: at.to_array(),
                        });
                        found.cuts.push(Cut {
                            edge: k,
                            t,
                            node: None,
                            at,
                        });
                        found.cuts.push(Cut {
                            edge: j,
                            t: s,
                            node: None,
                            at,
                        });
                    }
                }
            }
        }
    }
    found.searched = searched;
    Some(found)
}

/// A searched edge as the crossing search keeps it: its ends, drawn and by node, and its index.
#[derive(Clone, Copy)]
struct Item {
    a: DVec2,
    b: DVec2,
    ends: [u32; 2],
    edge: u32,
}

/// A segment a-b with what [`Line::interior_param`] asks of it computed once per query.
struct Line {
    a: DVec2,
    ab: DVec2,
    len2: f64,
    tol2: f64,
}

impl Line {
    fn new(a: DVec2, b: DVec2, tol: f64) -> Self {
        let ab = b - a;
        Line {
            a,
            ab,
            len2: ab.length_squared(),
            tol2: tol * tol,
        }
    }

    /// Where along a-b (0..1, away from both ends by more than `tol`) the point q lies, if
    /// within `tol` of the segment. Compares squares: no square root on the way.
    fn interior_param(&self, q: DVec2) -> Option<f64> {
        if self.len2 == 0.0 {
            return None;
        }
        let aq = q - self.a;
        // Distance to the line is |ab × aq| / |ab|: compared as squares.
        let cross = self.ab.perp_dot(aq);
        if cross * cross > self.tol2 * self.len2 {
            return None;
        }
        let t = aq.dot(self.ab) / self.len2;
        if !(0.0..=1.0).contains(&t) {
            return None;
        }
        let foot = self.a + self.ab * t;
        let bq = aq - self.ab;
        let inside = aq.length_squared() > self.tol2 && bq.length_squared() > self.tol2;
        (inside && q.distance_squared(foot) <= self.tol2).then_some(t)
    }
}

/// Parameters (t on a-b, s on c-d) of a proper crossing, away from every end by more than
/// `tol` (a crossing near an end is a T-junction, found as a node on the other edge). Segments
/// that lie along each other within `tol` (overlapping collinear lines) do not cross: where
/// they overlap, each one's ends lie on the other and are found as T-junctions.
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
    let off_line = |p: DVec2, q: DVec2, x: DVec2| {
        let len = (q - p).length();
        len > 0.0 && ((x - p).perp_dot(q - p) / len).abs() > tol
    };
    let along = |p, q, x, y| !off_line(p, q, x) && !off_line(p, q, y);
    if along(a, b, c, d) || along(c, d, a, b) {
        return None;
    }
    let x = a + r * t;
    let near_end = [a, b, c, d].iter().any(|p| p.distance(x) <= tol);
    (!near_end).then_some((t, u))
}

/// The network with every crossing and T-junction made a node, edges split there. New nodes
/// take the radius of the edge they split; sub-edges keep their edge's radius. Crossings within
/// `tol` of each other share a node; edges that become repeats of another (overlapping
/// collinear lines, or lines drawn twice) are dropped and counted. Refused when the network is
/// not flat, or has more than [`SPLIT_LIMIT`] crossings and T-junctions.
pub fn split_crossings(net: &Network, tol: f64) -> Result<(Network, SplitStats), SplitError> {
    split_within(net, tol, SPLIT_LIMIT)
}

fn split_within(
    net: &Network,
    tol: f64,
    limit: usize,
) -> Result<(Network, SplitStats), SplitError> {
    let Found {
        defects,
        cuts,
        searched,
    } = find(net, tol, limit).ok_or(SplitError::NotFlat { tol })?;
    if defects.total() > limit {
        return Err(SplitError::TooMany {
            counted: defects.counted(),
            limit,
        });
    }
    let mut stats = SplitStats {
        crossings: defects.crossings,
        t_junctions: defects.t_junctions,
        ..Default::default()
    };
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
        if e.a == e.b {
            edges.push(*e);
            continue;
        }
        if !searched[k] {
            // A repeat of an earlier edge, which carries the pieces.
            stats.overlaps_dropped += 1;
            continue;
        }
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
    Ok((
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
        let d = defects(&n, 1e-9, usize::MAX).listed;
        assert_eq!(d.len(), 1);
        assert!(matches!(d[0], Defect::Crossing { edges: [0, 1], .. }));
        let (s, stats) = split_crossings(&n, 1e-9).expect("flat");
        assert_eq!((s.nodes.len(), s.edges.len()), (5, 4));
        assert_eq!(stats.nodes_added, 1);
        assert!(defects(&s, 1e-9, usize::MAX).listed.is_empty());
    }

    #[test]
    fn a_t_junction_splits_the_edge_it_ends_on() {
        let n = net(
            &[[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            &[[0, 1], [2, 3]],
        );
        let d = defects(&n, 1e-9, usize::MAX).listed;
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

    /// Three collinear lines overlapping along x = 0 and a line ending on them: nodes only
    /// where lines end, however the drawing's plane is turned.
    #[test]
    fn overlapping_collinear_lines_are_noded_where_they_end() {
        let pts = [
            [0.0, 287.0],
            [20.0, 287.0],
            [0.0, 15.0],
            [0.0, 0.0],
            [0.0, 10.0],
            [185.0, 22.0],
            [0.0, 22.0],
        ];
        let flat = net(&pts, &[[0, 1], [2, 3], [2, 4], [3, 0], [5, 6]]);
        let tilt = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 0.2);
        let mut tilted = flat.clone();
        for n in &mut tilted.nodes {
            n.p = tilt * n.p + DVec3::new(5.0, -3.0, 7.0);
        }
        for n in [flat, tilted] {
            let (s, stats) = split_crossings(&n, 1e-6).expect("flat");
            assert_eq!(stats.crossings, 0);
            assert_eq!(stats.nodes_added, 0);
            // (0,0)-(0,10)-(0,15)-(0,22)-(0,287), the top line and the one from (185, 22).
            assert_eq!(s.edges.len(), 6, "{:?}", s.edges);
            assert_eq!(stats.overlaps_dropped, 3);
            assert!(defects(&s, 1e-6, usize::MAX).listed.is_empty());
            let total: f64 = s.edges.iter().map(|e| s.edge_length(e)).sum();
            assert!((total - (287.0 + 20.0 + 185.0)).abs() < 1e-9, "{total}");
        }
    }

    /// A 5 × 5 grid of lines drawn three times over: the repeats are searched once, the
    /// 25 crossings counted once, and noding keeps one copy of each piece.
    #[test]
    fn lines_drawn_over_and_over_are_searched_once() {
        let mut pts = Vec::new();
        let mut edges = Vec::new();
        for k in 0..5 {
            let c = k as f64 + 0.5;
            pts.extend([[c, 0.0], [c, 5.0], [0.0, c], [5.0, c]]);
            let n = 4 * k as u32;
            edges.extend([[n, n + 1], [n + 2, n + 3]]);
        }
        let once = edges.len();
        for copy in 0..2 {
            for k in 0..once {
                let [a, b] = edges[k];
                edges.push(if copy == 0 { [b, a] } else { [a, b] });
            }
        }
        let n = net(&pts, &edges);
        let d = defects(&n, 1e-9, 3);
        assert_eq!((d.crossings, d.t_junctions), (25, 0));
        assert_eq!(d.repeated_edges, 20);
        assert!(d.counted_all);
        assert_eq!(d.listed.len(), 3, "listing stops where asked");
        let (s, stats) = split_crossings(&n, 1e-9).expect("flat");
        // Each of the 10 lines in 6 pieces, once.
        assert_eq!(s.edges.len(), 60);
        assert_eq!(stats.nodes_added, 25);
        assert_eq!(stats.overlaps_dropped, 20);
        // Past the limit: refused with the count, nothing noded.
        let e = split_within(&n, 1e-9, 24).expect_err("25 crossings > 24");
        assert_eq!(
            e.to_string(),
            "the drawing has 25 crossings and 0 T-junctions, more than the 24 lamina makes \
             nodes of: its edges cross almost everywhere (a scribble, or edges between random \
             nodes)"
        );
    }

    #[test]
    fn networks_off_a_plane_have_no_crossings() {
        let mut n = net(
            &[[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]],
            &[[0, 1], [2, 3]],
        );
        n.nodes[3].p.z = 1.0;
        assert!(defects(&n, 1e-9, usize::MAX).listed.is_empty());
        assert!(split_crossings(&n, 1e-9).is_err());
    }

    /// Every defect by testing every node against every edge and every pair of edges.
    fn every_pair(n: &Network, tol: f64) -> Vec<Defect> {
        let (o, u, v) = plane(n, tol).expect("flat");
        let flat: Vec<DVec2> = n
            .nodes
            .iter()
            .map(|m| DVec2::new((m.p - o).dot(u), (m.p - o).dot(v)))
            .collect();
        let mut seen = HashSet::new();
        let searched: Vec<bool> = n
            .edges
            .iter()
            .map(|e| e.a != e.b && seen.insert((e.a.min(e.b), e.a.max(e.b))))
            .collect();
        let mut out = Vec::new();
        for (k, e) in n.edges.iter().enumerate().filter(|(k, _)| searched[*k]) {
            let (a, b) = (flat[e.a as usize], flat[e.b as usize]);
            let line = Line::new(a, b, tol);
            for (node, q) in flat.iter().enumerate() {
                let node = node as u32;
                if node != e.a && node != e.b && line.interior_param(*q).is_some() {
                    out.push(Defect::TJunction {
                        node,
                        edge: k as u32,
                        at: n.nodes[node as usize].p.to_array(),
                    });
                }
            }
            for (j, f) in n.edges.iter().enumerate().skip(k + 1) {
                if !searched[j] || [f.a, f.b].iter().any(|x| *x == e.a || *x == e.b) {
                    continue;
                }
                let (c, d) = (flat[f.a as usize], flat[f.b as usize]);
                if let Some((t, _)) = crossing(a, b, c, d, tol) {
                    let q = a + (b - a) * t;
                    out.push(Defect::Crossing {
                        edges: [k as u32, j as u32],
                        at: (o + u * q.x + v * q.y).to_array(),
                    });
                }
            }
        }
        out
    }

    #[test]
    fn the_search_finds_what_testing_every_pair_finds() {
        use rand::{Rng, SeedableRng};
        // More edges than one task holds; polylines (runs of neighbouring edges that share a
        // query), long random strokes (runs of one), grid lines on a coarse lattice (ends on
        // other lines: T-junctions, collinear overlaps) and strokes drawn twice; turned 30°
        // so the search's own axes are not the drawing's.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(55);
        let (mut pts, mut edges): (Vec<[f64; 2]>, Vec<[u32; 2]>) = (Vec::new(), Vec::new());
        let add = |pts: &mut Vec<[f64; 2]>, p: [f64; 2]| {
            pts.push(p);
            pts.len() as u32 - 1
        };
        while edges.len() < EDGE_CHUNK + 1500 {
            match rng.random_range(0..4) {
                0 => {
                    let mut p = [rng.random_range(0.0..100.0), rng.random_range(0.0..100.0)];
                    let mut last = add(&mut pts, p);
                    for _ in 0..rng.random_range(2..40) {
                        p[0] += rng.random_range(-1.5..1.5);
                        p[1] += rng.random_range(-1.5..1.5);
                        let next = add(&mut pts, p);
                        edges.push([last, next]);
                        last = next;
                    }
                }
                1 => {
                    let a = add(&mut pts, [rng.random_range(0.0..100.0), 50.0]);
                    let b = add(&mut pts, [50.0, rng.random_range(0.0..100.0)]);
                    edges.push([a, b]);
                }
                2 => {
                    let g = |r: &mut rand_chacha::ChaCha8Rng| r.random_range(0..20) as f64 * 5.0;
                    let (x, y, l) = (g(&mut rng), g(&mut rng), g(&mut rng) + 5.0);
                    let along = rng.random_bool(0.5);
                    let a = add(&mut pts, [x, y]);
                    let b = add(&mut pts, if along { [x + l, y] } else { [x, y + l] });
                    edges.push([a, b]);
                }
                _ => {
                    if let Some(&e) = edges.last() {
                        edges.push([e[1], e[0]]);
                    }
                }
            }
        }
        let turn = |p: &[f64; 2]| {
            let (s, c) = 30f64.to_radians().sin_cos();
            [c * p[0] - s * p[1], s * p[0] + c * p[1]]
        };
        let n = net(&pts.iter().map(turn).collect::<Vec<_>>(), &edges);
        let tol = 1e-6;
        let found = defects(&n, tol, usize::MAX);
        let expected = every_pair(&n, tol);
        let tj = expected
            .iter()
            .filter(|d| matches!(d, Defect::TJunction { .. }))
            .count();
        assert!(
            tj > 100 && expected.len() - tj > 1000,
            "{tj} of {}",
            expected.len()
        );
        assert_eq!(found.t_junctions, tj);
        assert_eq!(found.crossings, expected.len() - tj);
        assert!(found.listed == expected, "the lists differ");
    }
}
