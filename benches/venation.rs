//! Venation growth in a unit leaf (the ovate blade scaled to length 1), the configurations the
//! venation issue names: closed venation from 100,000 Poisson sources, open venation from
//! 10,000 uniformly random sources. D = 1/200 of the leaf and kill = 1.5·D in both.
//! `scripts/bench` runs this, the same jobs through the CLI for peak memory and nodes per
//! second, and the naive JavaScript peer on the same job.

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec2;
use lamina::grow::leaf::{grow_leaf, place_sources, LeafOptions, Placement};
use lamina::grow::outline::{Outline, Shape, SHAPE_LENGTH};
use lamina::grow::venation::{Mode, VenationOptions};

fn unit_leaf() -> Outline {
    Outline::shape(Shape::Ovate).scaled(DVec2::ZERO, 1.0 / SHAPE_LENGTH)
}

fn options(mode: Mode, sources: usize, placement: Placement) -> LeafOptions {
    let d = 1.0 / 200.0;
    LeafOptions {
        growth: VenationOptions {
            mode,
            step: d,
            kill: 1.5 * d,
            ..Default::default()
        },
        birth: 2.0 * d,
        sources: Some(sources),
        placement,
        tip_radius: 0.001,
        ..Default::default()
    }
}

/// The open job as JSON for the JavaScript peer: the same blade, root and sources.
fn write_peer_job(leaf: &Outline, root: DVec2, opts: &LeafOptions) {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let sources = place_sources(leaf, leaf, opts, &mut rng);
    let pts = |v: &[DVec2]| v.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>();
    let job = serde_json::json!({
        "outline": pts(leaf.points()),
        "root": [root.x, root.y],
        "sources": pts(&sources),
        "step": opts.growth.step,
        "kill": opts.growth.kill,
        "max_iterations": opts.growth.max_iterations,
    });
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("bench-data folder");
    std::fs::write(dir.join("venation-open-10k.json"), job.to_string()).expect("peer job");
}

fn bench(c: &mut Criterion) {
    let leaf = unit_leaf();
    let root = [leaf.default_root()];
    write_peer_job(
        &leaf,
        root[0],
        &options(Mode::Open, 10_000, Placement::Random),
    );
    let mut group = c.benchmark_group("venation");
    group.sample_size(10);
    let jobs = [
        (
            "closed 100k poisson sources",
            options(Mode::Closed, 100_000, Placement::Poisson),
        ),
        (
            "open 10k random sources",
            options(Mode::Open, 10_000, Placement::Random),
        ),
    ];
    for (name, opts) in jobs {
        let grown = grow_leaf(&leaf, &root, &opts, None).expect("grows");
        eprintln!(
            "{name}: {} sources, {} nodes, {} steps, {} left unreached",
            grown.growth.sources_placed,
            grown.network.nodes.len(),
            grown.growth.iterations,
            grown.growth.sources_left
        );
        group.bench_function(name, |b| {
            b.iter(|| grow_leaf(&leaf, &root, &opts, None).expect("grows"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
