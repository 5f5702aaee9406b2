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
    let g = solve(&input, Method::Newton);
    for s in [&l, &p, &g] {
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
        for method in [Method::Lbfgs, Method::Projection, Method::Newton] {
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
    for method in [Method::Lbfgs, Method::Projection, Method::Newton] {
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
    for method in [Method::Lbfgs, Method::Newton] {
        let opts = PlanarizeOptions {
            method,
            fix_axes: vec![(Selector::Node(7), DVec3::new(0.0, 0.1, 1.0))],
            ..Default::default()
        };
        let s = planarize(&input, &opts).expect("valid");
        assert!(s.converged, "{method:?}");
        assert_eq!(
            s.axes[7],
            DVec3::new(0.0, 0.1, 1.0).normalize(),
            "{method:?}"
        );
    }
}

/// Mean and largest angle of the axes from their references, degrees.
fn spread(s: &Solution) -> (f64, f64) {
    let a = &s.axis_deviation_deg;
    (
        a.iter().sum::<f64>() / a.len() as f64,
        a.iter().fold(0.0, |m: f64, &d| m.max(d)),
    )
}

#[test]
fn newton_is_as_close_to_the_references_as_lbfgs() {
    let mut inputs = vec![
        honeycomb_on(16, 100.0, 1, false),
        honeycomb_on(16, 100.0, 2, true),
        synthetic::honeycomb_shaped(20, 100.0, 3, synthetic::Shape::Saddle),
        synthetic::ellipsoid_dual(5, DVec3::new(1000.0, 700.0, 500.0), 100.0),
        synthetic::saddle(30, 1000.0, 1000.0, 100.0, 5),
    ];
    let mut tips = honeycomb(9, 60.0, 4);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
    tips.edges.retain(|_| rng.random_range(0.0..1.0) > 0.15);
    inputs.push(tips);
    for (k, input) in inputs.iter().enumerate() {
        let l = solve(input, Method::Lbfgs);
        let g = solve(input, Method::Newton);
        assert!(l.converged && g.converged, "input {k}");
        let ((lm, lx), (gm, gx)) = (spread(&l), spread(&g));
        assert!(
            gm <= lm + 0.01 && gx <= lx + 0.01,
            "input {k}: Newton {gm:.4}° mean, {gx:.4}° largest; L-BFGS {lm:.4}°, {lx:.4}°"
        );
    }
}

#[test]
fn newton_needs_no_more_iterations_on_a_larger_network() {
    // The same 2 × 2 m saddle meshed 8 times finer: L-BFGS goes from 106 to 189 iterations.
    let on_saddle = |n| synthetic::saddle(n, 1000.0, 1000.0, 100.0, 1);
    let small = solve(&on_saddle(12), Method::Newton);
    let large = solve(&on_saddle(96), Method::Newton);
    assert!(small.converged && large.converged);
    assert!(
        large.iterations <= small.iterations + 4,
        "{} iterations at 144 nodes, {} at 9,216",
        small.iterations,
        large.iterations
    );
}

#[test]
fn newton_gives_the_same_axes_on_any_number_of_threads() {
    // 11,520 nodes, so the factorisation's last supernodes are dense blocks of a hundred
    // columns or more for faer's kernels to split between threads (the 1.31 M-node ellipsoid
    // gave the same bits on 1, 2 and 3 threads too, checked by hand: a minute a run).
    let input = synthetic::ellipsoid_dual(24, DVec3::new(1000.0, 700.0, 500.0), 100.0);
    let opts = PlanarizeOptions {
        method: Method::Newton,
        fix_axes: vec![(Selector::Node(3), DVec3::Z)],
        ..Default::default()
    };
    let on = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| planarize(&input, &opts).expect("valid"))
    };
    let one = on(1);
    for threads in [2, 3] {
        let other = on(threads);
        assert_eq!(one.axes, other.axes, "{threads} threads");
        assert_eq!(one.iterations, other.iterations);
        assert_eq!(one.history, other.history);
    }
}

#[test]
fn newton_keeps_a_degree_four_node_and_reports_it() {
    let mut input = honeycomb(6, 100.0, 3);
    input.edges.push([14, 2]);
    let s = solve(&input, Method::Newton);
    assert!(s.over_constrained.contains(&14));
    assert!(s.axes.iter().all(|a| a.is_finite()));
    assert!(s.max_deviation.is_finite());
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

/// The deviation Gauss-Newton leaves at one α, solved to convergence.
fn deviation_at(input: &Input, alpha: f64) -> f64 {
    let s = planarize(
        input,
        &PlanarizeOptions {
            method: Method::Newton,
            alpha,
            // Met at once: the first α is kept.
            tolerance: 1e9,
            ..Default::default()
        },
    )
    .expect("valid input");
    assert_eq!(s.alpha_used, alpha);
    s.max_deviation
}

#[test]
fn newton_keeps_an_alpha_within_a_factor_1_5_of_the_largest_that_holds() {
    let surfaces = [
        ("calyx honeycomb", honeycomb_on(12, 100.0, 3, true)),
        (
            "ellipsoid",
            super::synthetic::ellipsoid_dual(4, DVec3::new(1000.0, 700.0, 500.0), 100.0),
        ),
        (
            "saddle",
            super::synthetic::saddle(14, 1000.0, 1500.0, 100.0, 7),
        ),
    ];
    for (name, input) in &surfaces {
        let tolerance = 0.01;
        let s = planarize(
            input,
            &PlanarizeOptions {
                method: Method::Newton,
                tolerance,
                ..Default::default()
            },
        )
        .expect("valid input");
        assert!(s.converged, "{name}: {} mm", s.max_deviation);
        // The largest α that holds, by bisection on log α between one that holds and the
        // α asked for (which must not, or there is nothing to find).
        let (mut lo, mut hi) = (s.alpha_used, PlanarizeOptions::default().alpha);
        assert!(
            deviation_at(input, hi) > tolerance,
            "{name}: α asked for holds"
        );
        assert!(deviation_at(input, lo) <= tolerance, "{name}");
        while hi / lo > 1.02 {
            let mid = (lo * hi).sqrt();
            if deviation_at(input, mid) <= tolerance {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert!(
            s.alpha_used * 1.5 >= lo,
            "{name}: kept α {:.3e}, {:.3e} holds",
            s.alpha_used,
            lo
        );
    }
}

/// The α [`newton_alpha`] keeps when the deviation left at α is `dev(α)`, and how many α it
/// tried.
fn schedule_keeps(dev: impl Fn(f64) -> f64, tolerance: f64) -> (f64, usize) {
    let mut s = Schedule::default();
    let mut alpha = 0.01;
    for tried in 1..100 {
        match newton_alpha(&mut s, alpha, dev(alpha), tolerance, &[]) {
            Next::Try(a) => alpha = a,
            Next::Stop => return (alpha, tried),
            Next::Return(a, _) => return (a, tried),
        }
    }
    panic!("no end");
}

#[test]
fn the_alpha_schedule_keeps_within_1_5_of_the_largest_that_holds_however_the_deviation_bends() {
    // The deviation as a power of α below the largest α that holds and another above it: a
    // bend like the one that stopped a 1.31 M-node ellipsoid at a tenth of the α that held,
    // when the power law through the last two α was trusted.
    let tol = 0.01;
    for star in [3e-6, 7.7e-5, 2.4e-4, 1e-3] {
        for (below, above) in [
            (1.0, 1.0),
            (0.87, 4.0),
            (0.5, 3.0),
            (0.3, 6.0),
            (2.0, 0.5),
            (0.87, 1.5),
            (0.6, 8.0),
        ] {
            let dev = |a: f64| {
                if a <= star {
                    tol * 0.999 * (a / star).powf(below)
                } else {
                    tol * 1.001 * (a / star).powf(above)
                }
            };
            let (kept, tried) = schedule_keeps(dev, tol);
            assert!(dev(kept) <= tol);
            assert!(
                star / kept <= 1.5,
                "largest {star:e}, powers {below}/{above}: kept {kept:e} after {tried} α"
            );
        }
    }
}
