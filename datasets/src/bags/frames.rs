//! A recording's stereo camera as the stereo VO's frame source: each
//! camera frame is the recorded pair stamped nearest its time (on the
//! recording's clock), decoded to grey levels when the VO first asks for
//! it; and the rectified camera its `CameraInfo` messages describe.

use gpodo_traits::{CameraParams, FrameRef, StereoFrameSource};
use gpodo_vision::GrayImage;

use super::images::{CameraInfo, StereoRecording};

/// A recorded stereo camera's frames (see the module).
pub struct BagFrames {
    recording: StereoRecording,
    /// The recording's stamp (ns) of a frame at time 0 s.
    base_ns: i64,
    /// How far a pair's stamp may be from the frame's time (ns).
    tolerance_ns: i64,
}

impl BagFrames {
    /// The frames of `recording`, a frame at `t` s being the pair stamped
    /// nearest `base_ns + t`, at most `tolerance_secs` away.
    pub fn new(recording: StereoRecording, base_ns: i64, tolerance_secs: f64) -> Self {
        Self {
            recording,
            base_ns,
            tolerance_ns: (tolerance_secs * 1e9).round() as i64,
        }
    }

    /// The camera the stereo VO should see these frames through:
    /// `mounting` with the intrinsics and baseline of the recorded camera
    /// infos ([`camera_from_info`]) when the topic map names both, else
    /// `mounting` as configured.
    ///
    /// # Errors
    /// As [`camera_from_info`].
    pub fn camera(&self, mounting: &CameraParams) -> Result<CameraParams, String> {
        match &self.recording.info {
            [Some(left), Some(right)] => camera_from_info(left, right, mounting),
            _ => Ok(*mounting),
        }
    }

    /// The pairs' times on the frames' clock (s from `base_ns`).
    pub fn times_secs(&self) -> Vec<f64> {
        self.recording
            .pairs
            .iter()
            .map(|(t, _, _)| (t - self.base_ns) as f64 * 1e-9)
            .collect()
    }
}

impl StereoFrameSource for BagFrames {
    fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String> {
        let stamp = self.base_ns + (frame.time_secs * 1e9).round() as i64;
        self.recording
            .gray_pair_near(stamp, self.tolerance_ns)
            .map_err(|e| format!("frame {} at {:.3} s: {e}", frame.index, frame.time_secs))
    }
}

/// `mounting` (where the camera sits on the body) with the rectified
/// intrinsics of a recorded pair: focal length and principal point from
/// the left projection `P`, the baseline from the right one's
/// `P[3] = −f · b`, the size from the messages.
///
/// # Errors
/// A message naming the field that is missing or out of range.
pub fn camera_from_info(
    left: &CameraInfo,
    right: &CameraInfo,
    mounting: &CameraParams,
) -> Result<CameraParams, String> {
    let f = left.p[0];
    if !(f.is_finite() && f > 0.0) {
        return Err(format!(
            "the left camera info's P[0] is {f}, expected a positive focal length (is the camera rectified?)"
        ));
    }
    if (left.width, left.height) != (right.width, right.height) || left.width == 0 {
        return Err(format!(
            "the camera infos are {}×{} and {}×{}, expected one non-empty size",
            left.width, left.height, right.width, right.height
        ));
    }
    let baseline = -right.p[3] / right.p[0];
    if !(baseline.is_finite() && baseline > 0.0) {
        return Err(format!(
            "the right camera info's P[3] / P[0] is {}, expected −baseline < 0",
            right.p[3] / right.p[0]
        ));
    }
    let (w, h) = (f64::from(left.width), f64::from(left.height));
    Ok(CameraParams {
        focal_px: f,
        principal_point_px: Some([left.p[2], left.p[6]]),
        baseline_m: baseline,
        image_size_px: [left.width, left.height],
        hfov_rad: 2.0 * (0.5 * w / f).atan(),
        vfov_rad: 2.0 * (0.5 * h / f).atan(),
        ..*mounting
    })
}
