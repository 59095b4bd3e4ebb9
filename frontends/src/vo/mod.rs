//! Visual odometry behind one interface, [`VisualOdometry`]: given two
//! processed camera frames, the relative pose with its covariance, or a
//! tracking failure; and place recognition for relocalisation and loop
//! closing.
//!
//! * [`simulated::SimulatedVo`]: a feature tracker simulated from ground
//!   truth in which skipping frames costs something (see its module);
//! * [`replay::ReplayVo`]: replays a VO log (a trajectory computed offline
//!   on all frames by any SLAM system) so the policies run on real
//!   recordings.

pub mod camera;
pub mod replay;
pub mod simulated;
pub mod stereo;

use nalgebra::{Isometry3, Matrix6};
use serde::{Deserialize, Serialize};

pub use camera::CameraParams;
pub use gpodo_traits::FrameRef;
pub use replay::{ReplayVo, ReplayVoParams};
pub use simulated::{SimulatedVo, SimulatedVoParams, TrackerErrorModel};

/// Why a frame is matched against another.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TrackPurpose {
    /// Tracking the current frame against the reference keyframe, with a
    /// motion prior when one is available.
    Tracking,
    /// Relocalising a lost tracker against a keyframe it recognised.
    Relocalisation,
    /// Closing a loop from a new keyframe to an old one.
    LoopClosure,
}

/// A request to estimate `reference_from_current`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackRequest {
    /// The frame the current one is matched against (a keyframe).
    pub reference: FrameRef,
    /// The frame being processed.
    pub current: FrameRef,
    /// The predicted `reference_from_current` (from wheel odometry or a
    /// constant-velocity model); `None` when there is none.
    pub prior: Option<Isometry3<f64>>,
    /// Why.
    pub purpose: TrackPurpose,
}

/// A successful relative pose measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoMeasurement {
    /// Estimated `reference_from_current`.
    pub relative: Isometry3<f64>,
    /// Its covariance as a right perturbation `relative · Exp(δ)`,
    /// `δ = [rotation; translation]` (factrs' order).
    pub covariance: Matrix6<f64>,
    /// The share of the reference keyframe's features found again in the
    /// current frame, in `[0, 1]` (what keyframe decisions read): the view
    /// overlap, times `min(1, s_cur / s_ref)` when features are counted.
    pub overlap: f64,
    /// The tracker's own call for a keyframe, whatever the overlap (the
    /// stereo VO's ORB-SLAM2 close-point trigger, when it is on; false
    /// otherwise).
    pub needs_keyframe: bool,
}

/// What tracking gave.
// Returned by value once per request, never stored in bulk: the size of
// the measurement does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrackOutcome {
    /// The relative pose.
    Tracked(VoMeasurement),
    /// Tracking failed.
    Lost,
}

/// How the errors of frames tracked against one keyframe relate, and so
/// which frames the pose graph may treat as independent measurements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorStructure {
    /// Frames tracked against one keyframe share that keyframe's map
    /// error (ORB-SLAM): only keyframes become pose-graph nodes, as in
    /// ORB-SLAM's local bundle adjustment, and the other processed frames
    /// hang from their reference keyframe.
    SharedPerKeyframe,
    /// Every measurement has its own error: every processed frame becomes
    /// a pose-graph node (what a replayed log, whose errors are unknown,
    /// and `error_model: independent` use).
    Independent,
}

/// A visual odometry front end.
pub trait VisualOdometry: Send {
    /// A short name for reports.
    fn name(&self) -> &str;

    /// How the errors of this odometry's measurements relate (default
    /// [`ErrorStructure::Independent`]).
    fn error_structure(&self) -> ErrorStructure {
        ErrorStructure::Independent
    }

    /// Estimates `reference_from_current`, or fails.
    fn track(&mut self, request: &TrackRequest) -> TrackOutcome;

    /// The probability that [`VisualOdometry::track`] succeeds for
    /// `request` (what an offline planner may use; 0 or 1 for a replay).
    fn success_probability(&self, request: &TrackRequest) -> f64;

    /// The overlap between two frames that the keyframe rule would read,
    /// predicted from the ground truth, for an offline planner that must
    /// know which keyframe the tracker will hold as its reference; `None`
    /// (the default) when this odometry cannot predict it.
    fn predicted_overlap(&self, reference: FrameRef, current: FrameRef) -> Option<f64> {
        let _ = (reference, current);
        None
    }

    /// Place recognition: the keyframes among `keyframes` that the current
    /// frame may be matched against, best first (empty when none is
    /// recognised).
    fn recognise(&self, current: FrameRef, keyframes: &[FrameRef]) -> Vec<FrameRef>;

    /// Told that the frame it last tracked became a keyframe: the links
    /// between keyframes a local bundle adjustment refined on it, oldest
    /// first (the default, none: no adjustment).
    fn keyframe_inserted(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        let _ = keyframe;
        Vec::new()
    }
}

/// A link between two keyframes as a local bundle adjustment refined it:
/// what replaces the visual edge that placed `current` against
/// `reference`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefinedLink {
    /// The keyframe `current` was tracked against.
    pub reference: FrameRef,
    /// The keyframe placed.
    pub current: FrameRef,
    /// `reference_from_current` (bodies).
    pub relative: Isometry3<f64>,
    /// Its covariance as a right perturbation, as a
    /// [`VoMeasurement`]'s.
    pub covariance: Matrix6<f64>,
}

/// The error of a relative pose measurement: `σ_t = (σ_t0 + k_t ‖t‖) / o^p`,
/// `σ_r = (σ_r0 + k_r |θ|) / o^p` for a relative motion `(t, θ)` seen with
/// overlap `o` (floored at 0.05).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorModel {
    /// σ_t0 (m).
    pub translation_sigma_m: f64,
    /// k_t.
    pub translation_sigma_per_m: f64,
    /// σ_r0 (rad).
    pub rotation_sigma_rad: f64,
    /// k_r.
    pub rotation_sigma_per_rad: f64,
    /// p.
    pub overlap_exponent: f64,
}

impl ErrorModel {
    /// Checks the fields (positive floors, non-negative slopes); errors
    /// name the field under `vo.`.
    ///
    /// # Errors
    /// [`crate::FrontendError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), crate::FrontendError> {
        for (field, v, floor) in [
            ("translation_sigma_m", self.translation_sigma_m, true),
            ("rotation_sigma_rad", self.rotation_sigma_rad, true),
            (
                "translation_sigma_per_m",
                self.translation_sigma_per_m,
                false,
            ),
            ("rotation_sigma_per_rad", self.rotation_sigma_per_rad, false),
            ("overlap_exponent", self.overlap_exponent, false),
        ] {
            let ok = v.is_finite() && if floor { v > 0.0 } else { v >= 0.0 };
            if !ok {
                return Err(crate::FrontendError::InvalidConfig {
                    field: format!("vo.{field}"),
                    expected: if floor {
                        "a positive standard deviation".into()
                    } else {
                        "a non-negative number".into()
                    },
                });
            }
        }
        Ok(())
    }

    /// `(σ_r, σ_t)` of a measurement of `relative` at `overlap`.
    pub fn sigmas(&self, relative: &Isometry3<f64>, overlap: f64) -> (f64, f64) {
        let shrink = overlap.max(0.05).powf(self.overlap_exponent);
        (
            (self.rotation_sigma_rad + self.rotation_sigma_per_rad * relative.rotation.angle())
                / shrink,
            (self.translation_sigma_m
                + self.translation_sigma_per_m * relative.translation.vector.norm())
                / shrink,
        )
    }
}

/// Block-diagonal covariance with isotropic rotation and translation
/// standard deviations, rotation first.
pub fn isotropic_covariance(rotation_sigma_rad: f64, translation_sigma_m: f64) -> Matrix6<f64> {
    let (r, t) = (rotation_sigma_rad.powi(2), translation_sigma_m.powi(2));
    Matrix6::from_diagonal(&nalgebra::Vector6::new(r, r, r, t, t, t))
}

/// The `[ω; ρ]` adjoint of `t`: `t · Exp(ξ) = Exp(Ad(t) ξ) · t`, a
/// perturbation carried through `t`.
pub fn adjoint(t: &Isometry3<f64>) -> Matrix6<f64> {
    let r = t.rotation.to_rotation_matrix().into_inner();
    let mut a = Matrix6::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    a.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    a.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(t.translation.vector.cross_matrix() * r));
    a
}
