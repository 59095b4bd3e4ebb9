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
use nalgebra::{Isometry3, Matrix6, Quaternion, Translation3, UnitQuaternion, Vector3};
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
}

impl Default for BackendParams {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            relative_tolerance: 1e-9,
            anchor_sigma: 1e-6,
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
    /// # Errors
    /// [`FrontendError::Backend`] for an edge with a bad node index or a
    /// covariance that is not positive definite, or a failed solve.
    pub fn optimize(&self, params: &BackendParams) -> Result<OptimizedGraph, FrontendError> {
        let n = self.initial.len();
        if n == 0 {
            return Ok(OptimizedGraph {
                poses: Vec::new(),
                initial_error: 0.0,
                final_error: 0.0,
                hit_iteration_limit: false,
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
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vo::isotropic_covariance;

    #[test]
    fn conversions_round_trip() {
        let p = Isometry3::from_parts(
            Translation3::new(1.0, -2.0, 0.5),
            UnitQuaternion::from_euler_angles(0.1, -0.2, 2.5),
        );
        let back = from_se3(&to_se3(&p));
        assert!((back.translation.vector - p.translation.vector).norm() < 1e-15);
        assert!(back.rotation.angle_to(&p.rotation) < 1e-12);
    }

    #[test]
    fn noiseless_edges_recover_a_known_trajectory_from_a_bad_start() {
        // A loop in 3-D: consecutive odometry edges plus one loop closure,
        // all exact; the initial guess is perturbed.
        let truth: Vec<Isometry3<f64>> = (0..12)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 12.0;
                Isometry3::from_parts(
                    Translation3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.1 * a.sin()),
                    UnitQuaternion::from_euler_angles(0.05 * a.cos(), 0.02, a + 1.5),
                )
            })
            .collect();
        let mut graph = PoseGraph::default();
        for (k, p) in truth.iter().enumerate() {
            let start = if k == 0 {
                *p
            } else {
                let e = k as f64 * 0.01;
                Isometry3::from_parts(
                    Translation3::new(e, -e, 0.5 * e),
                    UnitQuaternion::from_euler_angles(e, -e, 2.0 * e),
                ) * p
            };
            graph.add_node(start);
        }
        let cov = isotropic_covariance(1e-2, 1e-2);
        for k in 1..truth.len() {
            graph.add_edge(PoseGraphEdge {
                from: k - 1,
                to: k,
                measurement: truth[k - 1].inverse() * truth[k],
                covariance: cov,
                kind: EdgeKind::Odometry,
            });
        }
        graph.add_edge(PoseGraphEdge {
            from: 11,
            to: 0,
            measurement: truth[11].inverse() * truth[0],
            covariance: cov,
            kind: EdgeKind::LoopClosure,
        });
        let out = graph.optimize(&BackendParams::default()).unwrap();
        assert!(out.final_error < 1e-16, "{}", out.final_error);
        for (a, b) in out.poses.iter().zip(&truth) {
            assert!((a.translation.vector - b.translation.vector).norm() < 1e-8);
            assert!(a.rotation.angle_to(&b.rotation) < 1e-8);
        }
        assert_eq!(graph.count(EdgeKind::LoopClosure), 1);
    }

    #[test]
    fn a_bad_edge_is_an_error_not_a_panic() {
        let mut graph = PoseGraph::default();
        graph.add_node(Isometry3::identity());
        graph.add_edge(PoseGraphEdge {
            from: 0,
            to: 3,
            measurement: Isometry3::identity(),
            covariance: Matrix6::identity(),
            kind: EdgeKind::Odometry,
        });
        assert!(graph.optimize(&BackendParams::default()).is_err());
        let mut graph = PoseGraph::default();
        graph.add_node(Isometry3::identity());
        graph.add_node(Isometry3::identity());
        graph.add_edge(PoseGraphEdge {
            from: 0,
            to: 1,
            measurement: Isometry3::identity(),
            covariance: Matrix6::zeros(),
            kind: EdgeKind::Odometry,
        });
        let err = graph.optimize(&BackendParams::default()).unwrap_err();
        assert!(err.to_string().contains("positive definite"), "{err}");
    }
}
