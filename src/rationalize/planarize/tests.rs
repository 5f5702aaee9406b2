use super::synthetic::{honeycomb, honeycomb_on};
use super::*;
use rand::{Rng, SeedableRng};

fn solve(input: &Input, method: Method) -> Solution {
    planarize(
        input,
        &PlanarizeOptions {
            method,
            ..Default::default()
        },
    )
    .expect("valid input")
}

#[test]
fn both_methods_reach_the_tolerance_and_agree() {
    for calyx in [false, true] {
        both_agree(&honeycomb_on(16, 100.0, 1, calyx));
    }
}

fn both_agree(input: &Input) {
    let input = input.clone();
    let before = input
        .edges
        .iter()
        .map(|&[a, b]| panel(&input, &input.reference, a, b).deviation)
        .fold(0.0, f64::max);
    assert!(before > 0.1, "the reference axes are not planar: {before}");
    let l = solve(&input, Method::Lbfgs);
    let p = solve(&input, Method::Projection);
    for s in [&l, &p] {
        assert!(s.converged, "{:?}: {} mm", s.method, s.max_deviation);
        assert!(s.max_deviation < 0.01);
        assert!(s.over_constrained.is_empty());
        assert!(s.axis_deviation_deg.iter().all(|a| *a < 15.0));
    }
    let worst = l
        .axes
        .iter()
        .zip(&p.axes)
        .map(|(a, b)| a.dot(*b).clamp(-1.0, 1.0).acos().to_degrees())
        .fold(0.0, f64::max);
    assert!(worst < 1.0, "axes differ by {worst}°");
}

#[test]
fn random_networks_of_degree_at_most_three_converge() {
    for seed in 0..6 {
        let mut input = honeycomb(7, 50.0, seed);
        // Drop a few edges at random: tips and degree-2 nodes appear.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 100);
        input.edges.retain(|_| rng.random_range(0.0..1.0) > 0.15);
        for method in [Method::Lbfgs, Method::Projection] {
            let s = solve(&input, method);
            assert!(
                s.converged,
                "seed {seed} {method:?}: {} mm after {} iterations",
                s.max_deviation, s.iterations
            );
        }
    }
}

#[test]
fn the_plain_published_sweep_also_converges_but_needs_more_iterations() {
    let input = honeycomb_on(10, 100.0, 5, true);
    let plain = planarize(
        &input,
        &PlanarizeOptions {
            method: Method::Projection,
            plain_projection: true,
            ..Default::default()
        },
    )
    .expect("valid");
    let fast = solve(&input, Method::Projection);
    assert!(plain.converged && fast.converged);
    assert!(
        fast.iterations < plain.iterations,
        "accelerated {} vs plain {}",
        fast.iterations,
        plain.iterations
    );
}

#[test]
fn fixed_normals_make_flat_base_plates() {
    // Row 0 of the Calyx-like band is a horizontal arc at z = 0.
    let input = honeycomb_on(10, 100.0, 4, true);
    let opts = |method| PlanarizeOptions {
        method,
        fix_normals: vec![(Selector::parse("z<0.5").expect("selector"), DVec3::Z)],
        ..Default::default()
    };
    for method in [Method::Lbfgs, Method::Projection] {
        let s = planarize(&input, &opts(method)).expect("valid");
        assert!(s.converged, "{method:?}: {}", s.max_deviation);
        let base: Vec<&Panel> = s
            .panels
            .iter()
            .filter(|p| p.fixed_normal.is_some())
            .collect();
        assert_eq!(base.len(), 9, "the base row's edges");
        for p in base {
            let err = p.fixed_normal_error_deg.expect("measured");
            assert!(
                err < 0.01,
                "{method:?}: base panel {} off +Z by {err}°",
                p.edge
            );
        }
        assert!(s.impossible_normals.is_empty());
    }
}

#[test]
fn fixed_axes_stay_put() {
    let input = honeycomb(6, 100.0, 2);
    let opts = PlanarizeOptions {
        fix_axes: vec![(Selector::Node(7), DVec3::new(0.0, 0.1, 1.0))],
        ..Default::default()
    };
    let s = planarize(&input, &opts).expect("valid");
    assert!(s.converged);
    assert!(s.axes[7].distance(DVec3::new(0.0, 0.1, 1.0).normalize()) < 1e-15);
}

#[test]
fn a_degree_four_node_is_reported() {
    let mut input = honeycomb(6, 100.0, 3);
    // Node 14 gets a fourth edge.
    input.edges.push([14, 2]);
    let s = solve(&input, Method::Lbfgs);
    assert!(s.over_constrained.contains(&14), "{:?}", s.over_constrained);
}

#[test]
fn bad_input_is_named() {
    let mut input = honeycomb(4, 100.0, 1);
    input.positions[3].x = f64::NAN;
    assert_eq!(
        planarize(&input, &PlanarizeOptions::default()).err(),
        Some(PlanarizeError::NonFinite(3))
    );
    let mut input = honeycomb(4, 100.0, 1);
    let [a, b] = input.edges[2];
    input.positions[b as usize] = input.positions[a as usize];
    assert!(matches!(
        planarize(&input, &PlanarizeOptions::default()),
        Err(PlanarizeError::ZeroLength(2, _))
    ));
    let input = honeycomb(4, 100.0, 1);
    let bad = PlanarizeOptions {
        tolerance: 0.0,
        ..Default::default()
    };
    assert_eq!(
        planarize(&input, &bad).err(),
        Some(PlanarizeError::Tolerance(0.0))
    );
}

#[test]
fn selectors_parse_and_match() {
    let p = DVec3::new(1.0, 2.0, 3.0);
    assert!(Selector::parse("z<5").expect("ok").matches(0, p));
    assert!(!Selector::parse("x>=2").expect("ok").matches(0, p));
    assert!(Selector::parse("node=4").expect("ok").matches(4, p));
    assert!(Selector::parse("all").expect("ok").matches(9, p));
    assert!(Selector::parse("w<3").is_err());
    assert!(Selector::parse("z=3").is_err());
    assert!(Selector::parse("z<abc").is_err());
}
