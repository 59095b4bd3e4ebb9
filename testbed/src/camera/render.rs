//! A rectified stereo pair rendered from the precomputed ground: one ray
//! per pixel cast over the height map's maximum mipmap to the surface, the
//! radiance there, the depth along the left camera's optical axis, the
//! motion blur of the exposure, then the sensor's shot and read noise and
//! 8-bit quantisation.

use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::blur::blur;
use super::convert::as_f64;
use super::ground::GroundMaps;
use super::noise::mix;
use crate::TestbedError;

/// Rays longer than this meet nothing (m).
const MAX_RANGE_M: f64 = 30.0;

/// Rays start this far from the camera (m).
const MIN_RANGE_M: f64 = 0.01;

/// The image sensor: radiance to grey levels with shot and read noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorSpec {
    /// Grey level per unit radiance (default 300: ground of albedo 0.45
    /// lit at 50° reads about 110, as the PRL's sand does).
    pub gain_dn: f64,
    /// Electrons per grey level (default 40, a 10 000 e⁻ full well over
    /// 255 levels): shot noise has variance `level / electrons_per_dn`.
    pub electrons_per_dn: f64,
    /// Read noise (grey levels, standard deviation; default 0.8).
    pub read_noise_dn: f64,
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self {
            gain_dn: 300.0,
            electrons_per_dn: 40.0,
            read_noise_dn: 0.8,
        }
    }
}

impl SensorSpec {
    /// Checks every field.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming the field (under `prefix`).
    pub fn validate(&self, prefix: &str) -> Result<(), TestbedError> {
        for (name, v, lo) in [
            ("gain_dn", self.gain_dn, f64::MIN_POSITIVE),
            ("electrons_per_dn", self.electrons_per_dn, f64::MIN_POSITIVE),
            ("read_noise_dn", self.read_noise_dn, 0.0),
        ] {
            if !(v.is_finite() && v >= lo) {
                return Err(TestbedError::InvalidConfig {
                    field: format!("{prefix}.{name}"),
                    expected: "a finite non-negative number (positive for the gain and electrons)"
                        .into(),
                });
            }
        }
        Ok(())
    }
}

/// One rendered stereo frame.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoFrame {
    /// The left image.
    pub left: GrayImage,
    /// The right image.
    pub right: GrayImage,
    /// Depth along the left camera's optical axis per left pixel (m;
    /// infinite where the ray met nothing), row-major.
    pub depth_m: Vec<f32>,
}

/// One view before the sensor: radiance and depth per pixel.
struct View {
    width: usize,
    height: usize,
    radiance: Vec<f32>,
    depth_m: Vec<f32>,
}

/// Renders stereo frames of a testbed's ground through one camera.
pub struct StereoRenderer<'a> {
    camera: CameraParams,
    ground: &'a GroundMaps,
    sensor: SensorSpec,
    seed: u64,
}

impl<'a> StereoRenderer<'a> {
    /// A renderer of `ground` through `camera`, its image noise drawn from
    /// `seed` and the frame's index.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming a bad camera or sensor field.
    pub fn new(
        camera: CameraParams,
        ground: &'a GroundMaps,
        sensor: SensorSpec,
        seed: u64,
    ) -> Result<Self, TestbedError> {
        camera.validate("camera")?;
        sensor.validate("camera.sensor")?;
        Ok(Self {
            camera,
            ground,
            sensor,
            seed,
        })
    }

    /// The camera.
    pub fn camera(&self) -> &CameraParams {
        &self.camera
    }

    /// The pair seen from the body pose `world_from_body` at the middle of
    /// the exposure, the body moving by `exposure_motion`
    /// (`body_start_from_body_end`, identity for none) while the shutter
    /// is open; `frame` seeds its noise.
    pub fn render(
        &self,
        world_from_body: &Isometry3<f64>,
        exposure_motion: &Isometry3<f64>,
        frame: u64,
    ) -> StereoFrame {
        let body_from_left = self.camera.body_from_camera();
        let body_from_right = self.camera.body_from_right_camera();
        let (half_back, half_forward) = halves(exposure_motion);
        let mut images = [body_from_left, body_from_right].map(|body_from_camera| {
            let world_from_camera = world_from_body * body_from_camera;
            let mut view = self.trace_view(&world_from_camera);
            let start = world_from_body * half_back * body_from_camera;
            let end = world_from_body * half_forward * body_from_camera;
            if exposure_motion.translation.vector.norm() > 0.0
                || exposure_motion.rotation.angle() > 0.0
            {
                view.radiance = blur(
                    &self.camera,
                    view.width,
                    &view.radiance,
                    &view.depth_m,
                    &world_from_camera,
                    [&start, &end],
                );
            }
            view
        });
        let [left, right] = [0u64, 1].map(|camera| {
            let view = &images[camera as usize];
            self.expose(view, mix(self.seed ^ mix(frame) ^ camera))
        });
        let depth_m = std::mem::take(&mut images[0].depth_m);
        StereoFrame {
            left,
            right,
            depth_m,
        }
    }

    /// Radiance and depth of every pixel of the camera at
    /// `world_from_camera`, row by row in parallel (each pixel is its own
    /// computation, so the result does not depend on the threads).
    fn trace_view(&self, world_from_camera: &Isometry3<f64>) -> View {
        let [w, h] = self.camera.image_size_px.map(|n| n as usize);
        let origin = Point3::from(world_from_camera.translation.vector);
        let rows: Vec<(Vec<f32>, Vec<f32>)> = (0..h)
            .into_par_iter()
            .map(|v| {
                let rays: Vec<Vector3<f64>> = (0..w)
                    .map(|u| self.camera.pixel_ray(as_f64(u), as_f64(v)))
                    .collect();
                let dirs: Vec<Vector3<f64>> = rays
                    .iter()
                    .map(|ray| world_from_camera.rotation * ray.normalize())
                    .collect();
                let mut hits = Vec::with_capacity(w);
                self.ground
                    .first_hits(&origin, &dirs, MIN_RANGE_M, MAX_RANGE_M, &mut hits);
                let mut radiance = Vec::with_capacity(w);
                let mut depth = Vec::with_capacity(w);
                for ((ray, dir), hit) in rays.iter().zip(&dirs).zip(hits) {
                    match hit {
                        Some(t) => {
                            let p = origin + dir * t;
                            radiance.push(self.ground.radiance(p.x, p.y) as f32);
                            depth.push((t / ray.norm()) as f32);
                        }
                        None => {
                            radiance.push(self.ground.background as f32);
                            depth.push(f32::INFINITY);
                        }
                    }
                }
                (radiance, depth)
            })
            .collect();
        let mut view = View {
            width: w,
            height: h,
            radiance: Vec::with_capacity(w * h),
            depth_m: Vec::with_capacity(w * h),
        };
        for (r, d) in rows {
            view.radiance.extend(r);
            view.depth_m.extend(d);
        }
        view
    }

    /// Grey levels with shot and read noise, quantised to 8 bits; the
    /// noise is drawn in pixel order from `stream`.
    fn expose(&self, view: &View, stream: u64) -> GrayImage {
        let mut rng = ChaCha8Rng::seed_from_u64(stream);
        let s = self.sensor;
        let pixels = view
            .radiance
            .iter()
            .map(|&r| {
                let level = (f64::from(r) * s.gain_dn).max(0.0);
                let shot: f64 = StandardNormal.sample(&mut rng);
                let read: f64 = StandardNormal.sample(&mut rng);
                let noisy =
                    level + shot * (level / s.electrons_per_dn).sqrt() + read * s.read_noise_dn;
                noisy.round().clamp(0.0, 255.0) as u8
            })
            .collect();
        GrayImage::from_pixels(view.width, view.height, pixels)
            .unwrap_or_else(|_| GrayImage::filled(view.width, view.height, 0))
    }
}

/// The half motions back to the exposure's start and on to its end, from
/// its middle: `(body_mid_from_body_start, body_mid_from_body_end)`.
fn halves(body_start_from_body_end: &Isometry3<f64>) -> (Isometry3<f64>, Isometry3<f64>) {
    let half = Isometry3::from_parts(
        Translation3::from(body_start_from_body_end.translation.vector * 0.5),
        UnitQuaternion::from_scaled_axis(body_start_from_body_end.rotation.scaled_axis() * 0.5),
    );
    (half.inverse(), half)
}
