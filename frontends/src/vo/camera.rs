//! The camera's view and how much two views share: the overlap model of
//! the simulated (and replayed) visual odometry.
//!
//! The camera looks forward and down from a mast. Between two views its
//! motion, in the first view's optical frame (z forward, x right, y down),
//! loses part of the image to each of: panning (`|θ_y| / hfov`), tilting
//! (`|θ_x| / vfov`), rolling (`|θ_z| / π`), moving along the optical axis
//! (`|t_z| / depth_range`), sideways (`|t_x| / footprint_width`) and up or
//! down (`|t_y| / footprint_width`). The overlap is the product of what each
//! leaves, `Π (1 − loss)₊`: 1 for the same view, 0 when nothing is shared.

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::FrontendError;

/// The camera and what it sees. Defaults: an ExoTeR-like mast camera
/// (Bumblebee2-class, 66° × 50°), 1 m above the body origin, 20° down,
/// seeing the ground from about 1 to 4 m ahead.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraParams {
    /// Camera position in the body frame (m; default `[0.3, 0, 1.0]`).
    pub position_m: [f64; 3],
    /// Downward pitch of the optical axis (rad; default 0.35).
    pub pitch_down_rad: f64,
    /// Horizontal field of view (rad; default 1.15).
    pub hfov_rad: f64,
    /// Vertical field of view (rad; default 0.87).
    pub vfov_rad: f64,
    /// Depth of the seen ground along the optical axis (m; default 3):
    /// moving this far forward leaves nothing in common.
    pub depth_range_m: f64,
    /// Width of the seen ground (m; default 2.5).
    pub footprint_width_m: f64,
    /// Typical distance to the features (m; default 2), to turn a
    /// translation error into an image displacement.
    pub mean_depth_m: f64,
    /// Focal length (pixels; default 500).
    pub focal_px: f64,
    /// Exposure time (s; default 0.01), for the motion blur.
    pub exposure_secs: f64,
    /// Blur length at which the detected features halve (pixels; default
    /// 3, the radius of ORB's FAST circle).
    pub blur_half_px: f64,
}

impl Default for CameraParams {
    fn default() -> Self {
        Self {
            position_m: [0.3, 0.0, 1.0],
            pitch_down_rad: 0.35,
            hfov_rad: 1.15,
            vfov_rad: 0.87,
            depth_range_m: 3.0,
            footprint_width_m: 2.5,
            mean_depth_m: 2.0,
            focal_px: 500.0,
            exposure_secs: 0.01,
            blur_half_px: 3.0,
        }
    }
}

impl CameraParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidConfig`] naming the field (under `prefix`).
    pub fn validate(&self, prefix: &str) -> Result<(), FrontendError> {
        let positive = [
            ("hfov_rad", self.hfov_rad),
            ("vfov_rad", self.vfov_rad),
            ("depth_range_m", self.depth_range_m),
            ("footprint_width_m", self.footprint_width_m),
            ("mean_depth_m", self.mean_depth_m),
            ("focal_px", self.focal_px),
            ("blur_half_px", self.blur_half_px),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(FrontendError::InvalidConfig {
                    field: format!("{prefix}.{field}"),
                    expected: "a positive number".into(),
                });
            }
        }
        if !(self.exposure_secs.is_finite() && (0.0..=1.0).contains(&self.exposure_secs)) {
            return Err(FrontendError::InvalidConfig {
                field: format!("{prefix}.exposure_secs"),
                expected: "an exposure time in [0, 1] s".into(),
            });
        }
        if !(self.position_m.iter().all(|v| v.is_finite()) && self.pitch_down_rad.is_finite()) {
            return Err(FrontendError::InvalidConfig {
                field: format!("{prefix}.position_m"),
                expected: "finite coordinates and pitch".into(),
            });
        }
        Ok(())
    }

    /// `body_from_camera` with the optical convention (z forward, x right,
    /// y down).
    pub fn body_from_camera(&self) -> Isometry3<f64> {
        // Optical axes in the body frame: x → −y_body, y → −z_body,
        // z → x_body; then pitched down about body y.
        let optical = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
            0.0, 0.0, 1.0, //
            -1.0, 0.0, 0.0, //
            0.0, -1.0, 0.0,
        ));
        let pitch = Rotation3::from_axis_angle(&Vector3::y_axis(), self.pitch_down_rad);
        let [x, y, z] = self.position_m;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_rotation_matrix(&(pitch * optical)),
        )
    }

    /// The motion of the camera between two body poses:
    /// `camera1_from_camera2`.
    pub fn camera_motion(&self, body1_from_body2: &Isometry3<f64>) -> Isometry3<f64> {
        let c = self.body_from_camera();
        c.inverse() * body1_from_body2 * c
    }

    /// The fraction of the view shared by two camera poses related by
    /// `camera1_from_camera2`, in `[0, 1]`.
    pub fn overlap(&self, camera1_from_camera2: &Isometry3<f64>) -> f64 {
        let theta = camera1_from_camera2.rotation.scaled_axis();
        let t = camera1_from_camera2.translation.vector;
        let losses = [
            theta.y.abs() / self.hfov_rad,
            theta.x.abs() / self.vfov_rad,
            theta.z.abs() / std::f64::consts::PI,
            t.z.abs() / self.depth_range_m,
            t.x.abs() / self.footprint_width_m,
            t.y.abs() / self.footprint_width_m,
        ];
        losses.iter().map(|l| (1.0 - l).max(0.0)).product()
    }

    /// The overlap of the views from two body poses related by
    /// `body1_from_body2`.
    pub fn body_overlap(&self, body1_from_body2: &Isometry3<f64>) -> f64 {
        self.overlap(&self.camera_motion(body1_from_body2))
    }

    /// How far (pixels) an image point moves when the relative pose is
    /// wrong by `error` (`estimate⁻¹ · truth`): rotation angle plus
    /// translation over the mean feature depth, times the focal length.
    pub fn image_error_px(&self, error: &Isometry3<f64>) -> f64 {
        let camera_error = self.camera_motion(error);
        self.focal_px
            * (camera_error.rotation.angle()
                + camera_error.translation.vector.norm() / self.mean_depth_m)
    }
}

impl CameraParams {
    /// Nine points of the footprint in the body frame, where the
    /// terrain's texture is read (at their x–y position): a 3 × 3 grid
    /// across it (`±footprint_width_m / 3` sideways) and along the optical
    /// axis (`mean_depth_m` and `± depth_range_m / 3`), the extent the
    /// overlap model gives the seen ground (1.2–3.2 m ahead of the body by
    /// default). They lie on the optical axis' plane, not on the terrain:
    /// the overlap model has no ground height.
    pub fn footprint_body(&self) -> [Vector3<f64>; 9] {
        let body_from_camera = self.body_from_camera();
        let (across, along) = (self.footprint_width_m / 3.0, self.depth_range_m / 3.0);
        std::array::from_fn(|i| {
            let x = across * (i % 3) as f64 - across;
            let z = (self.mean_depth_m + along * (i / 3) as f64 - along).max(0.0);
            body_from_camera * nalgebra::Point3::new(x, 0.0, z)
        })
        .map(|p| p.coords)
    }

    /// The motion blur (pixels) of a frame taken while the body moves by
    /// `body_motion` per second: the image displacement
    /// ([`CameraParams::image_error_px`]) of the motion during the
    /// exposure.
    pub fn motion_blur_px(&self, body_motion_per_sec: &Isometry3<f64>) -> f64 {
        let s = self.exposure_secs;
        let during = Isometry3::from_parts(
            Translation3::from(body_motion_per_sec.translation.vector * s),
            UnitQuaternion::from_scaled_axis(body_motion_per_sec.rotation.scaled_axis() * s),
        );
        self.image_error_px(&during)
    }

    /// The share of features a blur of `blur_px` leaves,
    /// `1 / (1 + blur_px / blur_half_px)`.
    pub fn blur_factor(&self, blur_px: f64) -> f64 {
        1.0 / (1.0 + blur_px.max(0.0) / self.blur_half_px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_camera_looks_forward_and_down() {
        let c = CameraParams::default().body_from_camera();
        let axis = c.rotation * Vector3::z();
        assert!(axis.x > 0.9 && axis.z < -0.3, "{axis}");
        let right = c.rotation * Vector3::x();
        assert!((right - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn overlap_falls_with_turning_and_driving() {
        let cam = CameraParams::default();
        assert!((cam.body_overlap(&Isometry3::identity()) - 1.0).abs() < 1e-12);
        // A 0.23 rad turn on the spot pans the pitched camera by 0.23 ·
        // cos 0.35 (a sixth of the field of view), rolls it by 0.23 ·
        // sin 0.35 and swings it 0.3 sin 0.23 m sideways on the mast.
        let turn = Isometry3::rotation(Vector3::z() * 0.23);
        let o = cam.body_overlap(&turn);
        let expected = (1.0 - 0.23 * 0.35f64.cos() / 1.15)
            * (1.0 - 0.23 * 0.35f64.sin() / std::f64::consts::PI)
            * (1.0 - 0.3 * 0.23f64.sin() / 2.5);
        assert!((o - expected).abs() < 5e-3, "{o} vs {expected}");
        // Driving forward 0.5 m: along the optical axis by 0.5 cos 0.35,
        // and across the image by 0.5 sin 0.35.
        let drive = Isometry3::translation(0.5, 0.0, 0.0);
        let d = cam.body_overlap(&drive);
        let expected = (1.0 - 0.5 * 0.35f64.cos() / 3.0) * (1.0 - 0.5 * 0.35f64.sin() / 2.5);
        assert!((d - expected).abs() < 1e-9, "{d} vs {expected}");
        let far = Isometry3::translation(5.0, 0.0, 0.0);
        assert_eq!(cam.body_overlap(&far), 0.0);
        // Symmetric in the direction of the turn.
        let back = Isometry3::rotation(Vector3::z() * -0.23);
        assert!((cam.body_overlap(&back) - o).abs() < 1e-12);
    }

    #[test]
    fn the_footprint_lies_ahead_and_across_the_optical_axis() {
        let cam = CameraParams::default();
        let points = cam.footprint_body();
        // The centre: 2 m along an axis pitched 0.35 rad down from 1 m up
        // on the mast 0.3 m ahead.
        let centre = points[4];
        let expected = Vector3::new(0.3 + 2.0 * 0.35f64.cos(), 0.0, 1.0 - 2.0 * 0.35f64.sin());
        assert!((centre - expected).norm() < 1e-12, "{centre}");
        // Sideways points are 2.5/3 m to either side.
        assert!((points[3].y - points[5].y - 2.0 * 2.5 / 3.0).abs() < 1e-12);
        assert!(points[0].x < centre.x && points[6].x > centre.x);
    }

    #[test]
    fn blur_is_focal_times_the_angle_turned_during_the_exposure() {
        let cam = CameraParams::default();
        // 0.2 rad/s about the optical axis' perpendicular for 10 ms at
        // 500 px: 1 px, plus the mast's swing.
        let turn = Isometry3::rotation(Vector3::z() * 0.2);
        let b = cam.motion_blur_px(&turn);
        let swing = 0.3 * 0.2 * 0.01 / 2.0;
        assert!((b - 500.0 * (0.2 * 0.01 + swing)).abs() < 1e-3, "{b}");
        assert!((cam.blur_factor(3.0) - 0.5).abs() < 1e-15);
        assert_eq!(cam.blur_factor(0.0), 1.0);
    }

    #[test]
    fn image_error_is_focal_times_angle() {
        let cam = CameraParams::default();
        let e = cam.image_error_px(&Isometry3::rotation(Vector3::z() * 0.01));
        // 500 px · 0.01 rad, plus the camera's 3 mm swing on the mast
        // (0.3 m ahead of the axis) over the 2 m mean depth.
        assert!((e - (5.0 + 500.0 * 0.003 / 2.0)).abs() < 0.01, "{e}");
    }
}
