//! The objective as the optimiser sees it: a cost to minimise over
//! unclamped coordinates. Three small parts do its jobs: [`CostMap`]
//! (negation, scale, bound penalties and the chain rule through the
//! clamp), [`LastPoint`] (argmin asks for the cost and the gradient
//! separately, at the same point) and [`BestPoint`] (the best point
//! evaluated, by objective alone); [`Negated`] puts them together and
//! counts the evaluations.

use std::cell::{Cell, RefCell};

use argmin::core::{CostFunction, Error as ArgminError, Gradient};

use super::{LogBounds, Objective};
use crate::RegressorError;

/// One evaluation of the objective, before negation and scaling.
struct RawEvaluation {
    /// Where it was evaluated (the optimiser's point, clamped).
    clamped: Vec<f64>,
    value: f64,
    gradient: Vec<f64>,
}

/// Maps an evaluation of the objective to the optimiser's cost.
struct CostMap<'a> {
    bounds: &'a [LogBounds],
    /// The objective's scale (positive).
    scale: f64,
}

/// The optimiser's view of one evaluation.
struct Cost {
    /// The negated, scaled objective alone.
    objective: f64,
    /// With the bound penalties.
    total: f64,
    /// The gradient of `total` in the optimiser's coordinates.
    gradient: Vec<f64>,
}

impl CostMap<'_> {
    fn clamp(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(self.bounds)
            .map(|(u, b)| b.to_log(*u))
            .collect()
    }

    fn cost(&self, u: &[f64], raw: &RawEvaluation) -> Cost {
        let objective = -raw.value * self.scale;
        let mut total = objective;
        let mut gradient: Vec<f64> = raw
            .gradient
            .iter()
            .zip(u.iter().zip(self.bounds))
            .map(|(g, (u, b))| -g * b.derivative(*u) * self.scale)
            .collect();
        for ((g, u), b) in gradient.iter_mut().zip(u).zip(self.bounds) {
            let (p, dp) = b.penalty(*u);
            total += p;
            *g += dp;
        }
        Cost {
            objective,
            total,
            gradient,
        }
    }
}

/// A point, the cost there and its gradient.
type Evaluated = (Vec<f64>, f64, Vec<f64>);

/// The last point evaluated, with its cost and gradient.
#[derive(Default)]
struct LastPoint(RefCell<Option<Evaluated>>);

impl LastPoint {
    fn at(&self, u: &[f64]) -> Option<(f64, Vec<f64>)> {
        match self.0.borrow().as_ref() {
            Some((at, cost, grad)) if at.as_slice() == u => Some((*cost, grad.clone())),
            _ => None,
        }
    }

    fn set(&self, u: &[f64], cost: f64, grad: Vec<f64>) {
        *self.0.borrow_mut() = Some((u.to_vec(), cost, grad));
    }
}

/// The best point evaluated (its clamped coordinates, where the objective
/// was evaluated) and its cost, by objective alone.
#[derive(Default)]
struct BestPoint(RefCell<Option<(Vec<f64>, f64)>>);

impl BestPoint {
    fn offer(&self, clamped: Vec<f64>, cost: f64) {
        let improved = self.0.borrow().as_ref().is_none_or(|(_, c)| cost < *c);
        if improved {
            *self.0.borrow_mut() = Some((clamped, cost));
        }
    }
}

/// The negated, scaled objective in the optimiser's (unclamped)
/// coordinates.
pub(super) struct Negated<'a> {
    objective: &'a dyn Objective,
    map: CostMap<'a>,
    last: LastPoint,
    best: BestPoint,
    evaluations: Cell<usize>,
}

impl<'a> Negated<'a> {
    /// Evaluates `objective` at `u` and fixes the scale there:
    /// `value_scale` (e.g. `1/(n·p)`), further divided by the gradient norm
    /// at `u` when that exceeds 1, so that the optimiser's first step
    /// (along the raw gradient) is at most about one unit of `log θ`, as
    /// L-BFGS-B's first step is, whatever the data size. The start is
    /// evaluated once.
    ///
    /// # Errors
    /// The objective's error at `u`.
    pub(super) fn start(
        objective: &'a dyn Objective,
        bounds: &'a [LogBounds],
        u: &[f64],
        value_scale: f64,
    ) -> Result<Self, RegressorError> {
        let mut problem = Self {
            objective,
            map: CostMap {
                bounds,
                scale: value_scale,
            },
            last: LastPoint::default(),
            best: BestPoint::default(),
            evaluations: Cell::new(0),
        };
        let raw = problem.evaluate_raw(u)?;
        let grad = problem.map.cost(u, &raw).gradient;
        let norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
        if norm > 1.0 {
            problem.map.scale = value_scale / norm;
        }
        problem.record(u, raw);
        Ok(problem)
    }

    /// The objective's scale.
    pub(super) fn scale(&self) -> f64 {
        self.map.scale
    }

    /// Evaluations so far.
    pub(super) fn evaluations(&self) -> usize {
        self.evaluations.get()
    }

    /// The best objective so far (unscaled, to maximise).
    pub(super) fn best_value(&self) -> f64 {
        self.best
            .0
            .borrow()
            .as_ref()
            .map_or(f64::NEG_INFINITY, |(_, cost)| -cost / self.map.scale)
    }

    /// The best point evaluated and its objective (unscaled, to maximise).
    pub(super) fn into_best(self) -> (Vec<f64>, f64) {
        let scale = self.map.scale;
        // `start` recorded the start point, so there is always a best one.
        let (coords, cost) = self
            .best
            .0
            .into_inner()
            .unwrap_or_else(|| (Vec::new(), f64::INFINITY));
        (coords, -cost / scale)
    }

    fn evaluate(&self, u: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        if let Some(hit) = self.last.at(u) {
            return Ok(hit);
        }
        let raw = self.evaluate_raw(u)?;
        Ok(self.record(u, raw))
    }

    /// The objective and its gradient at the clamped `u`, unscaled and not
    /// cached (but counted).
    fn evaluate_raw(&self, u: &[f64]) -> Result<RawEvaluation, RegressorError> {
        let clamped = self.map.clamp(u);
        let (value, gradient) = self.objective.evaluate(&clamped)?;
        self.evaluations.set(self.evaluations.get() + 1);
        tracing::trace!(
            evaluation = self.evaluations.get(),
            value,
            "hyperparameter objective"
        );
        Ok(RawEvaluation {
            clamped,
            value,
            gradient,
        })
    }

    /// The optimiser's cost and gradient for `raw` (at `u`), kept as the
    /// last point and offered as the best.
    fn record(&self, u: &[f64], raw: RawEvaluation) -> (f64, Vec<f64>) {
        let cost = self.map.cost(u, &raw);
        self.best.offer(raw.clamped, cost.objective);
        self.last.set(u, cost.total, cost.gradient.clone());
        (cost.total, cost.gradient)
    }
}

impl CostFunction for &Negated<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, ArgminError> {
        Ok(self.evaluate(u)?.0)
    }
}

impl Gradient for &Negated<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Self::Param) -> Result<Vec<f64>, ArgminError> {
        Ok(self.evaluate(u)?.1)
    }
}
