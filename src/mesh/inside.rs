//! Whether a point is inside a closed mesh: the winding number of the mesh about the point,
//! counted along the vertical ray above it.
//!
//! # Method
//! The triangles are listed in the cells of a grid over their projections on the xy plane.
//! A point's winding number is the sum, over the triangles of its cell whose projection holds
//! the point and whose plane passes above it, of the sign of the triangle's normal's z (+1 when
//! the ray leaves the solid through it, for outward normals). For a closed mesh this is the
//! winding number from any direction, so it agrees with the slicer, which fills each section by
//! the non-zero rule: overlapping shells count once, and a mesh wound inside out is inside
//! where it is −1. A point whose vertical ray passes exactly through an edge or a corner is
//! moved by a few units in the last place of the mesh's size first (the same amount for every
//! query), and the projection test is a half-open one on the edge in a fixed vertex order, so
//! the two triangles sharing an edge never both count a point on it.

use glam::{DVec2, DVec3};

use super::TriMesh;

/// Cells of the grid, at most (a grid line per this many triangles' worth of cells).
const MAX_CELLS: usize = 1 << 20;
/// Triangle listings in all cells, at most: a mesh of large triangles gets a coarser grid.
const MAX_ENTRIES: usize = 1 << 24;

pub struct Winding<'a> {
    mesh: &'a TriMesh,
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    /// Added to every query's x and y.
    nudge: DVec2,
}

impl<'a> Winding<'a> {
    pub fn new(mesh: &'a TriMesh) -> Winding<'a> {
        let bbox = mesh.bbox();
        let (lo, hi) = (bbox.min.truncate(), bbox.max.truncate());
        let size = (hi - lo).max(DVec2::splat(1e-9));
        let n = mesh.triangles.len().max(1);
        // About one cell per triangle, square cells; coarser while the listings would be too many.
        let mut cell = (size.x * size.y / n as f64)
            .sqrt()
            .max(size.max_element() / 1024.0);
        let boxes: Vec<(DVec2, DVec2)> = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = mesh.corners(t).map(|p| p.truncate());
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let span = |cell: f64, v: f64, lo: f64, n: usize| -> usize {
            (((v - lo) / cell).floor().max(0.0) as usize).min(n - 1)
        };
        let (nx, ny) = loop {
            let nx = ((size.x / cell).ceil() as usize).clamp(1, MAX_CELLS);
            let ny = ((size.y / cell).ceil() as usize).clamp(1, MAX_CELLS);
            let entries: usize = boxes
                .iter()
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(a, b)| {
                    (span(cell, b.x, lo.x, nx) - span(cell, a.x, lo.x, nx) + 1)
                        * (span(cell, b.y, lo.y, ny) - span(cell, a.y, lo.y, ny) + 1)
                })
                .sum();
            if (entries <= MAX_ENTRIES && nx * ny <= MAX_CELLS) || (nx == 1 && ny == 1) {
                break (nx, ny);
            }
            cell *= 2.0;
        };
        let mut start = vec![0u32; nx * ny + 1];
        let cells_of = |(a, b): &(DVec2, DVec2)| {
            let (i0, i1) = (span(cell, a.x, lo.x, nx), span(cell, b.x, lo.x, nx));
            let (j0, j1) = (span(cell, a.y, lo.y, ny), span(cell, b.y, lo.y, ny));
            (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| j * nx + i))
        };
        let finite = |b: &(DVec2, DVec2)| b.0.is_finite() && b.1.is_finite();
        for b in boxes.iter().filter(|b| finite(b)) {
            for c in cells_of(b) {
                start[c + 1] += 1;
            }
        }
        for c in 0..nx * ny {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (t, b) in boxes.iter().enumerate().filter(|(_, b)| finite(b)) {
            for c in cells_of(b) {
                items[fill[c] as usize] = t as u32;
                fill[c] += 1;
            }
        }
        let scale = size.max_element().max(1e-6);
        Winding {
            mesh,
            lo,
            cell,
            nx,
            ny,
            start,
            items,
            nudge: DVec2::new(0.754_877_666, 0.569_840_291) * scale * 1e-12,
        }
    }

    /// The winding number of the mesh about `p` (0 outside a closed mesh).
    pub fn winding(&self, p: DVec3) -> i32 {
        let q = p.truncate() + self.nudge;
        if !q.is_finite() {
            return 0;
        }
        let rel = (q - self.lo) / self.cell;
        if rel.x < 0.0 || rel.y < 0.0 {
            return 0;
        }
        let (i, j) = (rel.x.floor() as usize, rel.y.floor() as usize);
        if i >= self.nx || j >= self.ny {
            return 0;
        }
        let c = j * self.nx + i;
        let mut w = 0;
        for &t in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
            let [a, b, cc] = self.mesh.corners(&self.mesh.triangles[t as usize]);
            let area = (b - a).truncate().perp_dot((cc - a).truncate());
            if area == 0.0 || !area.is_finite() {
                continue;
            }
            // Half-open on each edge, in the edge's own vertex order: a point on an edge shared
            // by two triangles is counted by exactly one of them.
            let side = |u: DVec3, v: DVec3| -> bool {
                let (u2, v2) = (u.truncate(), v.truncate());
                let (u2, v2, flip) = if u2.to_array() < v2.to_array() {
                    (u2, v2, false)
                } else {
                    (v2, u2, true)
                };
                let s = (v2 - u2).perp_dot(q - u2);
                // On the line counts as left, for both triangles alike.
                (s >= 0.0) != flip
            };
            let (s0, s1, s2) = (side(a, b), side(b, cc), side(cc, a));
            let ccw = area > 0.0;
            if !(s0 == ccw && s1 == ccw && s2 == ccw) {
                continue;
            }
            // Height of the triangle's plane above q.
            let n = (b - a).cross(cc - a);
            let z = a.z - (n.x * (q.x - a.x) + n.y * (q.y - a.y)) / n.z;
            if z > p.z {
                w += if n.z > 0.0 { 1 } else { -1 };
            }
        }
        w
    }

    pub fn inside(&self, p: DVec3) -> bool {
        self.winding(p) != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(lo: DVec3, hi: DVec3) -> TriMesh {
        TriMesh::cuboid(lo, hi)
    }

    #[test]
    fn points_in_a_cube_are_inside_on_its_diagonals_too() {
        let m = cube(DVec3::ZERO, DVec3::splat(10.0));
        assert!(m.signed_volume() > 0.0);
        let w = Winding::new(&m);
        // On the faces' diagonals (where two triangles meet), at corners' xy, in the middle.
        for p in [
            DVec3::new(5.0, 5.0, 5.0),
            DVec3::new(3.0, 3.0, 1.0),
            DVec3::new(7.0, 3.0, 9.0),
            DVec3::new(0.5, 9.5, 0.5),
            DVec3::new(2.5, 2.5, 9.99),
        ] {
            assert_eq!(w.winding(p), 1, "{p}");
        }
        for p in [
            DVec3::new(5.0, 5.0, 10.5),
            DVec3::new(5.0, 5.0, -0.5),
            DVec3::new(-1.0, 5.0, 5.0),
            DVec3::new(5.0, 11.0, 5.0),
            DVec3::new(3.0, 3.0, 10.01),
        ] {
            assert_eq!(w.winding(p), 0, "{p}");
        }
    }

    #[test]
    fn overlapping_shells_count_twice_and_an_inverted_one_negative() {
        let mut m = cube(DVec3::ZERO, DVec3::splat(10.0));
        let other = cube(DVec3::splat(5.0), DVec3::splat(15.0));
        let base = m.positions.len() as u32;
        m.positions.extend(other.positions);
        m.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        let w = Winding::new(&m);
        assert_eq!(w.winding(DVec3::splat(7.0)), 2);
        assert_eq!(w.winding(DVec3::splat(12.0)), 1);
        assert_eq!(w.winding(DVec3::splat(16.0)), 0);
        let mut inv = cube(DVec3::ZERO, DVec3::ONE);
        for t in &mut inv.triangles {
            t.swap(1, 2);
        }
        assert_eq!(Winding::new(&inv).winding(DVec3::splat(0.5)), -1);
    }
}
