//! The statistical tracker set beside the stereo VO on the same requests:
//! rendered drives over each soil, straight, turning in place and under blur;
//! every frame tracked against earlier ones at gaps of 0.4 to 20 s with a
//! wheel-odometry-like prior; for each request, the stereo VO's outcome and
//! error, and the statistical tracker's success probability and error
//! standard deviations. [`by_overlap`] bins both by geometric overlap and
//! [`differences`] compares them; `examples/tracker_calibration.rs` prints the
//! curves and fits the statistical tracker's parameters to them.

use std::sync::Arc;

use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::stereo::{StereoFrames, StereoVo, StereoVoParams};
use gpodo_frontends::vo::{
    FrameRef, SimulatedVo, SimulatedVoParams, TrackOutcome, TrackPurpose, TrackRequest,
    VisualOdometry,
};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::{BodyTwist, CameraParams};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use gpodo_testbed::camera::{FramePose, RenderedFrames};

/// Frames per second of every drive.
pub const FPS: f64 = 2.5;

/// One rendered drive: a soil, a speed and turn rate, and the mast's
/// extra rotation rate during the exposure (its vibration: the blur).
#[derive(Debug, Clone, Copy)]
pub struct Drive {
    /// A name for tables.
    pub name: &'static str,
    /// The soil of the whole patch.
    pub soil: fn() -> Soil,
    /// Forward speed (m/s).
    pub speed_mps: f64,
    /// Turn rate (rad/s).
    pub turn_radps: f64,
    /// The camera's extra yaw rate while the shutter is open (rad/s).
    pub shake_radps: f64,
    /// Frames.
    pub frames: usize,
}

impl Drive {
    /// The drives of the calibration: ExoTeR's 3 cm/s with a slow turn on
    /// compact soil, gravel and loose sand, straight at 0.1 m/s, turning
    /// in place at 0.1 rad/s, and the first drive with the mast shaking at
    /// 1 rad/s (a smear of about 4 px over a 10 ms exposure at
    /// 512 × 384), each `frames` long.
    pub fn calibration_set(frames: usize) -> Vec<Drive> {
        let base = Drive {
            name: "compact",
            soil: Soil::compact,
            speed_mps: 0.03,
            turn_radps: 0.01,
            shake_radps: 0.0,
            frames,
        };
        vec![
            base,
            Drive {
                name: "gravel",
                soil: Soil::gravel,
                ..base
            },
            Drive {
                name: "loose sand",
                soil: Soil::loose_sand,
                ..base
            },
            Drive {
                name: "straight at 0.1 m/s",
                speed_mps: 0.1,
                turn_radps: 0.0,
                ..base
            },
            Drive {
                name: "turning in place",
                speed_mps: 0.0,
                turn_radps: 0.1,
                ..base
            },
            Drive {
                name: "blurred",
                shake_radps: 1.0,
                ..base
            },
        ]
    }

    /// `world_from_body` at frame `k`: an arc from (1.5, 3) on a flat
    /// 9 × 9 m patch, heading +x, the camera 0.25 m up.
    fn pose(&self, k: usize) -> Isometry3<f64> {
        let t = k as f64 / FPS;
        let yaw = self.turn_radps * t;
        let (x, y) = if self.turn_radps.abs() < 1e-12 {
            (self.speed_mps * t, 0.0)
        } else {
            let r = self.speed_mps / self.turn_radps;
            (r * yaw.sin(), r * (1.0 - yaw.cos()))
        };
        Isometry3::from_parts(
            Translation3::new(1.5 + x, 3.0 + y, 0.25),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    }

    /// The frames' poses, each with its exposure's motion (the drive's
    /// and the shake's).
    pub fn frame_poses(&self, camera: &CameraParams) -> Vec<FramePose> {
        let yaw = (self.turn_radps + self.shake_radps) * camera.exposure_secs;
        let exposure_motion = Isometry3::from_parts(
            Translation3::new(self.speed_mps * camera.exposure_secs, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        );
        (0..self.frames)
            .map(|k| FramePose {
                world_from_body: self.pose(k),
                exposure_motion,
            })
            .collect()
    }

    /// The drive rendered (ground seed 11) through `stereo`'s camera, as
    /// `stereo` reads it, the true poses kept for the local map's
    /// ground-truth placement control.
    ///
    /// # Errors
    /// A ground that cannot be built.
    pub fn stereo_frames(&self, stereo: &StereoVoParams) -> Result<Arc<StereoFrames>, String> {
        let camera = stereo.camera;
        let ground = GroundMaps::build(
            &Terrain::flat(9.0).map_err(|e| e.to_string())?,
            &SoilMap::uniform((self.soil)(), 9.0).map_err(|e| e.to_string())?,
            &SceneSpec::default(),
            11,
        )
        .map_err(|e| e.to_string())?;
        let source = RenderedFrames::new(
            Arc::new(ground),
            camera,
            SensorSpec::default(),
            11,
            self.frame_poses(&camera),
        );
        let true_poses = source.true_camera_poses();
        Ok(Arc::new(
            StereoFrames::with_orb(camera, Arc::new(source), stereo.orb(&camera))
                .with_true_camera_poses(true_poses),
        ))
    }

    /// The drive as a traverse of its camera frames, with the statistical
    /// tracker's feature supply: the soil's texture times the share of
    /// features the exposure's blur leaves.
    ///
    /// # Errors
    /// A traverse that cannot be built.
    pub fn traverse(&self, camera: &CameraParams) -> Result<Traverse, String> {
        let times: Vec<f64> = (0..self.frames).map(|k| k as f64 / FPS).collect();
        let truth: Vec<Isometry3<f64>> = (0..self.frames).map(|k| self.pose(k)).collect();
        let twist = BodyTwist {
            linear_mps: Vector3::new(self.speed_mps, 0.0, 0.0),
            angular_radps: Vector3::new(0.0, 0.0, self.turn_radps),
        };
        let rate = Isometry3::from_parts(
            Translation3::new(self.speed_mps, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, self.turn_radps + self.shake_radps),
        );
        let supply = (self.soil)().texture * camera.blur_factor(camera.motion_blur_px(&rate));
        Traverse::new(
            self.name,
            times.clone(),
            truth,
            vec![twist; self.frames - 1],
            Vec::new(),
            times,
        )
        .and_then(|t| t.with_feature_supply(vec![supply; self.frames]))
        .map_err(|e| e.to_string())
    }
}

/// What both trackers made of one request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The drive's name.
    pub drive: &'static str,
    /// Gap between the frames (s).
    pub gap_secs: f64,
    /// The true body motion `reference_from_current`.
    pub truth: Isometry3<f64>,
    /// The geometric overlap of the two views (the camera's model).
    pub overlap: f64,
    /// The true relative rotation (rad) and translation (m).
    pub rotation_rad: f64,
    /// See `rotation_rad`.
    pub distance_m: f64,
    /// The frames' feature supply (texture × blur share).
    pub supply: f64,
    /// The stereo VO: `(rotation error vector (rad), translation error
    /// vector (m), inliers)` of a tracked request, in the body frame.
    pub stereo: Option<(Vector3<f64>, Vector3<f64>, usize)>,
    /// The statistical tracker's success probability.
    pub success_probability: f64,
    /// Its error standard deviations per axis, rotation (rad) and
    /// translation (m).
    pub sigmas: (f64, f64),
}

/// Every request of `drive`: each frame from the first on, every
/// `stride` frames, against each `gap` later, each tracker with its own
/// camera (by default the same one: ExoTeR's Bumblebee2 at 512 × 384).
///
/// # Errors
/// A drive whose ground or traverse cannot be built.
pub fn observe(
    drive: &Drive,
    stereo: &StereoVoParams,
    simulated: &SimulatedVoParams,
    gaps: &[usize],
    stride: usize,
) -> Result<Vec<Observation>, String> {
    let camera = stereo.camera;
    let poses = drive.frame_poses(&camera);
    let frames = drive.stereo_frames(stereo)?;
    let mut vo = StereoVo::new(stereo.clone(), frames).map_err(|e| e.to_string())?;
    let traverse = drive.traverse(&camera)?;
    let statistical = SimulatedVo::new(*simulated, &traverse).map_err(|e| e.to_string())?;
    let frame = |k: usize| FrameRef {
        index: k,
        time_secs: k as f64 / FPS,
    };
    let mut out = Vec::new();
    for &gap in gaps {
        for k in (0..drive.frames.saturating_sub(gap)).step_by(stride.max(1)) {
            let truth = poses[k].world_from_body.inverse() * poses[k + gap].world_from_body;
            let prior = Isometry3::from_parts(
                Translation3::from(truth.translation.vector * 0.95),
                truth.rotation * UnitQuaternion::from_euler_angles(0.0, 0.0, 0.0035),
            );
            let request = TrackRequest {
                reference: frame(k),
                current: frame(k + gap),
                prior: Some(prior),
                purpose: TrackPurpose::Tracking,
            };
            let stereo = match vo.track(&request) {
                TrackOutcome::Tracked(m) => {
                    let e = m.relative.inverse() * truth;
                    Some((
                        e.rotation.scaled_axis(),
                        e.translation.vector,
                        vo.tracked_inliers(frame(k + gap)).unwrap_or(0),
                    ))
                }
                TrackOutcome::Lost => None,
            };
            let (success_probability, overlap) = statistical
                .success_and_overlap(&request)
                .ok_or("a request outside the drive")?;
            out.push(Observation {
                drive: drive.name,
                gap_secs: gap as f64 / FPS,
                truth,
                overlap,
                rotation_rad: truth.rotation.angle(),
                distance_m: truth.translation.vector.norm(),
                supply: statistical
                    .feature_supply(k)
                    .min(statistical.feature_supply(k + gap)),
                stereo,
                success_probability,
                sigmas: statistical.request_sigmas(&request, &truth, overlap),
            });
        }
    }
    Ok(out)
}

/// Both trackers over the requests of one bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinSummary {
    /// Requests in the bin.
    pub count: usize,
    /// The stereo VO's share tracked.
    pub stereo_success: f64,
    /// The statistical tracker's mean success probability.
    pub statistical_success: f64,
    /// Requests the stereo VO tracked.
    pub tracked: usize,
    /// The stereo VO's error standard deviation per axis over its tracked
    /// requests (root mean square): rotation (rad), translation (m).
    pub stereo_sd: (f64, f64),
    /// The statistical tracker's over the same requests.
    pub statistical_sd: (f64, f64),
}

impl BinSummary {
    /// The header of [`BinSummary::table_row`]'s Markdown table.
    pub const TABLE_HEADER: &'static str = "| bin | requests | success, stereo | success, statistical | tracked | rotation sd (°), stereo | statistical | translation sd (mm), stereo | statistical |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|";

    /// This bin as a Markdown table row labelled `label` (degrees and
    /// millimetres).
    pub fn table_row(&self, label: &str) -> String {
        format!(
            "| {label} | {} | {:.2} | {:.2} | {} | {:.3} | {:.3} | {:.2} | {:.2} |",
            self.count,
            self.stereo_success,
            self.statistical_success,
            self.tracked,
            self.stereo_sd.0.to_degrees(),
            self.statistical_sd.0.to_degrees(),
            self.stereo_sd.1 * 1e3,
            self.statistical_sd.1 * 1e3,
        )
    }
}

/// [`observe`] over every drive of `drives`, in parallel, in the drives'
/// order.
///
/// # Errors
/// The first drive that cannot be built.
pub fn observe_all(
    drives: &[Drive],
    stereo: &StereoVoParams,
    simulated: &SimulatedVoParams,
    gaps: &[usize],
    stride: usize,
) -> Result<Vec<Observation>, String> {
    use rayon::prelude::*;
    Ok(drives
        .par_iter()
        .map(|d| observe(d, stereo, simulated, gaps, stride))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect())
}

/// The bin summary of `observations`.
pub fn summarise<'a>(observations: impl IntoIterator<Item = &'a Observation>) -> BinSummary {
    let (mut count, mut tracked) = (0usize, 0usize);
    let (mut s_stereo, mut s_stat) = (0.0, 0.0);
    let (mut e_r, mut e_t, mut v_r, mut v_t) = (0.0, 0.0, 0.0, 0.0);
    for o in observations {
        count += 1;
        s_stat += o.success_probability;
        if let Some((r, t, _)) = &o.stereo {
            tracked += 1;
            s_stereo += 1.0;
            e_r += r.norm_squared() / 3.0;
            e_t += t.norm_squared() / 3.0;
            v_r += o.sigmas.0 * o.sigmas.0;
            v_t += o.sigmas.1 * o.sigmas.1;
        }
    }
    let per = |x: f64, n: usize| if n > 0 { x / n as f64 } else { f64::NAN };
    BinSummary {
        count,
        stereo_success: per(s_stereo, count),
        statistical_success: per(s_stat, count),
        tracked,
        stereo_sd: (per(e_r, tracked).sqrt(), per(e_t, tracked).sqrt()),
        statistical_sd: (per(v_r, tracked).sqrt(), per(v_t, tracked).sqrt()),
    }
}

/// Bins of geometric overlap, 0.1 wide: `(lower edge, summary)` of each
/// non-empty one.
pub fn by_overlap(observations: &[Observation]) -> Vec<(f64, BinSummary)> {
    (0..10)
        .filter_map(|b| {
            let lo = b as f64 / 10.0;
            let hi = lo + 0.1;
            let inside: Vec<&Observation> = observations
                .iter()
                .filter(|o| o.overlap >= lo && (o.overlap < hi || (b == 9 && o.overlap <= 1.0)))
                .collect();
            (!inside.is_empty()).then(|| (lo, summarise(inside)))
        })
        .collect()
}

/// Where the two trackers' curves over overlap differ beyond the
/// tolerances (success probability by more than `success_tolerance`;
/// error standard deviation by more than the relative
/// `sd_tolerance`), over the bins with at least `min_samples` requests
/// (tracked ones, for the error): one line per difference.
pub fn differences(
    bins: &[(f64, BinSummary)],
    min_samples: usize,
    success_tolerance: f64,
    sd_tolerance: f64,
) -> Vec<String> {
    let mut out = Vec::new();
    for (lo, b) in bins {
        if b.count >= min_samples
            && (b.stereo_success - b.statistical_success).abs() > success_tolerance
        {
            out.push(format!(
                "overlap {lo:.1}: success {:.2} (stereo) against {:.2} ({} requests)",
                b.stereo_success, b.statistical_success, b.count
            ));
        }
        if b.tracked >= min_samples {
            for (what, stereo, stat) in [
                ("rotation", b.stereo_sd.0, b.statistical_sd.0),
                ("translation", b.stereo_sd.1, b.statistical_sd.1),
            ] {
                if (stat / stereo - 1.0).abs() > sd_tolerance {
                    out.push(format!(
                        "overlap {lo:.1}: {what} error sd {stereo:.3e} (stereo) against {stat:.3e} ({} tracked)",
                        b.tracked
                    ));
                }
            }
        }
    }
    out
}
