//! A feature tracker simulated from ground truth, in which skipping frames
//! costs something, as in a real one (ORB-SLAM-like):
//!
//! * **Overlap.** Two views share the fraction of the image that
//!   [`CameraParams::overlap`] leaves after the camera's rotation and
//!   translation between them.
//! * **Tracking.** A frame is tracked against its reference keyframe by
//!   projecting the keyframe's features with a motion prior and searching a
//!   window of `search_radius_px` around each projection. Guided tracking
//!   succeeds with probability `R((o − min_overlap)/s_o) · R((r − e)/s_e)`,
//!   `o` the overlap, `e` the prior's error in pixels
//!   ([`CameraParams::image_error_px`]), `r` the search radius, and
//!   `R(x) = clamp(½ + x/2, 0, 1)` a linear ramp: sure success when the
//!   overlap is at least `s_o` above its threshold and the prior error `s_e`
//!   inside the window, sure failure as far on the other side, even odds at
//!   the thresholds. A prior from wheel odometry that stays close to the
//!   truth lets the tracker bridge a longer gap. Without a prior, or when
//!   guided tracking fails, matching against the reference keyframe without
//!   a prior (bag of words) needs a larger overlap: `R((o −
//!   prior_free_min_overlap)/s_o)`.
//! * **Error.** The estimated relative pose is the truth perturbed by
//!   `N(0, σ²)` with `σ_t = (σ_t0 + k_t ‖t‖) / o^p` and
//!   `σ_r = (σ_r0 + k_r |θ|) / o^p`: larger motions and smaller overlaps
//!   give worse estimates.
//! * **Relocalisation and loop closing.** Only keyframes the current view
//!   overlaps by at least `recognition_min_overlap` are recognised (each
//!   with probability `recognition_probability`); matching against them is
//!   prior-free. After a loss the tracker relocalises only where it mapped
//!   before.
//!
//! Every draw comes from a generator seeded by `(seed, purpose, reference,
//! current)`, so a run's result does not depend on the order or the thread
//! in which requests are made.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use super::{
    CameraParams, ErrorModel, FrameRef, TrackOutcome, TrackPurpose, TrackRequest, VisualOdometry,
    VoMeasurement, isotropic_covariance,
};
use crate::FrontendError;
use crate::traverse::Traverse;

/// Settings of the simulated tracker. Every field has a default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulatedVoParams {
    /// The camera.
    pub camera: CameraParams,
    /// Overlap at which guided tracking succeeds half the time (default 0.3).
    pub min_overlap: f64,
    /// Half-width of the overlap thresholds' transition (default 0.05).
    pub overlap_softness: f64,
    /// Search radius of guided matching (pixels; default 15, ORB-SLAM's
    /// stereo window).
    pub search_radius_px: f64,
    /// Half-width of the search radius' transition (pixels; default 3).
    pub search_softness_px: f64,
    /// Overlap at which matching without a motion prior (against the
    /// reference keyframe, for relocalisation and loop closing) succeeds
    /// half the time (default 0.7).
    pub prior_free_min_overlap: f64,
    /// Least overlap with a keyframe for place recognition to propose it
    /// (default 0.5).
    pub recognition_min_overlap: f64,
    /// Probability that a keyframe above that overlap is recognised
    /// (default 0.9).
    pub recognition_probability: f64,
    /// At most this many recognised keyframes are proposed (default 3).
    pub max_candidates: usize,
    /// Translation error floor σ_t0 (m; default 0.002).
    pub translation_sigma_m: f64,
    /// Translation error per metre of relative translation k_t (default 0.02).
    pub translation_sigma_per_m: f64,
    /// Rotation error floor σ_r0 (rad; default 0.001).
    pub rotation_sigma_rad: f64,
    /// Rotation error per radian of relative rotation k_r (default 0.01).
    pub rotation_sigma_per_rad: f64,
    /// Exponent p of the overlap in the error (default 1).
    pub overlap_exponent: f64,
    /// Seed of every draw (default 0).
    pub seed: u64,
}

impl Default for SimulatedVoParams {
    fn default() -> Self {
        Self {
            camera: CameraParams::default(),
            min_overlap: 0.3,
            overlap_softness: 0.05,
            search_radius_px: 15.0,
            search_softness_px: 3.0,
            prior_free_min_overlap: 0.7,
            recognition_min_overlap: 0.5,
            recognition_probability: 0.9,
            max_candidates: 3,
            translation_sigma_m: 0.002,
            translation_sigma_per_m: 0.02,
            rotation_sigma_rad: 0.001,
            rotation_sigma_per_rad: 0.01,
            overlap_exponent: 1.0,
            seed: 0,
        }
    }
}

impl SimulatedVoParams {
    /// The measurement error model of these settings.
    pub fn error_model(&self) -> ErrorModel {
        ErrorModel {
            translation_sigma_m: self.translation_sigma_m,
            translation_sigma_per_m: self.translation_sigma_per_m,
            rotation_sigma_rad: self.rotation_sigma_rad,
            rotation_sigma_per_rad: self.rotation_sigma_per_rad,
            overlap_exponent: self.overlap_exponent,
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] naming the field (under `vo.`).
    pub fn validate(&self) -> Result<(), FrontendError> {
        self.camera.validate("vo.camera")?;
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidConfig {
                field: format!("vo.{field}"),
                expected: expected.into(),
            })
        };
        let fraction = |v: f64| (0.0..=1.0).contains(&v);
        for (field, v) in [
            ("min_overlap", self.min_overlap),
            ("prior_free_min_overlap", self.prior_free_min_overlap),
            ("recognition_min_overlap", self.recognition_min_overlap),
            ("recognition_probability", self.recognition_probability),
        ] {
            if !fraction(v) {
                return bad(field, "a fraction in [0, 1]");
            }
        }
        for (field, v) in [
            ("overlap_softness", self.overlap_softness),
            ("search_radius_px", self.search_radius_px),
            ("search_softness_px", self.search_softness_px),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, "a positive number");
            }
        }
        self.error_model().validate()?;
        if self.max_candidates == 0 {
            return bad("max_candidates", "at least 1");
        }
        Ok(())
    }
}

/// The linear ramp `clamp(½ + x/2, 0, 1)`: 0 below −1, 1 above 1.
fn ramp(x: f64) -> f64 {
    (0.5 + 0.5 * x).clamp(0.0, 1.0)
}

/// SplitMix64: mixes request keys into a generator seed.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The simulated tracker over one traverse.
#[derive(Debug, Clone)]
pub struct SimulatedVo {
    params: SimulatedVoParams,
    /// Ground-truth `world_from_body` at each camera frame.
    frames: Vec<Isometry3<f64>>,
}

impl SimulatedVo {
    /// A tracker seeing the traverse's camera frames from their true poses.
    ///
    /// # Errors
    /// As [`SimulatedVoParams::validate`].
    pub fn new(params: SimulatedVoParams, traverse: &Traverse) -> Result<Self, FrontendError> {
        params.validate()?;
        let frames = traverse
            .camera_times_secs()
            .iter()
            .map(|&t| traverse.ground_truth_at(t))
            .collect();
        Ok(Self { params, frames })
    }

    /// The settings.
    pub fn params(&self) -> &SimulatedVoParams {
        &self.params
    }

    fn truth(&self, reference: FrameRef, current: FrameRef) -> Option<Isometry3<f64>> {
        let (a, b) = (
            self.frames.get(reference.index)?,
            self.frames.get(current.index)?,
        );
        Some(a.inverse() * b)
    }

    fn rng(&self, purpose: u64, a: usize, b: usize) -> ChaCha8Rng {
        let key = mix(mix(mix(self.params.seed) ^ purpose) ^ a as u64) ^ b as u64;
        ChaCha8Rng::seed_from_u64(mix(key))
    }

    /// The probability that `request` succeeds (what [`VisualOdometry::track`]
    /// draws against), and the overlap of the two views; `None` for frames
    /// outside the traverse.
    pub fn success_and_overlap(&self, request: &TrackRequest) -> Option<(f64, f64)> {
        let truth = self.truth(request.reference, request.current)?;
        let p = &self.params;
        let overlap = p.camera.body_overlap(&truth);
        let free = ramp((overlap - p.prior_free_min_overlap) / p.overlap_softness);
        let success = match (request.purpose, request.prior) {
            (TrackPurpose::Tracking, Some(prior)) => {
                let error_px = p.camera.image_error_px(&(prior.inverse() * truth));
                let guided = ramp((overlap - p.min_overlap) / p.overlap_softness)
                    * ramp((p.search_radius_px - error_px) / p.search_softness_px);
                1.0 - (1.0 - guided) * (1.0 - free)
            }
            _ => free,
        };
        Some((success, overlap))
    }

    /// The error standard deviations `(rotation, translation)` of a
    /// measurement of `truth` at `overlap`.
    pub fn error_sigmas(&self, truth: &Isometry3<f64>, overlap: f64) -> (f64, f64) {
        self.params.error_model().sigmas(truth, overlap)
    }
}

impl VisualOdometry for SimulatedVo {
    fn name(&self) -> &str {
        "simulated"
    }

    fn track(&mut self, request: &TrackRequest) -> TrackOutcome {
        let Some((success, overlap)) = self.success_and_overlap(request) else {
            return TrackOutcome::Lost;
        };
        let Some(truth) = self.truth(request.reference, request.current) else {
            return TrackOutcome::Lost;
        };
        let purpose = request.purpose as u64 + 1;
        let mut rng = self.rng(purpose, request.reference.index, request.current.index);
        if rng.random::<f64>() >= success {
            return TrackOutcome::Lost;
        }
        let (sigma_r, sigma_t) = self.error_sigmas(&truth, overlap);
        let mut draw =
            |sigma: f64| Vector3::from_fn(|_, _| sigma * rng.sample::<f64, _>(StandardNormal));
        let (omega, v) = (draw(sigma_r), draw(sigma_t));
        let noise = Isometry3::from_parts(
            Translation3::from(v),
            UnitQuaternion::from_scaled_axis(omega),
        );
        TrackOutcome::Tracked(VoMeasurement {
            relative: truth * noise,
            covariance: isotropic_covariance(sigma_r, sigma_t),
            overlap,
        })
    }

    fn success_probability(&self, request: &TrackRequest) -> f64 {
        self.success_and_overlap(request).map_or(0.0, |(p, _)| p)
    }

    fn recognise(&self, current: FrameRef, keyframes: &[FrameRef]) -> Vec<FrameRef> {
        let p = &self.params;
        let mut found: Vec<(f64, FrameRef)> = keyframes
            .iter()
            .filter_map(|kf| {
                let truth = self.truth(*kf, current)?;
                let overlap = p.camera.body_overlap(&truth);
                if overlap < p.recognition_min_overlap {
                    return None;
                }
                let mut rng = self.rng(0, kf.index, current.index);
                (rng.random::<f64>() < p.recognition_probability).then_some((overlap, *kf))
            })
            .collect();
        found.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.index.cmp(&b.1.index)));
        found.truncate(p.max_candidates);
        found.into_iter().map(|(_, kf)| kf).collect()
    }
}
