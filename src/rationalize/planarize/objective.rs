//! The planarity objective and its gradient in the reduced coordinates.
//!
//! Each node's axis is d_i = u_i / |u_i| with u_i = b_i + Σ_k x_ik·t_ik: `b_i` is the reference
//! direction (or its projection into a fixed plane), `t_ik` the 0, 1 or 2 unit directions the
//! node may move in (a fixed axis, an axis held in a plane, a free axis: 2 DoF, as the paper
//! says). At x = 0 every axis is its reference.
//!
//! E(x) = Σ_edges w_ij·(ê_ij · (d_i × d_j))² + α·Σ_i |d_i − b_i|²
//!
//! The first term is zero exactly when each panel is planar (det(ê, d_i, d_j) = 0); the second
//! keeps axes near the reference. ∂/∂d_i of ê·(d_i × d_j) is d_j × ê, of it in d_j is ê × d_i;
//! the chain rule through the normalisation gives ∂d/∂x_k = (t_k − d (d·t_k)) / |u|.

use glam::DVec3;

/// How one node's axis may move: d = normalize(base + Σ x_k·t_k).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub base: DVec3,
    pub t: [DVec3; 2],
    pub dof: usize,
    /// Index of this node's first coordinate in x.
    pub offset: usize,
}

impl Frame {
    pub fn axis(&self, x: &[f64]) -> (DVec3, f64) {
        let mut u = self.base;
        for k in 0..self.dof {
            u += self.t[k] * x[self.offset + k];
        }
        let len = u.length();
        (u / len, len)
    }
}

/// The problem the solvers share.
pub struct Objective<'a> {
    pub frames: &'a [Frame],
    /// Unit edge directions and their weights.
    pub edges: &'a [(u32, u32, DVec3, f64)],
    pub alpha: f64,
    pub dims: usize,
}

impl Objective<'_> {
    pub fn axes(&self, x: &[f64]) -> Vec<DVec3> {
        self.frames.iter().map(|f| f.axis(x).0).collect()
    }

    pub fn cost(&self, x: &[f64]) -> f64 {
        let d = self.axes(x);
        let planar: f64 = self
            .edges
            .iter()
            .map(|&(a, b, e, w)| w * e.dot(d[a as usize].cross(d[b as usize])).powi(2))
            .sum();
        let close: f64 = self
            .frames
            .iter()
            .zip(&d)
            .map(|(f, d)| (*d - f.base).length_squared())
            .sum();
        planar + self.alpha * close
    }

    pub fn gradient(&self, x: &[f64]) -> Vec<f64> {
        let (d, len): (Vec<DVec3>, Vec<f64>) = self.frames.iter().map(|f| f.axis(x)).unzip();
        // dE/dd_i first, then through the normalisation.
        let mut g: Vec<DVec3> = self
            .frames
            .iter()
            .zip(&d)
            .map(|(f, d)| (*d - f.base) * (2.0 * self.alpha))
            .collect();
        for &(a, b, e, w) in self.edges {
            let (da, db) = (d[a as usize], d[b as usize]);
            let f = 2.0 * w * e.dot(da.cross(db));
            g[a as usize] += db.cross(e) * f;
            g[b as usize] += e.cross(da) * f;
        }
        let mut out = vec![0.0; self.dims];
        for (i, fr) in self.frames.iter().enumerate() {
            for k in 0..fr.dof {
                let t = fr.t[k];
                let dd = (t - d[i] * d[i].dot(t)) / len[i];
                out[fr.offset + k] = g[i].dot(dd);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn gradient_matches_finite_differences() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut unit = || {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize()
        };
        // Six nodes: free, free, in a plane, free, fixed, free.
        let mut frames = Vec::new();
        let mut offset = 0;
        for k in 0..6 {
            let base = unit();
            let any = base.any_orthonormal_pair();
            let dof = match k {
                2 => 1,
                4 => 0,
                _ => 2,
            };
            frames.push(Frame {
                base,
                t: [any.0, any.1],
                dof,
                offset,
            });
            offset += dof;
        }
        let edges: Vec<(u32, u32, DVec3, f64)> =
            [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (1, 4)]
                .iter()
                .map(|&(a, b)| (a, b, unit(), 0.5 + a as f64 * 0.1))
                .collect();
        let obj = Objective {
            frames: &frames,
            edges: &edges,
            alpha: 0.03,
            dims: offset,
        };
        let x: Vec<f64> = (0..offset).map(|k| 0.1 * (k as f64 - 2.0)).collect();
        let g = obj.gradient(&x);
        for k in 0..offset {
            let h = 1e-6;
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[k] += h;
            xm[k] -= h;
            let fd = (obj.cost(&xp) - obj.cost(&xm)) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-7 * (1.0 + fd.abs()),
                "coordinate {k}: analytic {} vs finite difference {fd}",
                g[k]
            );
        }
    }
}
