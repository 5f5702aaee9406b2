//! Assembly groups: split a network's nodes into k connected groups of about equal plate count
//! with few seams (edges whose ends lie in different groups), then tag every plate.
//!
//! Method: region growing plus greedy refinement.
//! 1. Seeds by farthest-point sampling in edge-length distance (the first is the node farthest
//!    from node 0), so groups start spread over the structure.
//! 2. Growing: the group with the least weight (a node weighs half its degree, so a group's
//!    weight is about its plate count) takes its nearest unassigned neighbour (Dijkstra from its
//!    seed). A component no seed reached goes whole to the lightest group.
//! 3. Refinement, keeping every group connected: first balance (while a group is outside ±15 %
//!    of the mean weight, move the boundary node that narrows the gap between two neighbouring
//!    groups and adds the least seam cost), then seams (a boundary node moves when that lowers
//!    the seam cost and keeps both groups within the balance; passes repeat until nothing
//!    moves, at most 50). A seam costs (median edge length / its length)²: seams go to long
//!    members, where the plies' overlap between their setbacks has room for a bolt row.
//!
//! A seam plate is split into two plates of half thickness, one tagged for each group, bolted
//! face to face (Calyx's half-thickness group edges).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;

use crate::geom::Ordered;

const BALANCE: f64 = 0.15;
const PASSES: usize = 50;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GroupError {
    #[error("groups= must be at least 1, got 0")]
    Zero,
    #[error("groups= {0}: more groups than the network's {1} nodes with edges")]
    TooMany(usize, usize),
}

/// Group (0-based) of every node; nodes without edges get group 0.
pub fn partition(
    positions: &[DVec3],
    edges: &[[u32; 2]],
    k: usize,
) -> Result<Vec<u32>, GroupError> {
    let n = positions.len();
    let mut adj: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for &[a, b] in edges {
        let (a, b) = (a as usize, b as usize);
        let w = positions[a].distance(positions[b]);
        adj[a].push((b, w));
        adj[b].push((a, w));
    }
    let used: Vec<usize> = (0..n).filter(|&v| !adj[v].is_empty()).collect();
    if k == 0 {
        return Err(GroupError::Zero);
    }
    if k > used.len() {
        return Err(GroupError::TooMany(k, used.len()));
    }
    let weight = |v: usize| adj[v].len() as f64 / 2.0;
    let mut lengths: Vec<f64> = adj.iter().flatten().map(|&(_, l)| l).collect();
    lengths.sort_by(f64::total_cmp);
    let median = lengths.get(lengths.len() / 2).copied().unwrap_or(1.0);
    let removed = |group: &[u32], v: usize, to: usize| seams_removed(&adj, group, v, to, median);

    // 1. Seeds: the node farthest from the first used node, then each time the node farthest
    // from all seeds so far (ties to the lower index).
    let farthest = |d: &[f64]| {
        *used
            .iter()
            .max_by(|&&a, &&b| d[a].total_cmp(&d[b]).then(b.cmp(&a)))
            .unwrap_or(&used[0])
    };
    let mut seeds = vec![farthest(&dijkstra(&adj, &[used[0]]))];
    let mut nearest = dijkstra(&adj, &seeds);
    while seeds.len() < k {
        let next = farthest(&nearest);
        seeds.push(next);
        for (v, d) in dijkstra(&adj, &[next]).into_iter().enumerate() {
            nearest[v] = nearest[v].min(d);
        }
    }

    // 2. Growing.
    const NONE: u32 = u32::MAX;
    let mut group = vec![NONE; n];
    let mut load = vec![0.0f64; k];
    let mut fronts: Vec<BinaryHeap<Reverse<(Ordered, usize)>>> = vec![BinaryHeap::new(); k];
    for (g, &s) in seeds.iter().enumerate() {
        fronts[g].push(Reverse((Ordered(0.0), s)));
    }
    loop {
        // The lightest group that can still grow.
        let mut order: Vec<usize> = (0..k).filter(|&g| !fronts[g].is_empty()).collect();
        if order.is_empty() {
            break;
        }
        order.sort_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b)));
        let g = order[0];
        let Some(Reverse((Ordered(d), v))) = fronts[g].pop() else {
            continue;
        };
        if group[v] != NONE {
            continue;
        }
        group[v] = g as u32;
        load[g] += weight(v);
        for &(w, len) in &adj[v] {
            if group[w] == NONE {
                fronts[g].push(Reverse((Ordered(d + len), w)));
            }
        }
    }
    for &v in &used {
        if group[v] != NONE {
            continue;
        }
        // An unreached component: all of it to the lightest group.
        let g = (0..k)
            .min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b)))
            .unwrap_or(0);
        let mut stack = vec![v];
        group[v] = g as u32;
        while let Some(u) = stack.pop() {
            load[g] += weight(u);
            for &(w, _) in &adj[u] {
                if group[w] == NONE {
                    group[w] = g as u32;
                    stack.push(w);
                }
            }
        }
    }
    for g in group.iter_mut() {
        if *g == NONE {
            *g = 0;
        }
    }

    // 3. Refinement.
    let mean = used.iter().map(|&v| weight(v)).sum::<f64>() / k as f64;
    let (low, high) = ((1.0 - BALANCE) * mean, (1.0 + BALANCE) * mean);
    // 3a. Balance: while some group is outside ±BALANCE of the mean, make the move that
    // narrows the gap between two neighbouring groups with the fewest added seams.
    for _ in 0..used.len() {
        let outside = |l: f64| l < low || l > high;
        if !load.iter().any(|&l| outside(l)) {
            break;
        }
        let mut best: Option<(Ordered, usize, usize)> = None; // (gain, node, to)
        for &v in &used {
            let from = group[v] as usize;
            let wv = weight(v);
            for &(w, _) in &adj[v] {
                let to = group[w] as usize;
                let helps = to != from
                    && (outside(load[from]) || outside(load[to]))
                    && load[from] - wv >= load[to] + wv;
                if !helps {
                    continue;
                }
                let gain = Ordered(removed(&group, v, to));
                if !best.is_some_and(|(g, bv, bt)| {
                    (gain, Reverse(v), Reverse(to)) <= (g, Reverse(bv), Reverse(bt))
                }) {
                    group[v] = to as u32;
                    let ok = connected(&adj, &group, from as u32);
                    group[v] = from as u32;
                    if ok {
                        best = Some((gain, v, to));
                    }
                }
            }
        }
        let Some((_, v, to)) = best else { break };
        let from = group[v] as usize;
        group[v] = to as u32;
        load[from] -= weight(v);
        load[to] += weight(v);
    }
    // 3b. Fewer seams, within the balance.
    for _ in 0..PASSES {
        let mut moved = false;
        for &v in &used {
            let from = group[v] as usize;
            let mut best: Option<(f64, usize)> = None;
            for &(w, _) in &adj[v] {
                let to = group[w] as usize;
                if to == from {
                    continue;
                }
                let gain = removed(&group, v, to);
                if gain > 1e-9 && !best.is_some_and(|(g, t)| gain < g || (gain == g && to >= t)) {
                    best = Some((gain, to));
                }
            }
            let Some((_, to)) = best else { continue };
            let wv = weight(v);
            if load[from] - wv < low || load[to] + wv > high {
                continue;
            }
            group[v] = to as u32;
            if !connected(&adj, &group, from as u32) {
                group[v] = from as u32;
                continue;
            }
            load[from] -= wv;
            load[to] += wv;
            moved = true;
        }
        if !moved {
            break;
        }
    }
    Ok(group)
}

/// What a seam on an edge `length` long costs when the median edge is `median` long: short
/// members cost more, so seams go where a bolt row fits.
fn seam_cost(median: f64, length: f64) -> f64 {
    (median / length.max(1e-9)).powi(2)
}

/// How much seam cost moving node `v` to group `to` removes (negative: adds).
fn seams_removed(
    adj: &[Vec<(usize, f64)>],
    group: &[u32],
    v: usize,
    to: usize,
    median: f64,
) -> f64 {
    let from = group[v];
    adj[v]
        .iter()
        .map(|&(u, l)| match group[u] {
            g if g as usize == to => seam_cost(median, l),
            g if g == from => -seam_cost(median, l),
            _ => 0.0,
        })
        .sum()
}

/// Whether the nodes of group `g` form one connected piece (or none).
fn connected(adj: &[Vec<(usize, f64)>], group: &[u32], g: u32) -> bool {
    let members: Vec<usize> = (0..adj.len())
        .filter(|&v| group[v] == g && !adj[v].is_empty())
        .collect();
    let Some(&start) = members.first() else {
        return true;
    };
    let mut seen = vec![false; adj.len()];
    let mut stack = vec![start];
    seen[start] = true;
    let mut count = 0;
    while let Some(u) = stack.pop() {
        count += 1;
        for &(w, _) in &adj[u] {
            if !seen[w] && group[w] == g {
                seen[w] = true;
                stack.push(w);
            }
        }
    }
    count == members.len()
}

fn dijkstra(adj: &[Vec<(usize, f64)>], from: &[usize]) -> Vec<f64> {
    let mut dist = vec![f64::INFINITY; adj.len()];
    let mut heap = BinaryHeap::new();
    for &s in from {
        dist[s] = 0.0;
        heap.push(Reverse((Ordered(0.0), s)));
    }
    while let Some(Reverse((Ordered(d), u))) = heap.pop() {
        if d > dist[u] {
            continue;
        }
        for &(w, len) in &adj[u] {
            let nd = d + len;
            if nd < dist[w] {
                dist[w] = nd;
                heap.push(Reverse((Ordered(nd), w)));
            }
        }
    }
    // Unreachable nodes count as nearest (never chosen as seeds over reachable far ones).
    dist.iter()
        .map(|&d| if d.is_finite() { d } else { -1.0 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rationalize::planarize::synthetic::square_grid as grid;

    #[test]
    fn groups_are_connected_balanced_and_cut_few_edges() {
        let (p, e) = grid(20, 10);
        let k = 4;
        let g = partition(&p, &e, k).expect("valid");
        let mut adj = vec![Vec::new(); p.len()];
        for &[a, b] in &e {
            adj[a as usize].push((b as usize, 1.0));
            adj[b as usize].push((a as usize, 1.0));
        }
        let mut plates = vec![0.0; k];
        for &[a, b] in &e {
            plates[g[a as usize] as usize] += 0.5;
            plates[g[b as usize] as usize] += 0.5;
        }
        let mean = e.len() as f64 / k as f64;
        for (gi, &count) in plates.iter().enumerate() {
            assert!(connected(&adj, &g, gi as u32), "group {gi} is in pieces");
            assert!(
                (count - mean).abs() <= BALANCE * mean + 2.0,
                "group {gi}: {count} plates, mean {mean}"
            );
        }
        let seams = e
            .iter()
            .filter(|&&[a, b]| g[a as usize] != g[b as usize])
            .count();
        // Four strips of a 20 × 10 grid would cut 30 edges; a good split stays near that.
        assert!(seams <= 45, "{seams} seams");
    }

    #[test]
    fn the_same_input_gives_the_same_groups_and_bad_k_is_refused() {
        let (p, e) = grid(7, 7);
        assert_eq!(partition(&p, &e, 3), partition(&p, &e, 3));
        assert_eq!(partition(&p, &e, 0), Err(GroupError::Zero));
        assert_eq!(partition(&p, &e, 50), Err(GroupError::TooMany(50, 49)));
    }
}
