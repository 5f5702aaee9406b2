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

use glam::DVec3;

/// Planarity figures of one quad.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct QuadMetrics {
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
    QuadMetrics {
        deviation,
        diagonal_distance,
        diagonal_rel_edge: ratio(diagonal_distance, edges),
        diagonal_rel_diagonal: ratio(diagonal_distance, diagonals),
        torsion_deg,
    }
}

/// The deviation of a polygon with more than four corners: the largest distance of a corner
/// from the plane through its centroid with the Newell normal. Triangles are planar.
pub fn polygon_deviation(p: &[DVec3]) -> f64 {
    if p.len() < 4 {
        return 0.0;
    }
    let mut n = DVec3::ZERO;
    for k in 0..p.len() {
        let (a, b) = (p[k], p[(k + 1) % p.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let Some(n) = n.try_normalize() else {
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
