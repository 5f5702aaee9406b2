//! Read + validate a 200k-edge network from DXF (one LINE per edge, the way Grasshopper bakes
//! curves: the worst case for welding) and from our JSON. `scripts/bench` runs this next to the
//! peers (ezdxf and Python's json reading the same files) and records peak memory.

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use dxf::entities::{Entity, EntityType, Line};
use dxf::{Drawing, Point};
use glam::DVec3;
use lamina::network::io::{read_network, write_network, ReadOptions, RenderOptions};
use lamina::network::{Edge, Network, Node};

pub const EDGES: usize = 200_000;

/// A jittered square lattice (about 316 × 316 nodes) trimmed to exactly `EDGES` edges:
/// degree-4 crossings, loops everywhere, deterministic.
fn lattice(edges: usize) -> Network {
    let side = ((edges / 2) as f64).sqrt().ceil() as u32 + 1;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut jitter = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let nodes = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f64, (i / side) as f64);
            Node::at(DVec3::new(x * 10.0 + jitter(), y * 10.0 + jitter(), 0.0))
        })
        .collect();
    let mut list = Vec::with_capacity(edges);
    'outer: for y in 0..side {
        for x in 0..side {
            let i = y * side + x;
            if x + 1 < side {
                list.push(Edge::new(i, i + 1));
            }
            if y + 1 < side {
                list.push(Edge::new(i, i + side));
            }
            if list.len() >= edges {
                break 'outer;
            }
        }
    }
    list.truncate(edges);
    Network {
        nodes,
        edges: list,
        ..Default::default()
    }
}

/// Writes the benchmark inputs once into target/bench-data and returns their paths.
pub fn inputs() -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("bench data folder");
    let (dxf_path, json_path) = (dir.join("lines-200k.dxf"), dir.join("lattice-200k.json"));
    let net = lattice(EDGES);
    if !dxf_path.exists() {
        let mut d = Drawing::new();
        d.header.version = dxf::enums::AcadVersion::R2000;
        for e in &net.edges {
            let (a, b) = (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p);
            d.add_entity(Entity::new(EntityType::Line(Line::new(
                Point::new(a.x, a.y, a.z),
                Point::new(b.x, b.y, b.z),
            ))));
        }
        d.save_file(&dxf_path).expect("write bench DXF");
    }
    if !json_path.exists() {
        write_network(&net, &json_path, &RenderOptions::default()).expect("write bench JSON");
    }
    (dxf_path, json_path)
}

fn bench(c: &mut Criterion) {
    let (dxf_path, json_path) = inputs();
    let opts = ReadOptions::default();
    let mut g = c.benchmark_group("read+validate 200k edges");
    g.sample_size(10);
    g.bench_function("dxf (200k LINE)", |b| {
        b.iter(|| {
            let imp = read_network(&dxf_path, &opts).expect("bench DXF reads");
            assert_eq!(imp.network.edges.len(), EDGES);
            imp.network.validate()
        })
    });
    g.bench_function("json", |b| {
        b.iter(|| {
            let imp = read_network(&json_path, &opts).expect("bench JSON reads");
            assert_eq!(imp.network.edges.len(), EDGES);
            imp.network.validate()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
