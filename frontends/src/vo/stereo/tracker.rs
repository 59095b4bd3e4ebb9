//! [`StereoVo`]: ORB-SLAM2's stereo tracking behind [`VisualOdometry`].
//!
//! * **Features**, once per frame and shared by every request that names
//!   the frame (a cache keyed by the frame's index): ORB on both images
//!   with ExoTeR's ORB-SLAM2 settings for the image's size, matched along
//!   the rows ([`gpodo_vision::stereo`]).
//! * **Map points**: the reference frame's stereo-matched keypoints closer
//!   than `max_depth_baselines` baselines (ORB-SLAM2's `ThDepth`, 40 on
//!   ExoTeR), placed by their disparity, or as the local bundle
//!   adjustment refined them.
//! * **Matching**: each map point is projected into the current frame by
//!   the prior and matched within `search_radius_px` times its level's
//!   scale (ORB-SLAM2's `TrackWithMotionModel`, 7 px for stereo, searched
//!   again at twice that when the first search does not track) to the
//!   current keypoints of the neighbouring levels, by Hamming distance
//!   below 100 (`TH_HIGH`) and a ratio test; without a prior, within
//!   `wide_search_px`.
//! * **Pose**: PnP with RANSAC seeded by the configuration's seed and the
//!   two frames' indices, then the robust motion-only refinement
//!   ([`super::pose`]); lost below `min_tracked_features` inliers
//!   (ORB-SLAM2's 30).
//! * **Local map** (off unless `local_map_keyframes` is set): once the
//!   reference's points have placed the frame, the points of the
//!   keyframes behind the reference are matched too and the pose refined
//!   on all, as ORB-SLAM2's `TrackLocalMap` does with the covisible
//!   keyframes'.
//! * **Overlap**, what the keyframe rule reads: ORB-SLAM2's ratio of the
//!   tracked inliers to the reference keyframe's points that are seen
//!   again (`mnMatchesInliers` against `TrackedMapPoints(nMinObs)` in
//!   `Tracking::NeedNewKeyFrame`; its stereo threshold is 0.75). Here the
//!   points seen again are the most inliers any frame tracked against the
//!   reference has had, so the ratio measures what tracking has lost since
//!   then, whatever share of its corners a frame finds again at best (a
//!   fresh keyframe's first tracked frame scores 1). A control,
//!   `overlap_denominator: shared_points`, counts ORB-SLAM2's points
//!   instead: the reference's that a keyframe behind it sees too.
//! * **Recognition**: by appearance only: the keyframes whose whole-image
//!   signatures correlate best with the current frame's, kept when their
//!   descriptors match the current frame's (ratio test) at least
//!   `min_tracked_features` times, most matches first.

use std::collections::HashMap;
use std::sync::Arc;

use gpodo_vision::hamming::{hamming, two_nearest_each};
use gpodo_vision::orb::OrbParams;
use gpodo_vision::stereo::StereoFeatures;
use nalgebra::{Isometry3, Matrix3, Matrix6, Point3};
use serde::{Deserialize, Serialize};

use super::frames::{Cached, StereoFrames};
use super::grid::KeypointGrid;
use super::pose::{Correspondence, StereoIntrinsics, ransac_pnp, refine_pose};
use crate::vo::{
    CameraParams, ErrorStructure, FrameRef, RefinedLink, TrackOutcome, TrackPurpose, TrackRequest,
    VisualOdometry, VoMeasurement,
};

pub mod local_ba;

/// Settings of the stereo VO.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StereoVoParams {
    /// Search radius around a map point's predicted pixel, per unit of its
    /// level's scale (px; default 7, ORB-SLAM2's stereo
    /// `TrackWithMotionModel`; 15 is its monocular one).
    pub search_radius_px: f64,
    /// Search radius without a prior (px at full resolution 1024 wide,
    /// scaled with the image; default 120).
    pub wide_search_px: f64,
    /// Fewest inliers of a tracked frame (default 30, ORB-SLAM2's).
    pub min_tracked_features: usize,
    /// Largest Hamming distance of a match (default 100, `TH_HIGH`).
    pub max_hamming: u32,
    /// A match's distance must be below this share of the second best's
    /// (default 0.9).
    pub ratio: f64,
    /// Map points farther than this many baselines are not used (default
    /// 40, ExoTeR's `ThDepth`).
    pub max_depth_baselines: f64,
    /// RANSAC's most iterations (default 200).
    pub ransac_iterations: usize,
    /// Seed of RANSAC's draws.
    pub seed: u64,
    /// ORB's feature cap (default: ExoTeR's 3000 at 1024 × 768, scaled
    /// with the image's pixel count: 750 at 512 × 384).
    pub features: Option<usize>,
    /// FAST's threshold in a cell without a corner at 20 (default 7,
    /// ExoTeR's `minThFAST`; 20 keeps only the strong corners).
    pub fast_min_threshold: u8,
    /// Keyframes before the reference (its parent, the parent's parent,
    /// …) whose map points are tracked too once the reference's have
    /// placed the frame, as ORB-SLAM2's `TrackLocalMap` tracks the points
    /// of the covisible keyframes (default 0: the reference's only).
    pub local_map_keyframes: usize,
    /// Search radius of such a point around its predicted pixel, per unit
    /// of its level's scale (px; default 4, ORB-SLAM2's
    /// `RadiusByViewingCos` for a nearly parallel view, `th = 1`).
    pub local_map_radius_px: f64,
    /// Where the local map's keyframes are placed: `chained` (default) by
    /// this VO's relative poses, as it must; `ground_truth`, by the frame
    /// source's ground truth, a control that sees it (for the rendered
    /// camera only).
    pub local_map_placement: LocalMapPlacement,
    /// What the overlap divides the tracked inliers by: `most_inliers`
    /// (default) or `shared_points`, ORB-SLAM2's (see
    /// [`OverlapDenominator`]).
    pub overlap_denominator: OverlapDenominator,
    /// ORB-SLAM2's stereo keyframe trigger, whatever the overlap
    /// (`bNeedToInsertClose` in `Tracking::NeedNewKeyFrame`): `[tracked,
    /// untracked]` calls for a keyframe when fewer than `tracked` close
    /// points (stereo keypoints within `max_depth_baselines`) are inliers
    /// while more than `untracked` are not (ORB-SLAM2's `[100, 70]`; the
    /// default, none, is off).
    pub close_points_keyframe: Option<[usize; 2]>,
    /// ORB-SLAM2's local bundle adjustment on each new keyframe: the new
    /// keyframe and up to this many keyframes behind it along the links
    /// it was tracked by (default 0: off; see [`local_ba`]).
    pub local_ba_keyframes: usize,
    /// Keyframes of that window sharing at least this many map points
    /// with the new one are adjusted with it; the others are held fixed
    /// (default 15, ORB-SLAM2's covisibility threshold).
    pub covisible_min_points: usize,
    /// The camera (default ExoTeR's Bumblebee2 at half resolution,
    /// 512 × 384, as rendered); a recording's camera infos, when its topic
    /// map names both, replace its intrinsics, size and baseline.
    pub camera: CameraParams,
}

impl Default for StereoVoParams {
    fn default() -> Self {
        Self {
            search_radius_px: 7.0,
            wide_search_px: 120.0,
            min_tracked_features: 30,
            max_hamming: 100,
            ratio: 0.9,
            max_depth_baselines: 40.0,
            ransac_iterations: 200,
            seed: 0,
            features: None,
            fast_min_threshold: 7,
            local_map_keyframes: 0,
            local_map_radius_px: 4.0,
            local_map_placement: LocalMapPlacement::Chained,
            overlap_denominator: OverlapDenominator::MostInliers,
            close_points_keyframe: None,
            local_ba_keyframes: 0,
            covisible_min_points: 15,
            camera: CameraParams::exoter_bumblebee2().scaled(0.5),
        }
    }
}

impl StereoVoParams {
    /// Checks every field; errors name it under `vo.`.
    ///
    /// # Errors
    /// [`crate::FrontendError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), crate::FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(crate::FrontendError::InvalidConfig {
                field: format!("vo.{field}"),
                expected: expected.into(),
            })
        };
        for (field, v) in [
            ("search_radius_px", self.search_radius_px),
            ("wide_search_px", self.wide_search_px),
            ("max_depth_baselines", self.max_depth_baselines),
            ("local_map_radius_px", self.local_map_radius_px),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, "a positive number");
            }
        }
        if !(self.ratio > 0.0 && self.ratio <= 1.0) {
            return bad("ratio", "a share in (0, 1]");
        }
        if self.min_tracked_features < 4 {
            return bad("min_tracked_features", "at least 4");
        }
        if self.max_hamming == 0 || self.max_hamming > 256 {
            return bad("max_hamming", "a distance in [1, 256]");
        }
        if self.covisible_min_points == 0 {
            return bad("covisible_min_points", "at least 1");
        }
        if self.ransac_iterations == 0 {
            return bad("ransac_iterations", "at least 1");
        }
        if self.features == Some(0) {
            return bad("features", "at least 1");
        }
        if !(1..=20).contains(&self.fast_min_threshold) {
            return bad(
                "fast_min_threshold",
                "a threshold in [1, 20] (the first is 20)",
            );
        }
        Ok(())
    }

    /// The ORB settings for `camera`'s images: ExoTeR's for its size
    /// (`OrbParams::exoter_for_size`), with this VO's feature cap and
    /// second FAST threshold.
    pub fn orb(&self, camera: &CameraParams) -> OrbParams {
        let [w, h] = camera.image_size_px.map(|n| n as usize);
        let exoter = OrbParams::exoter_for_size(w, h);
        OrbParams {
            features: self.features.unwrap_or(exoter.features),
            min_threshold: self.fast_min_threshold,
            ..exoter
        }
    }
}

/// Where the local map's keyframes are placed against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LocalMapPlacement {
    /// By chaining the VO's own relative poses back from the reference.
    Chained,
    /// By the frame source's true camera poses (a control; the chained
    /// pose where the source has none).
    GroundTruth,
}

/// What the overlap, the ratio the keyframe rule reads, divides a
/// frame's inliers by: how many of the reference keyframe's points a frame
/// could find again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OverlapDenominator {
    /// The most inliers any frame tracked against the reference has had.
    MostInliers,
    /// ORB-SLAM2's `TrackedMapPoints(nMinObs)` in `NeedNewKeyFrame`: the
    /// reference's map points with at least three observations, a stereo
    /// observation counting two (`MapPoint::AddObservation`), so the
    /// points a second keyframe sees too. Here: the reference's map points
    /// found in the keyframes behind it (its parent, or the local map's
    /// `local_map_keyframes`), projected there by the VO's own poses and
    /// matched within `local_map_radius_px` times their level's scale. A
    /// reference with no keyframe behind it counts all its points
    /// (ORB-SLAM2's `nMinObs = 2` while the map has two keyframes); one
    /// with fewer shared points than `min_tracked_features` falls back to
    /// the most inliers. The ratio can pass 1 (a frame matching points
    /// the reference made alone): it is capped there.
    SharedPoints,
}

/// The stereo visual odometry (see the module).
pub struct StereoVo {
    params: StereoVoParams,
    camera: CameraParams,
    intrinsics: StereoIntrinsics,
    frames: Arc<StereoFrames>,
    /// Per reference frame: the most inliers a frame tracked against it
    /// has had.
    seen_again: HashMap<usize, usize>,
    /// Per reference frame under [`OverlapDenominator::SharedPoints`]: its
    /// map points that a keyframe behind it sees too.
    shared_points: HashMap<usize, usize>,
    /// Per tracked frame: its inliers when it was last tracked.
    inliers: HashMap<usize, usize>,
    /// Per frame tracked or relocalised: its reference and
    /// `camera_from_reference`, the links the local map follows back.
    parents: HashMap<usize, (FrameRef, Isometry3<f64>)>,
    /// Per keyframe the local bundle adjustment has refined: per keypoint,
    /// its map point (that keyframe's camera) and its covariance given the
    /// adjusted poses, which replace the keypoint's own triangulation.
    refined_points: HashMap<usize, RefinedPoints>,
}

/// A keyframe's refined map points: per keypoint, the point (its camera)
/// and its covariance.
type RefinedPoints = HashMap<usize, (Point3<f64>, Matrix3<f64>)>;

/// What tracking one request found, before it is a measurement.
struct Tracked {
    /// `camera_from_reference`, left cameras.
    pose: Isometry3<f64>,
    covariance: Matrix6<f64>,
    inliers: usize,
    /// The correspondences the pose came from, and each one's current
    /// keypoint.
    correspondences: Vec<Correspondence>,
    keypoints: Vec<usize>,
    /// Per correspondence: an inlier of the pose.
    kept: Vec<bool>,
}

impl StereoVo {
    /// The VO over `frames` (whose camera it uses).
    ///
    /// # Errors
    /// [`crate::FrontendError::InvalidConfig`] naming a bad setting.
    pub fn new(
        params: StereoVoParams,
        frames: Arc<StereoFrames>,
    ) -> Result<Self, crate::FrontendError> {
        params.validate()?;
        let camera = *frames.camera();
        camera
            .validate("vo.camera")
            .map_err(|e| crate::FrontendError::InvalidConfig {
                field: e.field,
                expected: e.expected,
            })?;
        Ok(Self {
            intrinsics: StereoIntrinsics {
                focal_px: camera.focal_px,
                principal_px: camera.principal_point(),
                baseline_m: camera.baseline_m,
            },
            params,
            camera,
            frames,
            seen_again: HashMap::new(),
            shared_points: HashMap::new(),
            inliers: HashMap::new(),
            parents: HashMap::new(),
            refined_points: HashMap::new(),
        })
    }

    /// The features of `frame` (shared through the frames' cache).
    pub fn features(&self, frame: FrameRef) -> Cached {
        self.frames.features(frame)
    }

    /// How many map points `frame` makes as a reference (0 when its
    /// images cannot be had).
    pub fn map_point_count(&self, frame: FrameRef) -> usize {
        match self.features(frame).as_ref() {
            Ok(features) => self.map_points(frame, &features.stereo).len(),
            Err(_) => 0,
        }
    }

    /// How many inliers `frame` kept when this VO last tracked it (`None`
    /// when it has not).
    pub fn tracked_inliers(&self, frame: FrameRef) -> Option<usize> {
        self.inliers.get(&frame.index).copied()
    }

    /// The map points of a reference frame: `(keypoint, point, its
    /// covariance)` for each stereo match within the depth limit, placed
    /// by its disparity with its level's scale as each coordinate's
    /// standard deviation, or where the local bundle adjustment has
    /// refined it, as refined.
    fn map_points(
        &self,
        frame: FrameRef,
        features: &StereoFeatures,
    ) -> Vec<(usize, Point3<f64>, Matrix3<f64>)> {
        let refined = self.refined_points.get(&frame.index);
        self.close_keypoints(features)
            .map(|(k, d)| {
                if let Some(&(point, covariance)) = refined.and_then(|r| r.get(&k)) {
                    return (k, point, covariance);
                }
                let kp = &features.left.keypoints[k];
                let sigma = features.left.scales[usize::from(kp.level)];
                let (point, covariance) =
                    self.intrinsics
                        .triangulate([f64::from(kp.x), f64::from(kp.y)], d, sigma);
                (k, point, covariance)
            })
            .collect()
    }

    /// The close keypoints (ORB-SLAM2's): stereo matches nearer than
    /// `max_depth_baselines` baselines, each with its disparity.
    fn close_keypoints<'f>(
        &self,
        features: &'f StereoFeatures,
    ) -> impl Iterator<Item = (usize, f64)> + use<'f> {
        let max_depth = self.params.max_depth_baselines * self.intrinsics.baseline_m;
        let focal_baseline = self.intrinsics.focal_px * self.intrinsics.baseline_m;
        (0..features.left.keypoints.len()).filter_map(move |k| {
            let d = f64::from(features.disparity(k)?);
            (d > 0.0 && focal_baseline / d <= max_depth).then_some((k, d))
        })
    }

    /// Where the point `x` (current camera) falls in the image, if in
    /// front of the camera and inside the image.
    fn in_image(&self, x: &Point3<f64>) -> Option<[f64; 2]> {
        let [width, height] = self.camera.image_size_px.map(f64::from);
        let centre = (x.z > 0.0).then(|| self.intrinsics.project_left(x))?;
        ((0.0..width).contains(&centre[0]) && (0.0..height).contains(&centre[1])).then_some(centre)
    }

    /// `camera_from_reference` of the body motion `reference_from_current`.
    fn camera_prior(&self, body: &Isometry3<f64>) -> Isometry3<f64> {
        let b = self.camera.body_from_camera();
        (b.inverse() * body * b).inverse()
    }

    /// Tracks `request` (see the module); `None` when lost.
    fn track_request(&self, request: &TrackRequest) -> Option<Tracked> {
        let tracked = self
            .track_within(request, 1.0)
            .or_else(|| request.prior.and_then(|_| self.track_within(request, 2.0)))?;
        if self.params.local_map_keyframes == 0 || request.purpose == TrackPurpose::LoopClosure {
            return Some(tracked);
        }
        self.track_local_map(request, tracked)
    }

    /// The local map of `reference`: up to `local_map_keyframes`
    /// keyframes behind it along the links it was tracked by, nearest
    /// first, each with `reference_from_keyframe` (left cameras) as this
    /// VO chains it from its own relative poses (or as the ground truth
    /// places it, under [`LocalMapPlacement::GroundTruth`]).
    pub fn local_keyframes(&self, reference: FrameRef) -> Vec<(FrameRef, Isometry3<f64>)> {
        self.keyframes_behind(reference, self.params.local_map_keyframes)
    }

    /// Up to `count` keyframes behind `reference`, placed as
    /// [`Self::local_keyframes`] places them.
    fn keyframes_behind(
        &self,
        reference: FrameRef,
        count: usize,
    ) -> Vec<(FrameRef, Isometry3<f64>)> {
        let chained = self.chained_keyframes(reference.index, count);
        if self.params.local_map_placement == LocalMapPlacement::Chained {
            return chained;
        }
        let Some(reference_from_world) =
            self.frames.true_camera_pose(reference).map(|p| p.inverse())
        else {
            return chained;
        };
        chained
            .into_iter()
            .map(|(keyframe, pose)| {
                let true_pose = self
                    .frames
                    .true_camera_pose(keyframe)
                    .map(|world_from_keyframe| reference_from_world * world_from_keyframe);
                (keyframe, true_pose.unwrap_or(pose))
            })
            .collect()
    }

    /// [`Self::local_keyframes`] as the VO chains them.
    fn chained_keyframes(&self, reference: usize, count: usize) -> Vec<(FrameRef, Isometry3<f64>)> {
        let mut keyframes: Vec<(FrameRef, Isometry3<f64>)> = Vec::new();
        let (mut at, mut reference_from_at) = (reference, Isometry3::identity());
        while keyframes.len() < count {
            let Some(&(parent, at_from_parent)) = self.parents.get(&at) else {
                break;
            };
            if parent.index == reference || keyframes.iter().any(|(k, _)| k.index == parent.index) {
                break;
            }
            reference_from_at *= at_from_parent;
            keyframes.push((parent, reference_from_at));
            at = parent.index;
        }
        keyframes
    }

    /// [`OverlapDenominator::SharedPoints`] of `reference`: how many of
    /// its map points a keyframe behind it sees too (all of them when no
    /// keyframe is behind it).
    pub fn shared_point_count(&self, reference: FrameRef) -> usize {
        let features = self.features(reference);
        let Ok(features) = features.as_ref() else {
            return 0;
        };
        let features = &features.stereo;
        let points = self.map_points(reference, features);
        let behind = self.keyframes_behind(reference, self.params.local_map_keyframes.max(1));
        if behind.is_empty() {
            return points.len();
        }
        let mut shared = vec![false; points.len()];
        for (keyframe, reference_from_keyframe) in behind {
            let other = self.features(keyframe);
            let Ok(other) = other.as_ref() else {
                continue;
            };
            let other = &other.stereo;
            let grid = KeypointGrid::new(other);
            let keyframe_from_reference = reference_from_keyframe.inverse();
            let mut taken = vec![false; other.left.keypoints.len()];
            for ((k, point, _), shared) in points.iter().zip(shared.iter_mut()) {
                if *shared {
                    continue;
                }
                let Some(centre) = self.in_image(&(keyframe_from_reference * point)) else {
                    continue;
                };
                let level = usize::from(features.left.keypoints[*k].level);
                let radius = self.params.local_map_radius_px * features.left.scales[level];
                if let Some(found) = self.best_match((features, *k), (centre, radius), other, &grid)
                    && !std::mem::replace(&mut taken[found], true)
                {
                    *shared = true;
                }
            }
        }
        shared.into_iter().filter(|s| *s).count()
    }

    /// The overlap's denominator for a frame tracked against `reference`
    /// with `inliers` (see [`OverlapDenominator`]), its bookkeeping
    /// updated.
    fn seen_again(&mut self, reference: FrameRef, inliers: usize) -> usize {
        let most = self.seen_again.entry(reference.index).or_default();
        *most = (*most).max(inliers);
        let most = *most;
        if self.params.overlap_denominator == OverlapDenominator::MostInliers {
            return most;
        }
        let shared = match self.shared_points.get(&reference.index) {
            Some(&n) => n,
            None => {
                let n = self.shared_point_count(reference);
                tracing::debug!(
                    reference = reference.index,
                    shared_points = n,
                    first_inliers = inliers,
                    "stereo VO: the reference's points a keyframe behind it sees"
                );
                self.shared_points.insert(reference.index, n);
                n
            }
        };
        if shared < self.params.min_tracked_features {
            most
        } else {
            shared
        }
    }

    /// ORB-SLAM2's `TrackLocalMap` after `tracked` has placed the frame:
    /// the map points of the keyframes behind the reference, carried into
    /// its camera, projected by `tracked`'s pose and matched within
    /// `local_map_radius_px` to current keypoints no other point has
    /// taken (so a point that several keyframes saw, whose copies all
    /// match the same keypoint, counts once), then the pose refined on
    /// all; `None` below `min_tracked_features` inliers.
    fn track_local_map(&self, request: &TrackRequest, tracked: Tracked) -> Option<Tracked> {
        let current = self.features(request.current);
        let current = &current.as_ref().as_ref().ok()?.stereo;
        let grid = KeypointGrid::new(current);
        let mut taken = vec![false; current.left.keypoints.len()];
        for &k in &tracked.keypoints {
            taken[k] = true;
        }
        let mut correspondences = tracked.correspondences;
        let mut keypoints = tracked.keypoints;
        for (keyframe, reference_from_keyframe) in self.local_keyframes(request.reference) {
            let features = self.features(keyframe);
            let Ok(features) = features.as_ref() else {
                continue;
            };
            let features = &features.stereo;
            let r = reference_from_keyframe
                .rotation
                .to_rotation_matrix()
                .into_inner();
            for (k, point, point_covariance) in self.map_points(keyframe, features) {
                let point = reference_from_keyframe * point;
                let Some(centre) = self.in_image(&(tracked.pose * point)) else {
                    continue;
                };
                let kp = &features.left.keypoints[k];
                let radius =
                    self.params.local_map_radius_px * features.left.scales[usize::from(kp.level)];
                let Some(found) = self.best_match((features, k), (centre, radius), current, &grid)
                else {
                    continue;
                };
                if std::mem::replace(&mut taken[found], true) {
                    continue;
                }
                correspondences.push(correspondence(
                    current,
                    found,
                    point,
                    r * point_covariance * r.transpose(),
                ));
                keypoints.push(found);
            }
        }
        let refined = refine_pose(&correspondences, &self.intrinsics, &tracked.pose)?;
        (refined.inlier_count >= self.params.min_tracked_features).then_some(Tracked {
            pose: refined.pose,
            covariance: refined.covariance,
            inliers: refined.inlier_count,
            correspondences,
            keypoints,
            kept: refined.inliers,
        })
    }

    /// Tracks `request` with the prior's search window times `widen`.
    fn track_within(&self, request: &TrackRequest, widen: f64) -> Option<Tracked> {
        let reference = self.features(request.reference);
        let current = self.features(request.current);
        let (Ok(reference), Ok(current)) = (reference.as_ref(), current.as_ref()) else {
            return None;
        };
        let (reference, current) = (&reference.stereo, &current.stereo);
        let points = self.map_points(request.reference, reference);
        let prior = request.prior.map(|p| self.camera_prior(&p));
        let width = f64::from(self.camera.image_size_px[0]);
        let wide = self.params.wide_search_px * width / 1024.0;
        let grid = KeypointGrid::new(current);
        let mut correspondences = Vec::new();
        let mut keypoints = Vec::new();
        for (k, point, point_covariance) in &points {
            let kp = &reference.left.keypoints[*k];
            let scale = reference.left.scales[usize::from(kp.level)];
            let (centre, radius) = match &prior {
                Some(pose) => {
                    let x = pose * point;
                    if x.z <= 0.0 {
                        continue;
                    }
                    (
                        self.intrinsics.project_left(&x),
                        self.params.search_radius_px * widen * scale,
                    )
                }
                None => ([f64::from(kp.x), f64::from(kp.y)], wide),
            };
            let Some(found) = self.best_match((reference, *k), (centre, radius), current, &grid)
            else {
                continue;
            };
            correspondences.push(correspondence(current, found, *point, *point_covariance));
            keypoints.push(found);
        }
        if correspondences.len() < self.params.min_tracked_features {
            return None;
        }
        let seed = self.params.seed
            ^ (request.reference.index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ (request.current.index as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
        let (rough, count) = ransac_pnp(
            &correspondences,
            &self.intrinsics,
            self.params.ransac_iterations,
            seed,
        )?;
        if count < self.params.min_tracked_features {
            return None;
        }
        let refined = refine_pose(&correspondences, &self.intrinsics, &rough)?;
        if refined.inlier_count < self.params.min_tracked_features {
            return None;
        }
        Some(Tracked {
            pose: refined.pose,
            covariance: refined.covariance,
            inliers: refined.inlier_count,
            correspondences,
            keypoints,
            kept: refined.inliers,
        })
    }

    /// The current keypoint within `radius` of `centre`, at a level next to
    /// that of `reference`'s keypoint `keypoint`, nearest to its descriptor
    /// in Hamming distance, if below the limit and the ratio test.
    fn best_match(
        &self,
        (reference, keypoint): (&StereoFeatures, usize),
        (centre, radius): ([f64; 2], f64),
        current: &StereoFeatures,
        grid: &KeypointGrid,
    ) -> Option<usize> {
        let descriptor = &reference.left.descriptors[keypoint];
        let level = reference.left.keypoints[keypoint].level;
        let (mut best, mut second) = ((u32::MAX, usize::MAX), u32::MAX);
        for k in grid.within(centre, radius) {
            let kp = &current.left.keypoints[k];
            if kp.level.abs_diff(level) > 1 {
                continue;
            }
            let (du, dv) = (f64::from(kp.x) - centre[0], f64::from(kp.y) - centre[1]);
            if du * du + dv * dv > radius * radius {
                continue;
            }
            let d = hamming(descriptor, &current.left.descriptors[k]);
            if (d, k) < best {
                second = second.min(best.0);
                best = (d, k);
            } else {
                second = second.min(d);
            }
        }
        let (d, k) = best;
        (d <= self.params.max_hamming && f64::from(d) < self.params.ratio * f64::from(second))
            .then_some(k)
    }

    /// The measurement of a tracked request: the body motion
    /// `reference_from_current` and its covariance as a right
    /// perturbation (the camera's left perturbation carried through the
    /// mounting's adjoint), with the overlap against `seen_again` of the
    /// reference's points and, when `close_points_keyframe` is on, its
    /// call for a keyframe on `current`'s close points.
    fn measurement(
        &self,
        tracked: &Tracked,
        seen_again: usize,
        current: FrameRef,
    ) -> VoMeasurement {
        let (relative, covariance) = self.body_motion(&tracked.pose, &tracked.covariance);
        VoMeasurement {
            relative,
            covariance,
            overlap: (tracked.inliers as f64 / seen_again.max(1) as f64).min(1.0),
            needs_keyframe: self.params.close_points_keyframe.is_some_and(
                |[tracked_below, untracked_above]| {
                    let [inliers, others] = self.close_points(tracked, current);
                    inliers < tracked_below && others > untracked_above
                },
            ),
        }
    }

    /// The body motion `reference_from_current` of the left cameras'
    /// `camera_from_reference` and its covariance as a right perturbation
    /// (the camera's left perturbation `covariance` carried through the
    /// mounting's adjoint).
    fn body_motion(
        &self,
        camera_from_reference: &Isometry3<f64>,
        covariance: &Matrix6<f64>,
    ) -> (Isometry3<f64>, Matrix6<f64>) {
        let b = self.camera.body_from_camera();
        let adjoint = crate::vo::adjoint(&b);
        (
            b * camera_from_reference.inverse() * b.inverse(),
            adjoint * covariance * adjoint.transpose(),
        )
    }

    /// The current frame's close points (stereo keypoints within
    /// `max_depth_baselines`) that are inliers of `tracked`, and those
    /// that are not.
    fn close_points(&self, tracked: &Tracked, current: FrameRef) -> [usize; 2] {
        let features = self.features(current);
        let Ok(features) = features.as_ref() else {
            return [0, 0];
        };
        let close: Vec<usize> = self
            .close_keypoints(&features.stereo)
            .map(|(k, _)| k)
            .collect();
        let mut inlier = vec![false; features.stereo.left.keypoints.len()];
        for (&k, &kept) in tracked.keypoints.iter().zip(&tracked.kept) {
            inlier[k] |= kept;
        }
        let inliers = close.iter().filter(|&&k| inlier[k]).count();
        [inliers, close.len() - inliers]
    }

    /// How many of the current frame's descriptors find their match
    /// among `other`'s by the ratio test (brute force).
    fn appearance_matches(&self, current: &StereoFeatures, other: &StereoFeatures) -> usize {
        two_nearest_each(&current.left.descriptors, &other.left.descriptors)
            .iter()
            .filter(|n| {
                n.best <= self.params.max_hamming / 2
                    && f64::from(n.best) < self.params.ratio * f64::from(n.second)
            })
            .count()
    }
}

/// The map point `point` (with its covariance) seen at the current
/// keypoint `found`.
fn correspondence(
    current: &StereoFeatures,
    found: usize,
    point: Point3<f64>,
    point_covariance: Matrix3<f64>,
) -> Correspondence {
    let c = &current.left.keypoints[found];
    Correspondence {
        point,
        left_px: [f64::from(c.x), f64::from(c.y)],
        right_x: current.right_x[found].map(f64::from),
        sigma_px: current.left.scales[usize::from(c.level)],
        point_covariance,
    }
}

impl VisualOdometry for StereoVo {
    fn name(&self) -> &str {
        "stereo"
    }

    fn error_structure(&self) -> ErrorStructure {
        ErrorStructure::SharedPerKeyframe
    }

    fn track(&mut self, request: &TrackRequest) -> TrackOutcome {
        match self.track_request(request) {
            Some(tracked) => {
                let seen_again = self.seen_again(request.reference, tracked.inliers);
                let measurement = self.measurement(&tracked, seen_again, request.current);
                tracing::trace!(
                    reference = request.reference.index,
                    current = request.current.index,
                    inliers = tracked.inliers,
                    overlap = measurement.overlap,
                    "stereo VO tracked"
                );
                self.inliers.insert(request.current.index, tracked.inliers);
                if request.purpose != TrackPurpose::LoopClosure {
                    self.parents
                        .insert(request.current.index, (request.reference, tracked.pose));
                }
                TrackOutcome::Tracked(measurement)
            }
            None => {
                tracing::trace!(
                    reference = request.reference.index,
                    current = request.current.index,
                    "stereo VO lost"
                );
                TrackOutcome::Lost
            }
        }
    }

    /// The outcome of the same deterministic tracking: 1 or 0.
    fn success_probability(&self, request: &TrackRequest) -> f64 {
        f64::from(u8::from(self.track_request(request).is_some()))
    }

    /// ORB-SLAM2's local bundle adjustment on it, when
    /// `local_ba_keyframes` is set ([`local_ba`]).
    fn keyframe_inserted(&mut self, keyframe: FrameRef) -> Vec<RefinedLink> {
        self.adjust_local_map(keyframe)
    }

    /// Appearance only: the keyframes whose whole-image signatures
    /// correlate best with the current frame's (at least 0.5, the best
    /// [`RECOGNITION_SHORTLIST`]), kept when their descriptors match the
    /// current frame's at least `min_tracked_features` times (ratio test);
    /// most matches first, at most 3.
    fn recognise(&self, current: FrameRef, keyframes: &[FrameRef]) -> Vec<FrameRef> {
        let now = self.features(current);
        let Ok(now) = now.as_ref() else {
            return Vec::new();
        };
        let mut shortlist: Vec<(f32, FrameRef, Cached)> = keyframes
            .iter()
            .filter_map(|kf| {
                let other = self.features(*kf);
                let correlation = match other.as_ref() {
                    Ok(o) => o
                        .signature
                        .iter()
                        .zip(&now.signature)
                        .map(|(a, b)| a * b)
                        .sum(),
                    Err(_) => return None,
                };
                (correlation >= 0.5).then_some((correlation, *kf, other))
            })
            .collect();
        shortlist.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.index.cmp(&b.1.index)));
        shortlist.truncate(RECOGNITION_SHORTLIST);
        let mut found: Vec<(usize, FrameRef)> = shortlist
            .iter()
            .filter_map(|(_, kf, other)| {
                let other = other.as_ref().as_ref().ok()?;
                let n = self.appearance_matches(&now.stereo, &other.stereo);
                (n >= self.params.min_tracked_features).then_some((n, *kf))
            })
            .collect();
        found.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.index.cmp(&b.1.index)));
        found.truncate(3);
        found.into_iter().map(|(_, kf)| kf).collect()
    }
}

/// Keyframes whose descriptors recognition compares, after their
/// signatures.
pub const RECOGNITION_SHORTLIST: usize = 8;
