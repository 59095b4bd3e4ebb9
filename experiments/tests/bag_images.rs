//! A recording's camera: gpodo's own rendered MCAP reads back as the very
//! pairs its PNG folders hold, `bag info` lists the image and camera-info
//! topics, the stereo VO tracks on the recorded frames (against the bag's
//! ground truth), a bag written independently by Python's
//! `mcap-ros2-support` (colour and PNG-compressed images) decodes, and a
//! truncated image is an error naming its topic and time.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::sync::Arc;

use gpodo_datasets::bags::OnDamage;
use gpodo_datasets::bags::frames::{BagFrames, camera_from_info};
use gpodo_datasets::bags::images::{CameraTopics, read_stereo};
use gpodo_datasets::bags::messages::RosMessage;
use gpodo_datasets::bags::topic::read_topic;
use gpodo_experiments::commands::simulate::{
    CameraOutput, SimulateFormat, SimulateOptions, Written, simulate_to,
};
use gpodo_frontends::vo::stereo::{StereoFrames, StereoVo, StereoVoParams};
use gpodo_frontends::vo::{FrameRef, TrackOutcome, TrackPurpose, TrackRequest, VisualOdometry};
use gpodo_testbed::sim::preset::Preset;
use gpodo_traits::CameraParams;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// One 8-s training run and 8 s of the test traverse of seed 3, with the
/// camera at half the Bumblebee2's resolution at 2.5 fps.
fn options(format: SimulateFormat) -> SimulateOptions {
    SimulateOptions {
        preset: Preset::ExoterPrl,
        seed: 3,
        training_runs: Some(1),
        training_run_secs: Some(8.0),
        test_max_secs: Some(8.0),
        format,
        units: Default::default(),
        imu: true,
        camera: Some(CameraOutput {
            scale: 0.5,
            fps: 2.5,
            vo_ground_truth: false,
        }),
    }
}

fn topics() -> CameraTopics {
    CameraTopics {
        left: "/camera/left/image_raw".into(),
        right: "/camera/right/image_raw".into(),
        left_info: Some("/camera/left/camera_info".into()),
        right_info: Some("/camera/right/camera_info".into()),
    }
}

#[test]
fn gpodos_rendered_bag_reads_back_as_its_pngs_and_the_stereo_vo_tracks_on_it() {
    let tmp = tempfile::tempdir().unwrap();
    let written = simulate_to(&options(SimulateFormat::Mcap), &tmp.path().join("mcap")).unwrap();
    let png = simulate_to(&options(SimulateFormat::Png), &tmp.path().join("png")).unwrap();
    let bag: PathBuf = written
        .iter()
        .filter_map(|w| match w {
            Written::Bag { path, .. } => Some(path.clone()),
            _ => None,
        })
        .next_back()
        .unwrap();
    let frames_dir: PathBuf = png
        .iter()
        .filter_map(|w| match w {
            Written::Frames { dir, .. } => Some(dir.clone()),
            _ => None,
        })
        .next_back()
        .unwrap();

    // `bag info` names the encoding and size of each image topic.
    let info = gpodo_datasets::bags::BagInfo::read(&bag).unwrap();
    let left_info = info
        .topics
        .iter()
        .find(|t| t.topic == "/camera/left/image_raw")
        .unwrap();
    assert!(
        left_info.names.iter().any(|n| n.contains("mono8 512×384")),
        "{:?}",
        left_info.names
    );
    assert!((left_info.typical_rate_hz().unwrap() - 2.5).abs() < 1e-6);

    let recording = read_stereo(&bag, &topics(), OnDamage::Stop).unwrap();
    assert_eq!((recording.pairs.len(), recording.unpaired), (20, 0));
    let [Some(left), Some(right)] = recording.info.clone() else {
        panic!("no camera info");
    };
    let rendered = CameraParams::exoter_bumblebee2().scaled(0.5);
    let camera = camera_from_info(&left, &right, &rendered).unwrap();
    assert!((camera.focal_px - rendered.focal_px).abs() < 1e-9);
    assert!((camera.baseline_m - rendered.baseline_m).abs() < 1e-9);
    assert_eq!(camera.principal_point(), rendered.principal_point());

    // Frames on the bag's clock, 0 s at the first pair.
    let base = recording.pairs[0].0;
    let source = BagFrames::new(recording, base, 0.05);
    let times = source.times_secs();
    for k in [0usize, 7, 19] {
        let frame = FrameRef {
            index: k,
            time_secs: times[k],
        };
        let (l, r) = gpodo_traits::StereoFrameSource::pair(&source, frame).unwrap();
        let png_l =
            gpodo_vision::png_io::read_png_gray(&frames_dir.join(format!("left/{k:06}.png")))
                .unwrap();
        let png_r =
            gpodo_vision::png_io::read_png_gray(&frames_dir.join(format!("right/{k:06}.png")))
                .unwrap();
        assert_eq!(l.pixels(), png_l.pixels(), "left {k}");
        assert_eq!(r.pixels(), png_r.pixels(), "right {k}");
    }
    let late = FrameRef {
        index: 20,
        time_secs: times[19] + 1.0,
    };
    let missing = gpodo_traits::StereoFrameSource::pair(&source, late).unwrap_err();
    assert!(missing.contains("no stereo pair"), "{missing}");

    // The stereo VO on the recorded frames, against the bag's ground truth.
    let truth: Vec<(i64, Isometry3<f64>)> = read_topic(
        &bag,
        "/ground_truth/pose",
        "truth",
        &["geometry_msgs/PoseStamped"],
    )
    .unwrap()
    .into_iter()
    .filter_map(|m| match m.message {
        RosMessage::PoseStamped(h, p) => {
            let [x, y, z, w] = p.orientation;
            Some((
                h.stamp_ns,
                Isometry3::from_parts(
                    Translation3::from(p.position),
                    UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
                ),
            ))
        }
        _ => None,
    })
    .collect();
    let pose_at = |t: f64| {
        let stamp = base + (t * 1e9).round() as i64;
        truth
            .iter()
            .min_by_key(|(s, _)| (s - stamp).abs())
            .map(|(s, p)| {
                assert!((s - stamp).abs() < 1_000_000, "no truth at {t} s");
                *p
            })
            .unwrap()
    };
    let mut vo = StereoVo::new(
        StereoVoParams::default(),
        Arc::new(StereoFrames::new(camera, Arc::new(source))),
    )
    .unwrap();
    let mut tracked = 0;
    for k in 0..times.len() - 1 {
        let relative = pose_at(times[k]).inverse() * pose_at(times[k + 1]);
        let frame = |i: usize| FrameRef {
            index: i,
            time_secs: times[i],
        };
        let TrackOutcome::Tracked(m) = vo.track(&TrackRequest {
            reference: frame(k),
            current: frame(k + 1),
            prior: Some(relative),
            purpose: TrackPurpose::Tracking,
        }) else {
            continue;
        };
        tracked += 1;
        let error = (m.relative.translation.vector - relative.translation.vector).norm();
        let moved = relative.translation.vector.norm();
        assert!(
            error <= (0.005f64).max(0.1 * moved),
            "frames {k}–{}: {error} m off of {moved} m",
            k + 1
        );
    }
    assert!(tracked >= 17, "{tracked} of 19 tracked");
}

#[test]
fn a_bag_written_by_python_decodes_its_colour_and_compressed_images() {
    let Some(python) = gpodo_testkit::python_with(
        &["mcap_ros2.writer", "cv2", "numpy"],
        "mcap-ros2-support, opencv-python-headless and numpy",
    ) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("python.mcap");
    // Three pairs of 5 × 4 pixels: the left rgb8 with pixel (x, y) of
    // frame k = (10k + x, 20 + y, 3x + y), the right a PNG of grey
    // 7x + 11y + k; a fourth pair whose left image lost its last row.
    let script = r#"
import sys
import cv2, numpy as np
from mcap_ros2.writer import Writer
SEP = "=" * 80 + "\n"
HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" + SEP + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
IMAGE = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n" + SEP + HEADER
COMPRESSED = "std_msgs/Header header\nstring format\nuint8[] data\n" + SEP + HEADER
with open(sys.argv[1], "wb") as f:
    w = Writer(f)
    image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE)
    compressed = w.register_msgdef("sensor_msgs/msg/CompressedImage", COMPRESSED)
    for k in range(4):
        stamp = {"sec": 100 + k, "nanosec": 500000000}
        ns = (100 + k) * 10**9 + 500000000
        y, x = np.mgrid[0:4, 0:5]
        rgb = np.stack([10 * k + x, 20 + y, 3 * x + y], axis=2).astype(np.uint8)
        data = rgb.tobytes() if k < 3 else rgb[:3].tobytes()
        w.write_message("/stereo/left/image_rect", image, {"header": {"stamp": stamp, "frame_id": "left"}, "height": 4, "width": 5, "encoding": "rgb8", "is_bigendian": 0, "step": 15, "data": data}, log_time=ns, publish_time=ns)
        grey = (7 * x + 11 * y + k).astype(np.uint8)
        ok, png = cv2.imencode(".png", grey)
        w.write_message("/stereo/right/image_rect/compressed", compressed, {"header": {"stamp": stamp, "frame_id": "right"}, "format": "mono8; png compressed", "data": png.tobytes()}, log_time=ns, publish_time=ns)
    w.finish()
print("ok")
"#;
    let text = gpodo_testkit::run_python(&python, script, &[bag.as_os_str()]);
    assert_eq!(text.trim(), "ok");
    let topics = CameraTopics {
        left: "/stereo/left/image_rect".into(),
        right: "/stereo/right/image_rect/compressed".into(),
        left_info: None,
        right_info: None,
    };
    let recording = read_stereo(&bag, &topics, OnDamage::Stop).unwrap();
    assert_eq!(recording.pairs.len(), 4);
    let luma = |r: u32, g: u32, b: u32| ((299 * r + 587 * g + 114 * b + 500) / 1000) as u8;
    for k in 0..3i64 {
        let stamp = (100 + k) * 1_000_000_000 + 500_000_000;
        let (l, r) = recording.gray_pair_near(stamp, 0).unwrap();
        for y in 0..4u32 {
            for x in 0..5u32 {
                let i = (y * 5 + x) as usize;
                assert_eq!(
                    l.pixels()[i],
                    luma(10 * k as u32 + x, 20 + y, 3 * x + y),
                    "left {k} ({x}, {y})"
                );
                assert_eq!(
                    r.pixels()[i],
                    (7 * x + 11 * y + k as u32) as u8,
                    "right {k}"
                );
            }
        }
    }
    let e = recording.gray_pair_near(103_500_000_000, 0).unwrap_err();
    assert!(
        e.contains("/stereo/left/image_rect")
            && e.contains("103.500000")
            && e.contains("truncated"),
        "{e}"
    );
}

#[test]
fn a_topic_map_with_both_a_recorded_vo_and_a_camera_is_refused() {
    let log = gpodo_datasets::log::RoverLog {
        name: "empty".into(),
        wheel_names: Vec::new(),
        steer_names: Vec::new(),
        bogie_names: Vec::new(),
        samples: Vec::new(),
        ground_truth: Vec::new(),
        camera_times_secs: Vec::new(),
    };
    let mut map = gpodo_datasets::bags::write::written_topic_map(&log, 10.0);
    map.camera = Some(topics());
    map.vo = Some("/orb_slam/pose".into());
    let err =
        gpodo_datasets::bags::import::import_bag(std::path::Path::new("none.mcap"), "none", &map)
            .unwrap_err();
    assert!(err.to_string().contains("not both"), "{err}");
}
