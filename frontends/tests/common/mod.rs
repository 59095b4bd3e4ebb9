//! Hand-made traverses and the tracker they were designed around, shared
//! by the front end's integration tests.

#![allow(dead_code)]

use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_frontends::vo::SimulatedVoParams;
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// The sensor period (s).
pub const DT: f64 = 0.08;

/// A traverse sampled at 12.5 Hz with a 10 Hz camera; `pose(t)` gives
/// `(x, y, yaw)`. Odometry twists reproduce the ground truth exactly, minus
/// `velocity_error` (body frame, m/s); windows of 1 s hold `inputs`.
pub fn traverse(
    secs: f64,
    pose: impl Fn(f64) -> (f64, f64, f64),
    velocity_error: Vector3<f64>,
    inputs: &[f64],
) -> Traverse {
    let n = (secs / DT).round() as usize + 1;
    let times: Vec<f64> = (0..n).map(|k| k as f64 * DT).collect();
    let gt: Vec<Isometry3<f64>> = times
        .iter()
        .map(|&t| {
            let (x, y, yaw) = pose(t);
            Isometry3::from_parts(
                Translation3::new(x, y, 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            )
        })
        .collect();
    let twists: Vec<BodyTwist> = gt
        .windows(2)
        .map(|w| {
            let delta = w[0].inverse() * w[1];
            BodyTwist {
                linear_mps: delta.translation.vector / DT - velocity_error,
                angular_radps: delta.rotation.scaled_axis() / DT,
            }
        })
        .collect();
    let steps_per_window = (1.0 / DT).round() as usize;
    let windows: Vec<TraverseWindow> = (0..(n - 1) / steps_per_window)
        .map(|w| {
            let steps = w * steps_per_window..(w + 1) * steps_per_window;
            TraverseWindow {
                start_secs: times[steps.start],
                end_secs: times[steps.end],
                steps,
                inputs: inputs.to_vec(),
                true_residual: velocity_error,
            }
        })
        .collect();
    // The camera runs at 12.5 Hz on the sensor clock, so frames fall on
    // samples and the odometry between frames is exact.
    let camera: Vec<f64> = times[..n - 1].to_vec();
    Traverse::new("hand-made", times, gt, twists, windows, camera).unwrap()
}

/// An S-curve at 5 cm/s.
pub fn s_curve(t: f64) -> (f64, f64, f64) {
    let yaw = 0.6 * (0.05 * t).sin();
    // Integrate approximately: fine, the odometry is derived from it.
    (0.05 * t, 0.3 * (0.05 * t).sin() * (0.05 * t), yaw)
}

/// The tracker these hand-made traverses were designed around: its
/// defaults before the calibration against the stereo VO (a 500-px camera
/// with a 3-m depth range, guided tracking at even odds at overlap 0.3,
/// the earlier error scales, 300 features, a map-error share of 0.5), so
/// that their turns and gaps lose track where the tests say.
pub fn earlier_tracker() -> SimulatedVoParams {
    SimulatedVoParams {
        camera: gpodo_frontends::vo::CameraParams::default(),
        min_overlap: 0.3,
        translation_sigma_m: 0.0007,
        translation_sigma_per_m: 0.007,
        rotation_sigma_rad: 0.00035,
        rotation_sigma_per_rad: 0.0035,
        features_per_frame: 300.0,
        map_error_share: 0.5,
        ..SimulatedVoParams::default()
    }
}
