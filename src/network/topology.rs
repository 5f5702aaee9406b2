//! Graph queries: CSR adjacency, degrees, components, and chains (maximal paths through
//! degree-2 nodes) that writers turn into polylines.

use super::Network;

/// Compressed adjacency: for node `i`, `pairs[offsets[i]..offsets[i+1]]` lists
/// `(neighbour, edge index)`. A self-loop appears twice at its node, as in the degree count.
/// Edges with an end out of range are left out.
#[derive(Clone, Debug)]
pub struct Adjacency {
    pub offsets: Vec<u32>,
    pub pairs: Vec<(u32, u32)>,
}

impl Adjacency {
    pub fn neighbours(&self, node: u32) -> &[(u32, u32)] {
        let i = node as usize;
        &self.pairs[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    pub fn degree(&self, node: u32) -> usize {
        let i = node as usize;
        (self.offsets[i + 1] - self.offsets[i]) as usize
    }
}

/// A maximal run of edges through nodes of degree 2. `nodes[k]` and `nodes[k + 1]` are joined
/// by `edges[k]`. A closed chain (a loop of degree-2 nodes) repeats its first node at the end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chain {
    pub nodes: Vec<u32>,
    pub edges: Vec<u32>,
}

impl Chain {
    pub fn is_closed(&self) -> bool {
        self.nodes.len() > 2 && self.nodes.first() == self.nodes.last()
    }
}

impl Network {
    pub fn adjacency(&self) -> Adjacency {
        let n = self.nodes.len();
        let in_range = |a: u32, b: u32| (a as usize) < n && (b as usize) < n;
        let mut offsets = vec![0u32; n + 1];
        for e in self.edges.iter().filter(|e| in_range(e.a, e.b)) {
            offsets[e.a as usize + 1] += 1;
            offsets[e.b as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut pairs = vec![(0u32, 0u32); offsets[n] as usize];
        for (k, e) in self.edges.iter().enumerate() {
            if !in_range(e.a, e.b) {
                continue;
            }
            pairs[fill[e.a as usize] as usize] = (e.b, k as u32);
            fill[e.a as usize] += 1;
            pairs[fill[e.b as usize] as usize] = (e.a, k as u32);
            fill[e.b as usize] += 1;
        }
        Adjacency { offsets, pairs }
    }

    /// Splits the in-range edges into chains; every such edge is in exactly one chain. The order
    /// is deterministic: open chains from nodes of degree other than 2 in node order, then loops.
    pub fn chains(&self) -> Vec<Chain> {
        let adj = self.adjacency();
        let mut used = vec![false; self.edges.len()];
        let mut chains = Vec::new();
        let walk = |start: u32, first_edge: u32, used: &mut Vec<bool>| {
            let mut chain = Chain {
                nodes: vec![start],
                edges: Vec::new(),
            };
            let (mut at, mut via) = (start, first_edge);
            loop {
                used[via as usize] = true;
                chain.edges.push(via);
                let e = self.edges[via as usize];
                at = if e.a == at { e.b } else { e.a };
                chain.nodes.push(at);
                if adj.degree(at) != 2 || at == start {
                    break;
                }
                match adj.neighbours(at).iter().find(|&&(_, k)| !used[k as usize]) {
                    Some(&(_, k)) => via = k,
                    None => break,
                }
            }
            chain
        };
        for node in 0..self.nodes.len() as u32 {
            if adj.degree(node) == 2 {
                continue;
            }
            for &(_, k) in adj.neighbours(node) {
                if !used[k as usize] {
                    chains.push(walk(node, k, &mut used));
                }
            }
        }
        for node in 0..self.nodes.len() as u32 {
            for &(_, k) in adj.neighbours(node) {
                if !used[k as usize] {
                    chains.push(walk(node, k, &mut used));
                }
            }
        }
        chains
    }

    /// Connected components as a label per node (labels 0.., in order of first node).
    pub fn component_labels(&self) -> (Vec<u32>, usize) {
        let adj = self.adjacency();
        let mut label = vec![u32::MAX; self.nodes.len()];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for seed in 0..self.nodes.len() {
            if label[seed] != u32::MAX {
                continue;
            }
            label[seed] = count;
            stack.push(seed as u32);
            while let Some(v) = stack.pop() {
                for &(w, _) in adj.neighbours(v) {
                    if label[w as usize] == u32::MAX {
                        label[w as usize] = count;
                        stack.push(w);
                    }
                }
            }
            count += 1;
        }
        (label, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Edge, Network, Node};
    use glam::DVec3;

    fn net(n: usize, edges: &[(u32, u32)]) -> Network {
        Network {
            nodes: (0..n)
                .map(|i| Node::at(DVec3::new(i as f64, 0.0, 0.0)))
                .collect(),
            edges: edges.iter().map(|&(a, b)| Edge::new(a, b)).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn chains_cover_every_edge_once() {
        // A Y with a loop hanging off one arm and a separate triangle.
        let g = net(
            9,
            &[
                (0, 1),
                (1, 2),
                (1, 3),
                (3, 4),
                (4, 5),
                (5, 3),
                (6, 7),
                (7, 8),
                (8, 6),
            ],
        );
        let chains = g.chains();
        let mut seen: Vec<u32> = chains.iter().flat_map(|c| c.edges.clone()).collect();
        seen.sort();
        assert_eq!(seen, (0..9).collect::<Vec<_>>());
        let loops: Vec<_> = chains.iter().filter(|c| c.is_closed()).collect();
        assert_eq!(loops.len(), 2, "{chains:?}");
    }

    #[test]
    fn components_count_isolated_nodes() {
        let g = net(5, &[(0, 1), (2, 3)]);
        let (labels, count) = g.component_labels();
        assert_eq!(count, 3);
        assert_eq!(labels, vec![0, 0, 1, 1, 2]);
    }
}
