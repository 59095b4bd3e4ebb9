//! The simulated tracker's feature supply per camera frame, computed where
//! the soil map lives: the mean texture of the soils under the camera's
//! ground footprint ([`CameraParams::footprint_body`]) times the share of
//! features the motion blur leaves ([`CameraParams::blur_factor`] of
//! [`CameraParams::motion_blur_px`]), the true body motion being taken
//! over ±[`RATE_HALF_WINDOW_SECS`] around the frame. See
//! `frontends/README.md` for the model and its sources.

use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::CameraParams;
use gpodo_testbed::sim::soil::SoilMap;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Half the window over which a frame's body rate is measured (s): long
/// against the motion-capture jitter, short against a manoeuvre.
pub const RATE_HALF_WINDOW_SECS: f64 = 0.25;

/// The mean texture of the soils under the footprint of a camera on a body
/// at `world_from_body`, each soil's texture raised to `contrast`
/// (`SimulatedVoParams::texture_contrast`; 1 keeps the soils' values).
pub fn footprint_texture(
    soils: &SoilMap,
    camera: &CameraParams,
    contrast: f64,
    world_from_body: &Isometry3<f64>,
) -> f64 {
    let points = camera.footprint_body();
    let sum: f64 = points
        .iter()
        .map(|p| {
            let w = world_from_body * nalgebra::Point3::from(*p);
            soils.soil_at(w.x, w.y).texture.powf(contrast)
        })
        .sum();
    sum / points.len() as f64
}

/// The true body motion per second around time `t`.
fn body_rate(traverse: &Traverse, t: f64) -> Isometry3<f64> {
    // Clamped to the sampled span, as the ground truth is.
    let times = traverse.times_secs();
    let (first, last) = (times[0], times[times.len() - 1]);
    let a = (t - RATE_HALF_WINDOW_SECS).max(first);
    let b = (t + RATE_HALF_WINDOW_SECS).min(last);
    let motion = traverse.ground_truth_at(a).inverse() * traverse.ground_truth_at(b);
    let per_sec = if b > a { 1.0 / (b - a) } else { 0.0 };
    Isometry3::from_parts(
        Translation3::from(motion.translation.vector * per_sec),
        UnitQuaternion::from_scaled_axis(motion.rotation.scaled_axis() * per_sec),
    )
}

/// The feature supply of every camera frame of `traverse`, the soils'
/// textures raised to `contrast`.
pub fn feature_supply(
    soils: &SoilMap,
    camera: &CameraParams,
    contrast: f64,
    traverse: &Traverse,
) -> Vec<f64> {
    traverse
        .camera_times_secs()
        .iter()
        .map(|&t| {
            let texture = footprint_texture(soils, camera, contrast, &traverse.ground_truth_at(t));
            let blur = camera.motion_blur_px(&body_rate(traverse, t));
            texture * camera.blur_factor(blur)
        })
        .collect()
}
