//! The paper's iterative method (Gokmen §4.4.1), with Anderson acceleration.
//!
//! One sweep: estimate each panel's normal as the average of d_i × e and d_j × e (or take its
//! fixed normal), project every axis onto the planes of its panels, move it toward its
//! projections, pull it α toward its reference, and keep it in its frame.
//!
//! Two choices make the sweep land where L-BFGS does:
//! - Every panel pulls equally hard: a node moves `step` × (sum of its pulls) / (the network's
//!   largest degree), rather than `step` of the way to the mean of its projections. Moving to
//!   the mean weighs a panel at a degree-2 node 3/2 as much as one at a degree-3 node, and the
//!   sweep then converges to the planar configuration nearest the references in that skewed
//!   metric: 1.5° away from L-BFGS's answer on the Calyx fixture. With equal pulls every move
//!   lies in the span of the panel constraints' gradients, as in Cimmino's method, so the sweep
//!   ends at the nearest planar configuration, as L-BFGS does when α is small.
//! - Anderson acceleration (depth `MEMORY`) of the sweep as a fixed-point map, as Peng et al.
//!   (2018) use for projection-based geometry solvers: plain sweeps need ~3,000 iterations on
//!   the Calyx fixture because a few modes barely move. A step that raises the sweep's energy
//!   is replaced by the plain sweep and the memory cleared, so it never does worse than plain
//!   sweeps.

use std::collections::VecDeque;

use glam::DVec3;

use super::objective::Frame;

pub struct Run {
    pub iterations: usize,
    /// The largest panel deviation after each iteration, mm.
    pub history: Vec<f64>,
}

/// An iteration that moves no axis by more than this has converged for this α.
const STILL: f64 = 1e-14;
/// This α has done what it can when the largest deviation falls by less than `STALL_GAIN`
/// over `STALL_WINDOW` iterations.
const STALL_WINDOW: usize = 20;
const STALL_GAIN: f64 = 1e-3;
/// Anderson memory: how many past sweeps the extrapolation combines.
const MEMORY: usize = 6;

pub struct Sweep<'a> {
    pub frames: &'a [Frame],
    pub edges: &'a [(u32, u32, DVec3, f64)],
    pub edge_normal: &'a [Option<DVec3>],
    pub alpha: f64,
    pub step: f64,
    /// Per node, what its summed pulls are multiplied by: 1 / the largest degree (equal
    /// pulls), or 1 / its own degree (the mean of its projections, the paper's plain sweep).
    pub scale: &'a [f64],
    pub accelerate: bool,
}

impl Sweep<'_> {
    /// Writes one sweep from `axes` into `out` and returns the energy at `axes`: the squared
    /// distances of the axes from their panels' planes plus α × their squared distances from
    /// the references.
    fn apply(&self, axes: &[DVec3], pull: &mut [DVec3], out: &mut [DVec3]) -> f64 {
        pull.iter_mut().for_each(|p| *p = DVec3::ZERO);
        let mut energy = 0.0;
        for (k, &(a, b, e, _)) in self.edges.iter().enumerate() {
            let (da, db) = (axes[a as usize], axes[b as usize]);
            let normal = match self.edge_normal[k] {
                Some(nrm) => Some(nrm),
                None => (da.cross(e) + db.cross(e)).try_normalize(),
            };
            let Some(nrm) = normal else { continue };
            for (v, d) in [(a, da), (b, db)] {
                let off = d.dot(nrm);
                energy += off * off;
                pull[v as usize] -= nrm * off;
            }
        }
        for (i, d) in axes.iter().enumerate() {
            let f = &self.frames[i];
            let to_ref = f.base - *d;
            if f.dof > 0 {
                energy += self.alpha * to_ref.length_squared();
            }
            let next = *d + (pull[i] + to_ref * self.alpha) * (self.scale[i] * self.step);
            out[i] = constrain(f, next);
        }
        energy
    }
}

#[allow(clippy::too_many_arguments)]
pub fn solve(
    sweep: &Sweep,
    axes: &mut [DVec3],
    budget: usize,
    tolerance: f64,
    max_dev: &dyn Fn(&[DVec3]) -> f64,
    stop: &dyn Fn() -> bool,
) -> Run {
    let n = axes.len();
    let mut history = Vec::new();
    let mut pull = vec![DVec3::ZERO; n];
    let mut g = vec![DVec3::ZERO; n];
    let mut energy = sweep.apply(axes, &mut pull, &mut g);
    let mut memory: VecDeque<(Vec<DVec3>, Vec<DVec3>)> = VecDeque::new(); // (ΔG, ΔF)
    let mut last: Option<(Vec<DVec3>, Vec<DVec3>)> = None; // (G, F) of the previous iterate
    let mut next = vec![DVec3::ZERO; n];
    let mut g_next = vec![DVec3::ZERO; n];
    let mut iterations = 0;
    while iterations < budget && !stop() {
        iterations += 1;
        let f: Vec<DVec3> = g.iter().zip(axes.iter()).map(|(g, x)| *g - *x).collect();
        if let Some((g_prev, f_prev)) = last.take() {
            if memory.len() == MEMORY {
                memory.pop_front();
            }
            memory.push_back((
                g.iter().zip(&g_prev).map(|(a, b)| *a - *b).collect(),
                f.iter().zip(&f_prev).map(|(a, b)| *a - *b).collect(),
            ));
        }
        let gamma = if !sweep.accelerate {
            Vec::new()
        } else {
            least_squares(&memory, &f)
        };
        next.copy_from_slice(&g);
        for (c, (dg, _)) in gamma.iter().zip(&memory) {
            for (x, d) in next.iter_mut().zip(dg) {
                *x -= *d * *c;
            }
        }
        for (x, fr) in next.iter_mut().zip(sweep.frames) {
            *x = constrain(fr, *x);
        }
        let mut e_next = sweep.apply(&next, &mut pull, &mut g_next);
        let worse = e_next.is_nan() || e_next > energy;
        if !gamma.is_empty() && worse {
            // The extrapolation did worse than standing still: take the plain sweep instead.
            next.copy_from_slice(&g);
            e_next = sweep.apply(&next, &mut pull, &mut g_next);
            memory.clear();
        } else {
            last = Some((g.clone(), f));
        }
        let moved = next
            .iter()
            .zip(axes.iter())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        axes.copy_from_slice(&next);
        std::mem::swap(&mut g, &mut g_next);
        energy = e_next;
        let dev = max_dev(axes);
        history.push(dev);
        let stalled = history.len() > STALL_WINDOW
            && dev > (1.0 - STALL_GAIN) * history[history.len() - 1 - STALL_WINDOW];
        if dev <= tolerance || moved < STILL || stalled {
            break;
        }
    }
    Run {
        iterations,
        history,
    }
}

/// γ minimising |f − Σ γ_j ΔF_j|, by the normal equations with a little Tikhonov damping
/// (the columns of ΔF are often nearly dependent).
fn least_squares(memory: &VecDeque<(Vec<DVec3>, Vec<DVec3>)>, f: &[DVec3]) -> Vec<f64> {
    let m = memory.len();
    if m == 0 {
        return Vec::new();
    }
    let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
    let mut a = vec![vec![0.0; m + 1]; m];
    for i in 0..m {
        for j in 0..=i {
            let v = dot(&memory[i].1, &memory[j].1);
            a[i][j] = v;
            a[j][i] = v;
        }
        a[i][m] = dot(&memory[i].1, f);
    }
    let trace: f64 = (0..m).map(|i| a[i][i]).sum();
    if trace.is_nan() || trace <= 0.0 {
        return Vec::new();
    }
    for (i, row) in a.iter_mut().enumerate() {
        row[i] += 1e-10 * trace;
    }
    // Gaussian elimination with partial pivoting on the augmented matrix.
    for col in 0..m {
        let pivot = (col..m)
            .max_by(|&r, &s| a[r][col].abs().total_cmp(&a[s][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        let p = a[col][col];
        if p.abs() < 1e-300 {
            return Vec::new();
        }
        let pivot_row = a[col].clone();
        for row in a.iter_mut().skip(col + 1) {
            let factor = row[col] / p;
            for (x, y) in row.iter_mut().zip(&pivot_row).skip(col) {
                *x -= factor * y;
            }
        }
    }
    let mut gamma = vec![0.0; m];
    for r in (0..m).rev() {
        let s: f64 = (r + 1..m).map(|c| a[r][c] * gamma[c]).sum();
        gamma[r] = (a[r][m] - s) / a[r][r];
    }
    if gamma.iter().all(|g| g.is_finite()) {
        gamma
    } else {
        Vec::new()
    }
}

/// The unit vector nearest `d` that the frame allows.
fn constrain(f: &Frame, d: DVec3) -> DVec3 {
    match f.dof {
        0 => f.base,
        1 => {
            let m = f.base.cross(f.t[0]);
            (d - m * d.dot(m)).try_normalize().unwrap_or(f.base)
        }
        _ => d.try_normalize().unwrap_or(f.base),
    }
}
