//! A feature tracker simulated from ground truth, in which skipping frames
//! costs something, as in a real one (ORB-SLAM-like); the equations and
//! the source of every default are in `frontends/README.md`.
//!
//! * **Overlap.** Two views share the fraction `o` of the image that
//!   [`CameraParams::overlap`] leaves after the camera's motion between
//!   them.
//! * **Tracking.** A frame is tracked against its reference keyframe by
//!   projecting the keyframe's features with a motion prior and searching a
//!   window of `search_radius_px` around each projection. Guided tracking
//!   succeeds geometrically with probability `R((o − min_overlap)/s_o) ·
//!   R((r − e)/s_e)`, `e` the prior's error in pixels
//!   ([`CameraParams::image_error_px`]), `r` the search radius, and `R(x) =
//!   clamp(½ + x/2, 0, 1)` a linear ramp. Without a prior, or when guided
//!   tracking fails, matching against the reference keyframe without a
//!   prior (bag of words) needs a larger overlap: `R((o −
//!   prior_free_min_overlap)/s_o)`.
//! * **Features.** Each camera frame has a feature supply `s` (the
//!   terrain's texture under the camera's footprint times what the motion
//!   blur leaves, 1 for compact soil without blur, carried on the
//!   [`Traverse`]). A match of two frames finds `N ~ Poisson(F · min(s_ref,
//!   s_cur) · o)` features and succeeds only with `N ≥ n_min` (30 to track,
//!   50 to relocalise or close a loop, ORB-SLAM2's inlier thresholds): the
//!   success probability is the geometric one times `P(N ≥ n_min)`.
//! * **Error.** The estimated relative pose is the truth perturbed on the
//!   right by `δ = σ ⊙ z` with `σ_t = (σ_t0 + k_t ‖t‖) / (o^p √s_m)`,
//!   `σ_r = (σ_r0 + k_r |θ|) / (o^p √s_m)`, `s_m = min(s_ref, s_cur)`.
//!   Under `error_model: shared`, `z = √ρ z_k + √(1 − ρ) z_j`: `z_k ~ N(0,
//!   I)` is drawn once per reference keyframe `k` (its map's error, shared
//!   by every frame matched against it) and `z_j ~ N(0, I)` per request, so
//!   each measurement keeps the variance `σ²` and two frames of one
//!   keyframe correlate by `ρ` (`map_error_share`). Under `independent`,
//!   `z = z_j`.
//! * **Relocalisation and loop closing.** Only keyframes the current view
//!   overlaps by at least `recognition_min_overlap` are recognised (each
//!   with probability `recognition_probability`); matching against them is
//!   prior-free. After a loss the tracker relocalises only where it mapped
//!   before.
//!
//! * **Covisible keyframes** (off unless `covisibility_keyframes` is set):
//!   on each new keyframe, the links of the keyframes behind it are placed
//!   again together with measurements between the keyframes whose views
//!   overlap, as the stereo VO's local bundle adjustment places them
//!   ([`covisibility`]).
//!
//! Every draw comes from a generator seeded by `(seed, purpose, reference,
//! current)`, and a keyframe's map error by `(seed, reference)`, so a run's
//! result does not depend on the order or the thread in which requests
//! are made.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use super::{
    CameraParams, ErrorModel, ErrorStructure, FrameRef, RefinedLink, TrackOutcome, TrackPurpose,
    TrackRequest, VisualOdometry, VoMeasurement, isotropic_covariance,
};
use crate::FrontendError;
use crate::traverse::Traverse;

pub mod covisibility;

/// Settings of the simulated tracker. Every field has a default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulatedVoParams {
    /// The camera (default: the stereo VO's, ExoTeR's Bumblebee2 at
    /// 512 × 384, with the overlap model's `depth_range_m` 0.95, fitted to
    /// the stereo VO's inliers driving straight).
    pub camera: CameraParams,
    /// Overlap at which guided tracking succeeds half the time (default
    /// 0.15, where the stereo VO still tracks).
    pub min_overlap: f64,
    /// Half-width of the overlap thresholds' transition (default 0.05).
    pub overlap_softness: f64,
    /// Search radius of guided matching (pixels; default 15, ORB-SLAM2's
    /// monocular and RGB-D window; its stereo window is 7, retried at 14).
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
    /// Translation error floor σ_t0 (m; default 0.0012; the five error
    /// defaults are fitted to the stereo VO's errors on rendered drives,
    /// see `frontends/README.md`).
    pub translation_sigma_m: f64,
    /// Translation error per metre of relative translation k_t (default
    /// 0.00092).
    pub translation_sigma_per_m: f64,
    /// Rotation error floor σ_r0 (rad; default 0.00087).
    pub rotation_sigma_rad: f64,
    /// Rotation error per radian of relative rotation k_r (default
    /// 0.00057).
    pub rotation_sigma_per_rad: f64,
    /// Exponent p of the overlap in the error (default 1).
    pub overlap_exponent: f64,
    /// How the errors of frames tracked against one keyframe relate
    /// (default `shared`: they share the keyframe's map error).
    pub error_model: TrackerErrorModel,
    /// Under `error_model: shared`, the fraction ρ of a measurement's
    /// error variance that is its reference keyframe's map error, shared
    /// by every frame tracked against that keyframe (default 0.17, the stereo
    /// VO's measured correlation; 0: no
    /// sharing, 1: fully shared).
    pub map_error_share: f64,
    /// Whether features are counted: the traverse's per-frame feature
    /// supply (terrain texture and motion blur; a traverse without one is
    /// neutral) sets how many a match finds, which must reach the
    /// thresholds below, and scales the error by `1/√supply` (default
    /// true).
    pub terrain_features: bool,
    /// Exponent `c` on every soil's texture in the feature supply,
    /// `texture^c` (default 1: the soils' own values; 0: every soil alike;
    /// 2: the contrast squared, e.g. sand 0.25 → 0.0625, gravel 1.2 →
    /// 1.44). A parameter of the sensitivity sweep: no per-soil feature
    /// counts were found.
    pub texture_contrast: f64,
    /// Features F a match finds at full overlap on the reference texture
    /// (compact soil, no blur; default 156, the stereo VO's inliers per unit
    /// overlap between frames 0.4 s apart).
    pub features_per_frame: f64,
    /// Features tracking needs (default 30, ORB-SLAM2's local-map
    /// inliers).
    pub min_tracked_features: u32,
    /// Features relocalisation and loop closing need (default 50,
    /// ORB-SLAM2's inliers after relocalisation).
    pub min_relocalisation_features: u32,
    /// Keyframes behind a new keyframe that the covisible keyframes'
    /// adjustment takes in (default 0: off; see [`covisibility`]).
    pub covisibility_keyframes: usize,
    /// Least overlap of two keyframes' views for the adjustment to tie
    /// them by a measurement of their own (default 0.5).
    pub covisible_min_overlap: f64,
    /// Seed of every draw (default 0).
    pub seed: u64,
}

/// How the simulated tracker's errors are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackerErrorModel {
    /// Every frame tracked against keyframe `k` carries `k`'s map error
    /// (a fraction `map_error_share` of its variance) plus its own; only
    /// keyframes enter the pose graph (ORB-SLAM).
    #[default]
    Shared,
    /// Every measurement draws its own error and every processed frame
    /// enters the pose graph, so more frames always average the error
    /// down (`experiments/paper-independent.yaml` sets it, with the error
    /// scales calibrated for it).
    Independent,
}

impl Default for SimulatedVoParams {
    fn default() -> Self {
        Self {
            camera: CameraParams {
                depth_range_m: 0.95,
                ..CameraParams::exoter_bumblebee2().scaled(0.5)
            },
            min_overlap: 0.15,
            overlap_softness: 0.05,
            search_radius_px: 15.0,
            search_softness_px: 3.0,
            prior_free_min_overlap: 0.7,
            recognition_min_overlap: 0.5,
            recognition_probability: 0.9,
            max_candidates: 3,
            translation_sigma_m: 0.0012,
            translation_sigma_per_m: 0.00092,
            rotation_sigma_rad: 0.00087,
            rotation_sigma_per_rad: 0.00057,
            overlap_exponent: 1.0,
            error_model: TrackerErrorModel::Shared,
            map_error_share: 0.17,
            terrain_features: true,
            texture_contrast: 1.0,
            features_per_frame: 156.0,
            min_tracked_features: 30,
            min_relocalisation_features: 50,
            covisibility_keyframes: 0,
            covisible_min_overlap: 0.5,
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
            ("map_error_share", self.map_error_share),
            ("covisible_min_overlap", self.covisible_min_overlap),
        ] {
            if !fraction(v) {
                return bad(field, "a fraction in [0, 1]");
            }
        }
        for (field, v) in [
            ("overlap_softness", self.overlap_softness),
            ("search_radius_px", self.search_radius_px),
            ("search_softness_px", self.search_softness_px),
            ("features_per_frame", self.features_per_frame),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, "a positive number");
            }
        }
        if !(self.texture_contrast.is_finite() && self.texture_contrast >= 0.0) {
            return bad("texture_contrast", "a non-negative exponent");
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

/// `P(N ≥ k)` for `N ~ Poisson(λ)`: one minus the first `k` terms, each
/// from the one before.
pub fn poisson_at_least(k: u32, lambda: f64) -> f64 {
    if k == 0 {
        return 1.0;
    }
    if lambda.is_nan() || lambda <= 0.0 {
        return 0.0;
    }
    // Each term's logarithm, so that e^−λ does not underflow for large λ.
    let log_lambda = lambda.ln();
    let mut log_term = -lambda;
    let mut below = log_term.exp();
    for i in 1..k {
        log_term += log_lambda - f64::from(i).ln();
        below += log_term.exp();
    }
    (1.0 - below).clamp(0.0, 1.0)
}

/// SplitMix64: mixes request keys into a generator seed.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator key of a keyframe's map error (apart from the request
/// purposes 1–3 and place recognition's 0).
const MAP_ERROR_KEY: u64 = 16;

/// The simulated tracker over one traverse.
#[derive(Debug, Clone)]
pub struct SimulatedVo {
    params: SimulatedVoParams,
    /// Ground-truth `world_from_body` at each camera frame.
    frames: Vec<Isometry3<f64>>,
    /// Feature supply at each camera frame (1 = the reference texture).
    supply: Vec<f64>,
    /// The keyframes' links and the last measurement, for the covisible
    /// keyframes' adjustment.
    covisibility: covisibility::Links,
}

impl SimulatedVo {
    /// A tracker seeing the traverse's camera frames from their true poses.
    ///
    /// # Errors
    /// As [`SimulatedVoParams::validate`].
    pub fn new(params: SimulatedVoParams, traverse: &Traverse) -> Result<Self, FrontendError> {
        params.validate()?;
        let frames: Vec<Isometry3<f64>> = traverse
            .camera_times_secs()
            .iter()
            .map(|&t| traverse.ground_truth_at(t))
            .collect();
        let supply = (0..frames.len())
            .map(|i| {
                if params.terrain_features {
                    traverse.feature_supply_at(i)
                } else {
                    1.0
                }
            })
            .collect();
        Ok(Self {
            params,
            frames,
            supply,
            covisibility: covisibility::Links::default(),
        })
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

    /// The feature supply limiting a match of the two frames: the poorer
    /// of the two views, `min(s_ref, s_cur)`.
    fn supply_of(&self, request: &TrackRequest) -> Option<f64> {
        let (a, b) = (
            self.supply.get(request.reference.index)?,
            self.supply.get(request.current.index)?,
        );
        Some(a.min(*b))
    }

    /// The share of the reference keyframe's features found again in the
    /// current frame, `o · min(1, s_cur / s_ref)`: what the keyframe rule
    /// reads (ORB-SLAM compares tracked points with the reference's).
    fn refound_share(&self, request: &TrackRequest, overlap: f64) -> f64 {
        let (a, b) = (
            self.supply[request.reference.index],
            self.supply[request.current.index],
        );
        overlap * (b / a).min(1.0)
    }

    /// The feature supply of camera frame `index` (1 outside the traverse).
    pub fn feature_supply(&self, index: usize) -> f64 {
        self.supply.get(index).copied().unwrap_or(1.0)
    }

    /// The expected number of features a match of `request` finds at
    /// geometric overlap `overlap`: `n̄ = F · min(s_ref, s_cur) · o`.
    pub fn expected_features(&self, request: &TrackRequest, overlap: f64) -> f64 {
        self.params.features_per_frame * self.supply_of(request).unwrap_or(1.0) * overlap
    }

    /// The probability that the features found suffice: `P(N ≥ n_min)`
    /// for `N ~ Poisson(n̄)`, `n_min` the tracking or the relocalisation
    /// threshold by purpose; 1 when `terrain_features` is off.
    fn enough_features(&self, request: &TrackRequest, overlap: f64) -> f64 {
        let p = &self.params;
        if !p.terrain_features {
            return 1.0;
        }
        let needed = match request.purpose {
            TrackPurpose::Tracking => p.min_tracked_features,
            TrackPurpose::Relocalisation | TrackPurpose::LoopClosure => {
                p.min_relocalisation_features
            }
        };
        poisson_at_least(needed, self.expected_features(request, overlap))
    }

    /// The probability that `request` succeeds (what [`VisualOdometry::track`]
    /// draws against), and the geometric overlap of the two views; `None`
    /// for frames outside the traverse.
    pub fn success_and_overlap(&self, request: &TrackRequest) -> Option<(f64, f64)> {
        let truth = self.truth(request.reference, request.current)?;
        let p = &self.params;
        let overlap = p.camera.body_overlap(&truth);
        let free = ramp((overlap - p.prior_free_min_overlap) / p.overlap_softness);
        let geometric = match (request.purpose, request.prior) {
            (TrackPurpose::Tracking, Some(prior)) => {
                let error_px = p.camera.image_error_px(&(prior.inverse() * truth));
                let guided = ramp((overlap - p.min_overlap) / p.overlap_softness)
                    * ramp((p.search_radius_px - error_px) / p.search_softness_px);
                1.0 - (1.0 - guided) * (1.0 - free)
            }
            (TrackPurpose::Tracking, None)
            | (TrackPurpose::Relocalisation | TrackPurpose::LoopClosure, _) => free,
        };
        Some((geometric * self.enough_features(request, overlap), overlap))
    }

    /// The error standard deviations `(rotation, translation)` of a
    /// measurement of `truth` at geometric `overlap` on the reference
    /// texture.
    pub fn error_sigmas(&self, truth: &Isometry3<f64>, overlap: f64) -> (f64, f64) {
        self.params.error_model().sigmas(truth, overlap)
    }

    /// The same for `request`: divided by `√min(s_ref, s_cur)` (a pose
    /// fitted to `n` features errs as `1/√n`).
    pub fn request_sigmas(
        &self,
        request: &TrackRequest,
        truth: &Isometry3<f64>,
        overlap: f64,
    ) -> (f64, f64) {
        let (r, t) = self.error_sigmas(truth, overlap);
        // Exact for a neutral supply: 1/√1 = 1.
        let k = self.supply_of(request).unwrap_or(1.0).sqrt().recip();
        (r * k, t * k)
    }

    /// A measurement's error `Exp(σ ⊙ z)` (right), its own part drawn from
    /// `rng`; under `error_model: shared` the share `ρ` of its variance is
    /// the map error of keyframe `reference`.
    fn drawn_error(
        &self,
        rng: &mut ChaCha8Rng,
        reference: usize,
        (sigma_r, sigma_t): (f64, f64),
    ) -> Isometry3<f64> {
        let draw =
            |rng: &mut ChaCha8Rng| Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
        let (own_r, own_t) = (draw(rng), draw(rng));
        let (z_r, z_t) = match self.params.error_model {
            TrackerErrorModel::Independent => (own_r, own_t),
            TrackerErrorModel::Shared => {
                let mut map = self.rng(MAP_ERROR_KEY, reference, 0);
                let (map_r, map_t) = (draw(&mut map), draw(&mut map));
                let rho = self.params.map_error_share;
                let (shared, own) = (rho.sqrt(), (1.0 - rho).sqrt());
                (shared * map_r + own * own_r, shared * map_t + own * own_t)
            }
        };
        Isometry3::from_parts(
            Translation3::from(z_t * sigma_t),
            UnitQuaternion::from_scaled_axis(z_r * sigma_r),
        )
    }
}

impl VisualOdometry for SimulatedVo {
    fn name(&self) -> &str {
        "simulated"
    }

    fn error_structure(&self) -> ErrorStructure {
        match self.params.error_model {
            TrackerErrorModel::Shared => ErrorStructure::SharedPerKeyframe,
            TrackerErrorModel::Independent => ErrorStructure::Independent,
        }
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
        let (sigma_r, sigma_t) = self.request_sigmas(request, &truth, overlap);
        let noise = self.drawn_error(&mut rng, request.reference.index, (sigma_r, sigma_t));
        let measurement = VoMeasurement {
            relative: truth * noise,
            covariance: isotropic_covariance(sigma_r, sigma_t),
            overlap: self.refound_share(request, overlap),
            needs_keyframe: false,
        };
        if request.purpose != TrackPurpose::LoopClosure {
            self.covisibility.tracked(request, &measurement);
        }
        TrackOutcome::Tracked(measurement)
    }

    fn success_probability(&self, request: &TrackRequest) -> f64 {
        self.success_and_overlap(request).map_or(0.0, |(p, _)| p)
    }

    /// The covisible keyframes' adjustment, when `covisibility_keyframes`
    /// is set ([`covisibility`]).
    fn keyframe_inserted(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        self.adjust_covisible(keyframe)
    }

    fn predicted_overlap(&self, reference: FrameRef, current: FrameRef) -> Option<f64> {
        self.truth(reference, current)
            .map(|truth| self.params.camera.body_overlap(&truth))
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
