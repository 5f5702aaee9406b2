//! Closest points on a triangle mesh and the surface normal there, through an rstar tree of
//! triangle bounding boxes (a bounding-volume hierarchy): candidates come in order of box
//! distance, and the search stops once a box is farther than the best exact distance found.
//!
//! Normals are area-weighted vertex normals interpolated barycentrically, so they vary smoothly
//! across the mesh; their sense follows the triangles' winding.

use glam::DVec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::RTree;

use super::TriMesh;

type TriBox = GeomWithData<Rectangle<[f64; 3]>, u32>;

pub struct SurfaceIndex<'a> {
    mesh: &'a TriMesh,
    tree: RTree<TriBox>,
    vertex_normals: Vec<DVec3>,
}

/// The closest point on the mesh to a query.
#[derive(Clone, Copy, Debug)]
pub struct Closest {
    pub point: DVec3,
    pub distance: f64,
    pub triangle: u32,
    /// Barycentric coordinates of `point` in its triangle.
    pub bary: [f64; 3],
}

impl<'a> SurfaceIndex<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let tree = RTree::bulk_load(
            mesh.triangles
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    let [a, b, c] = mesh.corners(t);
                    let lo = a.min(b).min(c);
                    let hi = a.max(b).max(c);
                    TriBox::new(
                        Rectangle::from_corners(lo.to_array(), hi.to_array()),
                        i as u32,
                    )
                })
                .collect(),
        );
        let mut vertex_normals = vec![DVec3::ZERO; mesh.positions.len()];
        for t in &mesh.triangles {
            let [a, b, c] = mesh.corners(t);
            // Twice the area times the unit normal: area weighting for free.
            let n = (b - a).cross(c - a);
            for &v in t {
                vertex_normals[v as usize] += n;
            }
        }
        for n in &mut vertex_normals {
            *n = n.normalize_or_zero();
        }
        SurfaceIndex {
            mesh,
            tree,
            vertex_normals,
        }
    }

    /// None for a mesh without triangles, or a query that is not a finite point.
    pub fn closest(&self, p: DVec3) -> Option<Closest> {
        self.closest_within(p, f64::INFINITY)
    }

    /// The closest point if it is within `reach` of `p` (None otherwise, or for a mesh without
    /// triangles, or a query that is not a finite point): a far query stops at the first box.
    pub fn closest_within(&self, p: DVec3, reach: f64) -> Option<Closest> {
        if !p.is_finite() {
            return None;
        }
        let mut best: Option<Closest> = None;
        for (cand, box_d2) in self
            .tree
            .nearest_neighbor_iter_with_distance_2(&p.to_array())
        {
            let bound = best.map_or(reach, |b| b.distance.min(reach));
            if box_d2 > bound * bound {
                break;
            }
            let t = cand.data;
            let [a, b, c] = self.mesh.corners(&self.mesh.triangles[t as usize]);
            let (q, bary) = closest_on_triangle(p, a, b, c);
            let d = q.distance(p);
            // A degenerate triangle can give no point at all.
            if d.is_nan() {
                continue;
            }
            if d <= reach && best.is_none_or(|b| d < b.distance) {
                best = Some(Closest {
                    point: q,
                    distance: d,
                    triangle: t,
                    bary,
                });
            }
        }
        best
    }

    /// The area-weighted unit normal at vertex `v` (zero on a vertex of no triangle).
    pub fn vertex_normal(&self, v: u32) -> DVec3 {
        self.vertex_normals[v as usize]
    }

    /// The interpolated unit normal at a closest point (the face normal where the vertex normals
    /// cancel).
    pub fn normal(&self, c: &Closest) -> DVec3 {
        let t = self.mesh.triangles[c.triangle as usize];
        let n = (0..3)
            .map(|k| self.vertex_normals[t[k] as usize] * c.bary[k])
            .sum::<DVec3>();
        n.try_normalize().unwrap_or_else(|| {
            let [a, b, cc] = self.mesh.corners(&t);
            (b - a).cross(cc - a).normalize_or_zero()
        })
    }
}

/// The closest point of triangle abc to p, and its barycentric coordinates (Ericson, Real-Time
/// Collision Detection §5.1.5, by Voronoi regions).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriMesh {
        TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            colors: None,
        }
    }

    #[test]
    fn closest_points_and_normals_on_a_square() {
        let m = square();
        let idx = SurfaceIndex::new(&m);
        let c = idx
            .closest(DVec3::new(0.25, 0.75, 2.0))
            .expect("a triangle");
        assert!(c.point.distance(DVec3::new(0.25, 0.75, 0.0)) < 1e-12);
        assert!((c.distance - 2.0).abs() < 1e-12);
        assert!(idx.normal(&c).distance(DVec3::Z) < 1e-12);
        // Outside the square: the nearest corner region.
        let c = idx.closest(DVec3::new(2.0, -1.0, 0.0)).expect("a triangle");
        assert!(c.point.distance(DVec3::X) < 1e-12);
    }

    #[test]
    fn brute_force_agrees_on_random_points() {
        use rand::{Rng, SeedableRng};
        let m = square();
        let idx = SurfaceIndex::new(&m);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let p = DVec3::new(
                rng.random_range(-1.0..2.0),
                rng.random_range(-1.0..2.0),
                rng.random_range(-1.0..1.0),
            );
            let brute = m
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = m.corners(t);
                    closest_on_triangle(p, a, b, c).0.distance(p)
                })
                .fold(f64::INFINITY, f64::min);
            let c = idx.closest(p).expect("a triangle");
            assert!((c.distance - brute).abs() < 1e-12);
        }
    }
}
