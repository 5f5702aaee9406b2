//! Fewer, straighter members for fabrication (Calyx W4, done by hand in Rhino): every member of
//! a plate network becomes a cut, tagged, welded plate, so a grown network's chains of nearly
//! collinear degree-2 nodes, its stubs, its near-coincident junctions and its sharp joints all
//! cost work or cannot be welded.
//!
//! The steps, in order:
//! 1. **Prune** (`prune.rs`): branches of Horton-Strahler order below `prune_order`, and dangling
//!    stubs shorter than `min_length`. Loops are never pruned: only the trees hanging off the
//!    network's 2-core are ordered.
//! 2. **Chains** (`chains.rs`): the network splits into chains of degree-2 nodes between
//!    junctions. Junctions joined by a chain shorter than `merge_distance` (or `min_length`)
//!    merge when the merged joint has no more legs than the input allowed (three where the
//!    input had at most three) and every node of the chain stays within the deviation.
//! 3. **Douglas-Peucker** on each chain at the deviation; a chain that closes a loop keeps three
//!    members, and of chains joining the same two junctions only one may become a single
//!    member, so no loop collapses. Then each junction and tip moves (on the surface, within
//!    the deviation) to where its chains, fitted again, need the fewest members.
//! 4. **Embedding**: members that cross, or joints whose members' order around the node's
//!    normal changed, get back the original node farthest from the member, until neither
//!    happens. So the faces (cells) are the same as the input's.
//! 5. **Joints** (`joints.rs`): a node whose members meet at less than `min_angle` is moved (on
//!    the surface) or has a neighbour moved, within the deviation. Where a joint is still
//!    sharp, the chains at it are fitted again at `DP_SHARE` of the deviation from their
//!    original positions and repair runs once more; a joint left sharp is reported.
//!
//! Every original node that is not pruned stays within `max_deviation` of the member its chain
//! became (so of the network); `measure.rs` measures that exactly afterwards, along with the
//! report's figures before and after.

mod chains;
mod joints;
mod measure;
mod prune;
#[cfg(test)]
mod tests;

use glam::DVec3;

use crate::mesh::closest::SurfaceIndex;
use crate::network::{Edge, Network, Node};

pub use measure::{distance_to, Figures};

/// Where a joint is still sharp after repair, its lines are fitted again at this share of the
/// deviation, so that repair has the rest to use.
pub const DP_SHARE: f64 = 0.75;

/// The largest distance any option may give, mm: beyond it a network of members means nothing.
pub const MAX_DISTANCE: f64 = 1e6;

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Options {
    /// Every original node stays within this distance of the simplified network, mm.
    pub max_deviation: f64,
    /// Members shorter than this are removed where they can be: stubs dropped, junctions merged,
    /// a chain's vertex skipped. 0: off.
    pub min_length: f64,
    /// Junctions joined by a chain shorter than this merge. 0: off.
    pub merge_distance: f64,
    /// Joints where two members meet at less than this many degrees are repaired. 0: off.
    pub min_angle: f64,
    /// Branches of Horton-Strahler order below this are removed. 0 or 1: off.
    pub prune_order: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_deviation: 1.0,
            min_length: 0.0,
            merge_distance: 0.0,
            min_angle: 0.0,
            prune_order: 0,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SimplifyError {
    #[error("{0} must be a finite number above 0, not {1}")]
    NotPositive(&'static str, f64),
    #[error("{0} must be a finite number, 0 or more, not {1}")]
    Negative(&'static str, f64),
    #[error(
        "min_angle= must be below 90 degrees (no three members can all meet at more), not {0}"
    )]
    AngleTooLarge(f64),
    #[error("{0} must be at most 1e6 mm (1 km), not {1:e}")]
    TooLarge(&'static str, f64),
    #[error("node {0} has a position or normal that is not finite")]
    NonFinite(u32),
    #[error("edge {0} refers to node {1}, which does not exist")]
    MissingNode(usize, u32),
    #[error("edge {0} joins node {1} to itself")]
    SelfLoop(usize, u32),
    #[error("edges {0} and {1} join the same two nodes")]
    Parallel(usize, usize),
    #[error("the network has no edges")]
    Empty,
}

impl Options {
    pub fn check(&self) -> Result<(), SimplifyError> {
        let d = self.max_deviation;
        if !(d.is_finite() && d > 0.0) {
            return Err(SimplifyError::NotPositive("max_deviation=", d));
        }
        for (name, v) in [
            ("min_length=", self.min_length),
            ("merge_distance=", self.merge_distance),
            ("min_angle=", self.min_angle),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimplifyError::Negative(name, v));
            }
        }
        for (name, v) in [
            ("max_deviation=", d),
            ("min_length=", self.min_length),
            ("merge_distance=", self.merge_distance),
        ] {
            if v > MAX_DISTANCE {
                return Err(SimplifyError::TooLarge(name, v));
            }
        }
        if self.min_angle >= 90.0 {
            return Err(SimplifyError::AngleTooLarge(self.min_angle));
        }
        Ok(())
    }
}

/// A joint left below the minimum angle.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Joint {
    /// The node's index in the simplified network.
    pub node: u32,
    pub p: [f64; 3],
    pub angle: f64,
}

/// What simplification did, and the figures before and after.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    pub options: Options,
    pub before: Figures,
    pub after: Figures,
    /// Largest and mean distance of the original nodes still represented (not pruned) from
    /// the simplified network, mm, measured exactly afterwards.
    pub max_distance: f64,
    pub mean_distance: f64,
    pub pruned_members: usize,
    /// Nodes that lost every edge to pruning.
    pub pruned_nodes: usize,
    /// Input nodes with no edge at all: a network of members has no place for them.
    pub isolated_nodes_dropped: usize,
    pub stubs_removed: usize,
    pub merged_junctions: usize,
    /// Merges not made: the merged joint would have had more legs than the input allowed, or a
    /// node of the chain would have left the deviation, or a loop would have collapsed.
    pub merges_refused: usize,
    /// Junctions moved (within the deviation) so their chains need fewer members.
    pub junctions_moved: usize,
    pub short_members_left: usize,
    pub nodes_restored_for_embedding: usize,
    pub joints_repaired: usize,
    /// Chains fitted again, more tightly, to give a sharp joint room for repair.
    pub chains_refitted: usize,
    pub sharp_joints: Vec<Joint>,
    /// Crossings between members that could not be undone because they are in the input.
    pub input_crossings: usize,
}

#[derive(Clone, Debug)]
pub struct Simplified {
    pub network: Network,
    /// Per node of the simplified network, the node of the input it stands for.
    pub origin: Vec<u32>,
    pub report: Report,
}

/// The geometry simplification moves nodes on: the guide surface when there is one, else the
/// plane of each node's normal.
pub(crate) struct Guide<'a> {
    pub index: Option<SurfaceIndex<'a>>,
    /// Per node: unit reference normal, or zero where none is known (a 3D network with no
    /// normals and no surface).
    pub normals: Vec<DVec3>,
}

impl Guide<'_> {
    /// `p` on the surface, or `p` itself with no surface.
    pub fn project(&self, p: DVec3) -> DVec3 {
        match self.index.as_ref().and_then(|i| i.closest(p)) {
            Some(c) => c.point,
            None => p,
        }
    }

    /// Trial positions around `home`: 16 directions in the plane ⊥ `normal` at a quarter, half,
    /// three quarters and all of `reach`, each put on the surface.
    pub fn ring(&self, home: DVec3, normal: DVec3, reach: f64) -> impl Iterator<Item = DVec3> + '_ {
        const DIRECTIONS: usize = 16;
        let (t0, t1) = normal.normalize().any_orthonormal_pair();
        [0.25, 0.5, 0.75, 1.0].into_iter().flat_map(move |r| {
            (0..DIRECTIONS).map(move |k| {
                let t = std::f64::consts::TAU * k as f64 / DIRECTIONS as f64;
                self.project(home + r * reach * (t.cos() * t0 + t.sin() * t1))
            })
        })
    }

    /// The surface normal at the point closest to `p`, turned to agree with `near`.
    pub fn normal_at(&self, p: DVec3, near: DVec3) -> DVec3 {
        match self.index.as_ref().and_then(|i| i.closest(p)) {
            Some(c) => {
                let n = self.index.as_ref().map_or(near, |i| i.normal(&c));
                if n.dot(near) < 0.0 {
                    -n
                } else {
                    n
                }
            }
            None => near,
        }
    }
}

/// Simplifies `net` (see the module notes). `surface` is the guide surface the nodes stay on.
pub fn simplify(
    net: &Network,
    surface: Option<&crate::mesh::TriMesh>,
    opts: &Options,
) -> Result<Simplified, SimplifyError> {
    opts.check()?;
    check_network(net)?;
    let guide = Guide {
        normals: reference_normals(net, surface),
        index: surface.map(SurfaceIndex::new),
    };
    let normals = (!guide.normals.contains(&DVec3::ZERO)).then_some(&guide.normals);
    let before = Figures::of(net, normals.map(|n| n.as_slice()));

    let pruned = prune::prune(net, opts.prune_order, opts.min_length);
    let mut work = chains::Work::new(net, &pruned.keep_edge);
    let merges = work.merge_junctions(opts, &guide);
    work.douglas_peucker(opts.max_deviation);
    let relocated = work.relocate_junctions(&guide, opts.max_deviation);
    let short_left = work.skip_short(opts);
    let mut restored = 0;
    let mut repaired = 0;
    let mut refitted = 0;
    for pass in 0..2 {
        for _ in 0..4 {
            let (r, _) = work.restore_embedding(&guide, opts.max_deviation);
            restored += r;
            let fixed = joints::repair(&mut work, &guide, opts);
            repaired += fixed;
            if fixed == 0 {
                break;
            }
        }
        // The whole deviation went to fewer members; where a joint is still sharp, its lines
        // are fitted again within `DP_SHARE` of it, from where they were, to leave repair room.
        let sharp = joints::sharp(&work, opts);
        if pass == 1 || sharp.is_empty() {
            break;
        }
        refitted = work.loosen(&sharp, DP_SHARE * opts.max_deviation, opts.max_deviation);
    }
    // A repair may have moved a member across another: take nodes back once more.
    let (r, input_crossings) = work.restore_embedding(&guide, opts.max_deviation);
    restored += r;
    let (network, origin) = work.network(net, &guide);
    let sharp: Vec<Joint> = if opts.min_angle > 0.0 {
        measure::joint_angles(&network)
            .into_iter()
            .filter(|&(_, a)| a < opts.min_angle)
            .map(|(v, angle)| Joint {
                node: v,
                p: network.nodes[v as usize].p.to_array(),
                angle,
            })
            .collect()
    } else {
        Vec::new()
    };
    let out_normals: Option<Vec<DVec3>> =
        normals.map(|n| origin.iter().map(|&o| n[o as usize]).collect());
    let after = Figures::of(&network, out_normals.as_deref());
    let represented: Vec<DVec3> = net
        .nodes
        .iter()
        .zip(&pruned.keep_node)
        .filter(|(_, &k)| k)
        .map(|(n, _)| n.p)
        .collect();
    let distances = distance_to(&network, &represented);
    let max_distance = distances.iter().copied().fold(0.0, f64::max);
    let mean_distance = distances.iter().sum::<f64>() / distances.len().max(1) as f64;
    let isolated = net.nodes.len() - before.nodes;
    let report = Report {
        options: *opts,
        before,
        after,
        max_distance,
        mean_distance,
        pruned_members: pruned.members,
        pruned_nodes: pruned.keep_node.iter().filter(|&&k| !k).count() - isolated,
        isolated_nodes_dropped: isolated,
        stubs_removed: pruned.stubs,
        merged_junctions: merges.merged,
        merges_refused: merges.refused,
        junctions_moved: relocated,
        short_members_left: short_left,
        nodes_restored_for_embedding: restored,
        joints_repaired: repaired,
        chains_refitted: refitted,
        sharp_joints: sharp,
        input_crossings,
    };
    Ok(Simplified {
        network,
        origin,
        report,
    })
}

fn check_network(net: &Network) -> Result<(), SimplifyError> {
    for (i, n) in net.nodes.iter().enumerate() {
        if !n.p.is_finite() || n.normal.is_some_and(|m| !m.is_finite()) {
            return Err(SimplifyError::NonFinite(i as u32));
        }
    }
    if net.edges.is_empty() {
        return Err(SimplifyError::Empty);
    }
    let mut seen = std::collections::HashMap::with_capacity(net.edges.len());
    for (k, e) in net.edges.iter().enumerate() {
        for v in [e.a, e.b] {
            if v as usize >= net.nodes.len() {
                return Err(SimplifyError::MissingNode(k, v));
            }
        }
        if e.a == e.b {
            return Err(SimplifyError::SelfLoop(k, e.a));
        }
        if let Some(first) = seen.insert((e.a.min(e.b), e.a.max(e.b)), k) {
            return Err(SimplifyError::Parallel(first, k));
        }
    }
    Ok(())
}

/// Per node: the guide surface's normal there, else the stored normal, else +Z when the network
/// is flat in z; zero when none of these is known.
fn reference_normals(net: &Network, surface: Option<&crate::mesh::TriMesh>) -> Vec<DVec3> {
    if let Some(mesh) = surface {
        let index = SurfaceIndex::new(mesh);
        if !mesh.triangles.is_empty() {
            return net
                .nodes
                .iter()
                .map(|n| {
                    let c = index.closest(n.p).expect("a mesh with triangles");
                    let d = index.normal(&c);
                    match n.normal {
                        Some(s) if s.dot(d) < 0.0 => -d,
                        _ => d,
                    }
                })
                .collect();
        }
    }
    let z0 = net.nodes.first().map_or(0.0, |n| n.p.z);
    let scale = net.bbox().diagonal().max(1.0);
    let flat = net.nodes.iter().all(|n| (n.p.z - z0).abs() <= 1e-9 * scale);
    net.nodes
        .iter()
        .map(|n| match n.normal.and_then(|m| m.try_normalize()) {
            Some(m) => m,
            None if flat => DVec3::Z,
            None => DVec3::ZERO,
        })
        .collect()
}

/// A simplified network's node: the original's radius and normal, the guide's normal where the
/// node moved on a surface.
pub(crate) fn carried_node(orig: &Node, p: DVec3, guide: &Guide) -> Node {
    let moved = p != orig.p;
    let normal = match orig.normal {
        Some(n) if moved && guide.index.is_some() => Some(guide.normal_at(p, n)),
        other => other,
    };
    Node {
        p,
        normal,
        radius: orig.radius,
    }
}

/// A member standing for original edges `edges`: the largest of their radii (a member is cut
/// for its thickest part).
pub(crate) fn carried_edge(net: &Network, a: u32, b: u32, edges: &[u32]) -> Edge {
    let radius = edges
        .iter()
        .map(|&k| net.edges[k as usize].radius)
        .fold(0.0, f64::max);
    Edge { a, b, radius }
}
