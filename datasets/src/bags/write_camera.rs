//! A stereo camera recorded into a ROS 2 MCAP bag: each frame as two
//! `sensor_msgs/msg/Image` (mono8) and two `sensor_msgs/msg/CameraInfo`,
//! as ROS stereo drivers publish them. Both cameras share the rectified
//! `K`; the right camera's projection carries `P[3] = −f_x b`, so ROS
//! stereo nodes (and ORB-SLAM3 or rtabmap through them) read the baseline.

use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;

use super::cdr_write::{Cdr, HEADER, TIME, schema, stamp_ns};
use crate::DatasetError;

/// One rendered (or recorded) stereo pair: left, then right.
pub type StereoImages = (GrayImage, GrayImage);

/// A camera to record: its calibration, its frame times (on the log's
/// clock, increasing) and what produces the pair of frame `k` at time `t`.
pub struct CameraStream<'a> {
    /// The camera (image size, `K`, baseline).
    pub camera: CameraParams,
    /// Frame times (s on the log's clock), increasing.
    pub times_secs: Vec<f64>,
    /// The pair of frame `k` at time `t`.
    pub frames: Box<dyn FnMut(usize, f64) -> Result<StereoImages, DatasetError> + 'a>,
}

fn image_schema() -> String {
    schema(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
        ],
    )
}

fn camera_info_schema() -> String {
    schema(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n\
         float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n\
         sensor_msgs/RegionOfInterest roi\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            (
                "sensor_msgs/RegionOfInterest",
                "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
            ),
        ],
    )
}

/// The camera's optical frames: `camera_left`, `camera_right`.
const FRAMES: [&str; 2] = ["camera_left", "camera_right"];

/// `sensor_msgs/msg/Image` of `image` (mono8).
fn image_message(stamp_ns: u64, frame: &str, image: &GrayImage) -> Vec<u8> {
    let mut m = Cdr::new();
    m.header(stamp_ns, frame);
    m.u32(image.height() as u32);
    m.u32(image.width() as u32);
    m.string("mono8");
    m.0.push(0);
    m.u32(image.width() as u32);
    m.u32(image.pixels().len() as u32);
    m.0.extend_from_slice(image.pixels());
    m.0
}

/// The rectified intrinsic matrix `K` both cameras share, row-major.
pub fn intrinsics(camera: &CameraParams) -> [f64; 9] {
    let f = camera.focal_px;
    let [cx, cy] = camera.principal_point();
    [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0]
}

/// The rectified projection `P` of camera `index` (0 left, 1 right):
/// `[f 0 c_x T_x; 0 f c_y 0; 0 0 1 0]`, `T_x = −f b` for the right.
pub fn projection(camera: &CameraParams, index: usize) -> [f64; 12] {
    let f = camera.focal_px;
    let [cx, cy] = camera.principal_point();
    let tx = if index == 1 {
        -f * camera.baseline_m
    } else {
        0.0
    };
    [f, 0.0, cx, tx, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
}

/// `sensor_msgs/msg/CameraInfo` of camera `index` of `camera`: rectified,
/// no distortion (`plumb_bob`, zeros), identity `R`.
fn camera_info_message(stamp_ns: u64, camera: &CameraParams, index: usize) -> Vec<u8> {
    let [width, height] = camera.image_size_px;
    let mut m = Cdr::new();
    m.header(stamp_ns, FRAMES[index]);
    m.u32(height);
    m.u32(width);
    m.string("plumb_bob");
    m.sequence(&[0.0; 5]);
    m.f64s(&intrinsics(camera));
    m.f64s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    m.f64s(&projection(camera, index));
    m.u32(0);
    m.u32(0);
    for v in [0, 0, 0, 0] {
        m.u32(v);
    }
    m.0.push(0);
    m.0
}

/// The camera topics a bag written with a camera has, for its topic map.
pub fn written_camera_topics() -> super::images::CameraTopics {
    let topic = |side: &str, what: &str| format!("/camera/{side}/{what}");
    super::images::CameraTopics {
        left: topic("left", "image_raw"),
        right: topic("right", "image_raw"),
        left_info: Some(topic("left", "camera_info")),
        right_info: Some(topic("right", "camera_info")),
    }
}

/// The four channels of a stereo camera in a bag.
#[derive(Debug, Clone, Copy)]
pub(super) struct CameraChannels {
    images: [u16; 2],
    infos: [u16; 2],
}

impl CameraChannels {
    /// Adds the channels through `channel(type, schema, topic)`.
    pub(super) fn add(
        channel: &mut impl FnMut(&str, String, &str) -> Result<u16, DatasetError>,
    ) -> Result<Self, DatasetError> {
        let mut images = [0; 2];
        let mut infos = [0; 2];
        for (k, side) in ["left", "right"].iter().enumerate() {
            images[k] = channel(
                "sensor_msgs/msg/Image",
                image_schema(),
                &format!("/camera/{side}/image_raw"),
            )?;
            infos[k] = channel(
                "sensor_msgs/msg/CameraInfo",
                camera_info_schema(),
                &format!("/camera/{side}/camera_info"),
            )?;
        }
        Ok(Self { images, infos })
    }

    /// The messages of frame `k` at `time_secs`: `(channel, data, stamp)`.
    pub(super) fn frame(
        &self,
        stream: &mut CameraStream<'_>,
        k: usize,
        time_secs: f64,
    ) -> Result<Vec<(u16, Vec<u8>, u64)>, DatasetError> {
        let (left, right) = (stream.frames)(k, time_secs)?;
        let [width, height] = stream.camera.image_size_px.map(|n| n as usize);
        for image in [&left, &right] {
            if image.width() != width || image.height() != height {
                return Err(DatasetError::InvalidConfig {
                    field: "camera.image_size_px".into(),
                    expected: format!(
                        "frames of {width} × {height} pixels; frame {k} is {} × {}",
                        image.width(),
                        image.height()
                    ),
                });
            }
        }
        let t = stamp_ns(time_secs);
        let mut out = Vec::with_capacity(4);
        for (index, image) in [left, right].iter().enumerate() {
            out.push((
                self.infos[index],
                camera_info_message(t, &stream.camera, index),
                t,
            ));
            out.push((
                self.images[index],
                image_message(t, FRAMES[index], image),
                t,
            ));
        }
        Ok(out)
    }
}
