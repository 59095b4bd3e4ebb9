//! The pose-graph back end: processed frames are SE(3) nodes; wheel
//! odometry (parametric model plus predicted residual, its covariance from
//! the residual's variance), visual odometry, relocalisation and loop
//! closures are between-factors; the first node is anchored by a prior.
//! Optimised with factrs' Levenberg–Marquardt (sparse Cholesky with faer).

use factrs::containers::{FactorBuilder, Graph, Values};
use factrs::noise::GaussianNoise;
use std::cell::RefCell;
use std::rc::Rc;

use factrs::optimizers::{
    BaseOptParams, LevenMarquardt, LevenParams, OptError, OptObserver, Optimizer,
};
use factrs::residuals::{BetweenResidual, PriorResidual};
use factrs::variables::{SE3, SO3};
use nalgebra::{Isometry3, Matrix6, Quaternion, Translation3, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::FrontendError;

/// The node symbol: `X(i)` is node `i`, an SE(3) pose.
mod symbols {
    use factrs::assign_symbols;
    use factrs::variables::SE3;
    assign_symbols!(X: SE3);
}
use symbols::X;

/// What an edge measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeKind {
    /// Wheel odometry between consecutive processed frames.
    Odometry,
    /// Visual odometry from the reference keyframe to a tracked frame.
    VisualOdometry,
    /// A lost tracker matched against a keyframe it recognised.
    Relocalisation,
    /// A new keyframe matched against an old one.
    LoopClosure,
}

/// A relative pose measurement `from_T_to` between two nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseGraphEdge {
    /// First node.
    pub from: usize,
    /// Second node.
    pub to: usize,
    /// Measured `from_T_to`.
    pub measurement: Isometry3<f64>,
    /// Covariance of a right perturbation of the measurement, rotation
    /// first.
    pub covariance: Matrix6<f64>,
    /// Its kind.
    pub kind: EdgeKind,
}

/// The default of [`BackendParams::closure_chi2_max`].
pub const DEFAULT_CLOSURE_CHI2_MAX: f64 = 100.0;

/// Settings of the optimisation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BackendParams {
    /// Levenberg–Marquardt iteration limit (default 50).
    pub max_iterations: usize,
    /// Stop when the error falls by less than this fraction (default 1e-9).
    pub relative_tolerance: f64,
    /// Standard deviation of the prior on the first node's rotation (rad)
    /// and translation (m) (default 1e-6: the start pose is known).
    pub anchor_sigma: f64,
    /// The largest χ² (squared Mahalanobis norm of the 6-dof residual at
    /// the optimum) a loop closure or relocalisation edge may keep. Above
    /// it, the worst such edge is dropped and the graph optimised again,
    /// until none is (default 100; `null` keeps every edge). See
    /// [`PoseGraph::optimize`].
    pub closure_chi2_max: Option<f64>,
}

impl Default for BackendParams {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            relative_tolerance: 1e-9,
            anchor_sigma: 1e-6,
            closure_chi2_max: Some(DEFAULT_CLOSURE_CHI2_MAX),
        }
    }
}

impl BackendParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        if self.max_iterations == 0 {
            return Err(FrontendError::InvalidConfig {
                field: "backend.max_iterations".into(),
                expected: "at least 1".into(),
            });
        }
        for (field, v) in [
            ("relative_tolerance", self.relative_tolerance),
            ("anchor_sigma", self.anchor_sigma),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(FrontendError::InvalidConfig {
                    field: format!("backend.{field}"),
                    expected: "a positive number".into(),
                });
            }
        }
        if let Some(v) = self.closure_chi2_max
            && !(v.is_finite() && v > 0.0)
        {
            return Err(FrontendError::InvalidConfig {
                field: "backend.closure_chi2_max".into(),
                expected: "a positive number, or null to keep every closure".into(),
            });
        }
        Ok(())
    }
}

/// A pose graph: initial node poses, the anchored first node, the edges.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PoseGraph {
    /// Initial `world_from_node` of every node.
    pub initial: Vec<Isometry3<f64>>,
    /// The edges.
    pub edges: Vec<PoseGraphEdge>,
}

/// The outcome of an optimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimizedGraph {
    /// `world_from_node` of every node.
    pub poses: Vec<Isometry3<f64>>,
    /// Weighted squared error before (½ Σ ‖r‖²_Σ).
    pub initial_error: f64,
    /// And after.
    pub final_error: f64,
    /// Whether the iteration limit stopped it.
    pub hit_iteration_limit: bool,
    /// The loop closure and relocalisation edges dropped as inconsistent,
    /// by index into [`PoseGraph::edges`], in the order they were dropped.
    pub rejected: Vec<usize>,
}

/// Whether an edge of this kind joins frames far apart in time, matched
/// without the chain's prior, and so may be a false match.
fn is_closure(kind: EdgeKind) -> bool {
    matches!(kind, EdgeKind::LoopClosure | EdgeKind::Relocalisation)
}

/// The χ² of `edge` at `poses`: `δᵀ Σ⁻¹ δ`, `δ` the right perturbation
/// `measurement⁻¹ · from⁻¹ · to` (rotation vector first, then translation,
/// as the covariance is), `Σ` the edge's covariance. `None` where the
/// covariance is not positive definite or a node is missing.
pub fn edge_chi2(edge: &PoseGraphEdge, poses: &[Isometry3<f64>]) -> Option<f64> {
    let (from, to) = (poses.get(edge.from)?, poses.get(edge.to)?);
    let error = edge.measurement.inverse() * (from.inverse() * to);
    let r = error.rotation.scaled_axis();
    let t = error.translation.vector;
    let delta = Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z);
    let sym = 0.5 * (edge.covariance + edge.covariance.transpose());
    let whitened = sym.cholesky()?.solve(&delta);
    Some(delta.dot(&whitened))
}

/// nalgebra → factrs.
pub fn to_se3(pose: &Isometry3<f64>) -> SE3 {
    let q = pose.rotation.quaternion();
    let t = pose.translation.vector;
    SE3::from_rot_trans(
        SO3::from_xyzw(q.i, q.j, q.k, q.w),
        factrs::linalg::Vector3::new(t.x, t.y, t.z),
    )
}

/// factrs → nalgebra.
pub fn from_se3(pose: &SE3) -> Isometry3<f64> {
    let r = pose.rot();
    let t = pose.xyz();
    Isometry3::from_parts(
        Translation3::from(Vector3::new(t[0], t[1], t[2])),
        UnitQuaternion::from_quaternion(Quaternion::new(r.w(), r.x(), r.y(), r.z())),
    )
}

/// Keeps a copy of the optimiser's latest accepted values.
struct LastValues(Rc<RefCell<Option<Values>>>);

impl OptObserver for LastValues {
    fn on_step(&self, values: &Values, _iteration: i64) {
        *self.0.borrow_mut() = Some(values.clone());
    }
}

fn noise(covariance: &Matrix6<f64>, what: &str) -> Result<GaussianNoise<6>, FrontendError> {
    let sym = 0.5 * (covariance + covariance.transpose());
    GaussianNoise::<6>::from_matrix_cov(sym.as_view()).ok_or_else(|| {
        FrontendError::Backend(format!(
            "{what}: covariance is not positive definite: {sym}"
        ))
    })
}

impl PoseGraph {
    /// Adds a node with its initial pose and returns its index.
    pub fn add_node(&mut self, initial: Isometry3<f64>) -> usize {
        self.initial.push(initial);
        self.initial.len() - 1
    }

    /// Adds an edge.
    pub fn add_edge(&mut self, edge: PoseGraphEdge) {
        self.edges.push(edge);
    }

    /// Number of edges of a kind.
    pub fn count(&self, kind: EdgeKind) -> usize {
        self.edges.iter().filter(|e| e.kind == kind).count()
    }

    /// Optimises the graph, node 0 anchored at its initial pose.
    ///
    /// A false loop closure (a place matched to another that looks alike)
    /// pulls the whole graph toward it, since every edge is Gaussian. So
    /// after each optimisation the loop closure or relocalisation edge of
    /// largest χ² ([`edge_chi2`]) is dropped if it exceeds
    /// `closure_chi2_max`, and the rest optimised again from the initial
    /// poses, until every closure left is within it. Edges of other kinds
    /// are never dropped, and a graph whose closures all agree is optimised
    /// once.
    ///
    /// # Errors
    /// [`FrontendError::Backend`] for an edge with a bad node index or a
    /// covariance that is not positive definite, or a failed solve.
    pub fn optimize(&self, params: &BackendParams) -> Result<OptimizedGraph, FrontendError> {
        let mut active = vec![true; self.edges.len()];
        let mut rejected = Vec::new();
        loop {
            let mut out = self.optimize_edges(params, &active)?;
            let Some(limit) = params.closure_chi2_max else {
                return Ok(out);
            };
            let worst = self
                .edges
                .iter()
                .enumerate()
                .filter(|(i, e)| active[*i] && is_closure(e.kind))
                .filter_map(|(i, e)| edge_chi2(e, &out.poses).map(|c| (i, c)))
                .filter(|(_, c)| *c > limit)
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
            match worst {
                Some((i, chi2)) => {
                    tracing::debug!(
                        edge = i,
                        kind = ?self.edges[i].kind,
                        chi2,
                        "pose graph: inconsistent closure dropped"
                    );
                    active[i] = false;
                    rejected.push(i);
                }
                None => {
                    out.rejected = rejected;
                    return Ok(out);
                }
            }
        }
    }

    /// One optimisation over the edges flagged in `active`.
    fn optimize_edges(
        &self,
        params: &BackendParams,
        active: &[bool],
    ) -> Result<OptimizedGraph, FrontendError> {
        let n = self.initial.len();
        if n == 0 {
            return Ok(OptimizedGraph {
                poses: Vec::new(),
                initial_error: 0.0,
                final_error: 0.0,
                hit_iteration_limit: false,
                rejected: Vec::new(),
            });
        }
        let mut values = Values::new();
        for (i, pose) in self.initial.iter().enumerate() {
            values.insert(X(i as u32), to_se3(pose));
        }
        let mut graph = Graph::new();
        let anchor = GaussianNoise::<6>::from_scalar_sigma(params.anchor_sigma);
        graph.add_factor(
            FactorBuilder::new1(PriorResidual::new(to_se3(&self.initial[0])), X(0))
                .noise(anchor)
                .build(),
        );
        for (i, e) in self.edges.iter().enumerate() {
            if !active[i] {
                continue;
            }
            if e.from >= n || e.to >= n || e.from == e.to {
                return Err(FrontendError::Backend(format!(
                    "edge {i} joins nodes {} and {} of {n}",
                    e.from, e.to
                )));
            }
            let factor = FactorBuilder::new2(
                BetweenResidual::new(to_se3(&e.measurement)),
                X(e.from as u32),
                X(e.to as u32),
            )
            .noise(noise(&e.covariance, &format!("edge {i} ({:?})", e.kind))?)
            .build();
            graph.add_factor(factor);
        }
        let initial_error = graph.error(&values);
        let lm_params = LevenParams {
            base: BaseOptParams {
                max_iterations: params.max_iterations,
                error_tol_relative: params.relative_tolerance,
                error_tol_absolute: 0.0,
                error_tol: 0.0,
            },
            ..LevenParams::default()
        };
        let mut optimizer = LevenMarquardt::new(lm_params, graph);
        // factrs reports "failed to step" when no step lowers the error any
        // more (converged to rounding) and drops the values with it: keep
        // the last accepted iterate.
        let last = Rc::new(RefCell::new(None));
        optimizer.add_observer(LastValues(Rc::clone(&last)));
        let start = values.clone();
        let (result, hit_iteration_limit) = match optimizer.optimize(values) {
            Ok(v) => (v, false),
            Err(OptError::MaxIterations(v)) => (v, true),
            Err(OptError::FailedToStep) => (last.take().unwrap_or(start), false),
            Err(e) => return Err(FrontendError::Backend(format!("{e:?}"))),
        };
        let final_error = optimizer.graph().error(&result);
        let poses = (0..n)
            .map(|i| {
                result
                    .get::<_, SE3>(X(i as u32))
                    .map(from_se3)
                    .ok_or_else(|| {
                        FrontendError::Backend(format!("node {i} missing after optimisation"))
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(OptimizedGraph {
            poses,
            initial_error,
            final_error,
            hit_iteration_limit,
            rejected: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests;
