//! The network as chains between junctions, and what happens to the chains: junctions merged,
//! Douglas-Peucker, short members skipped, the embedding restored.

use std::collections::BTreeMap;

use glam::DVec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use super::prune::subnetwork;
use super::{carried_edge, carried_node, Guide, Options};
use crate::geom::{point_segment_distance as point_segment, segment_distance};
use crate::network::Network;

/// A chain of the network: original nodes from one junction to the next (the same node twice
/// for a loop), the original edges between them, and which of its nodes are kept.
pub(super) struct Line {
    pub nodes: Vec<u32>,
    pub edges: Vec<u32>,
    /// Ascending indices into `nodes`: the first and the last always.
    pub kept: Vec<usize>,
    /// The fewest members it may have: three for a loop, two for the second of two lines
    /// between the same junctions, else one.
    pub least: usize,
    pub alive: bool,
}

impl Line {
    pub fn members(&self) -> usize {
        self.kept.len() - 1
    }

    fn closes_loop(&self) -> bool {
        self.nodes[0] == self.nodes[self.nodes.len() - 1]
    }
}

/// One end of a member at a kept node: the member `member` of line `line`, and the kept node
/// at its other end.
#[derive(Clone, Copy, Debug)]
pub(super) struct Leg {
    pub line: u32,
    pub member: u32,
    pub other: u32,
}

pub(super) struct Work {
    pub orig: Vec<DVec3>,
    pub pos: Vec<DVec3>,
    pub lines: Vec<Line>,
    /// Each node's degree in the input (after pruning).
    degree_in: Vec<usize>,
}

pub(super) struct Merges {
    pub merged: usize,
    pub refused: usize,
}

impl Work {
    pub fn new(net: &Network, keep_edge: &[bool]) -> Self {
        let (sub, ids) = subnetwork(net, keep_edge);
        let adj = sub.adjacency();
        let lines = sub
            .chains()
            .into_iter()
            .map(|c| Line {
                kept: vec![0, c.nodes.len() - 1],
                edges: c.edges.iter().map(|&k| ids[k as usize]).collect(),
                nodes: c.nodes,
                least: 1,
                alive: true,
            })
            .collect();
        let orig: Vec<DVec3> = net.nodes.iter().map(|n| n.p).collect();
        Work {
            pos: orig.clone(),
            orig,
            lines,
            degree_in: (0..net.nodes.len() as u32).map(|v| adj.degree(v)).collect(),
        }
    }

    fn length(&self, line: &Line) -> f64 {
        line.nodes
            .windows(2)
            .map(|w| self.orig[w[0] as usize].distance(self.orig[w[1] as usize]))
            .sum()
    }

    /// How many line ends meet at each node.
    fn ends_per_node(&self) -> Vec<usize> {
        let mut d = vec![0; self.pos.len()];
        for l in self.lines.iter().filter(|l| l.alive) {
            d[l.nodes[0] as usize] += 1;
            d[l.nodes[l.nodes.len() - 1] as usize] += 1;
        }
        d
    }

    /// Merges junctions joined by a chain shorter than the merge distance (or the shortest
    /// member), shortest chain first, where the merged joint keeps the input's largest degree
    /// (three where the input had at most three), the chain's nodes stay within the deviation of
    /// the merged node, and no loop collapses.
    pub fn merge_junctions(&mut self, opts: &Options, guide: &Guide) -> Merges {
        let reach = opts.merge_distance.max(opts.min_length);
        let mut out = Merges {
            merged: 0,
            refused: 0,
        };
        if reach <= 0.0 {
            return out;
        }
        let mut degree = self.ends_per_node();
        let mut candidates: Vec<(f64, usize)> = self
            .lines
            .iter()
            .enumerate()
            .filter(|(_, l)| !l.closes_loop())
            .map(|(i, l)| (self.length(l), i))
            .filter(|&(len, _)| len < reach)
            .collect();
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        for (_, i) in candidates {
            let line = &self.lines[i];
            let (a, b) = (line.nodes[0], line.nodes[line.nodes.len() - 1]);
            if !line.alive || a == b || degree[a as usize] < 3 || degree[b as usize] < 3 {
                continue;
            }
            let merged = degree[a as usize] + degree[b as usize] - 2;
            let allowed = 3.max(self.degree_in[a as usize].max(self.degree_in[b as usize]));
            let q = guide.project(0.5 * (self.pos[a as usize] + self.pos[b as usize]));
            let near = line
                .nodes
                .iter()
                .all(|&v| self.orig[v as usize].distance(q) <= opts.max_deviation);
            if merged > allowed || !near || !self.merge_keeps_loops(i, a, b) {
                out.refused += 1;
                continue;
            }
            self.lines[i].alive = false;
            for l in self.lines.iter_mut().filter(|l| l.alive) {
                let last = l.nodes.len() - 1;
                for end in [0, last] {
                    if l.nodes[end] == b {
                        l.nodes[end] = a;
                    }
                }
            }
            self.pos[a as usize] = q;
            degree[a as usize] = merged;
            degree[b as usize] = 0;
            out.merged += 1;
        }
        out
    }

    /// Whether merging `b` into `a` along line `skip` leaves every loop at least three members
    /// long and no two single-edge lines between the same nodes.
    fn merge_keeps_loops(&self, skip: usize, a: u32, b: u32) -> bool {
        let rename = |v: u32| if v == b { a } else { v };
        let mut singles = BTreeMap::new();
        for (i, l) in self.lines.iter().enumerate() {
            if i == skip || !l.alive {
                continue;
            }
            let (x, y) = (rename(l.nodes[0]), rename(l.nodes[l.nodes.len() - 1]));
            if x == y && l.edges.len() < 3 {
                return false;
            }
            if l.edges.len() == 1 && singles.insert((x.min(y), x.max(y)), i).is_some() {
                return false;
            }
        }
        true
    }

    /// Douglas-Peucker on every line at `tol`, then as many more of the farthest nodes as a line
    /// needs to stay a loop (three members) or to differ from a parallel line (two).
    pub fn douglas_peucker(&mut self, tol: f64) {
        let mut first_between = BTreeMap::new();
        for i in 0..self.lines.len() {
            let l = &self.lines[i];
            if !l.alive {
                continue;
            }
            let (a, b) = (l.nodes[0], l.nodes[l.nodes.len() - 1]);
            self.lines[i].least = if a == b {
                3
            } else if first_between.insert((a.min(b), a.max(b)), i).is_some() {
                2
            } else {
                1
            };
            self.fit(i, tol);
        }
    }

    /// Douglas-Peucker on line `i` as its nodes are now, then its farthest nodes up to its least
    /// number of members.
    fn fit(&mut self, i: usize, tol: f64) {
        self.lines[i].kept = douglas_peucker(&self.pos, &self.lines[i].nodes, tol);
        while self.lines[i].members() < self.lines[i].least {
            let l = &self.lines[i];
            let worst = (0..l.members())
                .filter_map(|k| self.farthest(l, k))
                .max_by(|x, y| x.1.total_cmp(&y.1));
            match worst {
                Some((j, _)) => self.insert_kept(i, j),
                None => break,
            }
        }
    }

    /// Gives the lines at `nodes` room: every line with an end at one of them is fitted again
    /// at `tight` from its original positions, with its ends back where they were; other lines
    /// at those ends are fitted again at `tol`. Returns how many lines were fitted.
    pub fn loosen(&mut self, nodes: &[u32], tight: f64, tol: f64) -> usize {
        let at = |l: &Line, v: u32| l.nodes[0] == v || l.nodes[l.nodes.len() - 1] == v;
        let near: Vec<usize> = (0..self.lines.len())
            .filter(|&i| self.lines[i].alive && nodes.iter().any(|&v| at(&self.lines[i], v)))
            .collect();
        let mut ends: Vec<u32> = near
            .iter()
            .flat_map(|&i| {
                let l = &self.lines[i];
                [l.nodes[0], l.nodes[l.nodes.len() - 1]]
            })
            .collect();
        ends.sort_unstable();
        ends.dedup();
        let touched: Vec<usize> = (0..self.lines.len())
            .filter(|&i| self.lines[i].alive && ends.iter().any(|&v| at(&self.lines[i], v)))
            .collect();
        for &v in &ends {
            self.pos[v as usize] = self.orig[v as usize];
        }
        for &i in &touched {
            let n = self.lines[i].nodes.len();
            for j in 1..n - 1 {
                let v = self.lines[i].nodes[j] as usize;
                self.pos[v] = self.orig[v];
            }
            let t = if near.contains(&i) { tight } else { tol };
            self.fit(i, t);
        }
        touched.len()
    }

    /// Moves each junction and tip (on the surface, within `tol` of where it was) to the trial
    /// position where its lines, fitted again, need the fewest members. Returns how many moved.
    pub fn relocate_junctions(&mut self, guide: &Guide, tol: f64) -> usize {
        let mut ends: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (i, l) in self.lines.iter().enumerate().filter(|(_, l)| l.alive) {
            ends.entry(l.nodes[0]).or_default().push(i);
            ends.entry(l.nodes[l.nodes.len() - 1]).or_default().push(i);
        }
        let mut moved = 0;
        for (v, lines) in ends {
            let normal = guide.normals[v as usize];
            if lines.len() == 2 || normal == DVec3::ZERO || lines.windows(2).any(|w| w[0] == w[1]) {
                continue;
            }
            let members = |work: &Work| {
                lines
                    .iter()
                    .map(|&i| work.lines[i].members())
                    .sum::<usize>()
            };
            let home = self.pos[v as usize];
            let kept_home: Vec<Vec<usize>> =
                lines.iter().map(|&i| self.lines[i].kept.clone()).collect();
            let mut best = (members(self), home);
            for trial in guide.ring(home, normal, tol) {
                if trial.distance(self.orig[v as usize]) > tol {
                    continue;
                }
                self.pos[v as usize] = trial;
                for &i in &lines {
                    self.fit(i, tol);
                }
                let m = members(self);
                if m < best.0 {
                    best = (m, trial);
                }
            }
            self.pos[v as usize] = best.1;
            if best.1 == home {
                for (&i, kept) in lines.iter().zip(kept_home) {
                    self.lines[i].kept = kept;
                }
            } else {
                for &i in &lines {
                    self.fit(i, tol);
                }
                moved += 1;
            }
        }
        moved
    }

    /// The node of line `l` between the ends of member `k` farthest from it, and the distance;
    /// None when the member is one original edge.
    fn farthest(&self, l: &Line, k: usize) -> Option<(usize, f64)> {
        let (s, e) = (l.kept[k], l.kept[k + 1]);
        let (pa, pb) = (self.pos[l.nodes[s] as usize], self.pos[l.nodes[e] as usize]);
        (s + 1..e)
            .map(|j| (j, point_segment(self.pos[l.nodes[j] as usize], pa, pb)))
            .max_by(|x, y| x.1.total_cmp(&y.1).then(y.0.cmp(&x.0)))
    }

    fn insert_kept(&mut self, line: usize, j: usize) {
        let kept = &mut self.lines[line].kept;
        if let Err(at) = kept.binary_search(&j) {
            kept.insert(at, j);
        }
    }

    /// Skips a line's kept node where a member is shorter than `min_length` and the merged
    /// member still holds its nodes within the deviation. Returns how many members are still
    /// short.
    pub fn skip_short(&mut self, opts: &Options) -> usize {
        if opts.min_length <= 0.0 {
            return 0;
        }
        let tol = opts.max_deviation;
        for i in 0..self.lines.len() {
            if !self.lines[i].alive {
                continue;
            }
            let least = self.lines[i].least;
            let mut k = 0;
            while k < self.lines[i].members() && self.lines[i].members() > least {
                let l = &self.lines[i];
                let p = |m: usize| self.pos[l.nodes[l.kept[m]] as usize];
                if p(k).distance(p(k + 1)) >= opts.min_length {
                    k += 1;
                    continue;
                }
                // Drop the member's inner end: its start unless that is the line's first node.
                let drop = if k + 1 < l.members() { k + 1 } else { k };
                if drop == 0 {
                    k += 1;
                    continue;
                }
                let (s, e) = (l.kept[drop - 1], l.kept[drop + 1]);
                let (pa, pb) = (self.pos[l.nodes[s] as usize], self.pos[l.nodes[e] as usize]);
                let holds = (s..=e).all(|j| {
                    point_segment(self.orig[l.nodes[j] as usize], pa, pb) <= tol
                        && point_segment(self.pos[l.nodes[j] as usize], pa, pb) <= tol
                });
                if holds {
                    self.lines[i].kept.remove(drop);
                } else {
                    k += 1;
                }
            }
        }
        let mut short = 0;
        for l in self.lines.iter().filter(|l| l.alive) {
            for w in l.kept.windows(2) {
                let (pa, pb) = (
                    self.pos[l.nodes[w[0]] as usize],
                    self.pos[l.nodes[w[1]] as usize],
                );
                if pa.distance(pb) < opts.min_length {
                    short += 1;
                }
            }
        }
        short
    }

    /// Every kept node's legs, indexed by node.
    pub fn legs(&self) -> BTreeMap<u32, Vec<Leg>> {
        let mut legs: BTreeMap<u32, Vec<Leg>> = BTreeMap::new();
        for (i, l) in self.lines.iter().enumerate().filter(|(_, l)| l.alive) {
            for k in 0..l.members() {
                let (a, b) = (l.nodes[l.kept[k]], l.nodes[l.kept[k + 1]]);
                let leg = |other| Leg {
                    line: i as u32,
                    member: k as u32,
                    other,
                };
                legs.entry(a).or_default().push(leg(b));
                legs.entry(b).or_default().push(leg(a));
            }
        }
        legs
    }

    /// The largest distance of the nodes member `k` of line `line` stands for (their original
    /// positions, its end nodes included) from the member as it is now.
    pub fn member_deviation(&self, line: u32, k: u32) -> f64 {
        let l = &self.lines[line as usize];
        let (s, e) = (l.kept[k as usize], l.kept[k as usize + 1]);
        let (pa, pb) = (self.pos[l.nodes[s] as usize], self.pos[l.nodes[e] as usize]);
        (s..=e)
            .map(|j| point_segment(self.orig[l.nodes[j] as usize], pa, pb))
            .fold(0.0, f64::max)
    }

    /// Gives back original nodes until no two members cross (where the input's edges did not)
    /// and the members leave every junction in the order its original edges did about its
    /// normal. Returns how many nodes came back and how many crossings are the input's own.
    pub fn restore_embedding(&mut self, guide: &Guide, max_deviation: f64) -> (usize, usize) {
        let mut restored = 0;
        let mut stuck = 0;
        for _ in 0..64 {
            let mut split: Vec<(usize, usize)> = Vec::new();
            stuck = 0;
            for (x, y) in self.crossings(guide, max_deviation) {
                let before = split.len();
                for (i, k) in [x, y] {
                    if self.lines[i].kept[k + 1] - self.lines[i].kept[k] > 1 {
                        split.push((i, k));
                    }
                }
                if split.len() == before {
                    stuck += 1;
                }
            }
            split.extend(self.reordered_junctions(guide));
            split.sort_unstable();
            split.dedup();
            if split.is_empty() {
                break;
            }
            // Highest member first, so earlier members' indices stay put.
            for &(i, k) in split.iter().rev() {
                let Some((j, _)) = self.farthest(&self.lines[i], k) else {
                    continue;
                };
                self.insert_kept(i, j);
                restored += 1;
            }
        }
        (restored, stuck)
    }

    /// Pairs of members, as (line, member), that cross: in the plane of their ends' normals, and
    /// within twice the deviation of each other in space (so that two sheets of a surface do
    /// not count). Members that share a node do not count.
    fn crossings(
        &self,
        guide: &Guide,
        max_deviation: f64,
    ) -> Vec<((usize, usize), (usize, usize))> {
        type Item = GeomWithData<Rectangle<[f64; 3]>, (u32, u32)>;
        let mut members = Vec::new();
        for (i, l) in self.lines.iter().enumerate().filter(|(_, l)| l.alive) {
            for k in 0..l.members() {
                members.push((i, k, l.nodes[l.kept[k]], l.nodes[l.kept[k + 1]]));
            }
        }
        let items: Vec<Item> = members
            .iter()
            .enumerate()
            .map(|(m, &(_, _, a, b))| {
                let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
                Item::new(
                    Rectangle::from_corners(pa.min(pb).to_array(), pa.max(pb).to_array()),
                    (m as u32, 0),
                )
            })
            .collect();
        let tree = RTree::bulk_load(items);
        let mut out = Vec::new();
        for (m, &(i, k, a, b)) in members.iter().enumerate() {
            let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
            let env = AABB::from_corners(pa.min(pb).to_array(), pa.max(pb).to_array());
            for item in tree.locate_in_envelope_intersecting(&env) {
                let o = item.data.0 as usize;
                if o <= m {
                    continue;
                }
                let (j, q, c, d) = members[o];
                if a == c || a == d || b == c || b == d {
                    continue;
                }
                let normal = [a, b, c, d]
                    .iter()
                    .map(|&v| guide.normals[v as usize])
                    .sum::<DVec3>();
                let (pc, pd) = (self.pos[c as usize], self.pos[d as usize]);
                if cross(pa, pb, pc, pd, normal, 2.0 * max_deviation) {
                    out.push(((i, k), (j, q)));
                }
            }
        }
        out
    }

    /// Members (line, member) at junctions whose members leave in another order about the
    /// normal than the original edges did; only members that can take a node back.
    fn reordered_junctions(&self, guide: &Guide) -> Vec<(usize, usize)> {
        let mut ends: BTreeMap<u32, Vec<(usize, bool)>> = BTreeMap::new();
        for (i, l) in self.lines.iter().enumerate().filter(|(_, l)| l.alive) {
            ends.entry(l.nodes[0]).or_default().push((i, true));
            ends.entry(l.nodes[l.nodes.len() - 1])
                .or_default()
                .push((i, false));
        }
        let mut out = Vec::new();
        for (v, list) in ends {
            let normal = guide.normals[v as usize];
            if list.len() < 3 || normal == DVec3::ZERO {
                continue;
            }
            let (t0, t1) = normal.normalize().any_orthonormal_pair();
            let angle = |d: DVec3| d.dot(t1).atan2(d.dot(t0));
            let order = |now: bool| {
                let mut o: Vec<(f64, usize)> = list
                    .iter()
                    .enumerate()
                    .map(|(s, &(i, start))| {
                        let l = &self.lines[i];
                        let n = l.nodes.len() - 1;
                        let (at, next) = match (start, now) {
                            (true, false) => (self.orig[l.nodes[0] as usize], l.nodes[1]),
                            (false, false) => (self.orig[l.nodes[n] as usize], l.nodes[n - 1]),
                            (true, true) => (self.pos[v as usize], l.nodes[l.kept[1]]),
                            (false, true) => {
                                (self.pos[v as usize], l.nodes[l.kept[l.kept.len() - 2]])
                            }
                        };
                        let there = if now {
                            self.pos[next as usize]
                        } else {
                            self.orig[next as usize]
                        };
                        (angle(there - at), s)
                    })
                    .collect();
                o.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                o.into_iter().map(|(_, s)| s).collect::<Vec<_>>()
            };
            let (was, is) = (order(false), order(true));
            let start = is.iter().position(|&s| s == was[0]).unwrap_or(0);
            let same = (0..was.len()).all(|k| is[(start + k) % is.len()] == was[k]);
            if same {
                continue;
            }
            for &(i, start) in &list {
                let l = &self.lines[i];
                let k = if start { 0 } else { l.members() - 1 };
                if l.kept[k + 1] - l.kept[k] > 1 {
                    out.push((i, k));
                }
            }
        }
        out
    }

    /// The simplified network: kept nodes in the input's order, members line by line; and each
    /// node's index in the input.
    pub fn network(&self, net: &Network, guide: &Guide) -> (Network, Vec<u32>) {
        let mut used = vec![false; self.pos.len()];
        for l in self.lines.iter().filter(|l| l.alive) {
            for &j in &l.kept {
                used[l.nodes[j] as usize] = true;
            }
        }
        let origin: Vec<u32> = (0..self.pos.len() as u32)
            .filter(|&v| used[v as usize])
            .collect();
        let mut index = vec![u32::MAX; self.pos.len()];
        for (new, &old) in origin.iter().enumerate() {
            index[old as usize] = new as u32;
        }
        let nodes = origin
            .iter()
            .map(|&v| carried_node(&net.nodes[v as usize], self.pos[v as usize], guide))
            .collect();
        let mut edges = Vec::new();
        for l in self.lines.iter().filter(|l| l.alive) {
            for w in l.kept.windows(2) {
                let (a, b) = (l.nodes[w[0]], l.nodes[w[1]]);
                edges.push(carried_edge(
                    net,
                    index[a as usize],
                    index[b as usize],
                    &l.edges[w[0]..w[1]],
                ));
            }
        }
        let mut meta = net.meta.clone();
        meta.tags.insert(
            "simplified".into(),
            format!("from {} nodes, {} edges", net.nodes.len(), net.edges.len()),
        );
        (Network { nodes, edges, meta }, origin)
    }
}

/// Douglas-Peucker over the nodes of one chain: indices of the nodes kept, ends included.
fn douglas_peucker(pos: &[DVec3], nodes: &[u32], tol: f64) -> Vec<usize> {
    let last = nodes.len() - 1;
    let mut keep = vec![false; nodes.len()];
    keep[0] = true;
    keep[last] = true;
    let mut stack = vec![(0usize, last)];
    while let Some((s, e)) = stack.pop() {
        if e <= s + 1 {
            continue;
        }
        let (pa, pb) = (pos[nodes[s] as usize], pos[nodes[e] as usize]);
        let (mut worst, mut at) = (-1.0, s);
        for j in s + 1..e {
            let d = point_segment(pos[nodes[j] as usize], pa, pb);
            if d > worst {
                worst = d;
                at = j;
            }
        }
        // A loop's two ends are one node: its farthest node from there is always kept.
        if worst > tol || pa == pb {
            keep[at] = true;
            stack.push((s, at));
            stack.push((at, e));
        }
    }
    (0..nodes.len()).filter(|&j| keep[j]).collect()
}

/// Whether segments a–b and c–d cross in the plane ⊥ `normal` at points within `near` of each
/// other in space; with no normal, whether they meet in space.
fn cross(a: DVec3, b: DVec3, c: DVec3, d: DVec3, normal: DVec3, near: f64) -> bool {
    let Some(n) = normal.try_normalize() else {
        let scale = (b - a).length().max((d - c).length());
        return segment_distance(a, b, c, d) <= 1e-9 * scale;
    };
    let (t0, t1) = n.any_orthonormal_pair();
    let flat = |p: DVec3| (p.dot(t0), p.dot(t1));
    let (a2, b2, c2, d2) = (flat(a), flat(b), flat(c), flat(d));
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    let (o1, o2) = (orient(a2, b2, c2), orient(a2, b2, d2));
    let (o3, o4) = (orient(c2, d2, a2), orient(c2, d2, b2));
    if o1 * o2 > 0.0 || o3 * o4 > 0.0 || (o1 == 0.0 && o2 == 0.0) {
        return false;
    }
    let s = o3 / (o3 - o4);
    let t = o1 / (o1 - o2);
    (a + s * (b - a)).distance(c + t * (d - c)) <= near
}
