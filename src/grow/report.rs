//! The quality report of a grown vein network: the failure modes Gokmen Fig. 8 names made
//! countable. Zigzag behaviour is the mean turning angle along veins; incomplete growth shows as
//! sources left unreached and open tips; incorrect anastomosis as joints that are not Y or I,
//! sharp joints, and crossing edges.

use std::collections::BTreeMap;

use glam::DVec3;
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::network::Network;

/// A joint whose legs meet at less than this angle (degrees) is sharp.
pub const SHARP_JOINT: f64 = 20.0;

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    pub nodes: usize,
    pub edges: usize,
    pub components: usize,
    /// Independent loops, E − V + C.
    pub loops: usize,
    /// Node count by degree, keyed "0", "1", "2", "3", …
    pub nodes_by_degree: BTreeMap<String, usize>,
    /// Degree-1 nodes that are not roots: veins that ended without joining.
    pub open_tips: usize,
    /// Joints with more than 3 legs; Y and I joints only is the rule.
    pub not_y_or_i: usize,
    /// Joints where two legs meet at less than `SHARP_JOINT` degrees.
    pub sharp_joints: usize,
    /// Mean turning angle at degree-2 nodes (in space), degrees: the zigzag index.
    pub zigzag_deg: f64,
    /// The largest turning angle at a degree-2 node, degrees.
    pub max_turn_deg: f64,
    /// Edges whose radius exceeds half the largest root radius: the thick veins Peele counts.
    pub thick_edges: usize,
    /// Pairs of edges that cross or touch away from a shared node (in the XY projection).
    pub crossings: usize,
    /// The veins, and the dominant ones among them (Peele's Figure 1).
    pub veins: Veins,
}

/// Peele's Figure 1 made countable: "for lower vein growth rates, a smaller number of
/// dominant, thicker veins tend to form", and "more chaotic vein patterns" at higher ones.
///
/// A vein is a maximal chain of edges through nodes of degree 2, between junctions and tips
/// (a loop of degree-2 nodes is one vein). Its radius is its thickest edge's (under Murray's
/// law, the radius at its thick end). It is dominant when that radius is at least half the
/// petiole's: the thickest edge at a root, or the thickest edge of all when there is no root.
/// A network without radii has no dominant vein.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Veins {
    /// Veins of any radius.
    pub count: usize,
    /// The petiole's radius, mm.
    pub petiole_radius: f64,
    /// Dominant veins.
    pub dominant: usize,
    /// The dominant veins' mean radius over the petiole's (0 when there are none).
    pub dominant_radius_ratio: f64,
    /// The dominant veins' length, mm.
    pub dominant_length: f64,
    /// Turning along the dominant veins per unit length, degrees per mm: the sum over their
    /// inner nodes of the angle between the edges in and out, over their length (0 when they
    /// have no length).
    pub dominant_turning_deg_per_mm: f64,
}

impl Veins {
    /// Measures `net`; its first `roots` nodes are roots.
    pub fn of(net: &Network, roots: usize) -> Veins {
        let roots = roots.min(net.nodes.len()) as u32;
        let petiole_radius = net
            .edges
            .iter()
            .filter(|e| roots == 0 || e.a < roots || e.b < roots)
            .map(|e| e.radius)
            .fold(0.0, f64::max);
        let chains = net.chains();
        let mut out = Veins {
            count: chains.len(),
            petiole_radius,
            ..Default::default()
        };
        if petiole_radius <= 0.0 {
            return out;
        }
        let mut radius_sum = 0.0;
        let mut turning = 0.0;
        for chain in &chains {
            let radius = chain
                .edges
                .iter()
                .map(|&k| net.edges[k as usize].radius)
                .fold(0.0, f64::max);
            if radius < 0.5 * petiole_radius {
                continue;
            }
            out.dominant += 1;
            radius_sum += radius;
            let p: Vec<DVec3> = chain
                .nodes
                .iter()
                .map(|&v| net.nodes[v as usize].p)
                .collect();
            out.dominant_length += p.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
            // The turns at the inner nodes; a loop also turns where it starts.
            let mut turns: Vec<[DVec3; 3]> = p.windows(3).map(|w| [w[0], w[1], w[2]]).collect();
            if chain.is_closed() {
                turns.push([p[p.len() - 2], p[0], p[1]]);
            }
            for [a, b, c] in turns {
                turning += angle_deg(b - a, c - b);
            }
        }
        if out.dominant > 0 {
            out.dominant_radius_ratio = radius_sum / out.dominant as f64 / petiole_radius;
        }
        if out.dominant_length > 0.0 {
            out.dominant_turning_deg_per_mm = turning / out.dominant_length;
        }
        out
    }
}

impl Quality {
    /// Measures `net`; its first `roots` nodes are roots.
    pub fn of(net: &Network, roots: usize) -> Quality {
        let n = net.nodes.len();
        let adj = net.adjacency();
        let mut by_degree: BTreeMap<usize, usize> = BTreeMap::new();
        let (mut turns, mut turn_sum, mut max_turn) = (0usize, 0.0f64, 0.0f64);
        let mut sharp = 0;
        let cos_sharp = SHARP_JOINT.to_radians().cos();
        for v in 0..n {
            let legs: Vec<DVec3> = adj
                .neighbours(v as u32)
                .iter()
                .filter_map(|&(w, _)| (net.nodes[w as usize].p - net.nodes[v].p).try_normalize())
                .collect();
            *by_degree.entry(adj.degree(v as u32)).or_default() += 1;
            if legs.len() == 2 {
                // Turning angle: 0 for a straight vein.
                let turn = angle_deg(-legs[0], legs[1]);
                turns += 1;
                turn_sum += turn;
                max_turn = max_turn.max(turn);
            }
            if legs.len() >= 2 {
                let any_sharp = legs
                    .iter()
                    .enumerate()
                    .any(|(i, a)| legs[i + 1..].iter().any(|b| a.dot(*b) > cos_sharp));
                sharp += usize::from(any_sharp);
            }
        }
        let open_tips = (roots.min(n)..n)
            .filter(|&v| adj.degree(v as u32) == 1)
            .count();
        let components = net.component_labels().1;
        let root_radius = net.nodes[..roots.min(n)]
            .iter()
            .map(|v| v.radius)
            .fold(0.0, f64::max);
        let thick_edges = net
            .edges
            .iter()
            .filter(|e| e.radius > 0.5 * root_radius)
            .count();
        Quality {
            nodes: n,
            edges: net.edges.len(),
            components,
            loops: (net.edges.len() + components).saturating_sub(n),
            not_y_or_i: by_degree.range(4..).map(|(_, c)| c).sum(),
            nodes_by_degree: by_degree
                .into_iter()
                .map(|(d, c)| (d.to_string(), c))
                .collect(),
            open_tips,
            sharp_joints: sharp,
            zigzag_deg: if turns > 0 {
                turn_sum / turns as f64
            } else {
                0.0
            },
            max_turn_deg: max_turn,
            thick_edges,
            crossings: crossings(net),
            veins: Veins::of(net, roots),
        }
    }

    /// One line per figure, for people.
    pub fn lines(&self) -> Vec<String> {
        let degrees: Vec<String> = self
            .nodes_by_degree
            .iter()
            .map(|(d, c)| format!("{c} of degree {d}"))
            .collect();
        vec![
            format!(
                "{} nodes, {} edges, {} component(s), {} loop(s)",
                self.nodes, self.edges, self.components, self.loops
            ),
            format!("nodes: {}", degrees.join(", ")),
            format!("open tips: {}", self.open_tips),
            format!(
                "joints other than Y or I: {}; sharp joints (< {SHARP_JOINT}°): {}; crossing edges: {}{}",
                self.not_y_or_i,
                self.sharp_joints,
                if self.crossings >= MAX_CROSSINGS { "at least " } else { "" },
                self.crossings
            ),
            format!(
                "zigzag index: {:.2}° mean turn along veins (max {:.1}°)",
                self.zigzag_deg, self.max_turn_deg
            ),
            format!(
                "veins: {}, {} dominant (radius at least half the petiole's {:.3} mm), their \
                 mean radius {:.3} of the petiole's, turning {:.2}°/mm along them",
                self.veins.count,
                self.veins.dominant,
                self.veins.petiole_radius,
                self.veins.dominant_radius_ratio,
                self.veins.dominant_turning_deg_per_mm
            ),
        ]
    }
}

/// The angle between two directions, degrees (0 when either has no length). From the sine and
/// the cosine together: exact for the nearly straight turns veins mostly make, where an arc
/// cosine would magnify the rounding of the dot product a million times.
fn angle_deg(u: DVec3, v: DVec3) -> f64 {
    u.cross(v).length().atan2(u.dot(v)).to_degrees()
}

type EdgeBox = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// Crossings are counted up to this many: past it the drawing is broken whatever the count.
pub const MAX_CROSSINGS: usize = 1_000_000;

/// Edge pairs that cross or touch other than at a shared node, in the XY projection, counted
/// up to `MAX_CROSSINGS`.
fn crossings(net: &Network) -> usize {
    let n = net.nodes.len() as u32;
    let seg = |i: u32| {
        let e = &net.edges[i as usize];
        (
            net.nodes[e.a as usize].p.truncate(),
            net.nodes[e.b as usize].p.truncate(),
        )
    };
    let valid = |i: &u32| {
        let e = &net.edges[*i as usize];
        e.a < n && e.b < n && e.a != e.b
    };
    let ids: Vec<u32> = (0..net.edges.len() as u32).filter(valid).collect();
    let tree: RTree<EdgeBox> = RTree::bulk_load(
        ids.iter()
            .map(|&i| {
                let (a, b) = seg(i);
                EdgeBox::new(Rectangle::from_corners(a.to_array(), b.to_array()), i)
            })
            .collect(),
    );
    // Each edge counts its pairs with later edges; the queries run in parallel. A drawing that
    // retraces itself (k copies of a segment make k² pairs) stops counting at the cap.
    let found = AtomicUsize::new(0);
    ids.par_iter().for_each(|&i| {
        if found.load(Ordering::Relaxed) >= MAX_CROSSINGS {
            return;
        }
        let (a, b) = seg(i);
        let ei = &net.edges[i as usize];
        let bx = AABB::from_corners(a.to_array(), b.to_array());
        let here = tree
            .locate_in_envelope_intersecting(&bx)
            .filter(|other| {
                let j = other.data;
                let ej = &net.edges[j as usize];
                // Legs of one node overlap only if collinear and pointing the same way.
                let shared = [ej.a, ej.b].iter().any(|x| *x == ei.a || *x == ei.b);
                let (c, d) = seg(j);
                j > i && !shared && crate::geom::segments_touch(a, b, c, d)
            })
            .take(MAX_CROSSINGS)
            .count();
        found.fetch_add(here, Ordering::Relaxed);
    });
    found.into_inner().min(MAX_CROSSINGS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::{Edge, Node};

    fn net(points: &[(f64, f64)], edges: &[(u32, u32)]) -> Network {
        Network {
            nodes: points
                .iter()
                .map(|&(x, y)| Node::at(DVec3::new(x, y, 0.0)))
                .collect(),
            edges: edges.iter().map(|&(a, b)| Edge::new(a, b)).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn a_square_has_one_loop_and_right_angle_turns() {
        let q = Quality::of(
            &net(
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],
                &[(0, 1), (1, 2), (2, 3), (3, 0)],
            ),
            1,
        );
        assert_eq!(
            (q.loops, q.open_tips, q.crossings, q.not_y_or_i),
            (1, 0, 0, 0)
        );
        assert!((q.zigzag_deg - 90.0).abs() < 1e-9);
        assert_eq!(q.nodes_by_degree.get("2"), Some(&4));
    }

    #[test]
    fn crossings_sharp_joints_and_a_four_legged_joint_are_counted() {
        // An X of two edges that cross, and a star of four legs at node 4.
        let q = Quality::of(
            &net(
                &[
                    (0.0, 0.0),
                    (2.0, 2.0),
                    (0.0, 2.0),
                    (2.0, 0.0),
                    (10.0, 0.0),
                    (11.0, 0.0),
                    (9.0, 0.0),
                    (10.0, 1.0),
                    (11.0, 0.1),
                ],
                &[(0, 1), (2, 3), (4, 5), (4, 6), (4, 7), (4, 8)],
            ),
            0,
        );
        assert_eq!(q.crossings, 1);
        assert_eq!(q.not_y_or_i, 1);
        assert_eq!(q.sharp_joints, 1, "legs to (11, 0) and (11, 0.1)");
        assert_eq!(q.open_tips, 8);
    }

    fn with_radii(mut net: Network, radii: &[f64]) -> Network {
        for (e, &r) in net.edges.iter_mut().zip(radii) {
            e.radius = r;
        }
        net
    }

    #[test]
    fn veins_dominant_ones_and_their_turning_are_measured() {
        // A petiole (radius 1) to a junction; from it a straight vein (0.8) to a second
        // junction and a thin side vein (0.3); from the second junction a wiggly vein (0.6)
        // of three 5-mm zigzags and a thin side vein (0.2). Dominant: radius ≥ 0.5.
        let tree = with_radii(
            net(
                &[
                    (0.0, 0.0),
                    (0.0, 10.0),
                    (0.0, 20.0),
                    (10.0, 10.0),
                    (3.0, 24.0),
                    (0.0, 28.0),
                    (3.0, 32.0),
                    (-10.0, 20.0),
                ],
                &[(0, 1), (1, 2), (1, 3), (2, 4), (4, 5), (5, 6), (2, 7)],
            ),
            &[1.0, 0.8, 0.3, 0.6, 0.6, 0.6, 0.2],
        );
        let v = Veins::of(&tree, 1);
        assert_eq!((v.count, v.dominant), (5, 3));
        assert_eq!(v.petiole_radius, 1.0);
        assert!((v.dominant_radius_ratio - 0.8).abs() < 1e-15);
        assert!((v.dominant_length - 35.0).abs() < 1e-12);
        // Each zigzag corner turns by acos(0.6·(−0.6) + 0.8·0.8) = acos(0.28) = 73.74°.
        let turning = 2.0 * 0.28f64.acos().to_degrees() / 35.0;
        assert!((v.dominant_turning_deg_per_mm - turning).abs() < 1e-12);
        // The same drawing without a root: the petiole is the thickest edge.
        assert_eq!(Veins::of(&tree, 0), v);
        // Half the petiole's radius exactly is dominant; a hair under it is not.
        let mut at_half = tree.clone();
        at_half.edges[2].radius = 0.5;
        assert_eq!(Veins::of(&at_half, 1).dominant, 4);
        at_half.edges[2].radius = 0.5 - 1e-12;
        assert_eq!(Veins::of(&at_half, 1).dominant, 3);
    }

    #[test]
    fn a_loop_is_one_vein_that_turns_at_every_corner() {
        let square = with_radii(
            net(
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],
                &[(0, 1), (1, 2), (2, 3), (3, 0)],
            ),
            &[0.5; 4],
        );
        let v = Veins::of(&square, 1);
        assert_eq!((v.count, v.dominant), (1, 1));
        assert!((v.dominant_turning_deg_per_mm - 90.0).abs() < 1e-12);
        // Without radii nothing is dominant.
        let bare = Veins::of(&with_radii(square, &[0.0; 4]), 1);
        assert_eq!(
            (bare.count, bare.dominant, bare.dominant_length),
            (1, 0, 0.0)
        );
    }
}
