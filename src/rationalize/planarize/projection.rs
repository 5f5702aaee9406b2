//! The paper's iterative method (Gokmen §4.4.1): estimate each panel's normal as the average of
//! d_i × e and d_j × e (or take its fixed normal), project every axis onto the planes of its
//! panels, move it `step` of the way toward the average of those projections (and α·step toward
//! its reference), keep it in its frame, and repeat until the panels are within the tolerance
//! or nothing moves.

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

#[allow(clippy::too_many_arguments)]
pub fn solve(
    frames: &[Frame],
    edges: &[(u32, u32, DVec3, f64)],
    edge_normal: &[Option<DVec3>],
    axes: &mut [DVec3],
    alpha: f64,
    step: f64,
    budget: usize,
    tolerance: f64,
    max_dev: &dyn Fn(&[DVec3]) -> f64,
) -> Run {
    let n = axes.len();
    let mut history = Vec::new();
    let mut sum = vec![DVec3::ZERO; n];
    let mut count = vec![0u32; n];
    let mut iterations = 0;
    while iterations < budget {
        iterations += 1;
        sum.iter_mut().for_each(|s| *s = DVec3::ZERO);
        count.iter_mut().for_each(|c| *c = 0);
        for (k, &(a, b, e, _)) in edges.iter().enumerate() {
            let (da, db) = (axes[a as usize], axes[b as usize]);
            let normal = match edge_normal[k] {
                Some(nrm) => Some(nrm),
                None => (da.cross(e) + db.cross(e)).try_normalize(),
            };
            let Some(nrm) = normal else { continue };
            for (v, d) in [(a, da), (b, db)] {
                sum[v as usize] += d - nrm * d.dot(nrm);
                count[v as usize] += 1;
            }
        }
        let mut moved: f64 = 0.0;
        for i in 0..n {
            let d = axes[i];
            let target = if count[i] > 0 {
                sum[i] / count[i] as f64
            } else {
                d
            };
            let next = d + (target - d) * step + (frames[i].base - d) * (alpha * step);
            let next = constrain(&frames[i], next);
            moved = moved.max(next.distance(d));
            axes[i] = next;
        }
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
