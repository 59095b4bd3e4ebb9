//! Replays a visual-odometry log: a trajectory computed offline on all
//! camera frames by any SLAM or VO system (TUM format, see [`crate::tum`]),
//! so the gating policies can be run on a user's own recordings.
//!
//! The relative pose between two processed frames is the logged
//! `world_from_reference⁻¹ · world_from_current`; a frame the log does not
//! hold (within `time_tolerance_secs`) was not tracked, and so fails. The
//! covariance follows the same error model as the simulated tracker, and
//! the overlap and place recognition use the same camera model on the
//! logged poses.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use super::{
    CameraParams, ErrorModel, FrameRef, TrackOutcome, TrackRequest, VisualOdometry, VoMeasurement,
    isotropic_covariance,
};
use crate::FrontendError;
use crate::traverse::Traverse;
use crate::tum::StampedPose;

/// Which frame the logged poses describe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoggedFrame {
    /// The rover body (default).
    #[default]
    Body,
    /// The camera (optical frame); converted with the camera's mounting.
    Camera,
}

/// Settings of the replay. Every field but `path` has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReplayVoParams {
    /// The TUM trajectory file (in an experiment file, relative to it: the
    /// loader makes it absolute); omitted, the visual odometry recorded
    /// with each test run (a bag's `vo` topic).
    pub path: std::path::PathBuf,
    /// Largest difference between a camera frame's time and a logged time
    /// stamp for them to match (s; default 0.02).
    pub time_tolerance_secs: f64,
    /// The frame the log describes (default `body`).
    pub frame: LoggedFrame,
    /// The camera (mounting, for `frame: camera`; overlap model).
    pub camera: CameraParams,
    /// Translation error floor (m; default 0.002).
    pub translation_sigma_m: f64,
    /// Translation error per metre (default 0.02).
    pub translation_sigma_per_m: f64,
    /// Rotation error floor (rad; default 0.001).
    pub rotation_sigma_rad: f64,
    /// Rotation error per radian (default 0.01).
    pub rotation_sigma_per_rad: f64,
    /// Least overlap for place recognition (default 0.5).
    pub recognition_min_overlap: f64,
    /// At most this many recognised keyframes are proposed (default 3).
    pub max_candidates: usize,
}

impl Default for ReplayVoParams {
    fn default() -> Self {
        Self {
            path: std::path::PathBuf::new(),
            time_tolerance_secs: 0.02,
            frame: LoggedFrame::Body,
            camera: CameraParams::default(),
            translation_sigma_m: 0.002,
            translation_sigma_per_m: 0.02,
            rotation_sigma_rad: 0.001,
            rotation_sigma_per_rad: 0.01,
            recognition_min_overlap: 0.5,
            max_candidates: 3,
        }
    }
}

impl ReplayVoParams {
    /// The measurement error model of these settings (overlap exponent 1).
    pub fn error_model(&self) -> ErrorModel {
        ErrorModel {
            translation_sigma_m: self.translation_sigma_m,
            translation_sigma_per_m: self.translation_sigma_per_m,
            rotation_sigma_rad: self.rotation_sigma_rad,
            rotation_sigma_per_rad: self.rotation_sigma_per_rad,
            overlap_exponent: 1.0,
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
        if !(self.time_tolerance_secs.is_finite() && self.time_tolerance_secs > 0.0) {
            return bad("time_tolerance_secs", "a positive duration");
        }
        self.error_model().validate()?;
        if !(0.0..=1.0).contains(&self.recognition_min_overlap) {
            return bad("recognition_min_overlap", "a fraction in [0, 1]");
        }
        if self.max_candidates == 0 {
            return bad("max_candidates", "at least 1");
        }
        Ok(())
    }
}

/// Replayed visual odometry over one traverse.
#[derive(Debug, Clone)]
pub struct ReplayVo {
    params: ReplayVoParams,
    /// The logged body pose of each camera frame, `None` when not logged.
    frames: Vec<Option<Isometry3<f64>>>,
}

impl ReplayVo {
    /// Matches the traverse's camera frames to the log's poses.
    ///
    /// # Errors
    /// As [`ReplayVoParams::validate`]; [`FrontendError::InvalidTraverse`]
    /// when no camera frame matches a logged pose.
    pub fn new(
        params: ReplayVoParams,
        traverse: &Traverse,
        log: &[StampedPose],
    ) -> Result<Self, FrontendError> {
        params.validate()?;
        let camera = params.camera.body_from_camera();
        let frames: Vec<Option<Isometry3<f64>>> = traverse
            .camera_times_secs()
            .iter()
            .map(|&t| {
                let i = log.partition_point(|p| p.time_secs < t);
                [i.checked_sub(1), Some(i)]
                    .into_iter()
                    .flatten()
                    .filter_map(|j| log.get(j))
                    .filter(|p| (p.time_secs - t).abs() <= params.time_tolerance_secs)
                    .min_by(|a, b| (a.time_secs - t).abs().total_cmp(&(b.time_secs - t).abs()))
                    .map(|p| match params.frame {
                        LoggedFrame::Body => p.pose,
                        LoggedFrame::Camera => p.pose * camera.inverse(),
                    })
            })
            .collect();
        if frames.iter().all(Option::is_none) {
            return Err(FrontendError::InvalidTraverse {
                traverse: traverse.name().to_string(),
                detail: format!(
                    "no camera frame matches a pose of the VO log {} within {} s",
                    params.path.display(),
                    params.time_tolerance_secs
                ),
            });
        }
        Ok(Self { params, frames })
    }

    /// Number of camera frames the log holds a pose for.
    pub fn logged_frames(&self) -> usize {
        self.frames.iter().filter(|f| f.is_some()).count()
    }

    fn logged(&self, a: FrameRef, b: FrameRef) -> Option<Isometry3<f64>> {
        let (x, y) = (
            self.frames.get(a.index)?.as_ref()?,
            self.frames.get(b.index)?.as_ref()?,
        );
        Some(x.inverse() * y)
    }
}

impl VisualOdometry for ReplayVo {
    fn name(&self) -> &str {
        "replay"
    }

    fn track(&mut self, request: &TrackRequest) -> TrackOutcome {
        let Some(relative) = self.logged(request.reference, request.current) else {
            return TrackOutcome::Lost;
        };
        let p = &self.params;
        let overlap = p.camera.body_overlap(&relative);
        let (sigma_r, sigma_t) = p.error_model().sigmas(&relative, overlap);
        TrackOutcome::Tracked(VoMeasurement {
            relative,
            covariance: isotropic_covariance(sigma_r, sigma_t),
            overlap,
            needs_keyframe: false,
        })
    }

    fn success_probability(&self, request: &TrackRequest) -> f64 {
        if self.logged(request.reference, request.current).is_some() {
            1.0
        } else {
            0.0
        }
    }

    fn recognise(&self, current: FrameRef, keyframes: &[FrameRef]) -> Vec<FrameRef> {
        let p = &self.params;
        let mut found: Vec<(f64, FrameRef)> = keyframes
            .iter()
            .filter_map(|kf| {
                let overlap = p.camera.body_overlap(&self.logged(*kf, current)?);
                (overlap >= p.recognition_min_overlap).then_some((overlap, *kf))
            })
            .collect();
        found.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.index.cmp(&b.1.index)));
        found.truncate(p.max_candidates);
        found.into_iter().map(|(_, kf)| kf).collect()
    }
}
