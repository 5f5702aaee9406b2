//! The Calyx-like fixture as a planarize input (stored normals as references, 100 mm panels),
//! shared by the benchmarks.

use std::path::Path;

use lamina::network::io::{read_network, ReadOptions};
use lamina::rationalize::planarize::Input;

pub fn calyx() -> Input {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/networks/calyx_veins.json");
    let net = read_network(&path, &ReadOptions::default())
        .expect("fixture")
        .network;
    Input {
        positions: net.nodes.iter().map(|n| n.p).collect(),
        edges: net.edges.iter().map(|e| [e.a, e.b]).collect(),
        reference: net
            .nodes
            .iter()
            .map(|n| n.normal.expect("stored normal"))
            .collect(),
        heights: vec![100.0; net.nodes.len()],
    }
}
