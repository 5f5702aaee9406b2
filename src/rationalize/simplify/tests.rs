use glam::DVec3;

use super::measure::joint_angles;
use super::prune::strahler;
use super::*;
use crate::network::{Edge, Network, Node};

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

/// A path from `a` to `b` in `n` steps, wobbling ± `wobble` across its direction.
fn wobbly(
    points: &mut Vec<(f64, f64)>,
    edges: &mut Vec<(u32, u32)>,
    a: u32,
    b: u32,
    n: usize,
    wobble: f64,
) {
    let (pa, pb) = (points[a as usize], points[b as usize]);
    let (dx, dy) = (pb.0 - pa.0, pb.1 - pa.1);
    let len = (dx * dx + dy * dy).sqrt();
    let (nx, ny) = (-dy / len, dx / len);
    let mut prev = a;
    for k in 1..n {
        let t = k as f64 / n as f64;
        let w = if k % 2 == 0 { wobble } else { -wobble };
        points.push((pa.0 + t * dx + w * nx, pa.1 + t * dy + w * ny));
        let v = points.len() as u32 - 1;
        edges.push((prev, v));
        prev = v;
    }
    edges.push((prev, b));
}

fn opts(max_deviation: f64) -> Options {
    Options {
        max_deviation,
        ..Default::default()
    }
}

#[test]
fn a_wobbly_square_becomes_four_members_and_stays_a_loop() {
    let mut p = vec![(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)];
    let mut e = Vec::new();
    // Degree-3 corners: a stub on each keeps them junctions.
    for (a, b) in [(0, 1), (1, 2), (2, 3), (3, 0)] {
        wobbly(&mut p, &mut e, a, b, 20, 0.5);
    }
    for (k, &(dx, dy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .enumerate()
    {
        let (x, y) = p[k];
        p.push((x + 30.0 * dx, y + 30.0 * dy));
        e.push((k as u32, p.len() as u32 - 1));
    }
    let n = net(&p, &e);
    let s = simplify(&n, None, &opts(1.0)).unwrap();
    assert_eq!(s.network.edges.len(), 8, "4 sides + 4 stubs");
    let r = &s.report;
    assert_eq!((r.before.cycles, r.after.cycles), (1, 1));
    assert_eq!(r.before.faces, r.after.faces);
    assert!(
        r.max_distance <= 1.0 && r.max_distance >= 0.5 - 1e-9,
        "{}",
        r.max_distance
    );
    // The corners stay where they were: the stubs pin them within the deviation anyway.
    let d = distance_to(&s.network, &n.nodes.iter().map(|x| x.p).collect::<Vec<_>>());
    assert!(d.iter().all(|&x| x <= 1.0 + 1e-12));
}

#[test]
fn a_loop_alone_keeps_three_members_and_a_lens_keeps_two_paths() {
    // A nearly straight closed ring: Douglas-Peucker alone would fold it to nothing.
    let ring: Vec<(f64, f64)> = (0..40)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 40.0;
            (50.0 * t.cos(), 0.2 * t.sin())
        })
        .collect();
    let edges: Vec<(u32, u32)> = (0..40).map(|k| (k, (k + 1) % 40)).collect();
    let s = simplify(&net(&ring, &edges), None, &opts(5.0)).unwrap();
    assert_eq!(s.report.after.cycles, 1);
    assert!(s.network.edges.len() >= 3);
    // Two near-straight paths between the same two junctions (a lens) with tails.
    let mut p = vec![(0.0, 0.0), (100.0, 0.0), (-20.0, 0.0), (120.0, 0.0)];
    let mut e = vec![(2, 0), (1, 3)];
    wobbly(&mut p, &mut e, 0, 1, 10, 0.3);
    wobbly(&mut p, &mut e, 0, 1, 10, -0.3);
    let lens = net(&p, &e);
    let s = simplify(&lens, None, &opts(2.0)).unwrap();
    assert_eq!(s.report.after.cycles, 1);
    let mut pairs: Vec<(u32, u32)> = s
        .network
        .edges
        .iter()
        .map(|e| (e.a.min(e.b), e.a.max(e.b)))
        .collect();
    pairs.sort();
    pairs.dedup();
    assert_eq!(
        pairs.len(),
        s.network.edges.len(),
        "no two members join the same nodes"
    );
}

#[test]
fn strahler_orders_a_binary_tree_from_its_twigs_and_pruning_keeps_the_trunk() {
    // Root 0 → 1; 1 splits to 2 and 3; each of those splits into two twigs.
    let p = [
        (0.0, 0.0),
        (0.0, 10.0),
        (-10.0, 20.0),
        (10.0, 20.0),
        (-15.0, 30.0),
        (-5.0, 30.0),
        (5.0, 30.0),
        (15.0, 30.0),
        (-25.0, 25.0),
    ];
    let e = [
        (0, 1),
        (1, 2),
        (1, 3),
        (2, 4),
        (2, 5),
        (3, 6),
        (3, 7),
        (4, 8),
    ];
    let mut n = net(&p, &e);
    n.edges[0].radius = 2.0; // the stem is the thickest: its tip is the root
    let order = strahler(&n);
    assert_eq!(order, vec![3, 2, 2, 1, 1, 1, 1, 1]);
    let s = simplify(
        &n,
        None,
        &Options {
            prune_order: 2,
            ..opts(0.01)
        },
    )
    .unwrap();
    assert_eq!(s.report.pruned_members, 5);
    assert_eq!(s.network.edges.len(), 3);
    assert!(s.origin.contains(&0), "the root stays");
}

#[test]
fn a_sharp_branch_is_opened_to_the_minimum_angle_within_the_deviation() {
    // A straight vein with a branch leaving at 15°, both long enough to have room to move.
    let a = 15f64.to_radians();
    let p = vec![
        (0.0, 0.0),
        (50.0, 0.0),
        (100.0, 0.0),
        (50.0 + 60.0 * a.cos(), 60.0 * a.sin()),
        (-10.0, 10.0),
        (-10.0, -10.0),
    ];
    let e = [(0, 1), (1, 2), (1, 3), (0, 4), (0, 5)];
    let n = net(&p, &e);
    assert!(joint_angles(&n).iter().any(|&(_, x)| x < 16.0));
    let o = Options {
        min_angle: 30.0,
        ..opts(10.0)
    };
    let s = simplify(&n, None, &o).unwrap();
    let least = joint_angles(&s.network)
        .iter()
        .map(|x| x.1)
        .fold(180.0, f64::min);
    assert!(least >= 30.0, "smallest joint {least}°");
    assert!(s.report.sharp_joints.is_empty());
    assert!(s.report.joints_repaired >= 1);
    assert!(s.report.max_distance <= 10.0 + 1e-9);
    // At any deviation the result holds it, and a joint left sharp is reported.
    for dev in [0.5, 1.0, 2.0, 3.0, 5.0, 7.5] {
        let s = simplify(
            &n,
            None,
            &Options {
                min_angle: 30.0,
                ..opts(dev)
            },
        )
        .unwrap();
        let least = joint_angles(&s.network)
            .iter()
            .map(|x| x.1)
            .fold(180.0, f64::min);
        assert!(
            s.report.max_distance <= dev * (1.0 + 1e-12),
            "{dev}: {}",
            s.report.max_distance
        );
        assert_eq!(least < 30.0, !s.report.sharp_joints.is_empty(), "{dev}");
    }
    // With too small a deviation the joint cannot open: it is reported, not hidden.
    let tight = simplify(
        &n,
        None,
        &Options {
            min_angle: 30.0,
            ..opts(0.5)
        },
    )
    .unwrap();
    assert_eq!(tight.report.sharp_joints.len(), 1);
    assert!(tight.report.sharp_joints[0].angle < 30.0);
}

#[test]
fn a_member_that_would_cross_a_neighbour_keeps_the_node_that_goes_around_it() {
    // A bump over the top of a post: the bump's chord would cut through the post.
    let p = vec![(0.0, 0.0), (5.0, 3.0), (10.0, 0.0), (5.0, 1.0), (5.0, -5.0)];
    let e = [(0, 1), (1, 2), (3, 4)];
    let n = net(&p, &e);
    let s = simplify(&n, None, &opts(4.0)).unwrap();
    assert_eq!(s.network.edges.len(), 3, "the bump stays");
    assert!(s.report.nodes_restored_for_embedding >= 1);
}

#[test]
fn bad_options_and_networks_are_errors() {
    let n = net(&[(0.0, 0.0), (1.0, 0.0)], &[(0, 1)]);
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            simplify(&n, None, &opts(d)),
            Err(SimplifyError::NotPositive(..))
        ));
    }
    let bad_angle = Options {
        min_angle: 95.0,
        ..opts(1.0)
    };
    assert_eq!(
        simplify(&n, None, &bad_angle).err(),
        Some(SimplifyError::AngleTooLarge(95.0))
    );
    let looped = net(&[(0.0, 0.0), (1.0, 0.0)], &[(0, 1), (1, 1)]);
    assert_eq!(
        simplify(&looped, None, &opts(1.0)).err(),
        Some(SimplifyError::SelfLoop(1, 1))
    );
    let twice = net(&[(0.0, 0.0), (1.0, 0.0)], &[(0, 1), (1, 0)]);
    assert_eq!(
        simplify(&twice, None, &opts(1.0)).err(),
        Some(SimplifyError::Parallel(0, 1))
    );
    let missing = net(&[(0.0, 0.0)], &[(0, 3)]);
    assert_eq!(
        simplify(&missing, None, &opts(1.0)).err(),
        Some(SimplifyError::MissingNode(0, 3))
    );
}
