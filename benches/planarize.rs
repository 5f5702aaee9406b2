//! Node axes on the Calyx-like fixture (248 nodes, 273 edges, base plates held to +Z) by
//! L-BFGS, by the accelerated projection and by the paper's plain sweep; and L-BFGS on a
//! 100,489-node brick-wall network on a paraboloid. Each job prints its iterations and result
//! once before timing, and the large network is written to `target/bench-data` for the
//! whole-process runs. `scripts/bench` then runs the numpy peer (the paper's Python iterative
//! method, `scripts/peers/planarize_iterative.py`) on the Calyx job this writes to
//! `target/bench-data/planarize-calyx.json`.

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
#[path = "common/calyx.rs"]
mod common_calyx;
#[path = "common/network_file.rs"]
mod network_file;

use common_calyx::calyx;
use lamina::rationalize::planarize::synthetic::honeycomb;
use lamina::rationalize::planarize::{planarize, Input, Method, PlanarizeOptions, Selector};
use network_file::write_network_file;

/// The Calyx job for the peer: positions, edges, references, heights, the base plates.
fn write_peer_job(input: &Input) {
    let v = |p: &[DVec3]| p.iter().map(|q| q.to_array()).collect::<Vec<_>>();
    let job = serde_json::json!({
        "positions": v(&input.positions),
        "edges": input.edges,
        "reference": v(&input.reference),
        "heights": input.heights,
        "fixed_normal": {"below_z": 1.0, "normal": [0.0, 0.0, 1.0]},
        "tolerance": 0.01,
        "step": 0.5,
    });
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("bench-data folder");
    std::fs::write(dir.join("planarize-calyx.json"), job.to_string()).expect("peer job");
}

fn bench(c: &mut Criterion) {
    let input = calyx();
    write_peer_job(&input);
    let base = vec![(Selector::parse("z<1").expect("selector"), DVec3::Z)];
    let jobs = [
        ("calyx 248 nodes, lbfgs", Method::Lbfgs, false),
        ("calyx 248 nodes, projection", Method::Projection, false),
        (
            "calyx 248 nodes, plain projection",
            Method::Projection,
            true,
        ),
    ];
    let mut group = c.benchmark_group("planarize");
    group.sample_size(20);
    for (name, method, plain) in jobs {
        let opts = PlanarizeOptions {
            method,
            plain_projection: plain,
            fix_normals: base.clone(),
            ..Default::default()
        };
        let s = planarize(&input, &opts).expect("valid");
        eprintln!(
            "{name}: {} iterations, max deviation {:.5} mm, converged {}, α {:.2e}",
            s.iterations, s.max_deviation, s.converged, s.alpha_used
        );
        group.bench_function(name, |b| {
            b.iter(|| planarize(&input, &opts).expect("valid"))
        });
    }
    group.finish();

    let big = honeycomb(317, 100.0, 1);
    write_network_file(&big, "planarize-paraboloid-100k.json");
    let mut group = c.benchmark_group("planarize-large");
    group.sample_size(10);
    for (name, method) in [
        ("paraboloid 100k nodes, lbfgs", Method::Lbfgs),
        ("paraboloid 100k nodes, projection", Method::Projection),
    ] {
        let opts = PlanarizeOptions {
            method,
            ..Default::default()
        };
        let s = planarize(&big, &opts).expect("valid");
        eprintln!(
            "{name}: {} nodes, {} edges, {} iterations, max deviation {:.5} mm, converged {}, α {:.2e}",
            big.positions.len(),
            big.edges.len(),
            s.iterations,
            s.max_deviation,
            s.converged,
            s.alpha_used
        );
        group.bench_function(name, |b| b.iter(|| planarize(&big, &opts).expect("valid")));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
