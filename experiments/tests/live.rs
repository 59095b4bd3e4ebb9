//! `gpodo live --replay`: a simulated recording through a model fitted on
//! another recording of the same robot, as the robot would run it. The
//! odometry it writes is the motion model's twist plus what `gpodo predict`
//! predicts on the rows it writes, to 1e-12, with those predictions'
//! variances as its covariance; a model that does not say how its rows
//! were made is refused before anything is written.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::Path;
use std::process::Command;

use gpodo_datasets::bags::write::WheelUnits;
use gpodo_experiments::commands::simulate::{SimulateFormat, SimulateOptions, simulate_to};
use gpodo_testbed::sim::preset::Preset;

use common::{GPODO, assert_succeeded, bag_odometry, exoter, gpodo_quiet};

#[test]
fn the_replayed_odometry_is_the_wheels_plus_what_gpodo_predict_predicts_on_its_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    simulate_to(
        &SimulateOptions {
            preset: Preset::ExoterPrl,
            seed: 3,
            training_runs: Some(1),
            training_run_secs: Some(90.0),
            test_max_secs: Some(60.0),
            format: SimulateFormat::Mcap,
            units: WheelUnits::default(),
            imu: true,
            camera: None,
        },
        &dir.join("mcap"),
    )
    .unwrap();
    let topics = dir.join("mcap/topics.yaml");
    let indented: String = std::fs::read_to_string(&topics)
        .unwrap()
        .lines()
        .map(|l| format!("    {l}\n"))
        .collect();
    let experiment = dir.join("bag.yaml");
    std::fs::write(
        &experiment,
        format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{indented}motion_model: {{kind: weighted_jacobian}}\nregressors:\n  - {{kind: exact_gp, kernel: rbf, hyperopt: {{max_iters: 15}}}}\n"
        ),
    )
    .unwrap();
    let model = dir.join("m.gpodo");
    let out = gpodo_quiet(&[
        "fit".as_ref(),
        experiment.as_os_str(),
        "--regressor".as_ref(),
        "exact GP: rbf [hyperopt.max_iters=15]".as_ref(),
        "--save".as_ref(),
        model.as_os_str(),
    ]);
    assert_succeeded(&out, "gpodo fit: ");
    let (mcap, rows, predictions) = (
        dir.join("out.mcap"),
        dir.join("rows.csv"),
        dir.join("p.csv"),
    );
    let live = |model: &Path| {
        gpodo_quiet(&[
            "live".as_ref(),
            "--model".as_ref(),
            model.as_os_str(),
            "--rover".as_ref(),
            exoter().as_os_str(),
            "--topics".as_ref(),
            topics.as_os_str(),
            "--replay".as_ref(),
            dir.join("mcap/test.mcap").as_os_str(),
            "--out".as_ref(),
            mcap.as_os_str(),
            "--rows".as_ref(),
            rows.as_os_str(),
        ])
    };
    let out = live(&model);
    assert_succeeded(&out, "gpodo live: ");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("750 joint states"), "{said}");
    let out = gpodo_quiet(&[
        "predict".as_ref(),
        "--model".as_ref(),
        model.as_os_str(),
        "--input".as_ref(),
        rows.as_os_str(),
        "--out".as_ref(),
        predictions.as_os_str(),
    ]);
    assert_succeeded(&out, "gpodo predict: ");

    let gp = bag_odometry(&mcap, "/odom/gp");
    let wheel = bag_odometry(&mcap, "/odom/wheel");
    assert_eq!(gp.len(), 750);
    assert_eq!(wheel.len(), gp.len());
    let text = std::fs::read_to_string(&predictions).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "mean_res_vx,mean_res_vy,mean_res_vz,var_res_vx,var_res_vy,var_res_vz"
    );
    let predicted: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // The first joint state has no finished step yet; every later one has
    // its row.
    assert_eq!(predicted.len(), gp.len() - 1);
    for (k, p) in predicted.iter().enumerate() {
        let (g, w) = (&gp[k + 1], &wheel[k + 1]);
        assert_eq!(g.header.stamp_ns, w.header.stamp_ns);
        for c in 0..3 {
            let correction = g.twist.linear[c] - w.twist.linear[c];
            let scale = w.twist.linear[c].abs().max(p[c].abs()).max(1e-9);
            assert!(
                (correction - p[c]).abs() <= 1e-12 * scale,
                "message {}, axis {c}: {correction} against {}",
                k + 1,
                p[c]
            );
            let variance = g.twist_covariance[c * 7];
            assert!(
                (variance - p[3 + c].max(1e-8)).abs() <= 1e-12 * variance,
                "message {}, axis {c}: variance {variance} against {}",
                k + 1,
                p[3 + c]
            );
        }
        assert!(g.twist_covariance.iter().step_by(7).all(|v| *v >= 1e-8));
    }

    // SIGINT and SIGTERM stop a replay at recorded speed cleanly: the
    // process exits successfully, says it stopped, and what it wrote is a
    // finished MCAP holding the first outputs of the full replay, unchanged.
    #[cfg(unix)]
    for signal in ["-INT", "-TERM"] {
        let stopped = dir.join(format!("stopped{signal}.mcap"));
        let (rover, test_bag) = (exoter(), dir.join("mcap/test.mcap"));
        let args: [&std::ffi::OsStr; 12] = [
            "--quiet".as_ref(),
            "live".as_ref(),
            "--model".as_ref(),
            model.as_os_str(),
            "--rover".as_ref(),
            rover.as_os_str(),
            "--topics".as_ref(),
            topics.as_os_str(),
            "--replay".as_ref(),
            test_bag.as_os_str(),
            "--out".as_ref(),
            stopped.as_os_str(),
        ];
        let child = Command::new(GPODO)
            .args(args)
            .arg("--realtime")
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_secs(4));
        let killed = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let out = child.wait_with_output().unwrap();
        assert_succeeded(
            &out,
            &format!("gpodo live, stopped by SIG{}: ", &signal[1..]),
        );
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            said.contains("stopped before the recording's end"),
            "{said}"
        );
        let kept = bag_odometry(&stopped, "/odom/gp");
        assert!(
            !kept.is_empty() && kept.len() < gp.len() / 2,
            "{} outputs kept of {}",
            kept.len(),
            gp.len()
        );
        assert_eq!(kept[..], gp[..kept.len()]);
    }

    // Without `--replay`, a build without the `ros2` feature says how to
    // get one.
    if !cfg!(feature = "ros2") {
        let out = gpodo_quiet(&[
            "live".as_ref(),
            "--model".as_ref(),
            model.as_os_str(),
            "--rover".as_ref(),
            exoter().as_os_str(),
            "--topics".as_ref(),
            topics.as_os_str(),
        ]);
        assert!(!out.status.success());
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(
            said.contains("built without ROS 2") && said.contains("--features ros2"),
            "{said}"
        );
    }

    // A model without its row recipe (as version 2 wrote them) is refused,
    // and nothing is written.
    let mut old: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    old.as_object_mut().unwrap().remove("rows");
    let old_model = dir.join("old.gpodo");
    std::fs::write(&old_model, old.to_string()).unwrap();
    std::fs::remove_file(&mcap).unwrap();
    let out = live(&old_model);
    assert!(!out.status.success());
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("old.gpodo") && said.contains("does not say how"),
        "{said}"
    );
    assert!(!mcap.exists());
}
