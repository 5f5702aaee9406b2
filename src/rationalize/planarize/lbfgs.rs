//! L-BFGS through argmin on the objective of `objective.rs`.
//!
//! argmin's line search can fail with "search direction must be a descent direction" (the
//! L-BFGS memory went stale). Then the solve restarts from the best point seen with fresh
//! memory, alternating between the More-Thuente and Hager-Zhang line searches, a few times
//! before it gives up; it never panics. A line search that never settles (More-Thuente can
//! wander on a plateau) is stopped by an evaluation budget per round and handled the same way.
//! It runs in rounds of `ROUND` iterations and stops as soon as the panels are within the
//! tolerance.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{CostFunction, Error, Executor, Gradient, IterState, State, KV};
use argmin::solver::linesearch::{HagerZhangLineSearch, MoreThuenteLineSearch};
use argmin::solver::quasinewton::LBFGS;
use glam::DVec3;

use super::objective::Objective;

/// Iterations per round between tolerance checks.
const ROUND: usize = 25;
/// L-BFGS memory.
const MEMORY: usize = 7;
/// Cost evaluations allowed per iteration, on average over a round.
const EVALS_PER_ITERATION: usize = 30;
/// Line-search step bounds: a finite largest step lets More-Thuente stop on a plateau.
const STEP_BOUNDS: (f64, f64) = (1e-12, 1e4);
/// Restarts after a line-search failure before giving up on this α.
const RESTARTS: usize = 4;

pub struct Run {
    pub x: Vec<f64>,
    pub iterations: usize,
    pub history: Vec<f64>,
}

struct Problem<'a, 'b> {
    obj: &'a Objective<'b>,
    /// The lowest cost evaluated and its point: where to restart after a failure.
    best: &'a RefCell<(f64, Vec<f64>)>,
    /// Evaluations left in this round: a line search that never settles is stopped here.
    left: &'a Cell<usize>,
    /// The caller's stop: checked at every evaluation.
    stop: &'a dyn Fn() -> bool,
}

impl CostFunction for Problem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        let left = self.left.get();
        if left == 0 || (self.stop)() {
            return Err(Error::msg("evaluation budget of the round spent"));
        }
        self.left.set(left - 1);
        let c = self.obj.cost(x);
        let mut best = self.best.borrow_mut();
        if c.is_finite() && c < best.0 {
            *best = (c, x.clone());
        }
        Ok(c)
    }
}

impl Gradient for Problem<'_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, Error> {
        Ok(self.obj.gradient(x))
    }
}

/// Records the cost after every iteration.
struct Curve(Rc<RefCell<Vec<f64>>>);

type LbfgsState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

impl Observe<LbfgsState> for Curve {
    fn observe_iter(&mut self, state: &LbfgsState, _kv: &KV) -> Result<(), Error> {
        self.0.borrow_mut().push(state.get_cost());
        Ok(())
    }
}

pub fn solve(
    obj: &Objective,
    x0: Vec<f64>,
    budget: usize,
    tolerance: f64,
    max_dev: &dyn Fn(&[DVec3]) -> f64,
    stop: &dyn Fn() -> bool,
) -> Run {
    let best = RefCell::new((obj.cost(&x0), x0.clone()));
    let left = Cell::new(0);
    let problem = || Problem {
        obj,
        best: &best,
        left: &left,
        stop,
    };
    let curve = Rc::new(RefCell::new(Vec::new()));
    let mut x = x0;
    let mut iterations = 0;
    let mut failures = 0;
    if obj.dims == 0 {
        return Run {
            x,
            iterations,
            history: Vec::new(),
        };
    }
    while iterations < budget && failures <= RESTARTS && !stop() {
        let round = ROUND.min(budget - iterations) as u64;
        left.set(EVALS_PER_ITERATION * round as usize);
        let result = if failures % 2 == 0 {
            let ls = MoreThuenteLineSearch::new().with_bounds(STEP_BOUNDS.0, STEP_BOUNDS.1);
            ls.map_err(|_| ())
                .and_then(|ls| run(problem(), &curve, x.clone(), round, ls))
        } else {
            let ls = HagerZhangLineSearch::new().with_bounds(STEP_BOUNDS.0, STEP_BOUNDS.1);
            ls.map_err(|_| ())
                .and_then(|ls| run(problem(), &curve, x.clone(), round, ls))
        };
        match result {
            Ok((best, iters, converged)) => {
                x = best;
                iterations += iters.max(1);
                if converged || max_dev(&obj.axes(&x)) <= tolerance {
                    break;
                }
            }
            Err(()) => {
                // A failed line search: start again from the best point with fresh memory.
                failures += 1;
                x = best.borrow().1.clone();
                iterations += 1;
            }
        }
    }
    let lowest = best.borrow().1.clone();
    if obj.cost(&lowest) < obj.cost(&x) {
        x = lowest;
    }
    let history = curve.borrow().clone();
    Run {
        x,
        iterations,
        history,
    }
}

/// One round; Ok(best point, iterations, whether L-BFGS converged on its own).
fn run<'a, 'b, L>(
    problem: Problem<'a, 'b>,
    curve: &Rc<RefCell<Vec<f64>>>,
    x: Vec<f64>,
    iters: u64,
    linesearch: L,
) -> Result<(Vec<f64>, usize, bool), ()>
where
    LBFGS<L, Vec<f64>, Vec<f64>, f64>: argmin::core::Solver<Problem<'a, 'b>, LbfgsState>,
{
    let solver = LBFGS::new(linesearch, MEMORY)
        .with_tolerance_grad(1e-12)
        .and_then(|s| s.with_tolerance_cost(1e-14))
        .map_err(|_| ())?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(x).max_iters(iters))
        .add_observer(Curve(Rc::clone(curve)), ObserverMode::Always)
        .run()
        .map_err(|_| ())?;
    let state = res.state();
    let best = state
        .get_best_param()
        .or(state.get_param())
        .cloned()
        .ok_or(())?;
    let converged = matches!(
        state.get_termination_status(),
        argmin::core::TerminationStatus::Terminated(r)
            if *r != argmin::core::TerminationReason::MaxItersReached
    );
    Ok((best, state.get_iter() as usize, converged))
}
