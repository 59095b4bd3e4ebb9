//! A VO (the stereo VO, or the statistical tracker on the same drive) on a
//! rendered drive as the front end drives it, without the pose graph:
//! every frame looked at (every frame, or every `step`-th) tracked against
//! the reference keyframe with a wheel-odometry-like prior (5 % short,
//! 0.2° off in yaw), a keyframe when the overlap falls below 0.8 (the
//! front end's rule), and on each new keyframe the VO told so
//! ([`VisualOdometry::keyframe_inserted`]): with local bundle adjustment
//! (or covisible keyframes) on, its refined links re-place the keyframes.
//! [`run_chain`] and [`run_chain_with`] measure the final map against the
//! truth.

use std::sync::Arc;
use std::time::Instant;

use gpodo_frontends::vo::stereo::{StereoFrames, StereoVo, StereoVoParams};
use gpodo_frontends::vo::{FrameRef, TrackOutcome, TrackPurpose, TrackRequest, VisualOdometry};
use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector6};

use crate::commands::tracker_calibration::{Drive, FPS};

/// The gaps (frames) the relative errors are taken at.
pub const GAPS: [usize; 3] = [1, 5, 12];

fn frame(k: usize) -> FrameRef {
    FrameRef {
        index: k,
        time_secs: k as f64 / FPS,
    }
}

/// `δ = [rotation; translation]` with `truth = estimate · Exp(δ)`
/// (first order).
fn error(estimate: &Isometry3<f64>, truth: &Isometry3<f64>) -> Vector6<f64> {
    let d = estimate.inverse() * truth;
    let r = d.rotation.scaled_axis();
    let t = d.translation.vector;
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

/// The median of `v` (NaN when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A keyframe's link: its reference, `reference_from_keyframe` (bodies)
/// and the covariance of that motion.
type Link = (usize, Isometry3<f64>, Matrix6<f64>);

/// What a chain run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainOutcome {
    /// Per gap of [`GAPS`], the median translation (mm) and rotation (°)
    /// errors of the final map's relative poses.
    pub relative: Vec<(f64, f64)>,
    /// The position error at the last frame over the path length (%).
    pub drift_percent: f64,
    /// The keyframe links' mean NEES (6 when their covariances are right).
    pub nees: f64,
    /// The keyframe links' RMS translation error (mm): what the local
    /// bundle adjustment refines.
    pub link_rms_mm: f64,
    /// The keyframes' RMS position error in the map (mm): the links'
    /// errors accumulated along the chain.
    pub keyframe_rms_mm: f64,
    /// Keyframes made.
    pub keyframes: usize,
    /// Each keyframe's time in [`VisualOdometry::keyframe_inserted`] (s).
    pub keyframe_secs: Vec<f64>,
    /// Per keyframe: its link as it stands at the end (reference,
    /// `reference_from_keyframe` of the bodies, covariance).
    pub links: Vec<(usize, usize, Isometry3<f64>, Matrix6<f64>)>,
    /// The frame where track was lost, if it was.
    pub lost_at: Option<usize>,
}

/// Runs `params`' VO over `drive`'s `frames` as the module says.
///
/// # Panics
/// Never on a drive of at least one frame; a VO that cannot be built
/// (bad `params`) panics.
#[allow(clippy::expect_used)]
pub fn run_chain(
    drive: &Drive,
    frames: &Arc<StereoFrames>,
    params: &StereoVoParams,
) -> ChainOutcome {
    let mut vo = StereoVo::new(params.clone(), Arc::clone(frames)).expect("valid VO settings");
    run_chain_with(drive, &params.camera, &mut vo, 1)
}

/// Runs `vo` over `drive` as the module says, looking at every `step`-th
/// frame (1: the drive's 2.5 fps; 5: 0.5 fps), `camera` placing the
/// frames.
pub fn run_chain_with(
    drive: &Drive,
    camera: &gpodo_traits::CameraParams,
    vo: &mut dyn VisualOdometry,
    step: usize,
) -> ChainOutcome {
    let step = step.max(1);
    let truth: Vec<Isometry3<f64>> = drive
        .frame_poses(camera)
        .iter()
        .map(|p| p.world_from_body)
        .collect();
    let n = truth.len();
    // Keyframes' map poses; per frame, its keyframe and the tracked motion.
    let mut keyframe_pose: Vec<Option<Isometry3<f64>>> = vec![None; n];
    keyframe_pose[0] = Some(Isometry3::identity());
    let mut placed: Vec<Option<(usize, Isometry3<f64>)>> = vec![None; n];
    placed[0] = Some((0, Isometry3::identity()));
    // Per keyframe: its link (reference, motion, covariance) as it stands.
    let mut links: Vec<Option<Link>> = vec![None; n];
    let mut reference = 0;
    let mut keyframes = 1;
    let mut ba_secs = Vec::new();
    let mut lost_at = None;
    let mut last = 0;
    for k in (step..n).step_by(step) {
        let true_motion = truth[reference].inverse() * truth[k];
        let prior = Isometry3::from_parts(
            Translation3::from(true_motion.translation.vector * 0.95),
            true_motion.rotation * UnitQuaternion::from_euler_angles(0.0, 0.0, 0.0035),
        );
        let outcome = vo.track(&TrackRequest {
            reference: frame(reference),
            current: frame(k),
            prior: Some(prior),
            purpose: TrackPurpose::Tracking,
        });
        let TrackOutcome::Tracked(m) = outcome else {
            lost_at = Some(k);
            break;
        };
        placed[k] = Some((reference, m.relative));
        last = k;
        if m.overlap < 0.8 {
            links[k] = Some((reference, m.relative, m.covariance));
            keyframe_pose[k] = keyframe_pose[reference].map(|p| p * m.relative);
            keyframes += 1;
            reference = k;
            let started = Instant::now();
            let refined = vo.keyframe_inserted(frame(k));
            ba_secs.push(started.elapsed().as_secs_f64());
            for link in refined {
                let (r, c) = (link.reference.index, link.current.index);
                links[c] = Some((r, link.relative, link.covariance));
                keyframe_pose[c] = keyframe_pose[r].map(|p| p * link.relative);
                placed[c] = Some((r, link.relative));
            }
        }
    }
    // The final map: keyframes as they stand, other frames on theirs.
    let map: Vec<Option<Isometry3<f64>>> = (0..n)
        .map(|k| match keyframe_pose[k] {
            Some(p) => Some(p),
            None => placed[k].and_then(|(r, m)| keyframe_pose[r].map(|p| p * m)),
        })
        .collect();
    let start = truth[0];
    let relative = GAPS
        .iter()
        .map(|&gap| {
            let (mut t, mut r) = (Vec::new(), Vec::new());
            for k in 0..=last.saturating_sub(gap) {
                if let (Some(a), Some(b)) = (map[k], map[k + gap]) {
                    let e = error(&(a.inverse() * b), &(truth[k].inverse() * truth[k + gap]));
                    r.push(e.fixed_rows::<3>(0).norm().to_degrees());
                    t.push(1e3 * e.fixed_rows::<3>(3).norm());
                }
            }
            (median(t), median(r))
        })
        .collect();
    let path: f64 = truth[..=last]
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum();
    let end_error = map[last].map_or(f64::NAN, |p| {
        ((start * p).translation.vector - truth[last].translation.vector).norm()
    });
    let nees: Vec<f64> = links
        .iter()
        .enumerate()
        .filter_map(|(c, l)| {
            let (r, m, s) = (*l)?;
            let e = error(&m, &(truth[r].inverse() * truth[c]));
            let info = s.try_inverse()?;
            Some((e.transpose() * info * e)[(0, 0)])
        })
        .collect();
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let link_errors: Vec<f64> = links
        .iter()
        .enumerate()
        .filter_map(|(c, l)| {
            let (r, m, _) = (*l)?;
            Some(
                1e3 * error(&m, &(truth[r].inverse() * truth[c]))
                    .fixed_rows::<3>(3)
                    .norm(),
            )
        })
        .collect();
    let keyframe_errors: Vec<f64> = keyframe_pose
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let p = (*p)?;
            Some(1e3 * ((start * p).translation.vector - truth[k].translation.vector).norm())
        })
        .collect();
    ChainOutcome {
        relative,
        link_rms_mm: rms(&link_errors),
        keyframe_rms_mm: rms(&keyframe_errors),
        drift_percent: 100.0 * end_error / path.max(1e-9),
        nees: nees.iter().sum::<f64>() / nees.len().max(1) as f64,
        keyframes,
        keyframe_secs: ba_secs,
        links: links
            .iter()
            .enumerate()
            .filter_map(|(c, l)| l.map(|(r, m, s)| (r, c, m, s)))
            .collect(),
        lost_at,
    }
}
