//! The Husky recording in `../shared/data/ros/` (one of the real
//! recordings of `../shared/` that tests may read), as a ROS 1 bag and as
//! a zstd-chunked ROS 2 MCAP with the same 16806 messages: both are
//! recognised by their magic bytes and give the same topics, counts and
//! span (shared/data/README.md lists them).

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

use gpodo_datasets::bags::messages::{RosMessage, decode};

/// Every message of the topic in the file, decoded.
fn decoded(file: &str, topic: &str) -> Vec<RosMessage> {
    let mut out = Vec::new();
    visit_messages(&data(file), |m| {
        if m.topic == topic {
            let msg = decode(m.message_type, m.encoding, m.data)
                .unwrap_or_else(|e| panic!("{file} {topic} message {}: {}", m.index, e.0));
            out.push(msg);
        }
    })
    .unwrap();
    out
}

#[test]
fn every_message_decodes_to_the_same_values_from_ros1_and_cdr() {
    for (topic, count) in [
        ("/imu/data", 11865),
        ("/husky_velocity_controller/odom", 3952),
        ("/fix", 989),
    ] {
        let ros1 = decoded("husky_test1.bag", topic);
        let ros2 = decoded("husky_test1.mcap", topic);
        assert_eq!(ros1.len(), count);
        // Two serialisations, two decoding paths (packed vs aligned after
        // the CDR header): the same numbers, message by message.
        assert!(ros1 == ros2, "{topic}: the formats disagree");
    }
    let fixes = decoded("husky_test1.mcap", "/fix");
    let RosMessage::NavSatFix(first) = &fixes[0] else {
        panic!("not a NavSatFix")
    };
    assert!(
        (first.latitude - 42.375812).abs() < 1e-5 && (first.longitude + 71.147395).abs() < 1e-5
    );
    let RosMessage::Odometry(odom) =
        &decoded("husky_test1.bag", "/husky_velocity_controller/odom")[0]
    else {
        panic!("not an Odometry")
    };
    assert_eq!(
        (odom.header.frame_id.as_str(), odom.child_frame_id.as_str()),
        ("odom", "base_link")
    );
    let q = odom.pose.orientation;
    assert!(((q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt() - 1.0).abs() < 1e-6);
}

/// A `sensor_msgs/JointState` laid out by hand in both serialisations:
/// stamp 5 s 7 ns, frame `a`, one joint `j1` at position 1.5 and velocity
/// 2.5, no effort. In CDR the first `f64` sits at offset 32 after the
/// 4-byte header (aligned counting from after it; counting from the
/// buffer's start would insert 4 bytes of padding there), the second after
/// 4 bytes of padding.
#[test]
fn cdr_alignment_counts_from_after_the_encapsulation_header() {
    let mut cdr: Vec<u8> = vec![0, 1, 0, 0];
    cdr.extend(5i32.to_le_bytes()); // rel 0: sec
    cdr.extend(7u32.to_le_bytes()); // rel 4: nanosec
    cdr.extend(2u32.to_le_bytes()); // rel 8: frame_id length with NUL
    cdr.extend(b"a\0"); // rel 12
    cdr.extend([0, 0]); // rel 14: pad to 4
    cdr.extend(1u32.to_le_bytes()); // rel 16: one name
    cdr.extend(3u32.to_le_bytes()); // rel 20
    cdr.extend(b"j1\0"); // rel 24
    cdr.push(0); // rel 27: pad to 4
    cdr.extend(1u32.to_le_bytes()); // rel 28: one position
    cdr.extend(1.5f64.to_le_bytes()); // rel 32: already 8-aligned
    cdr.extend(1u32.to_le_bytes()); // rel 40: one velocity
    cdr.extend([0, 0, 0, 0]); // rel 44: pad to 8
    cdr.extend(2.5f64.to_le_bytes()); // rel 48
    cdr.extend(0u32.to_le_bytes()); // rel 56: no effort
    let mut ros1: Vec<u8> = Vec::new();
    ros1.extend(42u32.to_le_bytes()); // seq
    ros1.extend(5u32.to_le_bytes());
    ros1.extend(7u32.to_le_bytes());
    ros1.extend(1u32.to_le_bytes());
    ros1.extend(b"a");
    ros1.extend(1u32.to_le_bytes());
    ros1.extend(2u32.to_le_bytes());
    ros1.extend(b"j1");
    ros1.extend(1u32.to_le_bytes());
    ros1.extend(1.5f64.to_le_bytes());
    ros1.extend(1u32.to_le_bytes());
    ros1.extend(2.5f64.to_le_bytes());
    ros1.extend(0u32.to_le_bytes());
    let a = decode("sensor_msgs/msg/JointState", "cdr", &cdr).unwrap();
    let b = decode("sensor_msgs/JointState", "ros1", &ros1).unwrap();
    assert_eq!(a, b);
    let RosMessage::JointState(j) = a else {
        panic!()
    };
    assert_eq!(j.header.stamp_ns, 5_000_000_007);
    assert_eq!(
        (j.name, j.position, j.velocity),
        (vec!["j1".to_string()], vec![1.5], vec![2.5])
    );
    // The wrong type, or a truncated message, is an error, not a guess.
    let e = decode("sensor_msgs/JointState", "ros1", &ros1[..ros1.len() - 3]).unwrap_err();
    assert!(e.0.contains("more were needed"), "{}", e.0);
    let e = decode("geometry_msgs/TwistStamped", "ros1", &ros1).unwrap_err();
    assert!(
        e.0.contains("left over") || e.0.contains("needed"),
        "{}",
        e.0
    );
    let e = decode("std_msgs/String", "ros1", &ros1).unwrap_err();
    assert!(e.0.contains("not one gpodo reads"), "{}", e.0);
}

#[test]
fn gps_fixes_in_local_enu_span_the_drive_the_wheel_odometry_measured() {
    use gpodo_datasets::bags::enu::LocalEnu;
    let mut enu: Option<LocalEnu> = None;
    let mut gps = Vec::new();
    for m in decoded("husky_test1.bag", "/fix") {
        let RosMessage::NavSatFix(f) = m else {
            panic!()
        };
        if f.status < 0 {
            continue;
        }
        let frame = *enu.get_or_insert_with(|| LocalEnu::new(f.latitude, f.longitude, f.altitude));
        gps.push(frame.to_enu(f.latitude, f.longitude, f.altitude));
    }
    let mut odom = Vec::new();
    for m in decoded("husky_test1.bag", "/husky_velocity_controller/odom") {
        let RosMessage::Odometry(o) = m else { panic!() };
        odom.push(o.pose.position);
    }
    let length = |p: &[[f64; 3]]| -> f64 {
        p.windows(2)
            .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
            .sum()
    };
    let extent = |p: &[[f64; 3]]| -> f64 {
        let (xs, ys): (Vec<f64>, Vec<f64>) = p.iter().map(|q| (q[0], q[1])).unzip();
        let span = |v: &[f64]| {
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
        };
        span(&xs).hypot(span(&ys))
    };
    assert!(
        gps[0].iter().all(|v| v.abs() < 1e-9),
        "the first fix is the origin"
    );
    eprintln!(
        "GPS: {} fixes, path {:.1} m, extent {:.1} m; odometry: path {:.1} m, extent {:.1} m",
        gps.len(),
        length(&gps),
        extent(&gps),
        length(&odom),
        extent(&odom)
    );
    // Two independent sensors of the same drive: the GPS track in metres
    // (noisier, so a little longer) and the wheel odometry. Measured:
    // 395.2 m against 358.8 m of path, 156.9 m against 181.7 m of extent.
    for (what, g, o) in [
        ("path", length(&gps), length(&odom)),
        ("extent", extent(&gps), extent(&odom)),
    ] {
        let ratio = g / o;
        assert!(
            (0.8..1.25).contains(&ratio),
            "{what}: GPS {g:.1} m, odometry {o:.1} m"
        );
    }
}

#[test]
fn a_topic_is_read_for_a_role_that_names_what_it_needs() {
    use gpodo_datasets::bags::topic::read_topic;
    let bag = data("husky_test1.mcap");
    let imu = read_topic(&bag, "/imu/data", "imu", &["sensor_msgs/Imu"]).unwrap();
    assert_eq!(imu.len(), 11865);
    assert!(imu.windows(2).all(|w| w[0].log_time_ns <= w[1].log_time_ns));
    let e = read_topic(
        &bag,
        "/imu/data",
        "ground truth",
        &["nav_msgs/Odometry", "geometry_msgs/PoseStamped"],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("husky_test1.mcap")
            && e.contains("`/imu/data` is `sensor_msgs/msg/Imu`")
            && e.contains("ground truth role needs one of nav_msgs/Odometry"),
        "{e}"
    );
    let e = read_topic(&bag, "/joint_states", "joints", &["sensor_msgs/JointState"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no topic `/joint_states`")
            && e.contains("/fix, /husky_velocity_controller/odom, /imu/data"),
        "{e}"
    );
}

mod import {
    use super::data;
    use gpodo_datasets::bags::import::{TopicMap, import_bag};
    use gpodo_datasets::log::{read_log_csv, write_log_csv};

    fn map(yaml: &str) -> TopicMap {
        serde_saphyr::from_str(yaml).unwrap()
    }

    fn path_length(log: &gpodo_datasets::log::RoverLog) -> f64 {
        log.ground_truth
            .windows(2)
            .map(|w| {
                (w[1].translation.vector - w[0].translation.vector)
                    .xy()
                    .norm()
            })
            .sum()
    }

    #[test]
    fn the_husky_recording_becomes_a_rover_log_the_logs_dataset_reads() {
        // The recording's IMU has its y axis up (gravity reads +10 m/s² on
        // y at rest): rotate it by +90° about x into the body frame.
        let m = map(
            "imu: /imu/data\nimu_rotation_rpy_rad: [1.5707963267948966, 0, 0]\nground_truth: /husky_velocity_controller/odom\nrate_hz: 10\n",
        );
        for file in ["husky_test1.bag", "husky_test1.mcap"] {
            let (log, report) = import_bag(&data(file), "husky", &m).unwrap();
            // 10 Hz over the ~395 s every stream covers.
            assert!((3900..=3960).contains(&report.rows), "{file}: {report:?}");
            assert_eq!(report.streams[0].messages, 11865);
            // Odometry at 10 Hz, with intervals up to 0.21 s.
            assert!(report.streams[1].max_gap_bridged_secs < 0.25, "{report:?}");
            let tmp = tempfile::tempdir().unwrap();
            let (csv, _) = write_log_csv(&log, tmp.path()).unwrap();
            let back = read_log_csv(&csv).unwrap();
            assert_eq!(back.samples.len(), report.rows);
            // The resampled odometry keeps the distance driven (358.8 m at
            // its own 10 Hz).
            let length = path_length(&back);
            assert!((length - 358.8).abs() < 0.02 * 358.8, "{file}: {length} m");
            // Mean specific force ≈ gravity on +z, small mean roll and pitch.
            let n = back.samples.len() as f64;
            let mean = |f: &dyn Fn(&gpodo_traits::ProprioceptiveSample) -> f64| {
                back.samples.iter().map(f).sum::<f64>() / n
            };
            assert!(
                (mean(&|s| s.imu.unwrap().accel_mps2.z) - 9.8).abs() < 0.5,
                "{file}"
            );
            assert!(
                mean(&|s| s.imu.unwrap().roll_rad).abs() < 0.1
                    && mean(&|s| s.imu.unwrap().pitch_rad).abs() < 0.1,
                "{file}"
            );
        }
    }

    #[test]
    fn gnss_ground_truth_is_local_enu_and_gaps_are_not_bridged() {
        let (log, report) = import_bag(
            &data("husky_test1.mcap"),
            "husky_gps",
            &map("imu: /imu/data\nground_truth: /fix\n"),
        )
        .unwrap();
        assert!(report.rows > 3800, "{report:?}");
        let gt = &report.streams[1];
        assert!((0.35..=0.5).contains(&gt.max_gap_bridged_secs), "{gt:?}");
        assert!(log.ground_truth[0].translation.vector.norm() < 5.0);
        // GPS comes at 2.5 Hz: with at most 0.2 s bridged, only a row that
        // falls on a fix survives; the others are counted, not invented.
        let (_, tight) = import_bag(
            &data("husky_test1.mcap"),
            "x",
            &map("imu: /imu/data\nground_truth: /fix\nmax_gap_secs: 0.2\n"),
        )
        .unwrap();
        assert!(tight.rows <= 1, "{tight:?}");
        assert_eq!(tight.streams[1].rows_in_gaps, tight.rows_dropped);
        assert!(tight.rows_dropped > 3900);
        // A role fed the wrong type.
        let e = import_bag(
            &data("husky_test1.bag"),
            "x",
            &map("imu: /fix\nground_truth: /fix\n"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("the imu role needs one of sensor_msgs/Imu"),
            "{e}"
        );
    }

    /// The topic map of `experiments/husky-bags.yaml`.
    const HUSKY: &str = "imu: /imu/data
imu_rotation_rpy_rad: [1.5707963267948966, 0, 0]
ground_truth: /fix
gnss_heading: course
odometry: /husky_velocity_controller/odom
rate_hz: 10
max_gap_secs: 0.5
";

    #[test]
    fn the_ros1_and_mcap_copies_import_to_identical_rows() {
        let (a, ra) = import_bag(&data("husky_test1.bag"), "husky", &map(HUSKY)).unwrap();
        let (b, rb) = import_bag(&data("husky_test1.mcap"), "husky", &map(HUSKY)).unwrap();
        assert_eq!(a, b);
        assert_eq!(ra, rb);
        assert_eq!(ra.rows, 3952);
        let roles: Vec<&str> = ra.streams.iter().map(|s| s.role.as_str()).collect();
        assert_eq!(roles, ["imu", "ground_truth", "odometry"]);
        assert_eq!(ra.streams[2].messages, 3952);
        // Every stream spans the drive: none starts late or stops early.
        for s in &ra.streams {
            assert!(
                s.starts_late_secs < 1.0 && s.stops_early_secs < 1.0,
                "{s:?}"
            );
        }
        // The receiver's own σ (SBAS fixes): under 2 m horizontally.
        let [h, v] = ra.gnss_sigma_m.unwrap();
        assert!(h > 0.1 && h < 2.0 && v > h, "{h} {v}");
    }

    #[test]
    fn the_robot_odometry_and_the_gnss_course_describe_the_same_drive() {
        let (log, report) = import_bag(&data("husky_test1.mcap"), "husky", &map(HUSKY)).unwrap();
        let heading = report.gnss_heading.unwrap();
        // The robot drives mostly forwards, and the course is known on
        // most rows.
        assert!(heading.rows_from_course > 3000, "{heading:?}");
        assert!(
            heading.rows_reversed < heading.rows_from_course / 10,
            "{heading:?}"
        );
        // Over the drive, GPS distance ≈ odometry distance (the odometry's
        // scale is right: 358.1 m against 358.7 m): compare in 2-s strides.
        let (mut gps, mut odom) = (0.0, 0.0);
        for k in (0..log.samples.len() - 20).step_by(20) {
            let d = log.ground_truth[k + 20].translation.vector
                - log.ground_truth[k].translation.vector;
            gps += d.xy().norm();
            odom += log.samples[k..k + 20]
                .iter()
                .map(|s| 0.1 * s.odometry.unwrap().linear_mps.x.abs())
                .sum::<f64>();
        }
        assert!(
            (gps / odom - 1.0).abs() < 0.05,
            "GPS {gps} m, odometry {odom} m"
        );
        // In the course-aligned body frame the GPS velocity is forward: its
        // 2-s mean lateral part is small next to the forward part.
        let (mut forward, mut lateral) = (0.0, 0.0);
        for k in (0..log.samples.len() - 20).step_by(20) {
            let d = log.ground_truth[k + 20].translation.vector
                - log.ground_truth[k].translation.vector;
            let body = log.ground_truth[k + 10].rotation.inverse() * d;
            forward += body.x.abs();
            lateral += body.y.abs();
        }
        assert!(lateral < 0.25 * forward, "{lateral} vs {forward}");
    }
}

mod written {
    //! gpodo's own MCAP writer, read back: the TF ground truth equals the
    //! PoseStamped one, and the robot's odometry survives the trip.

    use gpodo_datasets::bags::import::{GroundTruthSource, import_bag};
    use gpodo_datasets::bags::tf::TfPair;
    use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
    use gpodo_datasets::log::RoverLog;
    use gpodo_traits::{BodyTwist, ProprioceptiveSample};
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    /// A robot driving a circle of radius 2 m at 0.5 m/s, 10 Hz, 30 s,
    /// reporting its own odometry.
    fn circle() -> RoverLog {
        let n = 300;
        let mut samples = Vec::new();
        let mut ground_truth = Vec::new();
        for k in 0..n {
            let t = k as f64 * 0.1;
            let yaw = 0.25 * t;
            let mut s = ProprioceptiveSample {
                time_secs: t,
                odometry: Some(BodyTwist {
                    linear_mps: Vector3::new(0.5, 0.0, 0.0),
                    angular_radps: Vector3::new(0.0, 0.0, 0.25),
                }),
                ..Default::default()
            };
            s.imu.get_or_insert_default().accel_mps2 = Vector3::new(0.0, 0.125, 9.81);
            s.imu.get_or_insert_default().gyro_radps = Vector3::new(0.0, 0.0, 0.25);
            samples.push(s);
            ground_truth.push(Isometry3::from_parts(
                Translation3::new(2.0 * yaw.sin(), 2.0 * (1.0 - yaw.cos()), 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            ));
        }
        RoverLog {
            name: "circle".into(),
            wheel_names: vec![],
            steer_names: vec![],
            bogie_names: vec![],
            samples,
            ground_truth,
            camera_times_secs: vec![],
        }
    }

    #[test]
    fn wheels_recorded_in_ticks_and_motor_rpm_come_back_in_rad_through_the_scales() {
        use gpodo_datasets::bags::write::{
            WheelRate, WheelUnits, write_mcap_with, written_topic_map_in,
        };
        use gpodo_traits::JointState;
        let mut log = circle();
        log.wheel_names = vec!["left".into(), "right".into()];
        for s in &mut log.samples {
            let t = s.time_secs;
            s.wheels = vec![
                JointState {
                    position_rad: 3.0 * t,
                    rate_radps: 3.0,
                },
                JointState {
                    position_rad: 5.0 * t,
                    rate_radps: 5.0,
                },
            ];
        }
        let units = WheelUnits::encoders(Some(42.0), 5.0, WheelRate::MotorRpm);
        // 2π / (42 · 5) rad per tick; 2π / (60 · 5) wheel rad/s per motor rpm.
        assert!((units.position_scale - 0.029_919_930_034_188_5).abs() < 1e-15);
        assert!((units.rate_scale - 0.020_943_951_023_931_95).abs() < 1e-15);
        let per_min = WheelUnits::encoders(None, 5.0, WheelRate::MotorRadPerMin);
        assert_eq!(
            (per_min.position_scale, per_min.rate_scale),
            (1.0, 1.0 / 300.0)
        );
        let tmp = tempfile::tempdir().unwrap();
        let bag = write_mcap_with(&log, tmp.path(), &[], units).unwrap();
        // Recorded in ticks and motor rpm: 3 rad/s is 143.2 motor rpm.
        let recorded = gpodo_datasets::bags::topic::read_topic(
            &bag.path,
            "/joint_states",
            "joints",
            &["sensor_msgs/JointState"],
        )
        .unwrap();
        let gpodo_datasets::bags::messages::RosMessage::JointState(m) = &recorded[10].message
        else {
            panic!("not a JointState");
        };
        assert!((m.velocity[0] - 3.0 * 300.0 / std::f64::consts::TAU).abs() < 1e-9);
        assert!((m.position[1] - 5.0 * 1.0 * 210.0 / std::f64::consts::TAU).abs() < 1e-9);
        let (back, _) = import_bag(
            &bag.path,
            "circle",
            &written_topic_map_in(&log, 10.0, units),
        )
        .unwrap();
        for (a, b) in back.samples.iter().zip(&log.samples) {
            for (x, y) in a.wheels.iter().zip(&b.wheels) {
                assert!((x.position_rad - y.position_rad).abs() < 1e-9);
                assert!((x.rate_radps - y.rate_radps).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn the_tf_ground_truth_equals_the_pose_topic_and_odometry_round_trips() {
        let tmp = tempfile::tempdir().unwrap();
        let log = circle();
        let bag = write_mcap(&log, tmp.path()).unwrap();
        assert_eq!(bag.messages, 5 * 300);
        let by_pose = written_topic_map(&log, 10.0);
        let mut by_tf = by_pose.clone();
        by_tf.ground_truth = GroundTruthSource::Tf {
            tf: TfPair {
                parent: "world".into(),
                child: "base_link".into(),
                topics: vec!["/tf".into()],
            },
        };
        let (a, ra) = import_bag(&bag.path, "circle", &by_pose).unwrap();
        let (b, rb) = import_bag(&bag.path, "circle", &by_tf).unwrap();
        assert_eq!(a, b);
        assert_eq!(ra.rows, 300);
        assert_eq!(rb.streams[1].topic, "TF world → base_link (/tf)");
        // The written log comes back: poses to rounding, odometry exactly.
        for (k, (s, p)) in a.samples.iter().zip(&a.ground_truth).enumerate() {
            assert!((s.time_secs - log.samples[k].time_secs).abs() < 1e-9);
            assert_eq!(s.odometry, log.samples[k].odometry);
            let d = p.inverse() * log.ground_truth[k];
            assert!(
                d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9,
                "{k}"
            );
        }
        // Frames the tree does not link are named.
        by_tf.ground_truth = GroundTruthSource::Tf {
            tf: TfPair {
                parent: "map".into(),
                child: "base_link".into(),
                topics: vec!["/tf".into()],
            },
        };
        let e = import_bag(&bag.path, "circle", &by_tf)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no TF chain from `map` to `base_link`") && e.contains("base_link, world"),
            "{e}"
        );
    }

    #[test]
    fn a_vo_topic_gives_camera_frames_within_the_log_and_every_pose() {
        let tmp = tempfile::tempdir().unwrap();
        let log = circle();
        // Every second, and two poses beyond the last sample (29.9 s).
        let vo: Vec<_> = (0..32)
            .map(|k| {
                let t = k as f64 + 0.05;
                (t, log.ground_truth[(10 * k).min(299)])
            })
            .collect();
        let bag = gpodo_datasets::bags::write::write_mcap_with_vo(&log, tmp.path(), &vo).unwrap();
        assert_eq!(bag.messages, 5 * 300 + 32);
        let mut map = written_topic_map(&log, 10.0);
        map.vo = Some("/vo/pose".into());
        let (imported, report) = import_bag(&bag.path, "circle", &map).unwrap();
        assert_eq!(report.vo_poses.len(), 32);
        assert_eq!(report.streams.last().unwrap().role, "vo");
        // Camera frames: the VO stamps inside the log (0.05 … 29.05 s).
        assert_eq!(imported.camera_times_secs.len(), 30);
        for (k, (t, pose)) in report.vo_poses.iter().enumerate() {
            assert!((t - vo[k].0).abs() < 1e-9);
            assert!((pose.translation.vector - vo[k].1.translation.vector).norm() < 1e-12);
        }
    }

    #[test]
    fn a_tf_ground_truth_reads_from_yaml() {
        let map: gpodo_datasets::bags::import::TopicMap = serde_saphyr::from_str(
            "imu: /imu/data\nground_truth: {tf: {parent: map, child: base_link, topics: [/tf, /tf_static]}}\n",
        )
        .unwrap();
        assert_eq!(
            map.ground_truth.to_string(),
            "TF map → base_link (/tf, /tf_static)"
        );
        let map: gpodo_datasets::bags::import::TopicMap =
            serde_saphyr::from_str("imu: /imu/data\nground_truth: /odom\n").unwrap();
        assert_eq!(map.ground_truth, GroundTruthSource::Topic("/odom".into()));
    }
}

mod damaged {
    //! Damaged or empty recordings give an error naming the file, never a
    //! panic or a silently shorter log.

    use super::data;
    use gpodo_datasets::bags::BagInfo;
    use gpodo_datasets::bags::import::{TopicMap, import_bag};

    fn map() -> TopicMap {
        serde_saphyr::from_str(
            "imu: /imu/data\nimu_rotation_rpy_rad: [1.5707963267948966, 0, 0]\nground_truth: /husky_velocity_controller/odom\n",
        )
        .unwrap()
    }

    /// `bytes` written to a file named `name` in a fresh directory.
    fn file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        (dir, path)
    }

    /// Both the info pass and the import fail, naming the file.
    fn both_fail(path: &std::path::Path) -> String {
        let info = BagInfo::read(path).map(|i| i.messages);
        let import = import_bag(path, "x", &map()).map(|(l, _)| l.samples.len());
        let (Err(a), Err(b)) = (info, import) else {
            panic!("{} was read without an error", path.display());
        };
        let (a, b) = (a.to_string(), b.to_string());
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(a.contains(&name) && b.contains(&name), "{a} / {b}");
        b
    }

    #[test]
    fn truncated_recordings_are_errors() {
        for source in ["husky_test1.mcap", "husky_test1.bag"] {
            let bytes = std::fs::read(data(source)).unwrap();
            for cut in [bytes.len() / 2, bytes.len() - 100] {
                let (_dir, path) = file(&format!("cut-{source}"), &bytes[..cut]);
                let e = both_fail(&path);
                eprintln!("{source} cut at {cut}: {e}");
            }
        }
    }

    #[test]
    fn a_corrupt_chunk_is_an_error() {
        for source in ["husky_test1.mcap", "husky_test1.bag"] {
            let mut bytes = std::fs::read(data(source)).unwrap();
            let middle = bytes.len() / 2;
            for b in &mut bytes[middle..middle + 64] {
                *b ^= 0x5a;
            }
            let (_dir, path) = file(&format!("corrupt-{source}"), &bytes);
            let e = both_fail(&path);
            eprintln!("{source} corrupted: {e}");
        }
    }

    #[test]
    fn empty_and_foreign_files_are_errors() {
        let (_a, empty) = file("empty.mcap", b"");
        assert!(both_fail(&empty).contains("empty.mcap"));
        let (_b, text) = file("notes.bag", b"time,x\n0,1\n");
        let e = both_fail(&text);
        assert!(e.contains("notes.bag"), "{e}");
        // A valid MCAP without a message: its topics are missing.
        let mut buffer = std::io::Cursor::new(Vec::new());
        {
            let mut w = mcap::Writer::new(&mut buffer).unwrap();
            w.finish().unwrap();
        }
        let (_c, no_messages) = file("no-messages.mcap", buffer.get_ref());
        let info = BagInfo::read(&no_messages).unwrap();
        assert_eq!(info.messages, 0);
        let e = import_bag(&no_messages, "x", &map())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no-messages.mcap: no topic `/imu/data`"), "{e}");
    }
}

mod fixtures {
    //! One message of every type gpodo decodes, written by an independent
    //! encoder (Python `rosbags`; `tests/fixtures/make_fixtures.py`) as a
    //! ROS 1 bag with lz4 chunks and as a ROS 2 MCAP, decoded here to the
    //! values the script wrote.

    use std::path::PathBuf;

    use gpodo_datasets::bags::messages::{
        Header, Imu, JointState, NavSatFix, Odometry, Pose, RosMessage, TransformStamped, Twist,
    };
    use gpodo_datasets::bags::topic::read_topic;

    fn fixture(name: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name)
    }

    fn header(frame: &str) -> Header {
        Header {
            stamp_ns: 100_250_000_000,
            frame_id: frame.into(),
        }
    }

    const Q: [f64; 4] = [0.5, -0.5, 0.5, 0.5];

    fn cov(n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|k| k as f64 * scale).collect()
    }

    fn cov9(scale: f64) -> [f64; 9] {
        std::array::from_fn(|k| k as f64 * scale)
    }

    fn expected() -> Vec<(&'static str, &'static str, RosMessage)> {
        vec![
            (
                "/joint_states",
                "sensor_msgs/JointState",
                RosMessage::JointState(JointState {
                    header: header("base_link"),
                    name: vec!["left_wheel".into(), "right_wheel_joint".into()],
                    position: vec![1.5, -2.25],
                    velocity: vec![0.5, 0.125],
                    effort: vec![],
                }),
            ),
            (
                "/imu",
                "sensor_msgs/Imu",
                RosMessage::Imu(Imu {
                    header: header("imu_link"),
                    orientation: Q,
                    orientation_covariance: cov9(0.25),
                    angular_velocity: [0.125, -0.25, 0.5],
                    angular_velocity_covariance: cov9(0.5),
                    linear_acceleration: [0.0, 0.75, 9.8125],
                    linear_acceleration_covariance: cov9(1.0),
                }),
            ),
            (
                "/odom",
                "nav_msgs/Odometry",
                RosMessage::Odometry(Odometry {
                    header: header("odom"),
                    child_frame_id: "base_link".into(),
                    pose: Pose {
                        position: [1.0, 2.0, -3.0],
                        orientation: Q,
                    },
                    pose_covariance: cov(36, 0.5),
                    twist: Twist {
                        linear: [0.75, 0.0, 0.0],
                        angular: [0.0, 0.0, -0.375],
                    },
                    twist_covariance: cov(36, 0.25),
                }),
            ),
            (
                "/fix",
                "sensor_msgs/NavSatFix",
                RosMessage::NavSatFix(NavSatFix {
                    header: header("gps"),
                    status: 1,
                    service: 3,
                    latitude: 42.375,
                    longitude: -71.125,
                    altitude: 12.5,
                    position_covariance: cov9(0.125),
                    position_covariance_type: 2,
                }),
            ),
            (
                "/pose",
                "geometry_msgs/PoseStamped",
                RosMessage::PoseStamped(
                    header("world"),
                    Pose {
                        position: [-1.5, 0.25, 4.0],
                        orientation: Q,
                    },
                ),
            ),
            (
                "/pose_cov",
                "geometry_msgs/PoseWithCovarianceStamped",
                RosMessage::PoseWithCovarianceStamped(
                    header("map"),
                    Pose {
                        position: [3.0, -4.0, 0.5],
                        orientation: Q,
                    },
                    cov(36, 2.0),
                ),
            ),
            (
                "/twist",
                "geometry_msgs/TwistStamped",
                RosMessage::TwistStamped(
                    header("base_link"),
                    Twist {
                        linear: [0.5, -0.25, 0.0],
                        angular: [0.0, 0.0, 1.25],
                    },
                ),
            ),
            (
                "/tf",
                "tf2_msgs/TFMessage",
                RosMessage::Tf(vec![
                    TransformStamped {
                        header: header("map"),
                        child_frame_id: "odom".into(),
                        translation: [1.0, 0.0, 0.0],
                        rotation: [0.0, 0.0, 0.0, 1.0],
                    },
                    TransformStamped {
                        header: header("odom"),
                        child_frame_id: "base_link".into(),
                        translation: [0.5, -0.5, 0.25],
                        rotation: Q,
                    },
                ]),
            ),
        ]
    }

    /// The fixtures this build reads.
    fn files() -> Vec<&'static str> {
        let mut files = vec!["messages.bag", "messages.mcap"];
        if cfg!(feature = "db3") {
            files.push("messages.db3");
        }
        files
    }

    #[test]
    fn a_db3_bag_is_read_with_the_feature_and_refused_with_advice_without() {
        let path = fixture("messages.db3");
        let info = gpodo_datasets::bags::BagInfo::read(&path);
        if cfg!(feature = "db3") {
            let info = info.unwrap();
            assert_eq!(info.format, gpodo_datasets::bags::BagFormat::Db3);
            assert_eq!(info.messages, 8);
        } else {
            let e = info.unwrap_err().to_string();
            assert!(
                e.contains("messages.db3") && e.contains("--features db3"),
                "{e}"
            );
        }
    }

    #[test]
    fn every_message_type_decodes_to_what_an_independent_encoder_wrote() {
        for file in files() {
            for (topic, ty, want) in expected() {
                let got = read_topic(&fixture(file), topic, "test", &[ty]).unwrap();
                assert_eq!(got.len(), 1, "{file} {topic}");
                assert_eq!(got[0].log_time_ns, 100_250_000_000, "{file} {topic}");
                assert_eq!(got[0].message, want, "{file} {topic}");
            }
        }
    }
}

mod names {
    //! `bag info` shows what a topic map needs: joint names, frame ids and
    //! TF pairs, from the independently written fixtures.

    use std::path::Path;

    #[test]
    fn bag_info_lists_joint_names_frames_and_transforms() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        for file in ["messages.bag", "messages.mcap"] {
            let info = gpodo_datasets::bags::BagInfo::read(&dir.join(file)).unwrap();
            let names = |topic: &str| {
                info.topics
                    .iter()
                    .find(|t| t.topic == topic)
                    .map(|t| t.names.clone())
                    .unwrap()
            };
            assert_eq!(
                names("/joint_states"),
                ["left_wheel", "right_wheel_joint"],
                "{file}"
            );
            assert_eq!(names("/odom"), ["odom → base_link"], "{file}");
            let text = info.to_text();
            assert!(
                text.contains("joints: left_wheel, right_wheel_joint"),
                "{file}: {text}"
            );
            assert!(text.contains("frames: odom → base_link"), "{file}: {text}");
            assert!(
                text.contains("transforms: map → odom, odom → base_link"),
                "{file}: {text}"
            );
        }
    }
}
