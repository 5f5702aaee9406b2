//! `lamina simplify` at scale: a degree-3 honeycomb on a paraboloid (or flat, `--flat`) whose
//! every edge is a chain of wobbling degree-2 nodes (as grown veins are), about 100,000 nodes;
//! the time of one simplification at a deviation of half the mean segment, best of three.
//! `--write FILE` also writes the network, for `lamina simplify` and the shapely peer
//! (`scripts/bench simplify`).
//!
//!     cargo bench --bench simplify [-- NODES] [--flat] [--write FILE]

use std::time::Instant;

use glam::DVec3;
use lamina::network::io::{write_network, RenderOptions};
use lamina::network::{Edge, Network, Node};
use lamina::rationalize::planarize::synthetic::{honeycomb_shaped, Shape};
use lamina::rationalize::simplify::{simplify, Options};

/// Each honeycomb edge becomes this many segments.
const SEGMENTS: usize = 8;

fn network(target: usize, flat: bool) -> Network {
    // A brick wall of n × n nodes has about 1.5 n² edges, each adding SEGMENTS - 1 nodes.
    let side = (target as f64 / (1.0 + 1.5 * (SEGMENTS - 1) as f64)).sqrt() as usize;
    let mut input = honeycomb_shaped(side.max(2), 100.0, 1, Shape::Paraboloid);
    if flat {
        for (p, n) in input.positions.iter_mut().zip(&mut input.reference) {
            (p.z, *n) = (0.0, DVec3::Z);
        }
    }
    let mut nodes: Vec<Node> = input
        .positions
        .iter()
        .zip(&input.reference)
        .map(|(&p, &n)| Node {
            p,
            normal: Some(n),
            radius: 1.0,
        })
        .collect();
    let mut edges = Vec::new();
    for (k, &[a, b]) in input.edges.iter().enumerate() {
        let (pa, pb) = (nodes[a as usize].p, nodes[b as usize].p);
        let normal = nodes[a as usize].normal.unwrap_or(DVec3::Z);
        let side = (pb - pa).cross(normal).normalize_or_zero();
        let reach = 0.02 * pa.distance(pb);
        let mut prev = a;
        for s in 1..SEGMENTS {
            let t = s as f64 / SEGMENTS as f64;
            // A deterministic wobble, different per edge.
            let w = ((k * 7 + s * 13) % 11) as f64 / 10.0 - 0.5;
            nodes.push(Node {
                p: pa.lerp(pb, t) + side * (reach * w),
                normal: Some(normal),
                radius: 1.0,
            });
            let v = nodes.len() as u32 - 1;
            edges.push(Edge::new(prev, v));
            prev = v;
        }
        edges.push(Edge::new(prev, b));
    }
    Network {
        nodes,
        edges,
        ..Default::default()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let target = args
        .iter()
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(100_000);
    let flat = args.iter().any(|a| a == "--flat");
    let net = network(target, flat);
    if let Some(k) = args.iter().position(|a| a == "--write") {
        let path = std::path::Path::new(args.get(k + 1).expect("--write FILE"));
        write_network(&net, path, &RenderOptions::default()).expect("a writable file");
    }
    let mean = net.lengths().map_or(1.0, |l| l.mean);
    let opts = Options {
        max_deviation: 0.5 * mean,
        min_angle: 30.0,
        ..Default::default()
    };
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..3 {
        let t = Instant::now();
        let done = simplify(&net, None, &opts).expect("a valid network");
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(done);
    }
    let r = last.expect("three runs").report;
    println!(
        "simplify{}: {} nodes, {} edges -> {} members ({:.1} % fewer), largest deviation {:.3} mm \
         of {:.3}, smallest joint {:.1}°, cycles {} -> {}: best of 3 {:.3} s",
        if flat { " (flat)" } else { "" },
        net.nodes.len(),
        net.edges.len(),
        r.after.members,
        100.0 * (1.0 - r.after.members as f64 / r.before.members as f64),
        r.max_distance,
        opts.max_deviation,
        r.after.smallest_joint_angle.unwrap_or(180.0),
        r.before.cycles,
        r.after.cycles,
        best
    );
}
