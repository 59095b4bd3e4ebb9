//! Trace events of a front-end session (`RUST_LOG=gpodo_frontends::run=trace`):
//! every pose-graph edge's error against the ground truth as it is added,
//! and every closure's χ² at the optimum, to find the edges a trajectory's
//! error comes from.

use nalgebra::{Isometry3, Matrix6};

use super::Session;
use crate::backend::{EdgeKind, OptimizedGraph, edge_chi2};

impl Session<'_> {
    /// An edge's error against the ground truth, as a trace event
    /// (`RUST_LOG=gpodo_frontends::run=trace`): the rotation error's
    /// axis-angle vector in the later body frame (degrees), the translation
    /// error (mm) and the edge's yaw standard deviation (degrees), to find
    /// the edges a trajectory's drift comes from.
    pub(super) fn trace_edge_error(
        &self,
        kind: EdgeKind,
        from: usize,
        to: usize,
        relative: &Isometry3<f64>,
        covariance: &Matrix6<f64>,
    ) {
        if !tracing::enabled!(tracing::Level::TRACE) {
            return;
        }
        let (Some(a), Some(b)) = (self.frame_of(from), self.frame_of(to)) else {
            return;
        };
        let truth = self.traverse.ground_truth_at(a.time_secs).inverse()
            * self.traverse.ground_truth_at(b.time_secs);
        let error = relative.inverse() * truth;
        let r = error.rotation.scaled_axis().map(f64::to_degrees);
        tracing::trace!(
            ?kind,
            from_secs = a.time_secs,
            to_secs = b.time_secs,
            roll_error_deg = r.x,
            pitch_error_deg = r.y,
            yaw_error_deg = r.z,
            translation_error_mm = error.translation.vector.norm() * 1e3,
            yaw_sigma_deg = covariance[(2, 2)].sqrt().to_degrees(),
            "edge against the truth"
        );
    }

    /// Every loop closure's and relocalisation's χ² at the optimum, and
    /// whether the back end dropped it.
    pub(super) fn trace_closures(&self, optimized: &OptimizedGraph) {
        if !tracing::enabled!(tracing::Level::TRACE) {
            return;
        }
        for (i, e) in self.graph.edges.iter().enumerate() {
            if matches!(e.kind, EdgeKind::LoopClosure | EdgeKind::Relocalisation) {
                tracing::trace!(
                    edge = i,
                    kind = ?e.kind,
                    chi2 = edge_chi2(e, &optimized.poses),
                    rejected = optimized.rejected.contains(&i),
                    "closure's χ² at the optimum"
                );
            }
        }
    }
}
