//! The camera: one description read by the rendered stereo camera (a
//! rectified pinhole pair) and by the statistical tracker's overlap model.
//!
//! **The pinhole pair.** Both cameras share one rectified `K` (focal
//! length `f` in pixels for x and y, principal point `(c_x, c_y)`), the
//! image size, and their orientation; the right camera sits `baseline_m`
//! along the left camera's x axis. A point `p` in the left camera's optical
//! frame (z forward, x right, y down) projects to
//! `(u, v) = (f p_x / p_z + c_x, f p_y / p_z + c_y)` in pixel coordinates
//! whose integers are pixel centres, and to the right image at disparity
//! `d = f b / p_z` to the left.
//!
//! **The overlap model** of the simulated (and replayed) visual odometry:
//! the camera looks forward and down from a mast. Between two views its
//! motion, in the first view's optical frame (z forward, x right, y down),
//! loses part of the image to each of: panning (`|θ_y| / hfov`), tilting
//! (`|θ_x| / vfov`), rolling (`|θ_z| / π`), moving along the optical axis
//! (`|t_z| / depth_range`), sideways (`|t_x| / footprint_width`) and up or
//! down (`|t_y| / footprint_width`). The overlap is the product of what each
//! leaves, `Π (1 − loss)₊`: 1 for the same view, 0 when nothing is shared.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A camera setting that is out of range: the field (dotted, under the
/// prefix given to [`CameraParams::validate`]) and what it should be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field}: expected {expected}")]
pub struct InvalidCameraField {
    /// The field, dotted (`vo.camera.focal_px`).
    pub field: String,
    /// What a valid value looks like.
    pub expected: String,
}

/// The camera and what it sees. Defaults: the statistical tracker's
/// ExoTeR-like mast camera (Bumblebee2-class, 66° × 50°), 1 m above the
/// body origin, 20° down, seeing the ground from about 1 to 4 m ahead, as a
/// 648 × 465 pinhole of focal 500 px (the size those fields of view give).
/// [`CameraParams::exoter_bumblebee2`] is ExoTeR's real mast camera.
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
    /// 19, the stereo VO's inliers on the rendered camera: a 4.4-px smear
    /// leaves 0.81 of them, `experiments/examples/tracker_calibration.rs`).
    pub blur_half_px: f64,
    /// Image size `[width, height]` (pixels; default `[648, 465]`).
    pub image_size_px: [u32; 2],
    /// Principal point `[c_x, c_y]` (pixels; default: the image centre,
    /// `(size − 1) / 2`).
    pub principal_point_px: Option<[f64; 2]>,
    /// Distance from the left to the right camera along the left camera's
    /// x axis (m; default 0.12).
    pub baseline_m: f64,
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
            blur_half_px: 19.0,
            image_size_px: [648, 465],
            principal_point_px: None,
            baseline_m: 0.12,
        }
    }
}

impl CameraParams {
    /// ExoTeR's mast Bumblebee2 as ORB-SLAM2's calibration has it: one
    /// rectified `K` for both cameras (f = 838 px, c = (509.75, 377.00)),
    /// 1024 × 768, baseline 0.1204 m; the left camera 0.035 m above the
    /// mast's tilt unit at (0.076, 0, 0.633) m in the body frame (about
    /// 0.92 m above flat ground: the body origin rides 0.25 m up), half
    /// the baseline left of the mast's axis, tilted 30° down (the lab's
    /// mission setting). The overlap model's fields of view follow from
    /// `K`; its other fields keep the tracker's defaults.
    pub fn exoter_bumblebee2() -> Self {
        let (width, height, focal): (f64, f64, f64) = (1024.0, 768.0, 838.0);
        let baseline_m = 0.12043;
        Self {
            position_m: [0.076, baseline_m / 2.0, 0.633 + 0.035],
            pitch_down_rad: 30f64.to_radians(),
            hfov_rad: 2.0 * (0.5 * width / focal).atan(),
            vfov_rad: 2.0 * (0.5 * height / focal).atan(),
            focal_px: focal,
            image_size_px: [1024, 768],
            principal_point_px: Some([509.75, 377.0]),
            baseline_m,
            ..Self::default()
        }
    }

    /// The same camera rendering at `scale` times the resolution: image
    /// size rounded, focal length and principal point scaled (pixel centres
    /// kept: `c' = (c + ½) s − ½`).
    pub fn scaled(&self, scale: f64) -> Self {
        let [cx, cy] = self.principal_point();
        let size = self
            .image_size_px
            .map(|n| ((f64::from(n) * scale).round() as u32).max(1));
        Self {
            focal_px: self.focal_px * scale,
            image_size_px: size,
            principal_point_px: Some([(cx + 0.5) * scale - 0.5, (cy + 0.5) * scale - 0.5]),
            ..*self
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`InvalidCameraField`] naming the field (under `prefix`).
    pub fn validate(&self, prefix: &str) -> Result<(), InvalidCameraField> {
        let invalid = |field: &str, expected: &str| InvalidCameraField {
            field: format!("{prefix}.{field}"),
            expected: expected.into(),
        };
        let positive = [
            ("hfov_rad", self.hfov_rad),
            ("vfov_rad", self.vfov_rad),
            ("depth_range_m", self.depth_range_m),
            ("footprint_width_m", self.footprint_width_m),
            ("mean_depth_m", self.mean_depth_m),
            ("focal_px", self.focal_px),
            ("blur_half_px", self.blur_half_px),
            ("baseline_m", self.baseline_m),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(field, "a positive number"));
            }
        }
        if !(self.exposure_secs.is_finite() && (0.0..=1.0).contains(&self.exposure_secs)) {
            return Err(invalid("exposure_secs", "an exposure time in [0, 1] s"));
        }
        if !(self.position_m.iter().all(|v| v.is_finite()) && self.pitch_down_rad.is_finite()) {
            return Err(invalid("position_m", "finite coordinates and pitch"));
        }
        let [width, height] = self.image_size_px;
        if width < 8 || height < 8 {
            return Err(invalid(
                "image_size_px",
                "[width, height] of at least 8 pixels each",
            ));
        }
        if let Some([cx, cy]) = self.principal_point_px {
            let inside = |c: f64, n: u32| c.is_finite() && (0.0..=f64::from(n) - 1.0).contains(&c);
            if !(inside(cx, width) && inside(cy, height)) {
                return Err(invalid(
                    "principal_point_px",
                    "[c_x, c_y] inside the image (pixels, from the top-left pixel's centre)",
                ));
            }
        }
        Ok(())
    }

    /// The principal point `[c_x, c_y]` (pixels).
    pub fn principal_point(&self) -> [f64; 2] {
        self.principal_point_px.unwrap_or_else(|| {
            let [w, h] = self.image_size_px;
            [0.5 * (f64::from(w) - 1.0), 0.5 * (f64::from(h) - 1.0)]
        })
    }

    /// The pixel `(u, v)` of a point in the camera's optical frame, or
    /// `None` behind the camera (`z ≤ 0`). It may lie outside the image.
    pub fn project(&self, p_camera: &Point3<f64>) -> Option<[f64; 2]> {
        if p_camera.z <= 0.0 {
            return None;
        }
        let [cx, cy] = self.principal_point();
        let f = self.focal_px;
        Some([
            f * p_camera.x / p_camera.z + cx,
            f * p_camera.y / p_camera.z + cy,
        ])
    }

    /// The direction through pixel `(u, v)` in the camera's optical frame,
    /// scaled to `z = 1`.
    pub fn pixel_ray(&self, u: f64, v: f64) -> Vector3<f64> {
        let [cx, cy] = self.principal_point();
        Vector3::new((u - cx) / self.focal_px, (v - cy) / self.focal_px, 1.0)
    }

    /// The disparity (pixels) of a point at depth `z_m` along the optical
    /// axis: `f b / z`.
    pub fn disparity_px(&self, z_m: f64) -> f64 {
        self.focal_px * self.baseline_m / z_m
    }

    /// `body_from_right`: the right camera, `baseline_m` along the left
    /// camera's x axis, with the same orientation.
    pub fn body_from_right_camera(&self) -> Isometry3<f64> {
        self.body_from_camera() * Translation3::new(self.baseline_m, 0.0, 0.0)
    }
}

impl CameraParams {
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
        assert!((cam.blur_factor(cam.blur_half_px) - 0.5).abs() < 1e-15);
        assert!((cam.blur_factor(19.0) - 0.5).abs() < 1e-15);
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

    #[test]
    fn a_pixel_ray_projects_back_to_its_pixel_and_scaling_keeps_pixel_centres() {
        let cam = CameraParams::exoter_bumblebee2();
        cam.validate("camera").unwrap();
        for (u, v) in [
            (0.0, 0.0),
            (509.75, 377.0),
            (1023.0, 767.0),
            (100.5, 600.25),
        ] {
            let p = Point3::from(cam.pixel_ray(u, v) * 2.7);
            let [pu, pv] = cam.project(&p).unwrap();
            assert!((pu - u).abs() < 1e-9 && (pv - v).abs() < 1e-9);
        }
        assert!(cam.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
        // Half resolution: the image's corners stay the image's corners.
        let half = cam.scaled(0.5);
        assert_eq!(half.image_size_px, [512, 384]);
        let far = Point3::from(cam.pixel_ray(-0.5, -0.5) * 3.0);
        let [u, v] = half.project(&far).unwrap();
        assert!((u + 0.5).abs() < 1e-9 && (v + 0.5).abs() < 1e-9, "{u} {v}");
        // f b / Z: 838 px · 0.12043 m / 2 m.
        assert!((cam.disparity_px(2.0) - 838.0 * 0.12043 / 2.0).abs() < 1e-12);
        // The right camera is the baseline to the left camera's right.
        let offset = cam.body_from_camera().inverse() * cam.body_from_right_camera();
        assert!((offset.translation.vector - Vector3::new(0.12043, 0.0, 0.0)).norm() < 1e-12);
        assert!(offset.rotation.angle() < 1e-12);
        // About 0.92 m above flat ground, the body origin riding 0.25 m up.
        assert!((cam.position_m[2] + 0.25 - 0.918).abs() < 1e-9);
    }

    #[test]
    fn bad_settings_name_their_field() {
        let mut cam = CameraParams::exoter_bumblebee2();
        cam.principal_point_px = Some([1024.0, 10.0]);
        let err = cam.validate("camera").unwrap_err();
        assert_eq!(err.field, "camera.principal_point_px");
        let mut cam = CameraParams {
            baseline_m: 0.0,
            ..CameraParams::default()
        };
        assert_eq!(
            cam.validate("vo.camera").unwrap_err().field,
            "vo.camera.baseline_m"
        );
        cam.baseline_m = 0.12;
        cam.image_size_px = [4, 480];
        assert_eq!(cam.validate("c").unwrap_err().field, "c.image_size_px");
        // The tracker's default is a consistent pinhole: its fields of view
        // are what its size and focal length give, to 1 %.
        let cam = CameraParams::default();
        let hfov = 2.0 * (0.5 * f64::from(cam.image_size_px[0]) / cam.focal_px).atan();
        let vfov = 2.0 * (0.5 * f64::from(cam.image_size_px[1]) / cam.focal_px).atan();
        assert!((hfov / cam.hfov_rad - 1.0).abs() < 0.01, "{hfov}");
        assert!((vfov / cam.vfov_rad - 1.0).abs() < 0.01, "{vfov}");
    }
}
