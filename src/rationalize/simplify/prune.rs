//! Pruning by Horton-Strahler order, and stubs by length.
//!
//! Orders come from peeling leaves: a tip's edge has order 1; a node whose hanging branches are
//! all ordered passes on their largest order, one more when two branches share it. Edges on
//! loops are never peeled, so loops stay. A component that is a tree is peeled towards its
//! root, the tip of its thickest edge (a grown leaf's petiole), so the main vein is ordered
//! from its twigs and not from its stem.

use std::collections::VecDeque;

use crate::network::Network;

pub(super) struct Pruned {
    pub keep_edge: Vec<bool>,
    /// False for nodes left with no edge (isolated input nodes included).
    pub keep_node: Vec<bool>,
    pub members: usize,
    pub stubs: usize,
}

/// Horton-Strahler order of every edge; `u32::MAX` for edges on or between loops.
pub(super) fn strahler(net: &Network) -> Vec<u32> {
    let adj = net.adjacency();
    let n = net.nodes.len();
    let mut remaining: Vec<usize> = (0..n as u32).map(|v| adj.degree(v)).collect();
    let mut protected = vec![false; n];
    let (labels, count) = net.component_labels();
    let mut nodes_in = vec![0usize; count];
    let mut edges_in = vec![0usize; count];
    for &l in &labels {
        nodes_in[l as usize] += 1;
    }
    for e in &net.edges {
        edges_in[labels[e.a as usize] as usize] += 1;
    }
    // The root of each tree: the tip on its thickest edge, ties to the lower index.
    let mut root: Vec<Option<(f64, u32)>> = vec![None; count];
    for v in 0..n as u32 {
        let l = labels[v as usize] as usize;
        if adj.degree(v) != 1 || edges_in[l] + 1 != nodes_in[l] {
            continue;
        }
        let r = net.edges[adj.neighbours(v)[0].1 as usize].radius;
        if root[l].is_none_or(|(best, _)| r > best) {
            root[l] = Some((r, v));
        }
    }
    for (_, v) in root.into_iter().flatten() {
        protected[v as usize] = true;
    }
    let mut best = vec![(0u32, 0u32); n]; // (largest order in, how many reach it)
    let mut order = vec![u32::MAX; net.edges.len()];
    let mut queue: VecDeque<u32> = (0..n as u32)
        .filter(|&v| remaining[v as usize] == 1 && !protected[v as usize])
        .collect();
    while let Some(v) = queue.pop_front() {
        if remaining[v as usize] != 1 {
            continue;
        }
        let Some(&(u, k)) = adj
            .neighbours(v)
            .iter()
            .find(|&&(_, k)| order[k as usize] == u32::MAX)
        else {
            continue;
        };
        let (m, c) = best[v as usize];
        let o = match c {
            0 => 1,
            1 => m,
            _ => m + 1,
        };
        order[k as usize] = o;
        remaining[v as usize] = 0;
        remaining[u as usize] -= 1;
        let b = &mut best[u as usize];
        if o > b.0 {
            *b = (o, 1);
        } else if o == b.0 {
            b.1 += 1;
        }
        if remaining[u as usize] == 1 && !protected[u as usize] {
            queue.push_back(u);
        }
    }
    order
}

/// Removes branches of order below `min_order` (when it is 2 or more), then dangling chains
/// shorter than `min_length` (when above 0) that end at a junction.
pub(super) fn prune(net: &Network, min_order: u32, min_length: f64) -> Pruned {
    let mut keep_edge = vec![true; net.edges.len()];
    if min_order >= 2 {
        for (k, o) in strahler(net).into_iter().enumerate() {
            if o < min_order {
                keep_edge[k] = false;
            }
        }
    }
    let mut stubs = 0;
    if min_length > 0.0 {
        let (kept, ids) = subnetwork(net, &keep_edge);
        let adj = kept.adjacency();
        for chain in kept.chains() {
            let (first, last) = (
                chain.nodes[0],
                *chain.nodes.last().expect("a chain has nodes"),
            );
            let (da, db) = (adj.degree(first), adj.degree(last));
            let dangling = (da == 1 && db >= 3) || (db == 1 && da >= 3);
            let length: f64 = chain
                .edges
                .iter()
                .map(|&k| kept.edge_length(&kept.edges[k as usize]))
                .sum();
            if dangling && length < min_length {
                for &k in &chain.edges {
                    keep_edge[ids[k as usize] as usize] = false;
                }
                stubs += 1;
            }
        }
    }
    let mut keep_node = vec![false; net.nodes.len()];
    for (e, _) in net.edges.iter().zip(&keep_edge).filter(|(_, &k)| k) {
        keep_node[e.a as usize] = true;
        keep_node[e.b as usize] = true;
    }
    Pruned {
        members: keep_edge.iter().filter(|&&k| !k).count(),
        keep_edge,
        keep_node,
        stubs,
    }
}

/// The same nodes with only the kept edges, in their order, and each kept edge's index in `net`.
pub(super) fn subnetwork(net: &Network, keep: &[bool]) -> (Network, Vec<u32>) {
    let ids: Vec<u32> = (0..net.edges.len() as u32)
        .filter(|&k| keep[k as usize])
        .collect();
    let sub = Network {
        nodes: net.nodes.clone(),
        edges: ids.iter().map(|&k| net.edges[k as usize]).collect(),
        meta: net.meta.clone(),
    };
    (sub, ids)
}
