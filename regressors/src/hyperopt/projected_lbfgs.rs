//! A bounded quasi-Newton method with L-BFGS-B's behaviour (Byrd, Lu,
//! Nocedal & Zhu 1995), written as an argmin [`Solver`]: the optimiser only
//! ever evaluates points inside the box, variables held at a bound by the
//! gradient are fixed for the step, and the L-BFGS direction (memory `m`,
//! two-loop recursion, initial scaling `sᵀy / yᵀy`) is computed in the
//! subspace of the free variables. The step follows the projected path
//! `P(x + α d)` with an Armijo backtracking search (quadratic interpolation,
//! `c₁ = 10⁻⁴`), which accepts `α = 1` on almost every iteration, so one
//! iteration costs about one objective-and-gradient evaluation (scipy's
//! L-BFGS-B, which GPy uses, needs about as many).
//!
//! It stops when the projected gradient `‖P(x − g) − x‖_∞` falls below the
//! gradient tolerance, when an iteration lowers the cost by less than the
//! cost tolerance, or when no step along the direction lowers it.

use std::collections::VecDeque;

use super::CostTolerance;
use argmin::core::{
    CostFunction, Error as ArgminError, Gradient, IterState, KV, Problem, Solver, State,
    TerminationReason, TerminationStatus,
};

/// The optimiser's state: parameters and gradients as plain vectors.
pub(super) type BoxState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// Sufficient-decrease constant of the Armijo condition.
const ARMIJO: f64 = 1e-4;
/// Step halvings (at most) before a line search gives up.
const MAX_BACKTRACKS: usize = 30;

/// Projected L-BFGS on the box `[lower, upper]` (infinite bounds allowed).
#[derive(Debug, Clone)]
pub struct ProjectedLbfgs {
    lower: Vec<f64>,
    upper: Vec<f64>,
    memory: usize,
    tol_projected_gradient: f64,
    tol_cost: CostTolerance,
    pairs: VecDeque<(Vec<f64>, Vec<f64>)>,
    /// Why the search stopped, when it stopped itself.
    stopped: Option<TerminationReason>,
}

impl ProjectedLbfgs {
    /// A solver for the box `[lower, upper]` with `memory` correction pairs,
    /// stopping at a projected-gradient norm below `tol_projected_gradient`
    /// or a relative decrease of the cost within `tol_cost`.
    pub fn new(
        lower: Vec<f64>,
        upper: Vec<f64>,
        memory: usize,
        tol_projected_gradient: f64,
        tol_cost: CostTolerance,
    ) -> Self {
        Self {
            lower,
            upper,
            memory: memory.max(1),
            tol_projected_gradient,
            tol_cost,
            pairs: VecDeque::new(),
            stopped: None,
        }
    }

    /// `x` projected onto the box.
    pub fn project(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.lower.iter().zip(&self.upper))
            .map(|(v, (lo, hi))| v.clamp(*lo, *hi))
            .collect()
    }

    /// `‖P(x − g) − x‖_∞`, zero exactly at a first-order point of the box.
    pub fn projected_gradient_norm(&self, x: &[f64], g: &[f64]) -> f64 {
        x.iter()
            .zip(g)
            .zip(self.lower.iter().zip(&self.upper))
            .map(|((x, g), (lo, hi))| ((x - g).clamp(*lo, *hi) - x).abs())
            .fold(0.0, f64::max)
    }

    /// Which variables may move: not at a bound that the gradient pushes
    /// against.
    fn free(&self, x: &[f64], g: &[f64]) -> Vec<bool> {
        x.iter()
            .zip(g)
            .zip(self.lower.iter().zip(&self.upper))
            .map(|((x, g), (lo, hi))| !((*x <= *lo && *g > 0.0) || (*x >= *hi && *g < 0.0)))
            .collect()
    }

    /// The L-BFGS direction `−H g` in the free subspace (zero elsewhere).
    fn direction(&self, g: &[f64], free: &[bool]) -> Vec<f64> {
        let dot = |a: &[f64], b: &[f64]| -> f64 {
            a.iter()
                .zip(b)
                .zip(free)
                .filter(|(_, f)| **f)
                .map(|((a, b), _)| a * b)
                .sum()
        };
        let mut q: Vec<f64> = g
            .iter()
            .zip(free)
            .map(|(g, f)| if *f { *g } else { 0.0 })
            .collect();
        let usable: Vec<(&Vec<f64>, &Vec<f64>, f64)> = self
            .pairs
            .iter()
            .filter_map(|(s, y)| {
                let sy = dot(s, y);
                (sy > 1e-12 * dot(y, y).max(f64::MIN_POSITIVE)).then_some((s, y, 1.0 / sy))
            })
            .collect();
        let mut alphas = Vec::with_capacity(usable.len());
        for (s, y, rho) in usable.iter().rev() {
            let a = rho * dot(s, &q);
            for ((q, y), f) in q.iter_mut().zip(y.iter()).zip(free) {
                if *f {
                    *q -= a * y;
                }
            }
            alphas.push(a);
        }
        if let Some((s, y, _)) = usable.last() {
            let gamma = dot(s, y) / dot(y, y);
            q.iter_mut().for_each(|v| *v *= gamma);
        }
        for ((s, y, rho), a) in usable.iter().zip(alphas.iter().rev()) {
            let b = rho * dot(y, &q);
            for ((q, s), f) in q.iter_mut().zip(s.iter()).zip(free) {
                if *f {
                    *q += (a - b) * s;
                }
            }
        }
        q.iter().map(|v| -v).collect()
    }
}

/// The cost at `x`, with a failed evaluation (e.g. a factorisation that
/// failed far from the start) read as `+∞` so that the search steps back.
fn cost_or_infinity<O>(problem: &mut Problem<O>, x: &Vec<f64>) -> Result<f64, ArgminError>
where
    O: CostFunction<Param = Vec<f64>, Output = f64>,
{
    match problem.cost(x) {
        Ok(c) if c.is_finite() => Ok(c),
        Ok(_) => Ok(f64::INFINITY),
        Err(e) => {
            tracing::debug!(error = %e, "objective failed during the line search; stepping back");
            Ok(f64::INFINITY)
        }
    }
}

/// An accepted line-search step: the new point, its cost and the step.
type AcceptedStep = (Vec<f64>, f64, Vec<f64>);

impl ProjectedLbfgs {
    /// A backtracking (Armijo) search from `x` along the L-BFGS direction,
    /// or steepest descent on the free variables when that is not downhill
    /// or there is no curvature yet: the accepted point, its cost and the
    /// step, or `None` when no projected step lowers the objective.
    fn line_search<O>(
        &mut self,
        problem: &mut Problem<O>,
        x: &[f64],
        f: f64,
        g: &[f64],
        free: &[bool],
    ) -> Result<Option<AcceptedStep>, ArgminError>
    where
        O: CostFunction<Param = Vec<f64>, Output = f64>,
    {
        let mut d = self.direction(g, free);
        let mut slope: f64 = g.iter().zip(&d).map(|(g, d)| g * d).sum();
        if slope.is_nan() || slope >= 0.0 {
            // Not a descent direction: forget the curvature, go downhill.
            self.pairs.clear();
            d = g
                .iter()
                .zip(free)
                .map(|(g, f)| if *f { -g } else { 0.0 })
                .collect();
            slope = g.iter().zip(&d).map(|(g, d)| g * d).sum();
        }
        // The first step (no curvature yet) is at most one unit long, as
        // L-BFGS-B's.
        let d_norm = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut alpha = if self.pairs.is_empty() && d_norm > 1.0 {
            1.0 / d_norm
        } else {
            1.0
        };
        for _ in 0..MAX_BACKTRACKS {
            let trial: Vec<f64> = self.project(
                &x.iter()
                    .zip(&d)
                    .map(|(x, d)| x + alpha * d)
                    .collect::<Vec<_>>(),
            );
            let step: Vec<f64> = trial.iter().zip(x).map(|(t, x)| t - x).collect();
            let predicted: f64 = g.iter().zip(&step).map(|(g, s)| g * s).sum();
            if step.iter().all(|s| *s == 0.0) || predicted.is_nan() || predicted >= 0.0 {
                return Ok(None);
            }
            let f_trial = cost_or_infinity(problem, &trial)?;
            if f_trial <= f + ARMIJO * predicted {
                return Ok(Some((trial, f_trial, step)));
            }
            // Minimiser of the quadratic through f, the slope and f_trial,
            // kept within [0.1, 0.5] of the current step.
            let next = if f_trial.is_finite() {
                let denominator = 2.0 * (f_trial - f - slope * alpha);
                if denominator > 0.0 {
                    -slope * alpha * alpha / denominator
                } else {
                    0.5 * alpha
                }
            } else {
                0.1 * alpha
            };
            alpha = next.clamp(0.1 * alpha, 0.5 * alpha);
        }
        Ok(None)
    }
}

impl<O> Solver<O, BoxState> for ProjectedLbfgs
where
    O: CostFunction<Param = Vec<f64>, Output = f64>
        + Gradient<Param = Vec<f64>, Gradient = Vec<f64>>,
{
    fn name(&self) -> &str {
        "projected L-BFGS (L-BFGS-B)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        mut state: BoxState,
    ) -> Result<(BoxState, Option<KV>), ArgminError> {
        let x0 = state.take_param().ok_or_else(|| {
            ArgminError::msg("projected L-BFGS needs an initial point (Executor::configure)")
        })?;
        let x0 = self.project(&x0);
        let cost = problem.cost(&x0)?;
        let gradient = problem.gradient(&x0)?;
        Ok((state.param(x0).cost(cost).gradient(gradient), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: BoxState,
    ) -> Result<(BoxState, Option<KV>), ArgminError> {
        let x = state
            .take_param()
            .ok_or_else(|| ArgminError::msg("projected L-BFGS lost its point"))?;
        let g = state
            .take_gradient()
            .ok_or_else(|| ArgminError::msg("projected L-BFGS lost its gradient"))?;
        let f = state.get_cost();
        let free = self.free(&x, &g);
        // As L-BFGS-B: when no step along the quasi-Newton direction lowers
        // the objective (its projection onto the box can turn it uphill),
        // forget the curvature pairs and retry once along steepest descent.
        let mut accepted = None;
        for attempt in 0..2 {
            if attempt == 1 {
                if self.pairs.is_empty() {
                    break;
                }
                tracing::debug!("line search failed; clearing the L-BFGS memory");
                self.pairs.clear();
            }
            accepted = self.line_search(problem, &x, f, &g, &free)?;
            if accepted.is_some() {
                break;
            }
        }
        let Some((x_new, f_new, s)) = accepted else {
            self.stopped = Some(TerminationReason::SolverExit(
                "no step along the search direction lowers the objective".into(),
            ));
            return Ok((state.param(x).gradient(g), None));
        };
        let g_new = problem.gradient(&x_new)?;
        let y: Vec<f64> = g_new.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy: f64 = s.iter().zip(&y).map(|(s, y)| s * y).sum();
        let yy: f64 = y.iter().map(|v| v * v).sum();
        if sy > f64::EPSILON * yy {
            self.pairs.push_back((s, y));
            if self.pairs.len() > self.memory {
                self.pairs.pop_front();
            }
        }
        if self.tol_cost.converged(f, f_new) {
            self.stopped = Some(TerminationReason::SolverConverged);
        }
        if self.projected_gradient_norm(&x_new, &g_new) < self.tol_projected_gradient {
            self.stopped = Some(TerminationReason::SolverConverged);
        }
        Ok((state.param(x_new).cost(f_new).gradient(g_new), None))
    }

    fn terminate(&mut self, state: &BoxState) -> TerminationStatus {
        if let Some(reason) = &self.stopped {
            return TerminationStatus::Terminated(reason.clone());
        }
        if state.get_iter() == 0
            && let (Some(x), Some(g)) = (state.get_param(), state.get_gradient())
            && self.projected_gradient_norm(x, g) < self.tol_projected_gradient
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

#[cfg(test)]
mod tests {
    use argmin::core::Executor;

    use super::*;

    /// No stopping on the cost: the tests converge on the gradient.
    const NEVER: CostTolerance = CostTolerance {
        relative: 0.0,
        unit: 1.0,
    };

    /// `½ xᵀ A x − bᵀ x` with a coupled SPD `A`.
    struct Quadratic {
        a: Vec<Vec<f64>>,
        b: Vec<f64>,
    }

    impl Quadratic {
        fn new() -> Self {
            Self {
                a: vec![
                    vec![4.0, 1.0, 0.5],
                    vec![1.0, 3.0, -0.4],
                    vec![0.5, -0.4, 2.0],
                ],
                b: vec![1.0, -2.0, 3.0],
            }
        }
        fn ax(&self, x: &[f64]) -> Vec<f64> {
            self.a
                .iter()
                .map(|row| row.iter().zip(x).map(|(a, x)| a * x).sum())
                .collect()
        }
    }

    impl CostFunction for Quadratic {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, ArgminError> {
            let ax = self.ax(x);
            Ok(x.iter()
                .zip(&ax)
                .zip(&self.b)
                .map(|((x, ax), b)| 0.5 * x * ax - b * x)
                .sum())
        }
    }

    impl Gradient for Quadratic {
        type Param = Vec<f64>;
        type Gradient = Vec<f64>;
        fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
            Ok(self
                .ax(x)
                .iter()
                .zip(&self.b)
                .map(|(ax, b)| ax - b)
                .collect())
        }
    }

    /// Rosenbrock in 4 dimensions, minimum 0 at (1, 1, 1, 1).
    struct Rosenbrock;

    impl CostFunction for Rosenbrock {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, ArgminError> {
            Ok(x.windows(2)
                .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
                .sum())
        }
    }

    impl Gradient for Rosenbrock {
        type Param = Vec<f64>;
        type Gradient = Vec<f64>;
        fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
            let mut g = vec![0.0; x.len()];
            for i in 0..x.len() - 1 {
                let r = x[i + 1] - x[i] * x[i];
                g[i] += -400.0 * x[i] * r - 2.0 * (1.0 - x[i]);
                g[i + 1] += 200.0 * r;
            }
            Ok(g)
        }
    }

    fn solve<O>(problem: O, solver: ProjectedLbfgs, x0: Vec<f64>) -> (Vec<f64>, f64, u64)
    where
        O: CostFunction<Param = Vec<f64>, Output = f64>
            + Gradient<Param = Vec<f64>, Gradient = Vec<f64>>,
    {
        let result = Executor::new(problem, solver)
            .configure(|s| s.param(x0).max_iters(500))
            .run()
            .unwrap();
        let state = result.state();
        (
            state.get_best_param().unwrap().clone(),
            state.get_best_cost(),
            state.get_iter(),
        )
    }

    /// `½ Σ_i c_i x_i²` rotated by a fixed chain of 2-D rotations, with
    /// curvatures `c_i` spread over three decades: a 40-D problem whose
    /// conditioning a short memory sees only in part.
    struct IllConditioned {
        curvature: Vec<f64>,
    }

    impl IllConditioned {
        fn new(d: usize) -> Self {
            Self {
                curvature: (0..d)
                    .map(|i| 10f64.powf(3.0 * i as f64 / (d - 1) as f64))
                    .collect(),
            }
        }
        /// `Rᵀ x` with `R` a product of rotations of adjacent coordinates.
        fn rotate(x: &[f64], inverse: bool) -> Vec<f64> {
            let mut z = x.to_vec();
            let (c, s) = (0.8f64, 0.6f64);
            let pairs: Vec<usize> = (0..z.len() - 1).collect();
            let order: Vec<usize> = if inverse {
                pairs.into_iter().rev().collect()
            } else {
                pairs
            };
            for i in order {
                let s = if inverse { -s } else { s };
                let (a, b) = (z[i], z[i + 1]);
                z[i] = c * a - s * b;
                z[i + 1] = s * a + c * b;
            }
            z
        }
    }

    impl CostFunction for IllConditioned {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, ArgminError> {
            let z = Self::rotate(x, false);
            Ok(z.iter()
                .zip(&self.curvature)
                .map(|(z, c)| 0.5 * c * z * z)
                .sum())
        }
    }

    impl Gradient for IllConditioned {
        type Param = Vec<f64>;
        type Gradient = Vec<f64>;
        fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
            let z = Self::rotate(x, false);
            let gz: Vec<f64> = z.iter().zip(&self.curvature).map(|(z, c)| c * z).collect();
            Ok(Self::rotate(&gz, true))
        }
    }

    #[test]
    fn a_longer_memory_needs_fewer_iterations_on_an_ill_conditioned_problem() {
        let d = 40;
        // The rotation is orthogonal: its inverse undoes it.
        let x: Vec<f64> = (0..d).map(|i| (i as f64 * 0.37).sin()).collect();
        let back = IllConditioned::rotate(&IllConditioned::rotate(&x, false), true);
        assert!(x.iter().zip(&back).all(|(a, b)| (a - b).abs() < 1e-12));
        let iterations = |memory: usize| {
            let solver = ProjectedLbfgs::new(vec![-10.0; d], vec![10.0; d], memory, 1e-8, NEVER);
            let (x, cost, iters) = solve(IllConditioned::new(d), solver, vec![1.0; d]);
            assert!(cost < 1e-12, "memory {memory}: cost {cost} at {x:?}");
            iters
        };
        let (short, long) = (iterations(3), iterations(30));
        assert!(
            long < short,
            "memory 30 took {long} iterations, memory 3 took {short}"
        );
    }

    #[test]
    fn agrees_with_the_unbounded_optimum_inside_the_box() {
        // A x = b solved by hand: the optimum lies inside [-5, 5]³.
        let q = Quadratic::new();
        let solver = ProjectedLbfgs::new(vec![-5.0; 3], vec![5.0; 3], 10, 1e-10, NEVER);
        let (x, _, iters) = solve(Quadratic::new(), solver, vec![0.0; 3]);
        let residual: Vec<f64> = q.ax(&x).iter().zip(&q.b).map(|(a, b)| a - b).collect();
        assert!(
            residual.iter().all(|r| r.abs() < 1e-8),
            "{x:?} {residual:?}"
        );
        assert!(iters < 20, "a 3-D quadratic took {iters} iterations");

        let solver = ProjectedLbfgs::new(vec![-2.0; 4], vec![2.0; 4], 10, 1e-10, NEVER);
        let (x, cost, _) = solve(Rosenbrock, solver, vec![-1.2, 1.0, -1.2, 1.0]);
        assert!(cost < 1e-14, "{cost}");
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-6), "{x:?}");
    }

    #[test]
    fn stops_on_a_bound_that_binds_and_satisfies_kkt() {
        // x₂ ≤ 0.5 binds (the unbounded optimum has x₂ ≈ 1.77); x₀, x₁ stay
        // free and must minimise the quadratic with x₂ fixed at 0.5.
        let q = Quadratic::new();
        let upper = vec![10.0, 10.0, 0.5];
        let solver = ProjectedLbfgs::new(vec![-10.0; 3], upper.clone(), 10, 1e-12, NEVER);
        let (x, _, _) = solve(Quadratic::new(), solver, vec![0.0; 3]);
        assert_eq!(x[2], 0.5, "the bound binds exactly: {x:?}");
        let g = q.gradient(&x).unwrap();
        assert!(g[0].abs() < 1e-8 && g[1].abs() < 1e-8, "{g:?}");
        assert!(g[2] < 0.0, "the gradient pushes against the bound: {g:?}");
        // The same with x₂ fixed by hand: a 2-D linear system.
        let (a, b) = (&q.a, &q.b);
        let r0 = b[0] - a[0][2] * 0.5;
        let r1 = b[1] - a[1][2] * 0.5;
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let x0 = (r0 * a[1][1] - a[0][1] * r1) / det;
        let x1 = (a[0][0] * r1 - a[1][0] * r0) / det;
        assert!((x[0] - x0).abs() < 1e-8 && (x[1] - x1).abs() < 1e-8);
    }

    #[test]
    fn a_bound_that_does_not_bind_changes_nothing() {
        let wide = ProjectedLbfgs::new(vec![-1e3; 4], vec![1e3; 4], 10, 1e-10, NEVER);
        let unbounded = ProjectedLbfgs::new(
            vec![f64::NEG_INFINITY; 4],
            vec![f64::INFINITY; 4],
            10,
            1e-10,
            NEVER,
        );
        let x0 = vec![-1.2, 1.0, -1.2, 1.0];
        let (a, ca, ia) = solve(Rosenbrock, wide, x0.clone());
        let (b, cb, ib) = solve(Rosenbrock, unbounded, x0);
        assert_eq!((a, ca, ia), (b, cb, ib));
    }

    #[test]
    fn never_evaluates_outside_the_box() {
        struct Guarded;
        impl CostFunction for Guarded {
            type Param = Vec<f64>;
            type Output = f64;
            fn cost(&self, x: &Vec<f64>) -> Result<f64, ArgminError> {
                assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{x:?}");
                Rosenbrock.cost(x)
            }
        }
        impl Gradient for Guarded {
            type Param = Vec<f64>;
            type Gradient = Vec<f64>;
            fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
                assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{x:?}");
                Rosenbrock.gradient(x)
            }
        }
        let solver = ProjectedLbfgs::new(vec![0.0; 4], vec![1.0; 4], 10, 1e-10, NEVER);
        let (x, cost, _) = solve(Guarded, solver, vec![0.9, 0.0, 0.3, 0.7]);
        assert!(cost < 1e-12 && x.iter().all(|v| (v - 1.0).abs() < 1e-6));
    }

    /// `x0 + x1`: a constant gradient (1, 1).
    struct Plane;

    impl CostFunction for Plane {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, ArgminError> {
            Ok(x[0] + x[1])
        }
    }

    impl Gradient for Plane {
        type Param = Vec<f64>;
        type Gradient = Vec<f64>;
        fn gradient(&self, _: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
            Ok(vec![1.0, 1.0])
        }
    }

    #[test]
    fn an_uphill_projected_step_clears_the_memory_instead_of_stopping() {
        // With the pair s = (−1, 1), y = (2, 3) the L-BFGS direction at
        // g = (1, 1) is (−6/13, 4/13): downhill, but x0 sits 1e-9 above its
        // bound, so the projected step is (−1e-9, 4/13), uphill at every
        // step length the search tries. L-BFGS-B then forgets the pairs and
        // steps along −g.
        let mut solver = ProjectedLbfgs::new(vec![0.0, -10.0], vec![10.0, 10.0], 10, 1e-12, NEVER);
        solver.pairs.push_back((vec![-1.0, 1.0], vec![2.0, 3.0]));
        let d = solver.direction(&[1.0, 1.0], &[true, true]);
        assert!(
            (d[0] + 6.0 / 13.0).abs() < 1e-12 && (d[1] - 4.0 / 13.0).abs() < 1e-12,
            "{d:?}"
        );
        let result = Executor::new(Plane, solver)
            .configure(|s| s.param(vec![1e-9, 0.0]).max_iters(1))
            .run()
            .unwrap();
        let state = result.state();
        assert_eq!(
            state.get_termination_reason(),
            Some(&TerminationReason::MaxItersReached)
        );
        let x = state.get_best_param().unwrap();
        assert_eq!(x[0], 0.0);
        assert!(state.get_best_cost() < -0.7, "{}", state.get_best_cost());
    }
}
