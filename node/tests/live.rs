//! The live pipeline on a simulated ExoTeR drive, against the batch
//! pipeline: its rows at whole seconds equal the batch's 1-s windows, its
//! predictions equal the saved model's on all its rows at once, and a
//! model it cannot run is refused with the file and the reason named.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_datasets::residuals::{log_steps, window_rows};
use gpodo_kinematics::spec::MotionModelSpec;

use common::{bag_messages, exoter_yaml, fitted};
use gpodo_node::{LiveModel, LiveSettings, NodeError, OdometryMode};
use gpodo_regressors::model_file::ModelFile;
use gpodo_traits::SampleMatrix;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-9)
}

#[test]
fn live_rows_are_the_batch_windows_and_predictions_are_the_saved_models() {
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    let mut live =
        LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
    assert_eq!(live.mode(), OdometryMode::Corrected);
    let log = &testbed.test[0];
    let outputs: Vec<_> = log
        .samples
        .iter()
        .map(|s| live.process(s).unwrap())
        .collect();

    // The batch's 1-s windows of the same log.
    let (motion, rover) = MotionModelSpec::default().build().unwrap();
    let steps = log_steps(log, motion.as_ref(), rover.unwrap().wheel_radius_m).unwrap();
    let windows = window_rows(&steps, 1.0);
    let t0 = log.samples[0].time_secs;
    let mut compared = 0;
    for w in &windows {
        // The sample at the window's end sees exactly its steps.
        let Some(out) = outputs
            .iter()
            .find(|o| (o.time_secs - w.end_secs).abs() < 1e-9)
        else {
            continue;
        };
        if (w.end_secs - w.start_secs - 1.0).abs() > 1e-9 || w.start_secs < t0 {
            continue;
        }
        let row = out.row.as_ref().unwrap();
        for (a, b) in row.iter().zip(&w.inputs) {
            assert!(close(*a, *b), "window at {} s: {a} vs {b}", w.start_secs);
        }
        compared += 1;
    }
    assert!(compared >= 10, "only {compared} windows ended on a sample");

    // Every row at once through the saved model, as `gpodo predict` does.
    let with_rows: Vec<_> = outputs.iter().filter(|o| o.row.is_some()).collect();
    assert_eq!(
        with_rows.len(),
        outputs.len() - 1,
        "every sample but the first has a row"
    );
    let rows: Vec<&[f64]> = with_rows
        .iter()
        .map(|o| o.row.as_deref().unwrap())
        .collect();
    let matrix = SampleMatrix::from_rows(live.columns().len(), &rows).unwrap();
    let batch = ModelFile::load(&path)
        .unwrap()
        .predictor()
        .unwrap()
        .predict(live.columns(), &matrix)
        .unwrap();
    for (i, out) in with_rows.iter().enumerate() {
        let correction = out.twist.linear_mps - out.uncorrected.linear_mps;
        for c in 0..3 {
            let (mean, var) = (batch.mean.get(i, c), batch.variance.get(i, c));
            // The correction is the uncorrected twist plus the mean, so it
            // carries that sum's rounding.
            let scale = out.uncorrected.linear_mps[c].abs().max(mean.abs());
            assert!(
                (correction[c] - mean).abs() <= 1e-12 * scale.max(1e-9),
                "row {i}, {c}: {} vs {mean}",
                correction[c]
            );
            assert!(
                close(out.variance[c], var.max(1e-8)),
                "row {i}, {c}: variance"
            );
        }
        assert_eq!(out.twist.angular_radps, out.uncorrected.angular_radps);
        assert!(out.variance.iter().all(|v| *v >= 1e-8));
    }
    // The pose integrates the published twists.
    let last = outputs.last().unwrap();
    let mut pose = nalgebra::Isometry3::identity();
    for pair in outputs.windows(2) {
        pose *= pair[0]
            .twist
            .pose_delta(pair[1].time_secs - pair[0].time_secs);
    }
    assert!((pose.translation.vector - last.pose.translation.vector).norm() < 1e-12);
}

#[test]
fn the_authors_mode_leaves_the_twist_and_squares_the_predicted_residual() {
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), true);
    let mut live =
        LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
    assert_eq!(live.mode(), OdometryMode::Authors);
    let log = &testbed.test[0];
    let predictor = ModelFile::load(&path).unwrap().predictor().unwrap();
    for s in log.samples.iter().take(40) {
        let out = live.process(s).unwrap();
        assert_eq!(out.twist, out.uncorrected);
        if let Some(row) = &out.row {
            let x = SampleMatrix::from_rows(row.len(), &[row]).unwrap();
            let p = predictor.predict(live.columns(), &x).unwrap();
            for c in 0..3 {
                let want = (p.mean.get(0, c) * p.mean.get(0, c)).max(1e-8);
                assert!(
                    close(out.variance[c], want),
                    "{} vs {want}",
                    out.variance[c]
                );
            }
        }
    }
}

#[test]
fn models_that_cannot_run_live_are_refused_with_the_file_and_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    // This robot has no IMU: the model reads roll, pitch and the IMU's
    // columns.
    let e = LiveModel::load(&path, &exoter_yaml(), false, false, LiveSettings::default())
        .err()
        .unwrap();
    let NodeError::MissingColumns { missing, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!(missing[..2], ["roll".to_string(), "pitch".to_string()]);
    assert!(e.to_string().contains("m.gpodo"), "{e}");

    // A model whose motion model read the ground truth's attitude, on a
    // robot without an IMU.
    let mut file = ModelFile::load(&path).unwrap();
    let recipe = file.rows.as_mut().unwrap();
    recipe.motion_model["attitude_without_imu"] = "ground_truth".into();
    let off_board = tmp.path().join("off-board.gpodo");
    file.save(&off_board).unwrap();
    let e = LiveModel::load(
        &off_board,
        &exoter_yaml(),
        false,
        false,
        LiveSettings::default(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("off-board.gpodo") && e.contains("ground truth"),
        "{e}"
    );

    // A file without its recipe (as version 2 wrote them).
    let mut file = ModelFile::load(&path).unwrap();
    file.rows = None;
    let old = tmp.path().join("old.gpodo");
    file.save(&old).unwrap();
    let e = LiveModel::load(&old, &exoter_yaml(), true, false, LiveSettings::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("old.gpodo") && e.contains("does not say how"),
        "{e}"
    );

    // A sample going back in time, or with a NaN, leaves the pipeline as
    // it was.
    let mut live =
        LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
    let samples = &testbed.test[0].samples;
    let first = live.process(&samples[0]).unwrap();
    let second = live.process(&samples[1]).unwrap();
    let e = live.process(&samples[0]).unwrap_err().to_string();
    assert!(e.contains("not after"), "{e}");
    let mut nan = samples[2].clone();
    nan.wheels[0].rate_radps = f64::NAN;
    let e = live.process(&nan).unwrap_err().to_string();
    assert!(e.contains("spd_") && e.contains("not finite"), "{e}");
    let third = live.process(&samples[2]).unwrap();
    let mut again =
        LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
    assert_eq!(again.process(&samples[0]).unwrap(), first);
    assert_eq!(again.process(&samples[1]).unwrap(), second);
    assert_eq!(again.process(&samples[2]).unwrap(), third);
}

#[test]
fn inputs_outside_the_training_range_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    // The same model with a training z-scoring whose spread is tiny for
    // one wheel's speed and huge for every other input.
    let mut file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let names: Vec<String> = serde_json::from_value(file["input_names"].clone()).unwrap();
    let std: Vec<f64> = names
        .iter()
        .map(|n| if n == "spd_fl_transl" { 1e-6 } else { 1e9 })
        .collect();
    file["input_standardizer"] = serde_json::json!({"mean": vec![0.0; names.len()], "std": std});
    let scaled = tmp.path().join("scaled.gpodo");
    std::fs::write(&scaled, file.to_string()).unwrap();
    let mut live = LiveModel::load(
        &scaled,
        &exoter_yaml(),
        true,
        false,
        LiveSettings::default(),
    )
    .unwrap();
    let outputs: Vec<_> = testbed.test[0]
        .samples
        .iter()
        .map(|s| live.process(s).unwrap())
        .collect();
    let flagged = outputs
        .iter()
        .filter(|o| !o.out_of_range.is_empty())
        .count();
    assert!(
        flagged > outputs.len() / 2,
        "{flagged} of {}",
        outputs.len()
    );
    for o in &outputs {
        let row = o.row.as_ref();
        let column = live
            .columns()
            .iter()
            .position(|c| c == "spd_fl_transl")
            .unwrap();
        let expected = row.is_some_and(|r| r[column].abs() > 4e-6);
        assert_eq!(o.out_of_range == ["spd_fl_transl".to_string()], expected);
    }
}

#[test]
fn a_joint_state_gets_the_imu_reading_of_its_time_whichever_topic_arrives_first() {
    use gpodo_datasets::bags::messages::RosMessage;
    use gpodo_node::feed::LiveFeed;
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    let mut log = testbed.test[0].clone();
    log.samples.truncate(200);
    log.ground_truth.truncate(200);
    log.camera_times_secs
        .retain(|t| *t <= log.samples[199].time_secs);
    let (map, messages) = bag_messages(tmp.path(), &log);
    let rover = gpodo_kinematics::RoverDescription::from_path(&exoter_yaml()).unwrap();
    let run = |order: &[usize]| {
        let mut model =
            LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
        let mut feed = LiveFeed::new(&map, &rover, &mut model).unwrap();
        let mut outputs = Vec::new();
        for &k in order {
            match &messages[k].1 {
                RosMessage::Imu(m) => feed.imu(m, 0),
                RosMessage::JointState(m) => outputs.push(feed.joints(m, 0)),
                _ => unreachable!(),
            }
        }
        outputs
    };
    let in_time: Vec<usize> = (0..messages.len()).collect();
    // The IMU a step ahead: each IMU message arrives before the joint
    // state that precedes it in time.
    let mut imu_ahead = in_time.clone();
    for k in 1..imu_ahead.len() {
        let (a, b) = (&messages[imu_ahead[k - 1]].1, &messages[imu_ahead[k]].1);
        if matches!(a, RosMessage::JointState(_)) && matches!(b, RosMessage::Imu(_)) {
            imu_ahead.swap(k - 1, k);
        }
    }
    assert_ne!(imu_ahead, in_time);
    let (a, b) = (run(&in_time), run(&imu_ahead));
    assert_eq!(a.len(), 200);
    assert!(
        a.iter().all(Result::is_ok),
        "{:?}",
        a.iter().find(|r| r.is_err())
    );
    let differs = a.iter().zip(&b).position(|(x, y)| x != y);
    assert_eq!(
        differs, None,
        "the outputs depend on which topic arrived first (from output {differs:?} on)"
    );
    // A joint state before any IMU reading of its time gives no output.
    let mut model =
        LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
    let mut feed = LiveFeed::new(&map, &rover, &mut model).unwrap();
    let first_joint = messages
        .iter()
        .find_map(|(_, m)| match m {
            RosMessage::JointState(j) => Some(j.clone()),
            _ => None,
        })
        .unwrap();
    let err = feed.joints(&first_joint, 0).unwrap_err();
    assert!(err.contains("before the first IMU message"), "{err}");
}

#[test]
fn a_replay_at_the_recorded_speed_takes_the_recording_time_and_gives_the_same_odometry() {
    use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
    use gpodo_node::replay::{Pace, Playback, replay};
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    let mut log = testbed.test[0].clone();
    let n = 30; // 2.32 s at 12.5 Hz
    log.samples.truncate(n);
    log.ground_truth.truncate(n);
    log.camera_times_secs
        .retain(|t| *t <= log.samples[n - 1].time_secs);
    let span = log.samples[n - 1].time_secs - log.samples[0].time_secs;
    let bag = write_mcap(&log, tmp.path()).unwrap().path;
    let map = written_topic_map(&log, 1.0 / 0.08);
    let rover = gpodo_kinematics::RoverDescription::from_path(&exoter_yaml()).unwrap();
    let run = |pace: Pace, out: &str| {
        let mut model =
            LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
        let out = tmp.path().join(out);
        let started = std::time::Instant::now();
        let summary = replay(
            &bag,
            &map,
            &rover,
            &mut model,
            &out,
            None,
            Playback::to_the_end(pace),
        )
        .unwrap();
        (
            started.elapsed().as_secs_f64(),
            summary,
            std::fs::read(out).unwrap(),
        )
    };
    let (fast_secs, fast, fast_bytes) = run(Pace::Fast, "fast.mcap");
    let (paced_secs, paced, paced_bytes) = run(Pace::Recorded, "paced.mcap");
    assert_eq!(fast.outputs, n);
    assert_eq!(paced.outputs, n);
    assert!(
        paced_secs >= span,
        "{paced_secs} s for a {span} s recording"
    );
    assert!(fast_secs < span, "{fast_secs} s as fast as it can");
    assert_eq!(fast_bytes, paced_bytes);
}

#[test]
fn bad_messages_give_no_output_and_leave_the_node_as_it_was() {
    use gpodo_datasets::bags::messages::RosMessage;
    use gpodo_node::feed::LiveFeed;
    let tmp = tempfile::tempdir().unwrap();
    let (testbed, path) = fitted(tmp.path(), false);
    let mut log = testbed.test[0].clone();
    log.samples.truncate(60);
    log.ground_truth.truncate(60);
    log.camera_times_secs
        .retain(|t| *t <= log.samples[59].time_secs);
    let (map, messages) = bag_messages(tmp.path(), &log);
    let rover = gpodo_kinematics::RoverDescription::from_path(&exoter_yaml()).unwrap();
    let run = |faults: bool| {
        let mut model =
            LiveModel::load(&path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
        let mut feed = LiveFeed::new(&map, &rover, &mut model).unwrap();
        let (mut outputs, mut refused) = (Vec::new(), Vec::new());
        let mut last_joint = None;
        for (k, (_, m)) in messages.iter().enumerate() {
            match m {
                RosMessage::Imu(m) => feed.imu(m, 0),
                RosMessage::JointState(m) => {
                    if faults && k % 10 == 5 {
                        // A NaN, a joint missing, time going backwards, in turn.
                        let mut bad = m.clone();
                        match (k / 10) % 3 {
                            0 => bad.velocity[0] = f64::NAN,
                            1 => {
                                bad.name.remove(0);
                                bad.position.remove(0);
                                bad.velocity.remove(0);
                                if !bad.effort.is_empty() {
                                    bad.effort.remove(0);
                                }
                            }
                            _ => {
                                let earlier: &gpodo_datasets::bags::messages::JointState =
                                    last_joint.unwrap();
                                bad.header.stamp_ns = earlier.header.stamp_ns - 40_000_000;
                            }
                        }
                        refused.push(feed.joints(&bad, 0).unwrap_err());
                    }
                    outputs.push(feed.joints(m, 0).unwrap());
                    last_joint = Some(m);
                }
                _ => unreachable!(),
            }
        }
        (outputs, refused)
    };
    let (clean, none) = run(false);
    let (faulted, refused) = run(true);
    assert!(none.is_empty());
    assert_eq!(refused.len(), 12, "{refused:?}");
    for (k, reason) in refused.iter().enumerate() {
        let expected = ["not finite", "no joint", "not after the previous"][k % 3];
        assert!(reason.contains(expected), "{reason}");
    }
    // Every good message gives what it gives without the bad ones.
    assert_eq!(clean, faulted);
    assert!(
        clean
            .iter()
            .all(|f| f.output.twist.linear_mps.iter().all(|v| v.is_finite()))
    );
}
