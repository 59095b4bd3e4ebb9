//! Tests of the rover log type and its CSV format.

use std::fs;
use std::path::{Path, PathBuf};

use gpodo_traits::{ImuSample, JointState, ProprioceptiveSample};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::*;

fn joint(position_rad: f64, rate_radps: f64) -> JointState {
    JointState {
        position_rad,
        rate_radps,
    }
}

/// A three-sample log with awkward values.
fn awkward_log() -> RoverLog {
    let times = [0.1 + 0.2, 0.5, 1e3 + 1e-9];
    let samples = times
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            let k = i as f64;
            ProprioceptiveSample {
                time_secs: t,
                wheels: vec![joint(1e-300, -0.0), joint(k / 3.0, 5e-324)],
                steering: vec![joint(-1.7347235e-18, f64::MIN_POSITIVE)],
                bogies: vec![joint(12.7, 1e300 * (k - 1.0))],
                imu: Some(ImuSample {
                    gyro_radps: Vector3::new(0.1 + 0.2, -0.0, 1e-7 * k),
                    accel_mps2: Vector3::new(0.0, 2.0_f64.sqrt(), 9.81),
                    roll_rad: std::f64::consts::PI / 7.0,
                    pitch_rad: -0.45 + k * 1e-17,
                }),
                attitude_rad: None,
                contact_angles_rad: Some(vec![1.0 / 3.0, -0.0]),
                odometry: None,
            }
        })
        .collect();
    let ground_truth = times
        .iter()
        .map(|&t| {
            Isometry3::from_parts(
                Translation3::new(t / 7.0, -0.0, 1e-300),
                UnitQuaternion::from_euler_angles(0.1 + 0.2, -t / 3.0, 2.0 * t),
            )
        })
        .collect();
    RoverLog {
        name: "awkward".into(),
        wheel_names: vec!["fl".into(), "front_right".into()],
        steer_names: vec!["fl".into()],
        bogie_names: vec!["rear".into()],
        samples,
        ground_truth,
        camera_times_secs: vec![0.1 + 0.2, 0.7, 1e-300 + 1.0],
    }
}

/// Every number of a log, as bits, with its names.
fn fingerprint(log: &RoverLog) -> (Vec<String>, Vec<u64>) {
    let layout = columns::LogLayout::of_log(log);
    let mut bits: Vec<u64> = log
        .samples
        .iter()
        .zip(&log.ground_truth)
        .flat_map(|(s, p)| layout.encode(s, p))
        .map(f64::to_bits)
        .collect();
    bits.extend(log.camera_times_secs.iter().map(|t| t.to_bits()));
    let mut names = vec![log.name.clone()];
    names.extend(
        log.wheel_names
            .iter()
            .chain(&log.steer_names)
            .chain(&log.bogie_names)
            .cloned(),
    );
    (names, bits)
}

fn written(log: &RoverLog) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = write_log_csv(log, dir.path()).unwrap();
    (dir, path)
}

/// Replaces the cell of `column` on 1-based `line` of a CSV file.
fn set_cell(path: &Path, line: usize, column: &str, value: &str) {
    let text = fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let j = lines[0].split(',').position(|c| c == column).unwrap();
    let mut cells: Vec<&str> = lines[line - 1].split(',').collect();
    cells[j] = value;
    lines[line - 1] = cells.join(",");
    fs::write(path, lines.join("\n") + "\n").unwrap();
}

/// Renames a header column of a CSV file.
fn rename_column(path: &Path, from: &str, to: &str) {
    let text = fs::read_to_string(path).unwrap();
    let (header, rest) = text.split_once('\n').unwrap();
    let header: Vec<&str> = header
        .split(',')
        .map(|c| if c == from { to } else { c })
        .collect();
    fs::write(path, format!("{}\n{rest}", header.join(","))).unwrap();
}

/// Removes a column from a CSV file.
fn drop_column(path: &Path, column: &str) {
    let text = fs::read_to_string(path).unwrap();
    let j = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == column)
        .unwrap();
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells.remove(j);
            cells.join(",")
        })
        .collect();
    fs::write(path, out.join("\n") + "\n").unwrap();
}

#[test]
fn written_log_reads_back_bit_identical() {
    let log = awkward_log();
    let (_dir, path) = written(&log);
    let back = read_log_csv(&path).unwrap();
    assert_eq!(fingerprint(&back), fingerprint(&log));
    assert_eq!(back, log);
}

#[test]
fn log_without_contact_or_camera_round_trips() {
    let mut log = awkward_log();
    log.camera_times_secs.clear();
    for s in &mut log.samples {
        s.contact_angles_rad = None;
    }
    let (_dir, path) = written(&log);
    let back = read_log_csv(&path).unwrap();
    assert_eq!(fingerprint(&back), fingerprint(&log));
}

#[test]
fn writes_log_and_camera_files_and_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let (log_path, camera_path) = write_log_csv(&awkward_log(), dir.path()).unwrap();
    assert_eq!(log_path, dir.path().join("awkward.csv"));
    assert_eq!(camera_path, dir.path().join("awkward.camera.csv"));
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 2);
    let header = fs::read_to_string(&log_path).unwrap();
    assert!(header.starts_with(
        "time_s,gt_x_m,gt_y_m,gt_z_m,gt_qw,gt_qx,gt_qy,gt_qz,roll_rad,pitch_rad,\
         gyro_x_radps,gyro_y_radps,gyro_z_radps,acc_x_mps2,acc_y_mps2,acc_z_mps2,\
         wheel_fl_pos_rad,wheel_fl_rate_radps,wheel_front_right_pos_rad,\
         wheel_front_right_rate_radps,steer_fl_pos_rad,steer_fl_rate_radps,\
         bogie_rear_pos_rad,bogie_rear_rate_radps,contact_fl_rad,contact_front_right_rad\n"
    ));
}

#[test]
fn failed_write_leaves_existing_files_untouched() {
    let log = awkward_log();
    let (dir, path) = written(&log);
    let before = fs::read(&path).unwrap();
    let mut bad = log.clone();
    bad.samples[1].imu.get_or_insert_default().roll_rad = f64::NAN;
    assert!(write_log_csv(&bad, dir.path()).is_err());
    assert_eq!(fs::read(&path).unwrap(), before);
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn write_into_missing_directory_fails_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no_such_dir");
    let err = write_log_csv(&awkward_log(), &missing).unwrap_err();
    assert!(matches!(err, DatasetError::Io { .. }), "{err}");
    assert!(err.to_string().contains("no_such_dir"), "{err}");
}

#[test]
fn rejects_name_that_is_not_a_file_stem() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["", "../evil", ".hidden", "a/b"] {
        let mut log = awkward_log();
        log.name = name.into();
        let err = write_log_csv(&log, dir.path()).unwrap_err();
        assert!(
            matches!(err, DatasetError::InvalidLog { .. }),
            "{name}: {err}"
        );
    }
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn reads_columns_in_any_order_with_spaces_and_x_extras() {
    let (_dir, path) = written(&awkward_log());
    let text = fs::read_to_string(&path).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    let reordered: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, cells)| {
            let mut out: Vec<String> = cells.iter().rev().map(|c| format!(" {c} ")).collect();
            out.push(if i == 0 {
                "x_note".into()
            } else {
                "free text".into()
            });
            out.join(",")
        })
        .collect();
    fs::write(&path, reordered.join("\n")).unwrap();
    let back = read_log_csv(&path).unwrap();
    // Joint names come in header order, here reversed.
    let mut expected = awkward_log();
    expected.wheel_names.reverse();
    for s in &mut expected.samples {
        s.wheels.reverse();
        s.contact_angles_rad.as_mut().unwrap().reverse();
    }
    assert_eq!(back.wheel_names, ["front_right", "fl"]);
    assert_eq!(fingerprint(&back), fingerprint(&expected));
}

#[test]
fn discovers_joint_names_from_header() {
    let mut log = awkward_log();
    log.wheel_names = vec!["left_front".into(), "w-2".into()];
    log.steer_names.clear();
    log.bogie_names = vec!["a".into()];
    for s in &mut log.samples {
        s.steering.clear();
    }
    let (_dir, path) = written(&log);
    let back = read_log_csv(&path).unwrap();
    assert_eq!(back.wheel_names, log.wheel_names);
    assert!(back.steer_names.is_empty());
    assert_eq!(back.bogie_names, ["a"]);
}

#[test]
fn rejects_unknown_column_naming_it() {
    let (_dir, path) = written(&awkward_log());
    rename_column(&path, "gyro_z_radps", "gyro_z_rads");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::UnknownColumn { column, .. } if column == "gyro_z_rads"),
        "{err}"
    );
    assert!(err.to_string().contains("awkward.csv"), "{err}");
}

#[test]
fn rejects_missing_column_naming_it() {
    let (_dir, path) = written(&awkward_log());
    drop_column(&path, "wheel_fl_rate_radps");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::MissingColumn { column, .. } if column == "wheel_fl_rate_radps"),
        "{err}"
    );
}

#[test]
fn rejects_missing_fixed_column() {
    let (_dir, path) = written(&awkward_log());
    drop_column(&path, "pitch_rad");
    let err = read_log_csv(&path).unwrap_err();
    assert!(matches!(&err, DatasetError::MissingColumn { column, .. } if column == "pitch_rad"));
}

#[test]
fn rejects_contact_angles_for_only_some_wheels() {
    let (_dir, path) = written(&awkward_log());
    drop_column(&path, "contact_front_right_rad");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::MissingColumn { column, .. } if column == "contact_front_right_rad"),
        "{err}"
    );
}

#[test]
fn rejects_contact_angle_of_unknown_wheel() {
    let (_dir, path) = written(&awkward_log());
    rename_column(&path, "contact_fl_rad", "contact_rr_rad");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::UnknownColumn { column, .. } if column == "contact_rr_rad")
    );
}

#[test]
fn rejects_non_numeric_cell_with_line_and_column() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 3, "acc_y_mps2", "1.0.0");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::NotANumber { line: 3, column, value, .. }
            if column == "acc_y_mps2" && value == "1.0.0"),
        "{err}"
    );
    let msg = err.to_string();
    assert!(msg.contains("awkward.csv") && msg.contains("line 3") && msg.contains("acc_y_mps2"));
}

#[test]
fn rejects_nan_with_line_and_column() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 4, "steer_fl_rate_radps", "NaN");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::NonFinite { line: 4, column, .. } if column == "steer_fl_rate_radps"),
        "{err}"
    );
}

#[test]
fn rejects_infinity_with_line_and_column() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 2, "gt_x_m", "inf");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::NonFinite { line: 2, column, .. } if column == "gt_x_m"),
        "{err}"
    );
}

#[test]
fn rejects_non_increasing_time_with_line() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 3, "time_s", "0.30000000000000004");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(err, DatasetError::NonIncreasingTime { line: 3, found, .. } if found == 0.1 + 0.2),
        "{err}"
    );
}

#[test]
fn rejects_empty_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.csv");
    fs::write(&path, "").unwrap();
    let err = read_log_csv(&path).unwrap_err();
    assert!(matches!(err, DatasetError::Empty { .. }), "{err}");
}

#[test]
fn rejects_header_without_samples() {
    let (_dir, path) = written(&awkward_log());
    let text = fs::read_to_string(&path).unwrap();
    fs::write(&path, text.lines().next().unwrap()).unwrap();
    let err = read_log_csv(&path).unwrap_err();
    assert!(matches!(err, DatasetError::Empty { .. }), "{err}");
}

#[test]
fn rejects_wrong_number_of_fields_with_line() {
    let (_dir, path) = written(&awkward_log());
    let mut text = fs::read_to_string(&path).unwrap();
    text.push_str("1,2,3\n");
    fs::write(&path, text).unwrap();
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(
            err,
            DatasetError::Shape {
                line: 5,
                found: 3,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn rejects_quaternion_far_from_unit_norm_with_line() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 3, "gt_qw", "2");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(err, DatasetError::NotAUnitQuaternion { line: 3, .. }),
        "{err}"
    );
}

#[test]
fn normalises_quaternion_close_to_unit_norm() {
    let (_dir, path) = written(&awkward_log());
    set_cell(&path, 2, "gt_qw", "1.0002");
    set_cell(&path, 2, "gt_qx", "0");
    set_cell(&path, 2, "gt_qy", "0");
    set_cell(&path, 2, "gt_qz", "0");
    let back = read_log_csv(&path).unwrap();
    assert_eq!(back.ground_truth[0].rotation, UnitQuaternion::identity());
}

#[test]
fn missing_camera_file_means_no_camera_frames() {
    let (_dir, path) = written(&awkward_log());
    fs::remove_file(path.with_file_name("awkward.camera.csv")).unwrap();
    assert!(read_log_csv(&path).unwrap().camera_times_secs.is_empty());
}

#[test]
fn rejects_non_increasing_camera_time_naming_camera_file() {
    let (_dir, path) = written(&awkward_log());
    let camera = path.with_file_name("awkward.camera.csv");
    fs::write(&camera, "time_s\n1\n2\n2\n").unwrap();
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::NonIncreasingTime { line: 4, path, .. } if *path == camera),
        "{err}"
    );
}

#[test]
fn rejects_unknown_column_in_camera_file() {
    let (_dir, path) = written(&awkward_log());
    fs::write(
        path.with_file_name("awkward.camera.csv"),
        "time_s,frame\n1,3\n",
    )
    .unwrap();
    let err = read_log_csv(&path).unwrap_err();
    assert!(matches!(&err, DatasetError::UnknownColumn { column, .. } if column == "frame"));
}

#[test]
fn validate_accepts_consistent_log() {
    awkward_log().validate().unwrap();
}

#[test]
fn validate_rejects_pose_count_mismatch() {
    let mut log = awkward_log();
    log.ground_truth.pop();
    assert!(matches!(
        log.validate(),
        Err(DatasetError::InvalidLog { sample: None, .. })
    ));
}

#[test]
fn validate_rejects_wrong_joint_count_naming_sample() {
    let mut log = awkward_log();
    log.samples[2].wheels.pop();
    assert!(matches!(
        log.validate(),
        Err(DatasetError::InvalidLog {
            sample: Some(2),
            ..
        })
    ));
}

#[test]
fn validate_rejects_contact_angles_in_some_samples_only() {
    let mut log = awkward_log();
    log.samples[1].contact_angles_rad = None;
    assert!(matches!(
        log.validate(),
        Err(DatasetError::InvalidLog {
            sample: Some(1),
            ..
        })
    ));
}

#[test]
fn validate_rejects_non_finite_value_naming_column() {
    let mut log = awkward_log();
    log.samples[1].imu.get_or_insert_default().gyro_radps.y = f64::INFINITY;
    let err = log.validate().unwrap_err();
    assert!(matches!(
        err,
        DatasetError::InvalidLog {
            sample: Some(1),
            ..
        }
    ));
    assert!(err.to_string().contains("gyro_y_radps"), "{err}");
}

#[test]
fn validate_rejects_non_increasing_times() {
    let mut log = awkward_log();
    log.samples[2].time_secs = log.samples[1].time_secs;
    assert!(matches!(
        log.validate(),
        Err(DatasetError::InvalidLog {
            sample: Some(2),
            ..
        })
    ));
    let mut log = awkward_log();
    log.camera_times_secs.reverse();
    assert!(log.validate().is_err());
}

#[test]
fn validate_rejects_joint_names_that_break_the_header() {
    for name in ["", "a,b", " fl", "fl\n"] {
        let mut log = awkward_log();
        log.bogie_names = vec![name.into()];
        assert!(log.validate().is_err(), "{name:?}");
    }
    let mut log = awkward_log();
    log.wheel_names = vec!["fl".into(), "fl".into()];
    assert!(log.validate().is_err());
}

#[test]
fn duration_and_path_length_follow_samples_and_ground_truth() {
    let mut log = awkward_log();
    log.ground_truth = [[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 2.0]]
        .iter()
        .map(|p| Isometry3::translation(p[0], p[1], p[2]))
        .collect();
    approx::assert_relative_eq!(log.duration_secs(), 1e3 + 1e-9 - (0.1 + 0.2));
    for (k, s) in log.samples.iter_mut().enumerate() {
        s.time_secs = k as f64;
    }
    approx::assert_relative_eq!(log.path_length_m(), 7.0);
}

#[test]
fn path_length_ignores_sample_to_sample_jitter() {
    // 3 m straight at 12.5 Hz with ±1 mm alternating jitter across the path:
    // summing every step would add ~0.6 m.
    let mut log = awkward_log();
    let template = log.samples[0].clone();
    log.samples = (0..=1250)
        .map(|k| {
            let mut s = template.clone();
            s.time_secs = k as f64 * 0.08;
            s
        })
        .collect();
    log.ground_truth = (0..=1250)
        .map(|k| {
            let jitter = if k % 2 == 0 { 1e-3 } else { -1e-3 };
            Isometry3::translation(3.0 * k as f64 / 1250.0, jitter, 0.0)
        })
        .collect();
    let length = log.path_length_m();
    assert!((length - 3.0).abs() < 0.01, "{length}");
}

#[test]
fn joints_are_reordered_by_name_and_missing_ones_are_named() {
    let log = awkward_log();
    let mut wheels = log.wheel_names.clone();
    wheels.reverse();
    let reordered = log
        .with_joint_order(&wheels, &log.steer_names, &log.bogie_names)
        .unwrap();
    let n = log.wheel_names.len();
    for (k, s) in reordered.samples.iter().enumerate() {
        for i in 0..n {
            assert_eq!(s.wheels[i], log.samples[k].wheels[n - 1 - i]);
            if let (Some(a), Some(b)) = (&s.contact_angles_rad, &log.samples[k].contact_angles_rad)
            {
                assert_eq!(a[i], b[n - 1 - i]);
            }
        }
    }
    assert_eq!(reordered.wheel_names, wheels);
    let mut wrong = wheels.clone();
    wrong[0] = "nope".into();
    let err = log
        .with_joint_order(&wrong, &log.steer_names, &log.bogie_names)
        .unwrap_err()
        .to_string();
    assert!(err.contains("nope"), "{err}");
}

/// The awkward log with the robot's own odometry in every sample.
fn with_odometry(mut log: RoverLog) -> RoverLog {
    for (k, s) in log.samples.iter_mut().enumerate() {
        s.odometry = Some(gpodo_traits::BodyTwist {
            linear_mps: Vector3::new(0.1 + 0.2, -0.0, 1e-300 * k as f64),
            angular_radps: Vector3::new(5e-324, 1.0 / 3.0, -(k as f64)),
        });
    }
    log
}

#[test]
fn odometry_columns_round_trip_bit_identical() {
    let log = with_odometry(awkward_log());
    let (_dir, path) = written(&log);
    let header = fs::read_to_string(&path).unwrap();
    assert!(
        header.lines().next().unwrap().ends_with(
            "odom_vx_mps,odom_vy_mps,odom_vz_mps,odom_wx_radps,odom_wy_radps,odom_wz_radps"
        ),
        "{header}"
    );
    let back = read_log_csv(&path).unwrap();
    assert_eq!(fingerprint(&back), fingerprint(&log));
    assert_eq!(back, log);
}

#[test]
fn odometry_needs_all_six_columns_and_every_sample() {
    let (_dir, path) = written(&with_odometry(awkward_log()));
    drop_column(&path, "odom_wz_radps");
    let err = read_log_csv(&path).unwrap_err();
    assert!(
        matches!(&err, DatasetError::MissingColumn { column, .. } if column == "odom_wz_radps"),
        "{err}"
    );
    let mut log = with_odometry(awkward_log());
    log.samples[2].odometry = None;
    let err = log.validate().unwrap_err().to_string();
    assert!(
        err.contains("odometry must be given in every sample"),
        "{err}"
    );
}

#[test]
fn a_log_cut_in_time_keeps_every_sample_once_with_its_camera_frames() {
    let mut log = awkward_log();
    log.samples[2].time_secs = 1.5;
    log.camera_times_secs = vec![0.1 + 0.2, 0.5, 1.5];
    let mut longer = log.clone();
    for k in 3..10 {
        let mut s = log.samples[2].clone();
        s.time_secs = 1.5 + k as f64;
        longer.samples.push(s);
        longer.ground_truth.push(log.ground_truth[2]);
    }
    // 0.3 … 10.5 s: 80 % of the duration ends at 8.46 s.
    let (train, test) = longer.split_in_time(0.8).unwrap();
    assert_eq!(
        (train.name.as_str(), test.name.as_str()),
        ("awkward-train", "awkward-test")
    );
    assert_eq!(
        train.samples.len() + test.samples.len(),
        longer.samples.len()
    );
    assert_eq!(train.samples.last().unwrap().time_secs, 7.5);
    assert_eq!(test.samples[0].time_secs, 8.5);
    assert_eq!(train.camera_times_secs, vec![0.1 + 0.2, 0.5, 1.5]);
    assert!(test.camera_times_secs.is_empty());
    train.validate().unwrap();
    test.validate().unwrap();
    // Too short a part, or a fraction that is not one, is refused.
    let e = log.split_in_time(0.5).unwrap_err().to_string();
    assert!(e.contains("each part needs two"), "{e}");
    let e = log.split_in_time(1.0).unwrap_err().to_string();
    assert!(e.contains("train_fraction"), "{e}");
}
