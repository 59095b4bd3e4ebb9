//! The Husky recording in `../shared/data/ros/` (issue 17 allows tests to
//! read it), as a ROS 1 bag and as a zstd-chunked ROS 2 MCAP with the same
//! 16806 messages: both are recognised by their magic bytes and give the
//! same topics, counts and span (shared/data/README.md lists them).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_datasets::bags::{BagFormat, BagInfo, ros1_type_name, visit_messages};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/ros")
        .join(name)
}

#[test]
fn both_recordings_hold_the_documented_topics() {
    let expected = [
        ("/fix", "sensor_msgs/NavSatFix", 989),
        ("/husky_velocity_controller/odom", "nav_msgs/Odometry", 3952),
        ("/imu/data", "sensor_msgs/Imu", 11865),
    ];
    let mut spans = Vec::new();
    for (file, format) in [
        ("husky_test1.bag", BagFormat::Ros1),
        ("husky_test1.mcap", BagFormat::Mcap),
    ] {
        let info = BagInfo::read(&data(file)).unwrap();
        assert_eq!(info.format, format, "{file}");
        assert_eq!(info.messages, 16806, "{file}");
        assert_eq!(info.topics.len(), 3, "{file}");
        for ((topic, ty, count), t) in expected.iter().zip(&info.topics) {
            assert_eq!(t.topic, *topic, "{file}");
            assert_eq!(ros1_type_name(&t.message_type), *ty, "{file}");
            assert_eq!(t.count, *count, "{file} {topic}");
        }
        let imu = &info.topics[2];
        assert!(
            (imu.rate_hz() - 30.0).abs() < 1.5,
            "{file}: IMU at {} Hz",
            imu.rate_hz()
        );
        assert!(
            (info.duration_secs() - 395.0).abs() < 2.0,
            "{file}: {} s",
            info.duration_secs()
        );
        assert!(info.to_text().contains("/imu/data"));
        spans.push((info.start_ns, info.end_ns));
    }
    assert_eq!(
        spans[0], spans[1],
        "the two formats carry the same receive times"
    );
}

#[test]
fn the_same_message_bytes_in_both_formats_differ_only_by_serialisation() {
    // ROS 1 and CDR serialise a NavSatFix differently, but both carry the
    // first fix's latitude (42.375812° N) as a little-endian f64.
    for file in ["husky_test1.bag", "husky_test1.mcap"] {
        let mut first_fix = None;
        visit_messages(&data(file), |m| {
            if m.topic == "/fix" && first_fix.is_none() {
                first_fix = Some(m.data.to_vec());
            }
        })
        .unwrap();
        let bytes = first_fix.unwrap();
        let found = bytes.windows(8).any(|w| {
            let v = f64::from_le_bytes(w.try_into().unwrap());
            (v - 42.375812).abs() < 1e-5
        });
        assert!(found, "{file}: no latitude 42.3758 in the first /fix");
    }
}
