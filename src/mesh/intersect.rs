//! Self-intersection of a triangle mesh: every pair of triangles that meet anywhere other than
//! along the vertices and edges they share.
//!
//! Broad phase: a uniform grid over triangle bounding boxes (each pair is tested in one bucket
//! only: the one holding the low corner of the overlap of their boxes), buckets in parallel.
//! Narrow phase: orientation signs, in floating point. Triangles sharing an edge meet only if
//! they fold flat onto each other; triangles sharing a vertex meet elsewhere only if the edge
//! opposite that vertex in one crosses the other.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use super::TriMesh;

impl TriMesh {
    /// Pairs (i < j) of triangles that intersect improperly, sorted.
    pub fn self_intersections(&self) -> Vec<(u32, u32)> {
        let n = self.triangles.len();
        if n < 2 {
            return Vec::new();
        }
        let boxes: Vec<(DVec3, DVec3)> = self
            .triangles
            .iter()
            .map(|t| {
                let c = self.corners(t);
                (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]))
            })
            .collect();
        let mean = boxes
            .iter()
            .map(|(lo, hi)| (*hi - *lo).max_element())
            .sum::<f64>()
            / n as f64;
        let width = (2.0 * mean).max(1e-12);
        let key = |p: DVec3| {
            let k = (p / width).floor();
            (k.x as i64, k.y as i64, k.z as i64)
        };
        let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
        for (t, (lo, hi)) in boxes.iter().enumerate() {
            let (a, b) = (key(*lo), key(*hi));
            for x in a.0..=b.0 {
                for y in a.1..=b.1 {
                    for z in a.2..=b.2 {
                        grid.entry((x, y, z)).or_default().push(t as u32);
                    }
                }
            }
        }
        let mut buckets: Vec<((i64, i64, i64), Vec<u32>)> = grid.into_iter().collect();
        buckets.sort_unstable_by_key(|(k, _)| *k);
        let mut pairs: Vec<(u32, u32)> = buckets
            .par_iter()
            .flat_map_iter(|(k, ts)| {
                let mut out = Vec::new();
                for (x, &i) in ts.iter().enumerate() {
                    for &j in &ts[x + 1..] {
                        let (bi, bj) = (boxes[i as usize], boxes[j as usize]);
                        let lo = bi.0.max(bj.0);
                        let hi = bi.1.min(bj.1);
                        if lo.cmpgt(hi).any() || key(lo) != *k {
                            continue;
                        }
                        if self.triangles_meet(i, j) {
                            out.push((i.min(j), i.max(j)));
                        }
                    }
                }
                out.into_iter()
            })
            .collect();
        pairs.sort_unstable();
        pairs
    }

    fn triangles_meet(&self, i: u32, j: u32) -> bool {
        let (ti, tj) = (self.triangles[i as usize], self.triangles[j as usize]);
        triangles_meet(ti, self.corners(&ti), tj, self.corners(&tj))
    }
}

/// Whether triangles `ti` and `tj` (vertex ids, for what they share, and corner positions)
/// meet anywhere other than along their shared vertices and edge.
pub fn triangles_meet(ti: [u32; 3], pi: [DVec3; 3], tj: [u32; 3], pj: [DVec3; 3]) -> bool {
    let (lo_i, hi_i) = (pi[0].min(pi[1]).min(pi[2]), pi[0].max(pi[1]).max(pi[2]));
    let (lo_j, hi_j) = (pj[0].min(pj[1]).min(pj[2]), pj[0].max(pj[1]).max(pj[2]));
    if lo_i.cmpgt(hi_j).any() || lo_j.cmpgt(hi_i).any() {
        return false;
    }
    let mut shared = [(0usize, 0usize); 3];
    let mut count = 0;
    for (a, va) in ti.iter().enumerate() {
        for (b, vb) in tj.iter().enumerate() {
            if va == vb {
                shared[count] = (a, b);
                count += 1;
            }
        }
    }
    let shared = &shared[..count];
    // Möller's early out: a triangle wholly on one side of the other's plane (its shared
    // corners aside) cannot meet it.
    if count < 2 && (one_side(pi, pj, tj, ti) || one_side(pj, pi, ti, tj)) {
        return false;
    }
    match shared.len() {
        0 => {
            (0..3).any(|k| segment_meets_triangle(pi[k], pi[(k + 1) % 3], pj))
                || (0..3).any(|k| segment_meets_triangle(pj[k], pj[(k + 1) % 3], pi))
        }
        1 => {
            let (a, b) = shared[0];
            segment_meets_triangle(pi[(a + 1) % 3], pi[(a + 2) % 3], pj)
                || segment_meets_triangle(pj[(b + 1) % 3], pj[(b + 2) % 3], pi)
        }
        2 => {
            // Folded flat: the free corners coplanar with the edge, on the same side.
            let (a0, _) = shared[0];
            let (a1, _) = shared[1];
            let free_i = 3 - a0 - a1;
            let b_free = (0..3)
                .find(|&b| shared.iter().all(|&(_, sb)| sb != b))
                .expect("two shared corners leave one free");
            let (u, v) = (pi[a0], pi[a1]);
            let (x, y) = (pi[free_i], pj[b_free]);
            let scale = (v - u).length() * (x - u).length() * (y - u).length();
            let vol = orient(u, v, x, y);
            let side = (v - u).cross(x - u).dot((v - u).cross(y - u));
            vol.abs() <= 1e-12 * scale && side > 0.0
        }
        _ => false,
    }
}

/// Whether the corners of `q` not shared with `p` lie strictly on one side of p's plane.
fn one_side(p: [DVec3; 3], q: [DVec3; 3], tq: [u32; 3], tp: [u32; 3]) -> bool {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let span = (p[1] - p[0]).length().max((p[2] - p[0]).length());
    let eps = 1e-9 * n.length() * span.max((q[0] - p[0]).length());
    let (mut above, mut below) = (false, false);
    for k in 0..3 {
        if tp.contains(&tq[k]) {
            continue;
        }
        let d = n.dot(q[k] - p[0]);
        if d > eps {
            above = true;
        } else if d < -eps {
            below = true;
        } else {
            return false;
        }
    }
    above != below
}

/// Six times the signed volume of (a, b, c, d).
fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

/// Whether segment pq meets the closed triangle t. Points within a relative 1e-9 of the
/// triangle's plane count as on it, so triangles that lie in one plane (the six parts of a
/// subdivided face) are compared in that plane and not by the noise of their volumes.
fn segment_meets_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let reach = (p - t[0]).length().max((q - t[0]).length()) + (t[1] - t[0]).length();
    let eps = 1e-9 * n.length() * reach;
    let flat = |o: f64| if o.abs() <= eps { 0.0 } else { o };
    let (op, oq) = (
        flat(orient(t[0], t[1], t[2], p)),
        flat(orient(t[0], t[1], t[2], q)),
    );
    if (op > 0.0 && oq > 0.0) || (op < 0.0 && oq < 0.0) {
        return false;
    }
    if op == 0.0 && oq == 0.0 {
        return coplanar_segment_meets_triangle(p, q, t);
    }
    let s = [
        orient(p, q, t[0], t[1]),
        orient(p, q, t[1], t[2]),
        orient(p, q, t[2], t[0]),
    ];
    s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
}

fn coplanar_segment_meets_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let drop = n.abs().max_position();
    let flat = |v: DVec3| {
        let a = v.to_array();
        let k: Vec<f64> = (0..3).filter(|&i| i != drop).map(|i| a[i]).collect();
        glam::DVec2::new(k[0], k[1])
    };
    let (p, q) = (flat(p), flat(q));
    let t = t.map(flat);
    let inside = |x: glam::DVec2| {
        let s = [0, 1, 2].map(|k| (t[(k + 1) % 3] - t[k]).perp_dot(x - t[k]));
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    };
    if inside(p) || inside(q) {
        return true;
    }
    (0..3).any(|k| segments_cross(p, q, t[k], t[(k + 1) % 3]))
}

fn segments_cross(a: glam::DVec2, b: glam::DVec2, c: glam::DVec2, d: glam::DVec2) -> bool {
    let o = |p: glam::DVec2, q: glam::DVec2, r: glam::DVec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (o(a, b, c), o(a, b, d));
    let (d3, d4) = (o(c, d, a), o(c, d, b));
    ((d1 > 0.0) != (d2 > 0.0) || d1 == 0.0 || d2 == 0.0)
        && ((d3 > 0.0) != (d4 > 0.0) || d3 == 0.0 || d4 == 0.0)
        && !(d1 == 0.0 && d2 == 0.0 && {
            // Collinear: overlap of the projections.
            let dir = b - a;
            let (s0, s1) = ((c - a).dot(dir), (d - a).dot(dir));
            s0.max(s1) < 0.0 || s0.min(s1) > dir.length_squared()
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra(offset: DVec3) -> TriMesh {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        TriMesh {
            positions: p.iter().map(|x| *x + offset).collect(),
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            colors: None,
        }
    }

    fn joined(a: TriMesh, b: TriMesh) -> TriMesh {
        let n = a.positions.len() as u32;
        let mut m = a;
        m.positions.extend(b.positions);
        m.triangles
            .extend(b.triangles.iter().map(|t| t.map(|v| v + n)));
        m
    }

    #[test]
    fn a_closed_tetrahedron_does_not_meet_itself() {
        assert!(tetra(DVec3::ZERO).self_intersections().is_empty());
    }

    #[test]
    fn overlapping_and_apart_solids() {
        let apart = joined(tetra(DVec3::ZERO), tetra(DVec3::new(3.0, 0.0, 0.0)));
        assert!(apart.self_intersections().is_empty());
        let overlap = joined(tetra(DVec3::ZERO), tetra(DVec3::splat(0.2)));
        assert!(!overlap.self_intersections().is_empty());
    }

    #[test]
    fn a_spike_through_a_neighbour_is_found() {
        // A fan round vertex 0 whose second triangle is pushed through the first.
        let m = TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(0.5, 0.5, -1.0),
                DVec3::new(0.5, 0.5, 1.0),
            ],
            triangles: vec![[0, 1, 2], [0, 3, 4]],
            colors: None,
        };
        assert_eq!(m.self_intersections(), vec![(0, 1)]);
    }
}
