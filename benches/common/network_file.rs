//! A planarize input written as network JSON (positions, stored normals as references), for
//! the benchmarks' whole-process runs.

use std::path::Path;

use lamina::network::io::{write_network, RenderOptions};
use lamina::network::{Edge, Network, Node};
use lamina::rationalize::planarize::Input;

/// Writes `input` to `target/bench-data/NAME`.
pub fn write_network_file(input: &Input, name: &str) {
    let net = Network {
        nodes: input
            .positions
            .iter()
            .zip(&input.reference)
            .map(|(p, n)| Node {
                p: *p,
                normal: Some(*n),
                radius: 0.0,
            })
            .collect(),
        edges: input.edges.iter().map(|&[a, b]| Edge::new(a, b)).collect(),
        ..Default::default()
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("bench-data folder");
    write_network(&net, &dir.join(name), &RenderOptions::default()).expect("network file");
}
