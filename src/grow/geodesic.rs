//! Geodesic veins along mesh edges (Bachman, "Vein Structures"): a tree grows from a root
//! vertex through the edges of a mesh of any topology towards source vertices.
//!
//! Each iteration:
//! 1. every live source has a shortest mesh-edge path to the tree; the tree vertex at its end
//!    is a growth site, and the path's first edge (leaving the tree) picks up one unit of
//!    weight;
//! 2. each growth site grows along the edge to a vertex off the tree closest to the weighted
//!    centre of its weighted edges' far ends;
//! 3. sources the tree now touches are removed; repeat until none remain.
//!
//! Bachman reran the shortest paths every iteration, which he reports as very slow on fine
//! meshes. Here one multi-source Dijkstra labelling (distance to the tree, the site at the
//! path's end, the path's first vertex off the tree) is kept, and only updated from the
//! vertices the tree gained: the tree only grows, so distances only fall. The labels keep the
//! shortest-path forest they came along; a vertex joining the tree hands its subtree the same
//! paths, now ending at it, by a walk down the forest (no priority queue), and a Dijkstra then
//! enters only the vertices some path through the new tree vertices brings strictly closer.
//! Each source reads its site and first edge in O(1). The baselines live in
//! `benches/geodesic.rs`: a fresh multi-source Dijkstra every iteration (`Labels::recompute`),
//! and Bachman's own step, a Dijkstra from each source every iteration.
//!
//! Output: the tree as a `Network` whose every edge is a mesh edge (or, with smoothing,
//! Catmull-Rom resampled branches snapped back onto the surface); radii grow with the number of
//! sources each edge carries, r = tip · w^(1/n) (Murray's law with every reached source a tip).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rstar::primitives::GeomWithData;
use rstar::RTree;

use super::surface::{birth_for_count, poisson_points, used_vertices, Channel, SurfaceError};
use crate::mesh::closest::SurfaceIndex;
use crate::mesh::TriMesh;
use crate::network::{Edge, Network, Node};

/// The mesh's edge graph, compressed rows: the neighbours of v are
/// `targets[offsets[v]..offsets[v + 1]]`, with their edge lengths.
pub struct MeshGraph {
    pub offsets: Vec<u32>,
    pub targets: Vec<u32>,
    pub lengths: Vec<f64>,
}

impl MeshGraph {
    pub fn new(mesh: &TriMesh) -> Self {
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 6);
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let n = mesh.positions.len();
        let mut offsets = vec![0u32; n + 1];
        for &(a, _) in &pairs {
            offsets[a as usize + 1] += 1;
        }
        for v in 0..n {
            offsets[v + 1] += offsets[v];
        }
        let lengths = pairs
            .iter()
            .map(|&(a, b)| mesh.positions[a as usize].distance(mesh.positions[b as usize]))
            .collect();
        MeshGraph {
            offsets,
            targets: pairs.into_iter().map(|(_, b)| b).collect(),
            lengths,
        }
    }

    pub fn vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Neighbours of `v` and the lengths of the edges to them.
    pub fn neighbours(&self, v: u32) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize;
        self.targets[r.clone()]
            .iter()
            .copied()
            .zip(self.lengths[r].iter().copied())
    }
}

/// No vertex: the first vertex of a tree vertex's path, or an unreached vertex's site.
pub const NONE: u32 = u32::MAX;

/// The multi-source shortest-path labelling from the tree: for every vertex its distance to
/// the tree, the tree vertex its path ends at (the growth site), and the path's first vertex
/// off the tree; and the shortest-path forest the labels came along, so that a vertex joining
/// the tree can hand its subtree the shorter paths without a priority queue.
pub struct Labels {
    pub dist: Vec<f64>,
    pub site: Vec<u32>,
    pub first: Vec<u32>,
    /// The vertex each label came from (NONE on the tree, off it, and after `recompute`) and
    /// the length of the edge to it.
    from: Vec<u32>,
    from_len: Vec<f64>,
    /// Each vertex's children in the forest as a doubly linked list.
    child: Vec<u32>,
    next: Vec<u32>,
    prev: Vec<u32>,
    heap: BinaryHeap<Entry>,
    stack: Vec<u32>,
    shifted: Vec<u32>,
    /// Vertices whose label changed in the last `relabel` (a measure of the work done).
    pub changed: usize,
}

#[derive(PartialEq)]
struct Entry(f64, u32);

impl Eq for Entry {}

impl Ord for Entry {
    /// Smallest distance first, then smallest vertex: a min-heap with a fixed order.
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Labels {
    /// Every vertex unreached.
    pub fn new(vertices: usize) -> Self {
        Labels {
            dist: vec![f64::INFINITY; vertices],
            site: vec![NONE; vertices],
            first: vec![NONE; vertices],
            from: vec![NONE; vertices],
            from_len: vec![0.0; vertices],
            child: vec![NONE; vertices],
            next: vec![NONE; vertices],
            prev: vec![NONE; vertices],
            heap: BinaryHeap::new(),
            stack: Vec::new(),
            shifted: Vec::new(),
            changed: 0,
        }
    }

    /// The recompute-everything baseline: forgets every label and runs a plain multi-source
    /// Dijkstra from the whole tree (no forest kept).
    pub fn recompute(&mut self, g: &MeshGraph, in_tree: &[bool], tree: &[u32]) {
        self.dist.fill(f64::INFINITY);
        self.site.fill(NONE);
        self.first.fill(NONE);
        self.from.fill(NONE);
        self.child.fill(NONE);
        self.changed = 0;
        for &s in tree {
            self.dist[s as usize] = 0.0;
            self.site[s as usize] = s;
            self.heap.push(Entry(0.0, s));
        }
        self.dijkstra(g, in_tree, false);
    }

    /// Brings the labels up to date after `seeds` joined the tree (`in_tree` already says so).
    ///
    /// A vertex whose path ran through a seed keeps that path, now ending at the seed: the
    /// seeds' subtrees of the forest are walked top down and each label recomputed as its
    /// parent's plus the edge (the sum a fresh Dijkstra would form along the same path), with
    /// the seed as site. Then a Dijkstra from the edges leaving the seeds and those subtrees
    /// enters only the vertices it brings strictly closer. The result is the fresh labelling's
    /// distances exactly; where two paths are equally long, the site may differ.
    pub fn relabel(&mut self, g: &MeshGraph, in_tree: &[bool], seeds: &[u32]) {
        for &s in seeds {
            self.unlink(s);
            self.dist[s as usize] = 0.0;
            self.site[s as usize] = s;
            self.first[s as usize] = NONE;
        }
        self.shifted.clear();
        for &s in seeds {
            self.push_children(s);
            while let Some(v) = self.stack.pop() {
                let p = self.from[v as usize];
                self.dist[v as usize] = self.dist[p as usize] + self.from_len[v as usize];
                self.site[v as usize] = s;
                self.first[v as usize] = if p == s { v } else { self.first[p as usize] };
                self.shifted.push(v);
                self.push_children(v);
            }
        }
        self.changed = seeds.len() + self.shifted.len();
        for &x in seeds {
            self.relax(g, in_tree, x, true);
        }
        for i in 0..self.shifted.len() {
            self.relax(g, in_tree, self.shifted[i], true);
        }
        self.dijkstra(g, in_tree, true);
    }

    /// Settles the queue, keeping the forest up to date if `forest`.
    fn dijkstra(&mut self, g: &MeshGraph, in_tree: &[bool], forest: bool) {
        while let Some(Entry(d, x)) = self.heap.pop() {
            if d > self.dist[x as usize] {
                continue;
            }
            self.changed += 1;
            self.relax(g, in_tree, x, forest);
        }
    }

    fn push_children(&mut self, v: u32) {
        let mut c = self.child[v as usize];
        while c != NONE {
            self.stack.push(c);
            c = self.next[c as usize];
        }
    }

    /// Gives each neighbour of `x` the path through `x` where that is strictly shorter (and
    /// makes it `x`'s child in the forest if `forest`).
    fn relax(&mut self, g: &MeshGraph, in_tree: &[bool], x: u32, forest: bool) {
        let d = self.dist[x as usize];
        let (site, first) = (self.site[x as usize], self.first[x as usize]);
        let from_tree = in_tree[x as usize];
        for (y, len) in g.neighbours(x) {
            let nd = d + len;
            if nd < self.dist[y as usize] {
                self.dist[y as usize] = nd;
                self.site[y as usize] = site;
                self.first[y as usize] = if from_tree { y } else { first };
                if forest {
                    self.unlink(y);
                    self.link(y, x, len);
                }
                self.heap.push(Entry(nd, y));
            }
        }
    }

    /// Makes `v` a child of `p` in the forest (`v` not linked).
    fn link(&mut self, v: u32, p: u32, len: f64) {
        let head = self.child[p as usize];
        self.from[v as usize] = p;
        self.from_len[v as usize] = len;
        self.prev[v as usize] = NONE;
        self.next[v as usize] = head;
        if head != NONE {
            self.prev[head as usize] = v;
        }
        self.child[p as usize] = v;
    }

    /// Takes `v` out of its parent's children (nothing if it has no parent).
    fn unlink(&mut self, v: u32) {
        let p = self.from[v as usize];
        if p == NONE {
            return;
        }
        let (before, after) = (self.prev[v as usize], self.next[v as usize]);
        if before == NONE {
            self.child[p as usize] = after;
        } else {
            self.next[before as usize] = after;
        }
        if after != NONE {
            self.prev[after as usize] = before;
        }
        self.from[v as usize] = NONE;
    }
}

/// The vertices a mesh-edge path leads to from `root` (root included).
pub fn reachable(g: &MeshGraph, root: u32) -> Vec<bool> {
    let mut seen = vec![false; g.vertices()];
    let mut stack = vec![root];
    seen[root as usize] = true;
    while let Some(v) = stack.pop() {
        for (u, _) in g.neighbours(v) {
            if !std::mem::replace(&mut seen[u as usize], true) {
                stack.push(u);
            }
        }
    }
    seen
}

/// Sampled source vertices, and how many samples had no path from the root.
pub struct Sampled {
    pub vertices: Vec<u32>,
    pub skipped: usize,
}

/// About `count` source vertices: Poisson-disk points on the surface (spaced by the density
/// channel, dark = dense, or uniformly), each moved to its nearest vertex; repeats dropped, and
/// points whose vertex the root cannot reach skipped.
pub fn sample_sources(
    mesh: &TriMesh,
    g: &MeshGraph,
    root: u32,
    count: usize,
    density: Option<Channel>,
    seed: u64,
) -> Result<Sampled, SurfaceError> {
    let b = birth_for_count(mesh, count, density);
    let hi = if density.is_some() { 2.0 * b } else { b };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let points = poisson_points(mesh, b, hi, density, &mut rng)?;
    let reach = reachable(g, root);
    let used = used_vertices(mesh);
    let tree: RTree<GeomWithData<[f64; 3], u32>> = RTree::bulk_load(
        (0..mesh.positions.len())
            .filter(|&v| used[v])
            .map(|v| GeomWithData::new(mesh.positions[v].to_array(), v as u32))
            .collect(),
    );
    let mut vertices = Vec::with_capacity(points.len());
    let mut skipped = 0;
    for p in points {
        match tree.nearest_neighbor(&p.to_array()) {
            Some(v) if reach[v.data as usize] => vertices.push(v.data),
            _ => skipped += 1,
        }
    }
    vertices.sort_unstable();
    vertices.dedup();
    Ok(Sampled { vertices, skipped })
}

/// How the labels are kept up to date as the tree grows. The library's way is `Incremental`;
/// the benchmark's baseline recomputes everything.
pub trait Relabel {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], labels: &mut Labels);
}

/// Dijkstra from the vertices the tree gained only.
pub struct Incremental;

impl Relabel for Incremental {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], labels: &mut Labels) {
        labels.relabel(g, in_tree, added);
    }
}

#[derive(Clone, Debug)]
pub struct VeinOptions {
    /// Radius of an edge carrying one source, mm.
    pub tip_radius: f64,
    /// r = tip · w^(1/murray) for an edge carrying w sources. Default 3.
    pub murray: f64,
    /// Catmull-Rom points added between neighbouring vertices of a branch (0: the mesh edges
    /// themselves).
    pub smooth: usize,
}

impl Default for VeinOptions {
    fn default() -> Self {
        VeinOptions {
            tip_radius: 0.5,
            murray: 3.0,
            smooth: 0,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VeinError {
    #[error("the surface has no triangles")]
    NoTriangles,
    #[error("root= {0}: the mesh has {1} vertices")]
    Root(u32, usize),
    #[error("source= {0}: the mesh has {1} vertices")]
    Source(u32, usize),
    #[error("source= {0}: no mesh edge path leads from the root (vertex {1}) to it")]
    Unreachable(u32, u32),
    #[error("no sources apart from the root: give source= V or sources= N")]
    NoSources,
    #[error("tip_radius= must be a positive distance in mm, got {0}")]
    TipRadius(f64),
    #[error("murray= must be positive, got {0}")]
    Murray(f64),
}

/// The grown tree on the mesh.
#[derive(Clone, Debug)]
pub struct VeinTree {
    /// Tree vertices in the order they joined, the root first.
    pub order: Vec<u32>,
    /// Parent of each mesh vertex on the tree (NONE for the root and off the tree).
    pub parent: Vec<u32>,
    /// The sources, as given (duplicates and the root dropped).
    pub sources: Vec<u32>,
    pub iterations: usize,
    /// Vertex labels changed over the whole run: the work the shortest paths took.
    pub relabelled: usize,
}

/// Grows veins from `root` to every source, keeping the labels up to date with `relabel`.
pub fn grow_veins(
    g: &MeshGraph,
    positions: &[DVec3],
    root: u32,
    sources: &[u32],
    relabel: &mut impl Relabel,
) -> Result<VeinTree, VeinError> {
    let n = g.vertices();
    if root as usize >= n {
        return Err(VeinError::Root(root, n));
    }
    if let Some(&s) = sources.iter().find(|&&s| s as usize >= n) {
        return Err(VeinError::Source(s, n));
    }
    let mut live: Vec<u32> = sources.iter().copied().filter(|&s| s != root).collect();
    live.sort_unstable();
    live.dedup();
    if live.is_empty() {
        return Err(VeinError::NoSources);
    }
    let given = live.clone();
    let mut in_tree = vec![false; n];
    let mut parent = vec![NONE; n];
    in_tree[root as usize] = true;
    let mut order = vec![root];
    let mut labels = Labels::new(n);
    relabel.update(g, &in_tree, &[root], &mut labels);
    let mut relabelled = labels.changed;
    if let Some(&s) = live
        .iter()
        .find(|&&s| labels.dist[s as usize].is_infinite())
    {
        return Err(VeinError::Unreachable(s, root));
    }
    let mut iterations = 0;
    // (site, first vertex) of every live source's path, then the weighted pulls per site.
    let mut pulls: Vec<(u32, u32)> = Vec::with_capacity(live.len());
    let mut added: Vec<u32> = Vec::new();
    while !live.is_empty() {
        iterations += 1;
        pulls.clear();
        pulls.extend(
            live.iter()
                .map(|&s| (labels.site[s as usize], labels.first[s as usize])),
        );
        pulls.sort_unstable();
        added.clear();
        let mut i = 0;
        while i < pulls.len() {
            let site = pulls[i].0;
            let mut j = i;
            let (mut centre, mut weight) = (DVec3::ZERO, 0.0);
            while j < pulls.len() && pulls[j].0 == site {
                centre += positions[pulls[j].1 as usize];
                weight += 1.0;
                j += 1;
            }
            centre /= weight;
            // The edge off the tree whose far end is closest to the weighted centre.
            let pick = g
                .neighbours(site)
                .filter(|&(u, _)| !in_tree[u as usize])
                .map(|(u, _)| (positions[u as usize].distance_squared(centre), u))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            if let Some((_, u)) = pick {
                in_tree[u as usize] = true;
                parent[u as usize] = site;
                order.push(u);
                added.push(u);
            }
            i = j;
        }
        live.retain(|&s| !in_tree[s as usize]);
        relabel.update(g, &in_tree, &added, &mut labels);
        relabelled += labels.changed;
    }
    Ok(VeinTree {
        order,
        parent,
        sources: given,
        iterations,
        relabelled,
    })
}

impl VeinTree {
    /// Sources carried by the edge into each tree vertex (0 off the tree).
    pub fn weights(&self) -> Vec<u32> {
        let mut w = vec![0u32; self.parent.len()];
        for &s in &self.sources {
            w[s as usize] += 1;
        }
        for &v in self.order.iter().rev() {
            let p = self.parent[v as usize];
            if p != NONE {
                w[p as usize] += w[v as usize];
            }
        }
        w
    }
}

/// The tree as a network: nodes in the order they joined (the root first), each edge from a
/// parent to its child, radius from the sources it carries; with `smooth` > 0 each branch
/// between branch points is resampled as a Catmull-Rom curve snapped onto the surface.
pub fn to_network(
    mesh: &TriMesh,
    tree: &VeinTree,
    opts: &VeinOptions,
) -> Result<Network, VeinError> {
    if !(opts.tip_radius.is_finite() && opts.tip_radius > 0.0) {
        return Err(VeinError::TipRadius(opts.tip_radius));
    }
    if !(opts.murray.is_finite() && opts.murray > 0.0) {
        return Err(VeinError::Murray(opts.murray));
    }
    let index = SurfaceIndex::new(mesh);
    let w = tree.weights();
    let radius = |v: u32| opts.tip_radius * (w[v as usize].max(1) as f64).powf(1.0 / opts.murray);
    let mut id = vec![NONE; mesh.positions.len()];
    let mut net = Network::default();
    for (k, &v) in tree.order.iter().enumerate() {
        id[v as usize] = k as u32;
        net.nodes.push(Node {
            p: mesh.positions[v as usize],
            normal: Some(index.vertex_normal(v)),
            radius: radius(v),
        });
    }
    for &v in &tree.order[1..] {
        net.edges.push(Edge {
            a: id[tree.parent[v as usize] as usize],
            b: id[v as usize],
            radius: radius(v),
        });
    }
    if opts.smooth > 0 {
        net = smooth(&net, &index, opts.smooth);
    }
    net.meta.generator = Some("veins/geodesic".into());
    let p = &mut net.meta.parameters;
    p.insert("sources".into(), tree.sources.len().into());
    p.insert("iterations".into(), tree.iterations.into());
    p.insert("tip_radius".into(), opts.tip_radius.into());
    p.insert("murray".into(), opts.murray.into());
    p.insert("smooth".into(), opts.smooth.into());
    Ok(net)
}

/// Each branch (a chain between nodes of degree other than 2) as a uniform Catmull-Rom curve through its nodes with `k` points added per span, every point snapped to
/// the surface; radii are interpolated. Branch points and tips keep their places.
fn smooth(net: &Network, index: &SurfaceIndex, k: usize) -> Network {
    let mut out = Network {
        nodes: net.nodes.clone(),
        edges: Vec::new(),
        meta: net.meta.clone(),
    };
    for chain in net.chains() {
        let nodes = &chain.nodes;
        let at = |i: isize| {
            let i = i.clamp(0, nodes.len() as isize - 1) as usize;
            net.nodes[nodes[i] as usize]
        };
        for s in 0..nodes.len() - 1 {
            let (p0, p1, p2, p3) = (
                at(s as isize - 1).p,
                at(s as isize).p,
                at(s as isize + 1).p,
                at(s as isize + 2).p,
            );
            let (r1, r2) = (at(s as isize).radius, at(s as isize + 1).radius);
            let mut prev = nodes[s];
            for j in 1..=k {
                let t = j as f64 / (k + 1) as f64;
                let q = catmull_rom(p0, p1, p2, p3, t);
                let Some(c) = index.closest(q) else { continue };
                let r = r1 + (r2 - r1) * t;
                let id = out.nodes.len() as u32;
                out.nodes.push(Node {
                    p: c.point,
                    normal: Some(index.normal(&c)),
                    radius: r,
                });
                out.edges.push(Edge {
                    a: prev,
                    b: id,
                    radius: r,
                });
                prev = id;
            }
            out.edges.push(Edge {
                a: prev,
                b: nodes[s + 1],
                radius: r2,
            });
        }
    }
    out
}

/// The uniform Catmull-Rom segment from p1 (t = 0) to p2 (t = 1).
fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, t: f64) -> DVec3 {
    let (t2, t3) = (t * t, t * t * t);
    (p1 * 2.0
        + (p2 - p0) * t
        + (p0 * 2.0 - p1 * 5.0 + p2 * 4.0 - p3) * t2
        + (p1 * 3.0 - p0 - p2 * 3.0 + p3) * t3)
        * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    /// A torus grid with every vertex jittered, so no two paths are equally long.
    fn jittered_torus(around: usize, across: usize, seed: u64) -> TriMesh {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut positions = Vec::new();
        for i in 0..around {
            let u =
                std::f64::consts::TAU * (i as f64 + rng.random_range(-0.3..0.3)) / around as f64;
            for j in 0..across {
                let v = std::f64::consts::TAU * (j as f64 + rng.random_range(-0.3..0.3))
                    / across as f64;
                let r = 30.0 + 10.0 * v.cos();
                positions.push(DVec3::new(r * u.cos(), r * u.sin(), 10.0 * v.sin()));
            }
        }
        let id = |i: usize, j: usize| ((i % around) * across + j % across) as u32;
        let mut triangles = Vec::new();
        for i in 0..around {
            for j in 0..across {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        TriMesh {
            positions,
            triangles,
            colors: None,
        }
    }

    struct Recompute(Vec<u32>);

    impl Relabel for Recompute {
        fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], l: &mut Labels) {
            self.0.extend_from_slice(added);
            l.recompute(g, in_tree, &self.0);
        }
    }

    #[test]
    fn incremental_labels_grow_the_same_tree_as_recomputing_them() {
        for seed in 1..4 {
            let mesh = jittered_torus(40, 20, seed);
            let g = MeshGraph::new(&mesh);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let sources: Vec<u32> = (0..60).map(|_| rng.random_range(0..800)).collect();
            let a = grow_veins(&g, &mesh.positions, 0, &sources, &mut Incremental).expect("grows");
            let b = grow_veins(&g, &mesh.positions, 0, &sources, &mut Recompute(Vec::new()))
                .expect("grows");
            assert!(a.iterations > 5);
            assert_eq!(a.order, b.order, "seed {seed}");
            assert_eq!(a.parent, b.parent, "seed {seed}");
            assert!(a.relabelled < b.relabelled);
            for s in &a.sources {
                assert!(a.order.contains(s), "source {s} reached");
            }
        }
    }

    /// Runs the incremental update and checks its distances against a fresh Dijkstra's
    /// after every iteration.
    struct Checked {
        tree: Vec<u32>,
        fresh: Labels,
        iterations: usize,
    }

    impl Relabel for Checked {
        fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], l: &mut Labels) {
            Incremental.update(g, in_tree, added, l);
            self.tree.extend_from_slice(added);
            self.fresh.recompute(g, in_tree, &self.tree);
            assert_eq!(l.dist, self.fresh.dist, "iteration {}", self.iterations);
            for v in 0..l.dist.len() {
                // Equally long paths may end at different sites, but each label's site and
                // first vertex must be a tree vertex and its neighbour off the tree.
                let (site, first) = (l.site[v], l.first[v]);
                assert!(in_tree[site as usize]);
                if in_tree[v] {
                    assert_eq!((site, first), (v as u32, NONE));
                } else {
                    assert!(!in_tree[first as usize]);
                    assert!(g.neighbours(site).any(|(u, _)| u == first));
                }
            }
            self.iterations += 1;
        }
    }

    #[test]
    fn incremental_distances_equal_a_fresh_dijkstra_after_every_iteration() {
        // A regular torus (many equally long paths) and a jittered one.
        let regular = {
            let mut m = jittered_torus(36, 18, 1);
            for (k, p) in m.positions.iter_mut().enumerate() {
                let (i, j) = (k / 18, k % 18);
                let (u, v) = (
                    std::f64::consts::TAU * i as f64 / 36.0,
                    std::f64::consts::TAU * j as f64 / 18.0,
                );
                let r = 30.0 + 10.0 * v.cos();
                *p = DVec3::new(r * u.cos(), r * u.sin(), 10.0 * v.sin());
            }
            m
        };
        for mesh in [regular, jittered_torus(36, 18, 9)] {
            let g = MeshGraph::new(&mesh);
            let mut rng = ChaCha8Rng::seed_from_u64(4);
            let sources: Vec<u32> = (0..80).map(|_| rng.random_range(0..648)).collect();
            let mut checked = Checked {
                tree: Vec::new(),
                fresh: Labels::new(g.vertices()),
                iterations: 0,
            };
            let tree = grow_veins(&g, &mesh.positions, 7, &sources, &mut checked).expect("grows");
            assert!(checked.iterations > 10);
            assert!(tree.sources.iter().all(|s| tree.order.contains(s)));
        }
    }

    #[test]
    fn weights_count_the_sources_downstream() {
        // A path 0-1-2-3 with sources 2 and 3: edges into 1, 2, 3 carry 2, 2, 1.
        let tree = VeinTree {
            order: vec![0, 1, 2, 3],
            parent: vec![NONE, 0, 1, 2],
            sources: vec![2, 3],
            iterations: 3,
            relabelled: 0,
        };
        assert_eq!(tree.weights(), vec![2, 2, 2, 1]);
    }

    #[test]
    fn unreachable_and_out_of_range_sources_are_named() {
        // Two separate triangles.
        let mesh = TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(5.0, 0.0, 0.0),
                DVec3::new(6.0, 0.0, 0.0),
                DVec3::new(5.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [3, 4, 5]],
            colors: None,
        };
        let g = MeshGraph::new(&mesh);
        let grow = |s: &[u32]| grow_veins(&g, &mesh.positions, 0, s, &mut Incremental).err();
        assert_eq!(grow(&[4]), Some(VeinError::Unreachable(4, 0)));
        assert_eq!(grow(&[9]), Some(VeinError::Source(9, 6)));
        assert_eq!(grow(&[2]), None);
        assert_eq!(grow(&[0]), Some(VeinError::NoSources));
    }
}
