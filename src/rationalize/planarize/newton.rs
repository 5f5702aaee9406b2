//! Gauss-Newton on the objective of `objective.rs`, solved through the edges' planarity
//! Jacobian with a sparse Cholesky factorisation (faer).
//!
//! E(x) = |c(x)|² + α·Σ_i |r_i(x)|², with c_e = √w·ê·(d_a × d_b) one residual per edge and
//! r_i = d_i − b_i three per node. With J = ∂c/∂x (E × n, four non-zeros per row) and the
//! block-diagonal D = ∂r/∂x (a 3 × dof block per node, M = DᵀD), the Gauss-Newton step solves
//!
//!   (JᵀJ + αM)·δ = −(Jᵀc + α·Dᵀr).
//!
//! The push-through identity turns that n × n system into one per edge: with q = Dᵀr,
//!
//!   (αI + J M⁻¹ Jᵀ)·μ = J M⁻¹ q − c,   δ = M⁻¹(Jᵀμ − q),
//!
//! and S = αI + J M⁻¹ Jᵀ is sparse: S_ef ≠ 0 only where edges e and f share a node (five
//! entries per column on a degree-3 network). Its pattern does not change between iterations,
//! so the fill-reducing ordering and symbolic factorisation are done once per solve and only
//! the numeric factorisation is repeated. This is the SQP step of "planarity as the constraint,
//! closeness as the objective" with the constraint relaxed by α: α → 0 gives the exact
//! least-change projection onto planar panels.
//!
//! The neglected second-order term is Σ c_e ∇²c_e, small next to αM wherever c is (c ~ α·|x|
//! at the optimum), so the iteration converges linearly at a rate about the axes' angle from
//! their references, independent of the network's size. A backtracking line search on E keeps
//! every step a descent.
//!
//! Every per-node and per-edge quantity is computed independently (in parallel with rayon)
//! and every sum is taken in a fixed order, so the result does not depend on the thread count.
//! The numeric factorisation walks the supernodes in order and hands its dense blocks to faer's
//! kernels on every thread of the pool: they split the work by output block, so each entry is
//! summed in the same order on any number of threads (a test compares the axes bit for bit on
//! 1, 2 and 3 threads; on 1.31 M nodes too, by hand). Solves stay on one thread: one column.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use glam::DVec3;
use rayon::prelude::*;

use super::objective::{Frame, Objective};

/// Gauss-Newton has converged when no coordinate moves more than this (radians of axis).
const STEP_TOLERANCE: f64 = 1e-9;
/// Backtracking halvings before a step is given up on.
const HALVINGS: usize = 30;
/// Armijo constant.
const ARMIJO: f64 = 1e-4;
/// Conjugate-gradient steps on a new S, preconditioned by an old factorisation, before S is
/// factorised afresh; and the relative residual they must reach.
const PCG_STEPS: usize = 12;
const PCG_TOLERANCE: f64 = 1e-10;

/// The sparsity of S = αI + J M⁻¹ Jᵀ over the edges that move (at least one end free).
pub struct Pattern {
    /// Edge number of each row/column of S.
    rows: Vec<usize>,
    system: System,
    /// Per node: its incident rows of S (sorted), as a CSR list.
    node_start: Vec<usize>,
    node_rows: Vec<usize>,
    /// Per node, for each pair (i ≤ j) of its incident rows (in node_rows order, i outer): the
    /// position of entry (max, min) in the values.
    pair_start: Vec<usize>,
    pair_pos: Vec<usize>,
    /// Position of each column's diagonal entry.
    diag: Vec<usize>,
}

/// S's structure and factorisations.
struct System {
    /// Lower triangle, column-major.
    structure: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// The last numeric factorisation, kept as the preconditioner of the next solves at the
    /// same α; `factor_alpha` is that α (None before the first).
    factor: Vec<f64>,
    factor_alpha: Option<f64>,
    /// Workspace of the factorisation and of the triangular solves, kept between iterations
    /// (allocating them afresh each time was a fifth of the time on a million nodes).
    factor_scratch: MemBuffer,
    solve_scratch: MemBuffer,
}

#[derive(Debug, thiserror::Error)]
pub enum NewtonError {
    #[error("the sparse factorisation could not allocate its memory")]
    OutOfMemory,
}

impl Pattern {
    pub fn new(frames: &[Frame], edges: &[(u32, u32, DVec3, f64)]) -> Result<Pattern, NewtonError> {
        let n = frames.len();
        let rows: Vec<usize> = (0..edges.len())
            .filter(|&k| {
                let (a, b, _, _) = edges[k];
                frames[a as usize].dof + frames[b as usize].dof > 0
            })
            .collect();
        // Incident rows per node (only nodes that move carry entries).
        let mut count = vec![0usize; n + 1];
        for &k in &rows {
            let (a, b, _, _) = edges[k];
            for v in [a, b] {
                if frames[v as usize].dof > 0 {
                    count[v as usize + 1] += 1;
                }
            }
        }
        let mut node_start = count;
        for v in 0..n {
            node_start[v + 1] += node_start[v];
        }
        let mut fill = node_start.clone();
        let mut node_rows = vec![0usize; node_start[n]];
        for (r, &k) in rows.iter().enumerate() {
            let (a, b, _, _) = edges[k];
            // A self-loop cannot reach here (zero-length edges are refused), but a repeated
            // edge can: its pair of rows shares both nodes and both contribute.
            for v in [a, b] {
                if frames[v as usize].dof > 0 {
                    node_rows[fill[v as usize]] = r;
                    fill[v as usize] += 1;
                }
            }
        }
        // Column r holds every row ≥ r that shares a node with it.
        let m = rows.len();
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::new();
        let mut diag = Vec::with_capacity(m);
        col_ptr.push(0);
        let mut scratch = Vec::new();
        for (r, &k) in rows.iter().enumerate() {
            let (a, b, _, _) = edges[k];
            scratch.clear();
            scratch.push(r);
            for v in [a as usize, b as usize] {
                scratch.extend(
                    node_rows[node_start[v]..node_start[v + 1]]
                        .iter()
                        .copied()
                        .filter(|&s| s > r),
                );
            }
            scratch.sort_unstable();
            scratch.dedup();
            diag.push(row_idx.len());
            row_idx.extend_from_slice(&scratch);
            col_ptr.push(row_idx.len());
        }
        let mut pair_start = Vec::with_capacity(n + 1);
        let mut pair_pos = Vec::new();
        pair_start.push(0);
        for v in 0..n {
            let inc = &node_rows[node_start[v]..node_start[v + 1]];
            for (i, &ri) in inc.iter().enumerate() {
                for &rj in &inc[i..] {
                    let (hi, lo) = (ri.max(rj), ri.min(rj));
                    let col = &row_idx[col_ptr[lo]..col_ptr[lo + 1]];
                    let at = col.binary_search(&hi).expect("a shared node's pair");
                    pair_pos.push(col_ptr[lo] + at);
                }
            }
            pair_start.push(pair_pos.len());
        }
        let structure = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            structure.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|_| NewtonError::OutOfMemory)?;
        let mut factor = Vec::new();
        factor
            .try_reserve_exact(symbolic.len_val())
            .map_err(|_| NewtonError::OutOfMemory)?;
        factor.resize(symbolic.len_val(), 0.0);
        let factor_scratch = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(factor_par(), Default::default()),
        )
        .map_err(|_| NewtonError::OutOfMemory)?;
        let solve_scratch = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq))
            .map_err(|_| NewtonError::OutOfMemory)?;
        Ok(Pattern {
            rows,
            system: System {
                structure,
                symbolic,
                factor,
                factor_alpha: None,
                factor_scratch,
                solve_scratch,
            },
            node_start,
            node_rows,
            pair_start,
            pair_pos,
            diag,
        })
    }
}

/// S·x for the lower triangle `values` of S.
/// The numeric factorisation's dense kernels on every thread of the pool it runs in.
fn factor_par() -> Par {
    Par::rayon(rayon::current_num_threads())
}

fn product(structure: &SymbolicSparseColMat<usize>, values: &[f64], x: &[f64]) -> Vec<f64> {
    let col_ptr = structure.col_ptr();
    let row_idx = structure.row_idx();
    let mut y = vec![0.0; x.len()];
    for j in 0..x.len() {
        for p in col_ptr[j]..col_ptr[j + 1] {
            let (i, v) = (row_idx[p], values[p]);
            y[i] += v * x[j];
            if i != j {
                y[j] += v * x[i];
            }
        }
    }
    y
}

impl System {
    /// Solves S·μ = rhs in place. The factorisation of an earlier S preconditions conjugate
    /// gradients on this one (S changes little between Gauss-Newton iterations, so a few steps
    /// do); S is factorised afresh only when that does not converge, or α has changed (a new α
    /// moves S's smallest eigenvalues too far for a few steps). None if S is not positive
    /// definite.
    fn solve(&mut self, values: &[f64], mut rhs: Vec<f64>, alpha: f64) -> Option<Vec<f64>> {
        if self.factor_alpha == Some(alpha) {
            if let Some(x) = self.pcg(values, &rhs) {
                return Some(x);
            }
        }
        self.factor_alpha = None;
        let s = SparseColMatRef::new(self.structure.as_ref(), values);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                s,
                Side::Lower,
                LltRegularization::default(),
                factor_par(),
                MemStack::new(&mut self.factor_scratch),
                Default::default(),
            )
            .ok()?;
        self.factor_alpha = Some(alpha);
        self.precondition(&mut rhs);
        Some(rhs)
    }

    /// x ← (the factorised S)⁻¹·x.
    fn precondition(&mut self, x: &mut [f64]) {
        let m = x.len();
        LltRef::new(&self.symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, m, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_scratch),
        );
    }

    /// Preconditioned conjugate gradients; None if the relative residual does not reach
    /// `PCG_TOLERANCE` in `PCG_STEPS` steps.
    fn pcg(&mut self, values: &[f64], b: &[f64]) -> Option<Vec<f64>> {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let norm_b = dot(b, b).sqrt();
        if norm_b == 0.0 {
            return Some(vec![0.0; b.len()]);
        }
        let mut x = b.to_vec();
        self.precondition(&mut x);
        let sx = product(&self.structure, values, &x);
        let mut r: Vec<f64> = b.iter().zip(&sx).map(|(b, s)| b - s).collect();
        let mut z = r.clone();
        self.precondition(&mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        for _ in 0..PCG_STEPS {
            if dot(&r, &r).sqrt() <= PCG_TOLERANCE * norm_b {
                return Some(x);
            }
            let sp = product(&self.structure, values, &p);
            let psp = dot(&p, &sp);
            if psp.is_nan() || psp <= 0.0 {
                return None;
            }
            let a = rz / psp;
            for i in 0..x.len() {
                x[i] += a * p[i];
                r[i] -= a * sp[i];
            }
            z.copy_from_slice(&r);
            self.precondition(&mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (p, z) in p.iter_mut().zip(&z) {
                *p = z + beta * *p;
            }
        }
        (dot(&r, &r).sqrt() <= PCG_TOLERANCE * norm_b).then_some(x)
    }
}

/// One node's linearisation: its axis' derivatives D (3 × dof), M⁻¹ and q = Dᵀr.
#[derive(Clone, Copy, Default)]
struct NodeLin {
    dd: [DVec3; 2],
    m_inv: [[f64; 2]; 2],
    q: [f64; 2],
    d: DVec3,
}

fn linearise(f: &Frame, x: &[f64]) -> NodeLin {
    let (d, len) = f.axis(x);
    let mut lin = NodeLin {
        d,
        ..Default::default()
    };
    let r = d - f.base;
    for k in 0..f.dof {
        let t = f.t[k];
        lin.dd[k] = (t - d * d.dot(t)) / len;
        lin.q[k] = lin.dd[k].dot(r);
    }
    match f.dof {
        1 => lin.m_inv[0][0] = 1.0 / lin.dd[0].length_squared(),
        2 => {
            let (a, b, c) = (
                lin.dd[0].length_squared(),
                lin.dd[0].dot(lin.dd[1]),
                lin.dd[1].length_squared(),
            );
            let det = a * c - b * b;
            lin.m_inv = [[c / det, -b / det], [-b / det, a / det]];
        }
        _ => {}
    }
    lin
}

fn apply(m: &[[f64; 2]; 2], v: [f64; 2]) -> [f64; 2] {
    [
        m[0][0] * v[0] + m[0][1] * v[1],
        m[1][0] * v[0] + m[1][1] * v[1],
    ]
}

pub struct Run {
    pub x: Vec<f64>,
    pub iterations: usize,
    pub history: Vec<f64>,
}

/// Gauss-Newton from `x0` at the objective's α until the step is negligible or `budget`
/// iterations are spent.
pub fn solve(
    obj: &Objective,
    pattern: &mut Pattern,
    x0: Vec<f64>,
    budget: usize,
    stop: &dyn Fn() -> bool,
) -> Run {
    let mut x = x0;
    let mut history = Vec::new();
    let mut iterations = 0;
    if pattern.rows.is_empty() {
        return Run {
            x,
            iterations,
            history,
        };
    }
    let mut cost = obj.cost(&x);
    let mut values = vec![0.0; pattern.system.structure.compute_nnz()];
    let mut last_step: Option<f64> = None;
    while iterations < budget && !stop() {
        iterations += 1;
        let lin: Vec<NodeLin> = obj.frames.par_iter().map(|f| linearise(f, &x)).collect();
        // Each row's Jacobian: coefficients on its two ends' coordinates, and its residual.
        let jac: Vec<([f64; 2], [f64; 2], f64)> = pattern
            .rows
            .par_iter()
            .map(|&k| {
                let (a, b, e, w) = obj.edges[k];
                let (la, lb) = (&lin[a as usize], &lin[b as usize]);
                let s = w.sqrt();
                let ga = lb.d.cross(e) * s;
                let gb = e.cross(la.d) * s;
                let c = s * e.dot(la.d.cross(lb.d));
                (
                    [ga.dot(la.dd[0]), ga.dot(la.dd[1])],
                    [gb.dot(lb.dd[0]), gb.dot(lb.dd[1])],
                    c,
                )
            })
            .collect();
        // The row's coefficients at node v (it is the edge's first or second end).
        let coef = |r: usize, v: usize| -> [f64; 2] {
            let (a, _, _, _) = obj.edges[pattern.rows[r]];
            if a as usize == v {
                jac[r].0
            } else {
                jac[r].1
            }
        };
        values.iter_mut().for_each(|v| *v = 0.0);
        for &p in &pattern.diag {
            values[p] = obj.alpha;
        }
        let mut rhs: Vec<f64> = jac.iter().map(|j| -j.2).collect();
        for (v, l) in lin.iter().enumerate() {
            let inc = &pattern.node_rows[pattern.node_start[v]..pattern.node_start[v + 1]];
            if inc.is_empty() {
                continue;
            }
            let mq = apply(&l.m_inv, l.q);
            let mut p = pattern.pair_start[v];
            for (i, &ri) in inc.iter().enumerate() {
                let gi = coef(ri, v);
                let mg = apply(&l.m_inv, gi);
                rhs[ri] += gi[0] * mq[0] + gi[1] * mq[1];
                for &rj in &inc[i..] {
                    let gj = coef(rj, v);
                    values[pattern.pair_pos[p]] += mg[0] * gj[0] + mg[1] * gj[1];
                    p += 1;
                }
            }
        }
        let Some(mu) = pattern.system.solve(&values, rhs, obj.alpha) else {
            // Not positive definite (α = 0 on an over-constrained node): stop where we are.
            break;
        };
        // δ_v = M⁻¹(Σ_r g_rv μ_r − q_v).
        let delta: Vec<[f64; 2]> = (0..lin.len())
            .into_par_iter()
            .map(|v| {
                let l = &lin[v];
                let mut acc = [-l.q[0], -l.q[1]];
                for &r in &pattern.node_rows[pattern.node_start[v]..pattern.node_start[v + 1]] {
                    let g = coef(r, v);
                    acc[0] += g[0] * mu[r];
                    acc[1] += g[1] * mu[r];
                }
                apply(&l.m_inv, acc)
            })
            .collect();
        let mut step = vec![0.0; x.len()];
        for (f, dv) in obj.frames.iter().zip(&delta) {
            for k in 0..f.dof {
                step[f.offset + k] = dv[k];
            }
        }
        let largest = step.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        if !largest.is_finite() {
            break;
        }
        // Directional derivative of E along the step: 2·(Jᵀc + αq)·δ.
        let mut slope = 0.0;
        for (r, j) in jac.iter().enumerate() {
            let (a, b, _, _) = obj.edges[pattern.rows[r]];
            let (da, db) = (delta[a as usize], delta[b as usize]);
            slope +=
                2.0 * j.2 * (j.0[0] * da[0] + j.0[1] * da[1] + j.1[0] * db[0] + j.1[1] * db[1]);
        }
        for (l, dv) in lin.iter().zip(&delta) {
            slope += 2.0 * obj.alpha * (l.q[0] * dv[0] + l.q[1] * dv[1]);
        }
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..HALVINGS {
            let trial: Vec<f64> = x.iter().zip(&step).map(|(a, s)| a + t * s).collect();
            let c = obj.cost(&trial);
            if c.is_finite() && c <= cost + ARMIJO * t * slope.min(0.0) {
                x = trial;
                cost = c;
                moved = true;
                break;
            }
            t *= 0.5;
        }
        history.push(cost);
        if !moved || t * largest < STEP_TOLERANCE {
            break;
        }
        // Linear convergence at rate ρ leaves about ρ/(1 − ρ) of the last step to go: stop
        // when that is below the tolerance instead of taking one more step to see it.
        let moved_by = t * largest;
        if let Some(before) = last_step {
            let rate: f64 = moved_by / before;
            if rate < 0.5 && moved_by * rate / (1.0 - rate) < STEP_TOLERANCE {
                break;
            }
        }
        last_step = Some(moved_by);
    }
    Run {
        x,
        iterations,
        history,
    }
}
