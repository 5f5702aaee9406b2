//! The cell graph (Hart, "Growth Forms"): cells are the vertices of a triangulated closed
//! oriented surface, adjacency its edges.
//!
//! Stored as a rotation system: each cell lists its neighbours counter-clockwise seen from
//! outside, so the faces are the triples (v, rᵢ, rᵢ₊₁). The faces, their orientation and the
//! manifold property all follow from the lists; [`CellGraph::check`] verifies that they do.
//! Division (the paper's Figure 2) edits the lists of the cell and its ring directly; the hole
//! (Figure 9) rebuilds the lists of the cells it touches from their faces.

use std::collections::BTreeMap;

/// Why the graph is not a triangulated closed oriented manifold.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GraphError {
    #[error("cell {cell}: {problem}")]
    Cell { cell: u32, problem: String },
    #[error("the graph has {components} components")]
    Components { components: usize },
    #[error("V − E + F = {euler} is odd or above 2: not a closed oriented surface")]
    Euler { euler: i64 },
}

/// A triangulated closed oriented manifold of cells.
#[derive(Clone, Debug, PartialEq)]
pub struct CellGraph {
    nbrs: Vec<Vec<u32>>,
}

/// The counts of [`CellGraph::check`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Census {
    pub cells: usize,
    pub edges: usize,
    pub faces: usize,
    pub genus: usize,
    pub min_degree: usize,
    pub max_degree: usize,
}

/// Neighbour lists saved before an operation that may be undone.
pub struct Saved {
    len: usize,
    lists: Vec<(u32, Vec<u32>)>,
}

/// How a division placed its two cells: the ring indices of the two neighbours that gained an
/// edge, and the new cell's id (the dividing cell keeps its id as the other child).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    pub kept: u32,
    pub new: u32,
    /// Neighbours joined to both children.
    pub shared: [u32; 2],
}

impl CellGraph {
    /// Builds the rotation system of a closed oriented triangle surface (faces counter-clockwise
    /// seen from outside).
    pub fn from_faces(cells: usize, faces: &[[u32; 3]]) -> Result<CellGraph, GraphError> {
        let mut g = CellGraph {
            nbrs: vec![Vec::new(); cells],
        };
        let mut around: Vec<Vec<(u32, u32)>> = vec![Vec::new(); cells];
        for f in faces {
            for k in 0..3 {
                let (v, a, b) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
                around
                    .get_mut(v as usize)
                    .ok_or_else(|| cell_error(v, "index out of range"))?
                    .push((a, b));
            }
        }
        for (v, pairs) in around.iter().enumerate() {
            g.nbrs[v] = chain(v as u32, pairs)?;
        }
        g.check()?;
        Ok(g)
    }

    /// The tetrahedron every form starts from, with its corner positions (unit edges).
    pub fn tetrahedron() -> (CellGraph, [glam::DVec3; 4]) {
        let s = 0.5 / 2f64.sqrt();
        let p = [
            glam::DVec3::new(s, s, s),
            glam::DVec3::new(s, -s, -s),
            glam::DVec3::new(-s, s, -s),
            glam::DVec3::new(-s, -s, s),
        ];
        let faces = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        let g = CellGraph::from_faces(4, &faces).expect("the tetrahedron is a closed surface");
        (g, p)
    }

    pub fn len(&self) -> usize {
        self.nbrs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nbrs.is_empty()
    }

    pub fn neighbours(&self, v: u32) -> &[u32] {
        &self.nbrs[v as usize]
    }

    pub fn degree(&self, v: u32) -> usize {
        self.nbrs[v as usize].len()
    }

    pub fn adjacent(&self, a: u32, b: u32) -> bool {
        self.nbrs[a as usize].contains(&b)
    }

    /// Every face once, counter-clockwise from outside, led by its smallest cell.
    pub fn faces(&self) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(2 * self.nbrs.len());
        for (v, ring) in self.nbrs.iter().enumerate() {
            let v = v as u32;
            for k in 0..ring.len() {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                if v < a && v < b {
                    out.push([v, a, b]);
                }
            }
        }
        out
    }

    /// Divides `cell` as the paper's Figure 2: the cell is replaced by two joined cells whose
    /// n + 2 edges reach its n neighbours. Ring positions `i` and `j` (distinct) are the two
    /// neighbours that join both children; the kept child takes the arc from i to j.
    pub fn divide(&mut self, cell: u32, i: usize, j: usize) -> Split {
        let ring = self.nbrs[cell as usize].clone();
        let n = ring.len();
        debug_assert!(i < n && j < n && i != j);
        let new = self.nbrs.len() as u32;
        let arc = |from: usize, to: usize| {
            let mut out = Vec::new();
            let mut k = from;
            loop {
                out.push(ring[k]);
                if k == to {
                    break out;
                }
                k = (k + 1) % n;
            }
        };
        let mut kept = arc(i, j);
        let mut other = arc(j, i);
        // Cells strictly inside the new cell's arc now see it instead of the old one.
        for &u in &other[1..other.len() - 1] {
            replace(&mut self.nbrs[u as usize], cell, &[new]);
        }
        // Going round ring[i]: ring[i+1], cell, ring[i−1] becomes ring[i+1], kept, new, ring[i−1].
        replace(&mut self.nbrs[ring[i] as usize], cell, &[cell, new]);
        replace(&mut self.nbrs[ring[j] as usize], cell, &[new, cell]);
        kept.push(new);
        other.push(cell);
        self.nbrs[cell as usize] = kept;
        self.nbrs.push(other);
        Split {
            kept: cell,
            new,
            shared: [ring[i], ring[j]],
        }
    }

    /// The neighbour lists of `cells`, to put back with [`CellGraph::restore`].
    pub fn save(&self, cells: &[u32]) -> Saved {
        Saved {
            len: self.nbrs.len(),
            lists: cells
                .iter()
                .map(|&v| (v, self.nbrs[v as usize].clone()))
                .collect(),
        }
    }

    /// Undoes every change since `save`, if it touched only the saved cells and added cells.
    pub fn restore(&mut self, saved: Saved) {
        self.nbrs.truncate(saved.len);
        for (v, list) in saved.lists {
            self.nbrs[v as usize] = list;
        }
    }

    /// Replaces cells `p` and `q` by a tube: the ring of `p`, then `rings`, then the ring of `q`,
    /// consecutive loops joined by the triangles `zip(x, y)` gives (see [`zip_loops`]). The
    /// rings hold `p`, `q` and new cells (ids from `len()` on), in the rotational sense of q's
    /// ring seen from p. The genus grows by one. `p` and `q` must be at least four hops apart.
    pub fn tunnel(
        &mut self,
        p: u32,
        q: u32,
        rings: &[Vec<u32>],
        mut zip: impl FnMut(&[u32], &[u32]) -> Vec<[u32; 3]>,
    ) -> Result<(), GraphError> {
        let grow_to = rings
            .iter()
            .flatten()
            .map(|&v| v as usize + 1)
            .max()
            .unwrap_or(0);
        if grow_to > self.nbrs.len() {
            self.nbrs.resize(grow_to, Vec::new());
        }
        let ring_p = self.nbrs[p as usize].clone();
        let ring_q = self.nbrs[q as usize].clone();
        // Faces kept around the affected cells, minus those of p and q.
        let mut touched: Vec<u32> = ring_p.iter().chain(&ring_q).copied().collect();
        touched.extend(rings.iter().flatten());
        let mut faces: BTreeMap<u32, Vec<(u32, u32)>> = BTreeMap::new();
        for &v in ring_p.iter().chain(&ring_q) {
            let ring = &self.nbrs[v as usize];
            for k in 0..ring.len() {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                if a != p && b != p && a != q && b != q {
                    faces.entry(v).or_default().push((a, b));
                }
            }
        }
        // New faces run the hole's edges forwards round p's ring and round q's ring, as the
        // removed faces did. A zip runs its first loop forwards and uses its second loop's
        // edges forwards too, so every loop after the first is reversed when it leads a zip.
        let mut loops: Vec<Vec<u32>> = vec![ring_p];
        loops.extend(rings.iter().cloned());
        loops.push(ring_q);
        for k in 0..loops.len() - 1 {
            let x: Vec<u32> = if k == 0 {
                loops[0].clone()
            } else {
                loops[k].iter().rev().copied().collect()
            };
            for f in zip(&x, &loops[k + 1]) {
                for k in 0..3 {
                    faces
                        .entry(f[k])
                        .or_default()
                        .push((f[(k + 1) % 3], f[(k + 2) % 3]));
                }
            }
        }
        for &v in &touched {
            let pairs = faces.get(&v).map(Vec::as_slice).unwrap_or(&[]);
            self.nbrs[v as usize] = chain(v, pairs)?;
        }
        Ok(())
    }

    /// Checks that the rotation system is a triangulated closed oriented manifold: every
    /// neighbour list has at least three distinct cells, adjacency is symmetric, every face
    /// (v, a, b) is seen the same way round from a and from b, the graph is connected, and
    /// V − E + F = 2 − 2g.
    pub fn check(&self) -> Result<Census, GraphError> {
        let n = self.nbrs.len();
        let mut darts = 0usize;
        let (mut lo, mut hi) = (usize::MAX, 0);
        for (v, ring) in self.nbrs.iter().enumerate() {
            let v = v as u32;
            let d = ring.len();
            if d < 3 {
                return Err(cell_error(v, format!("degree {d} is below 3")));
            }
            lo = lo.min(d);
            hi = hi.max(d);
            darts += d;
            let mut sorted = ring.clone();
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) || sorted.binary_search(&v).is_ok() {
                return Err(cell_error(
                    v,
                    "a neighbour appears twice, or the cell itself",
                ));
            }
            for k in 0..d {
                let (a, b) = (ring[k], ring[(k + 1) % d]);
                if a as usize >= n || b as usize >= n {
                    return Err(cell_error(v, "neighbour index out of range"));
                }
                // Face (v, a, b) seen from a is (a, b, v), from b it is (b, v, a).
                if successor(&self.nbrs[a as usize], b) != Some(v)
                    || successor(&self.nbrs[b as usize], v) != Some(a)
                {
                    return Err(cell_error(
                        v,
                        format!("face ({v}, {a}, {b}) is not the same face from its other cells"),
                    ));
                }
            }
        }
        let components = self.components();
        if components != 1 {
            return Err(GraphError::Components { components });
        }
        let (edges, faces) = (darts / 2, darts / 3);
        let euler = n as i64 - edges as i64 + faces as i64;
        if euler > 2 || euler % 2 != 0 {
            return Err(GraphError::Euler { euler });
        }
        Ok(Census {
            cells: n,
            edges,
            faces,
            genus: ((2 - euler) / 2) as usize,
            min_degree: lo,
            max_degree: hi,
        })
    }

    fn components(&self) -> usize {
        let mut seen = vec![false; self.nbrs.len()];
        let mut count = 0;
        for s in 0..self.nbrs.len() {
            if seen[s] {
                continue;
            }
            count += 1;
            seen[s] = true;
            let mut stack = vec![s as u32];
            while let Some(v) = stack.pop() {
                for &u in &self.nbrs[v as usize] {
                    if !std::mem::replace(&mut seen[u as usize], true) {
                        stack.push(u);
                    }
                }
            }
        }
        count
    }
}

fn cell_error(cell: u32, problem: impl Into<String>) -> GraphError {
    GraphError::Cell {
        cell,
        problem: problem.into(),
    }
}

fn successor(ring: &[u32], x: u32) -> Option<u32> {
    let k = ring.iter().position(|&u| u == x)?;
    Some(ring[(k + 1) % ring.len()])
}

/// Replaces `old` in a neighbour list by `with`, in order.
fn replace(ring: &mut Vec<u32>, old: u32, with: &[u32]) {
    let k = ring
        .iter()
        .position(|&u| u == old)
        .expect("a division's ring cell lists the dividing cell");
    ring.splice(k..k + 1, with.iter().copied());
}

/// Orders the (a, b) pairs of the faces (v, a, b) into one cycle of neighbours.
fn chain(v: u32, pairs: &[(u32, u32)]) -> Result<Vec<u32>, GraphError> {
    if pairs.len() < 3 {
        return Err(cell_error(
            v,
            format!("{} faces: fewer than 3", pairs.len()),
        ));
    }
    let next: BTreeMap<u32, u32> = pairs.iter().copied().collect();
    if next.len() != pairs.len() {
        return Err(cell_error(
            v,
            "two faces leave by the same edge: not a manifold",
        ));
    }
    let start = pairs[0].0;
    let mut ring = vec![start];
    let mut at = start;
    loop {
        at = *next
            .get(&at)
            .ok_or_else(|| cell_error(v, "the faces round the cell do not close"))?;
        if at == start {
            break;
        }
        ring.push(at);
        if ring.len() > pairs.len() {
            return Err(cell_error(v, "the faces round the cell do not close"));
        }
    }
    if ring.len() != pairs.len() {
        return Err(cell_error(
            v,
            "the faces round the cell form more than one fan: not a manifold",
        ));
    }
    Ok(ring)
}

/// Triangles joining loop `x` (run forwards) to loop `y` (run backwards), `x.len() + y.len()` of
/// them, starting at the pair `(x[0], y[0])` and advancing the loops evenly (for equal loops: an
/// antiprism), so every cell gains one or two cross edges.
pub fn zip_loops(x: &[u32], y: &[u32]) -> Vec<[u32; 3]> {
    let (nx, ny) = (x.len(), y.len());
    let (mut i, mut j) = (0usize, 0usize); // steps taken on each loop
    let mut out = Vec::with_capacity(nx + ny);
    let yat = |j: usize| y[(ny - j % ny) % ny];
    // Cross edges already made, as (i mod nx, j mod ny): none may be made twice, or the band
    // would close on itself before it has gone round.
    let mut made = std::collections::BTreeSet::from([(0usize, 0usize)]);
    let free = |made: &std::collections::BTreeSet<(usize, usize)>, i: usize, j: usize| {
        (i == nx && j == ny) || (i <= nx && j <= ny && !made.contains(&(i % nx, j % ny)))
    };
    while i < nx || j < ny {
        let can_x = free(&made, i + 1, j);
        let can_y = free(&made, i, j + 1);
        // The first step goes along x, so the band never has to wrap round y early.
        let step_x = if i == 0 && j == 0 {
            true
        } else if can_x && can_y {
            // Evenly interleaved: the loop that is behind in its share of the way round.
            (2 * i + 1) * ny <= (2 * j + 1) * nx
        } else {
            can_x
        };
        if step_x {
            out.push([x[i % nx], x[(i + 1) % nx], yat(j)]);
            i += 1;
        } else {
            out.push([yat(j + 1), yat(j), x[i % nx]]);
            j += 1;
        }
        made.insert((i % nx, j % ny));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tetrahedron_is_a_sphere() -> Result<(), GraphError> {
        let (g, p) = CellGraph::tetrahedron();
        let c = g.check()?;
        assert_eq!((c.cells, c.edges, c.faces, c.genus), (4, 6, 4, 0));
        // Faces point outwards.
        for f in g.faces() {
            let [a, b, c] = f.map(|v| p[v as usize]);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
        Ok(())
    }

    #[test]
    fn division_adds_one_cell_three_edges_and_two_faces() -> Result<(), GraphError> {
        let (mut g, _) = CellGraph::tetrahedron();
        for step in 0..200u32 {
            let cell = (step * 7919) % g.len() as u32;
            let n = g.degree(cell);
            let (i, j) = ((step as usize) % n, (step as usize + n / 2) % n);
            let before = g.check()?;
            let shared = [g.neighbours(cell)[i], g.neighbours(cell)[j]];
            let deg_before = shared.map(|u| g.degree(u));
            let s = g.divide(cell, i, j);
            let after = g.check()?;
            assert_eq!(after.cells, before.cells + 1);
            assert_eq!(after.edges, before.edges + 3);
            assert_eq!(after.faces, before.faces + 2);
            assert_eq!(after.genus, 0);
            assert!(g.adjacent(s.kept, s.new));
            assert_eq!(s.shared, shared);
            assert_eq!(shared.map(|u| g.degree(u)), deg_before.map(|d| d + 1));
            assert_eq!(g.degree(s.kept) + g.degree(s.new), n + 4);
        }
        Ok(())
    }

    #[test]
    fn a_broken_rotation_is_caught() {
        let (mut g, _) = CellGraph::tetrahedron();
        g.nbrs[0].swap(0, 1);
        assert!(matches!(g.check(), Err(GraphError::Cell { .. })));
        let (mut g, _) = CellGraph::tetrahedron();
        g.nbrs[3].pop();
        assert!(g.check().is_err());
    }

    #[test]
    fn a_tunnel_adds_a_handle() -> Result<(), GraphError> {
        // An octahedron subdivided until two cells are four hops apart.
        let (mut g, _) = CellGraph::tetrahedron();
        for step in 0..60u32 {
            let cell = (step * 31) % g.len() as u32;
            let n = g.degree(cell);
            g.divide(cell, 0, n / 2);
        }
        let far = farthest(&g, 0);
        assert!(far.1 >= 4, "cells only {} hops apart", far.1);
        let (p, q) = (0, far.0);
        let n0 = g.len() as u32;
        let ring = vec![p, n0, q, n0 + 1];
        let before = g.check()?;
        g.tunnel(p, q, &[ring], zip_loops)?;
        let after = g.check()?;
        assert_eq!(after.genus, before.genus + 1);
        assert_eq!(after.cells, before.cells + 2);
        Ok(())
    }

    pub(super) fn farthest(g: &CellGraph, from: u32) -> (u32, usize) {
        let mut hops = vec![usize::MAX; g.len()];
        hops[from as usize] = 0;
        let mut queue = std::collections::VecDeque::from([from]);
        let mut last = (from, 0);
        while let Some(v) = queue.pop_front() {
            last = (v, hops[v as usize]);
            for &u in g.neighbours(v) {
                if hops[u as usize] == usize::MAX {
                    hops[u as usize] = hops[v as usize] + 1;
                    queue.push_back(u);
                }
            }
        }
        last
    }
}

#[cfg(test)]
mod tunnel_props {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn tunnels_of_any_shape_keep_a_manifold() -> Result<(), GraphError> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for case in 0..200 {
            let (mut g, _) = CellGraph::tetrahedron();
            for _ in 0..150 {
                let cell = rng.random_range(0..g.len() as u32);
                let n = g.degree(cell);
                let i = rng.random_range(0..n);
                let j = (i + 1 + rng.random_range(0..n - 1)) % n;
                g.divide(cell, i, j);
            }
            let p = rng.random_range(0..g.len() as u32);
            let (q, hops) = super::tests::farthest(&g, p);
            if hops < 5 {
                continue;
            }
            let k = rng.random_range(1..4usize);
            let sides = rng.random_range(3..9usize);
            let mut next = g.len() as u32;
            let mut rings = Vec::new();
            for r in 1..=k {
                let mut ring = Vec::new();
                for s in 0..sides {
                    if r == 1 && s == 0 {
                        ring.push(p);
                    } else if r == k && s == sides / 2 {
                        ring.push(q);
                    } else {
                        ring.push(next);
                        next += 1;
                    }
                }
                rings.push(ring);
            }
            let before = g.check()?.genus;
            g.tunnel(p, q, &rings, zip_loops)?;
            assert_eq!(g.check()?.genus, before + 1, "case {case}");
        }
        Ok(())
    }
}

#[cfg(test)]
mod zip_props {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn zips_use_every_directed_edge_once() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..2000 {
            let nx = rng.random_range(3..9u32);
            let ny = rng.random_range(3..9u32);
            let x: Vec<u32> = (0..nx).collect();
            let y: Vec<u32> = (100..100 + ny).collect();
            let f = zip_loops(&x, &y);
            let mut darts = std::collections::BTreeSet::new();
            for t in &f {
                for k in 0..3 {
                    assert!(darts.insert((t[k], t[(k + 1) % 3])), "{nx} {ny} {f:?}");
                }
            }
        }
    }
}
