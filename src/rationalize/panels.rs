//! Panels and their planarity. A network edge (i, j) with node axes d_i, d_j and heights h_i,
//! h_j becomes the quad q = (v_i, v_j, v_j + h_j·d_j, v_i + h_i·d_i) (Gokmen §4.3.1, Fig. 11).
//!
//! Metrics of a quad (q0, q1, q2, q3), the same for panels lamina makes and panels it audits:
//! - deviation: the distance of q2 from the plane through q0, q1, q3 (mm). For a panel this is
//!   h_j·|d_j·(e × d_i)| / |e × d_i|, the distance of the fourth corner from the plane of the
//!   other three.
//! - diagonal distance: the distance between the lines q0q2 and q1q3 (mm), also relative to the
//!   mean edge length (as COMPAS reports flatness) and to the mean diagonal (as libigl does).
//! - torsion: the angle between the planes (q0, q1, q3) and (q0, q1, q2) along the edge q0q1,
//!   degrees: 0 for a planar panel.
//!
//! Figures of any polygon (n ≥ 3 corners):
//! - flatness (ISO 1101): the width of the thinnest zone between two parallel planes that holds
//!   every corner, the minimum zone. Exact: the thinnest zone of a point set rests on a face and
//!   a vertex or on two edges of its convex hull (Houle and Toussaint 1988), so the width is the
//!   least over the normals of every corner triple and of every two corner pairs with no corner
//!   in common of the extent along that normal. For a quad, the least of the tetrahedron's four
//!   heights and the distances between its three pairs of opposite edges.
//! - best fit: the largest distance of a corner from the least-squares plane (through the
//!   centroid, normal the covariance's least eigenvector).
//! - normal: the minimum zone's, turned to agree with the polygon's Newell normal.

use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen};

/// Polygons with more corners than this get no flatness: the exact search grows as n⁵.
pub const MAX_FLATNESS_CORNERS: usize = 48;

/// Planarity figures of one quad (the quad's own ones zero for other polygons).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct QuadMetrics {
    /// ISO 1101 minimum-zone flatness, mm (NaN over `MAX_FLATNESS_CORNERS` corners).
    pub flatness: f64,
    /// Largest distance from the least-squares plane, mm.
    pub best_fit: f64,
    /// Unit normal of the minimum zone.
    pub normal: [f64; 3],
    pub deviation: f64,
    pub diagonal_distance: f64,
    pub diagonal_rel_edge: f64,
    pub diagonal_rel_diagonal: f64,
    pub torsion_deg: f64,
}

/// The quad of edge (a, b): (v_a, v_b, v_b + h_b·d_b, v_a + h_a·d_a).
pub fn panel_quad(va: DVec3, vb: DVec3, da: DVec3, db: DVec3, ha: f64, hb: f64) -> [DVec3; 4] {
    [va, vb, vb + db * hb, va + da * ha]
}

/// The deviation alone (the distance of q2 from the plane of q0, q1, q3), for tolerance checks.
pub fn quad_deviation(q: [DVec3; 4]) -> f64 {
    match (q[1] - q[0]).cross(q[3] - q[0]).try_normalize() {
        Some(n) => (q[2] - q[0]).dot(n).abs(),
        None => 0.0,
    }
}

/// Every figure of a polygon: the quad ones for four corners, the Newell deviation as the
/// corner figure of other n-gons (triangles: 0).
pub fn polygon_metrics(p: &[DVec3]) -> QuadMetrics {
    if p.len() == 4 {
        return quad_metrics([p[0], p[1], p[2], p[3]]);
    }
    let mut m = QuadMetrics {
        flatness: 0.0,
        best_fit: 0.0,
        normal: [0.0; 3],
        deviation: polygon_deviation(p),
        diagonal_distance: 0.0,
        diagonal_rel_edge: 0.0,
        diagonal_rel_diagonal: 0.0,
        torsion_deg: 0.0,
    };
    plane_figures(&mut m, p);
    m
}

/// Flatness, its normal and the best-fit figure of `m`'s polygon `p`.
fn plane_figures(m: &mut QuadMetrics, p: &[DVec3]) {
    let newell = newell_normal(p);
    let (width, normal) = if p.len() <= MAX_FLATNESS_CORNERS {
        min_zone(p).unwrap_or((0.0, newell))
    } else {
        (f64::NAN, newell)
    };
    let normal = if normal.dot(newell) < 0.0 {
        -normal
    } else {
        normal
    };
    m.flatness = width;
    m.normal = normal.to_array();
    m.best_fit = best_fit(p);
}

/// The minimum zone: its width and unit normal; None when every corner lies on one line.
pub fn min_zone(p: &[DVec3]) -> Option<(f64, DVec3)> {
    let extent = |n: DVec3| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in p {
            let t = q.dot(n);
            lo = lo.min(t);
            hi = hi.max(t);
        }
        hi - lo
    };
    let size = p
        .iter()
        .map(|q| q.distance(p[0]))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut best: Option<(f64, DVec3)> = None;
    let mut consider = |n: DVec3| {
        // A normal from nearly parallel lines is noise: keep those of a real angle.
        if n.length() <= 1e-12 * size * size {
            return;
        }
        let n = n.normalize();
        let w = extent(n);
        if best.is_none_or(|(b, _)| w < b) {
            best = Some((w, n));
        }
    };
    let c = p.len();
    for i in 0..c {
        for j in i + 1..c {
            for k in j + 1..c {
                consider((p[j] - p[i]).cross(p[k] - p[i]));
            }
        }
    }
    for i in 0..c {
        for j in i + 1..c {
            for k in i + 1..c {
                for l in k + 1..c {
                    if k == j || l == j {
                        continue;
                    }
                    consider((p[j] - p[i]).cross(p[l] - p[k]));
                }
            }
        }
    }
    best
}

/// The largest distance of a corner from the least-squares plane.
pub fn best_fit(p: &[DVec3]) -> f64 {
    if p.len() < 4 {
        return 0.0;
    }
    let c = p.iter().copied().sum::<DVec3>() / p.len() as f64;
    let mut m = [[0.0; 3]; 3];
    for q in p {
        let d = (*q - c).to_array();
        for r in 0..3 {
            for s in 0..3 {
                m[r][s] += d[r] * d[s];
            }
        }
    }
    let n = least_eigenvector(m);
    p.iter().map(|q| (*q - c).dot(n).abs()).fold(0.0, f64::max)
}

/// The unit eigenvector of the least eigenvalue of a symmetric 3 × 3 matrix.
fn least_eigenvector(a: [[f64; 3]; 3]) -> DVec3 {
    let eigen = SymmetricEigen::new(Matrix3::from_fn(|r, c| a[r][c]));
    let k = eigen.eigenvalues.imin();
    let v = eigen.eigenvectors.column(k);
    DVec3::new(v[0], v[1], v[2]).normalize_or(DVec3::Z)
}

/// Newell's sum over a polygon's edges: twice its vector area.
fn newell_sum(p: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for k in 0..p.len() {
        let (a, b) = (p[k], p[(k + 1) % p.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    n
}

/// The Newell normal of a polygon (unit; +z when it has no area).
fn newell_normal(p: &[DVec3]) -> DVec3 {
    newell_sum(p).normalize_or(DVec3::Z)
}

pub fn quad_metrics(q: [DVec3; 4]) -> QuadMetrics {
    // Degenerate (three corners collinear): any fourth corner fits a plane, deviation 0.
    let deviation = quad_deviation(q);
    let diagonal_distance = line_distance(q[0], q[2], q[1], q[3]);
    let edges: f64 = (0..4).map(|k| q[k].distance(q[(k + 1) % 4])).sum::<f64>() / 4.0;
    let diagonals = 0.5 * (q[0].distance(q[2]) + q[1].distance(q[3]));
    let e = q[1] - q[0];
    let torsion_deg = match (
        e.cross(q[3] - q[0]).try_normalize(),
        e.cross(q[2] - q[1]).try_normalize(),
    ) {
        (Some(a), Some(b)) => a.dot(b).clamp(-1.0, 1.0).acos().to_degrees(),
        _ => 0.0,
    };
    let mut m = QuadMetrics {
        flatness: 0.0,
        best_fit: 0.0,
        normal: [0.0; 3],
        deviation,
        diagonal_distance,
        diagonal_rel_edge: ratio(diagonal_distance, edges),
        diagonal_rel_diagonal: ratio(diagonal_distance, diagonals),
        torsion_deg,
    };
    plane_figures(&mut m, &q);
    m
}

/// The deviation of a polygon with more than four corners: the largest distance of a corner
/// from the plane through its centroid with the Newell normal. Triangles are planar.
pub fn polygon_deviation(p: &[DVec3]) -> f64 {
    if p.len() < 4 {
        return 0.0;
    }
    let Some(n) = newell_sum(p).try_normalize() else {
        return 0.0;
    };
    let c = p.iter().copied().sum::<DVec3>() / p.len() as f64;
    p.iter().map(|q| (*q - c).dot(n).abs()).fold(0.0, f64::max)
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// Distance between the infinite lines through a–b and c–d (parallel lines: point to line).
fn line_distance(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (u, v, w) = (b - a, d - c, c - a);
    match u.cross(v).try_normalize() {
        Some(n) => w.dot(n).abs(),
        None => match u.try_normalize() {
            Some(u) => (w - u * w.dot(u)).length(),
            None => w.length(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_planar_quad_has_zero_metrics_and_a_twisted_one_does_not() {
        let flat = [
            DVec3::ZERO,
            DVec3::X * 10.0,
            DVec3::new(10.0, 0.0, 5.0),
            DVec3::new(0.0, 0.0, 5.0),
        ];
        let m = quad_metrics(flat);
        assert_eq!(
            (m.deviation, m.diagonal_distance, m.torsion_deg),
            (0.0, 0.0, 0.0)
        );
        // Lift the fourth corner 1 mm out of the plane y = 0.
        let mut twisted = flat;
        twisted[2].y = 1.0;
        let m = quad_metrics(twisted);
        assert!((m.deviation - 1.0).abs() < 1e-12);
        assert!((m.torsion_deg - 1.0f64.atan2(5.0).to_degrees()).abs() < 1e-9);
        assert!(m.diagonal_distance > 0.0 && m.diagonal_distance < 1.0);
    }

    #[test]
    fn panel_deviation_is_the_closed_form() {
        let (va, vb) = (DVec3::ZERO, DVec3::new(7.0, 1.0, 0.5));
        let da = DVec3::new(0.1, -0.2, 1.0).normalize();
        let db = DVec3::new(-0.3, 0.1, 1.0).normalize();
        let h = 100.0;
        let q = panel_quad(va, vb, da, db, h, h);
        let e = vb - va;
        let closed = h * db.dot(e.cross(da)).abs() / e.cross(da).length();
        assert!((quad_metrics(q).deviation - closed).abs() < 1e-9);
    }

    #[test]
    fn a_twisted_square_has_flatness_w_and_a_corner_figure_near_2w() {
        for (side, w) in [(1000.0, 1.0), (100.0, 0.01), (10.0, 2.0)] {
            let q = [
                DVec3::new(0.0, 0.0, w / 2.0),
                DVec3::new(side, 0.0, -w / 2.0),
                DVec3::new(side, side, w / 2.0),
                DVec3::new(0.0, side, -w / 2.0),
            ];
            let m = quad_metrics(q);
            assert!(
                (m.flatness - w).abs() <= 1e-12 * side,
                "{side} {w}: {}",
                m.flatness
            );
            // The corner figure: 2w measured along the tilted plane's normal.
            let tilt = (1.0 + (w / side).powi(2) * 2.0).sqrt();
            assert!(
                (m.deviation - 2.0 * w / tilt).abs() < 1e-9 * side,
                "{}",
                m.deviation
            );
            // Best fit: the plane z = 0, every corner w/2 from it.
            assert!((m.best_fit - w / 2.0).abs() < 1e-9 * side, "{}", m.best_fit);
            let n = DVec3::from(m.normal);
            assert!((n.z.abs() - 1.0).abs() < 1e-6 && n.z > 0.0);
        }
    }

    #[test]
    fn a_planar_ngon_has_zero_flatness_in_any_pose() {
        let rot = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let p: Vec<DVec3> = (0..9)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 9.0;
                rot * DVec3::new(50.0 * t.cos(), 30.0 * t.sin(), 0.0) + DVec3::new(1e3, -2e3, 7.0)
            })
            .collect();
        let m = polygon_metrics(&p);
        assert!(m.flatness < 1e-9 && m.best_fit < 1e-9, "{m:?}");
        assert!((DVec3::from(m.normal) - rot * DVec3::Z).length() < 1e-9);
    }

    #[test]
    fn flatness_is_the_thinnest_zone_over_sampled_directions() {
        // Against a dense search over directions: never thinner, and close.
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for n in [4, 5, 7, 12] {
            let p: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(100.0 * rnd(), 100.0 * rnd(), 3.0 * rnd()))
                .collect();
            let (w, normal) = min_zone(&p).unwrap();
            let extent = |d: DVec3| {
                let t: Vec<f64> = p.iter().map(|q| q.dot(d)).collect();
                t.iter().cloned().fold(f64::MIN, f64::max)
                    - t.iter().cloned().fold(f64::MAX, f64::min)
            };
            assert!((extent(normal) - w).abs() < 1e-9);
            let mut sampled = f64::MAX;
            for a in 0..200 {
                for b in 0..200 {
                    let (th, ph) = (
                        a as f64 / 200.0 * 0.2,
                        b as f64 / 200.0 * std::f64::consts::TAU,
                    );
                    let d = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                    sampled = sampled.min(extent(d));
                }
            }
            assert!(w <= sampled + 1e-12, "{n}: {w} > {sampled}");
            assert!(w > 0.95 * sampled, "{n}: {w} vs {sampled}");
        }
    }

    #[test]
    fn newell_deviation_of_a_pentagon() {
        let mut p: Vec<DVec3> = (0..5)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 5.0;
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        assert!(polygon_deviation(&p) < 1e-12);
        p[0].z = 0.5;
        assert!(polygon_deviation(&p) > 0.1);
    }
}
