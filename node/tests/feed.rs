//! The feed's IMU hold: a joint state gets the latest IMU reading stamped
//! at or before it, whatever order the two topics' messages arrive in;
//! and the diagnostics' percentiles and warnings.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_datasets::bags::write::DiagnosticStatus;
use gpodo_node::diagnostics::{Health, percentile};
use gpodo_node::feed::Fed;
use gpodo_node::pipeline::{LiveOutput, LiveSettings, ModelSummary};
use gpodo_traits::BodyTwist;
use nalgebra::Isometry3;

#[test]
fn percentiles_are_nearest_rank() {
    let v: Vec<f64> = (1..=100).map(f64::from).collect();
    assert_eq!(percentile(&v, 50.0), Some(50.0));
    assert_eq!(percentile(&v, 99.0), Some(99.0));
    assert_eq!(percentile(&v, 100.0), Some(100.0));
    assert_eq!(percentile(&[3.0], 99.0), Some(3.0));
    assert_eq!(percentile(&[], 50.0), None);
    // Order does not matter.
    let mut r = v.clone();
    r.reverse();
    assert_eq!(percentile(&r, 99.0), Some(99.0));
}

fn fed(imu_age_secs: Option<f64>, out_of_range: &[&str]) -> Fed {
    Fed {
        stamp_ns: 0,
        imu_age_secs,
        output: LiveOutput {
            time_secs: 0.0,
            row: None,
            covered_secs: 0.0,
            inputs: Vec::new(),
            uncorrected: BodyTwist::default(),
            twist: BodyTwist::default(),
            variance: [1.0; 6],
            pose: Isometry3::identity(),
            pose_covariance: [0.0; 36],
            uncorrected_pose: Isometry3::identity(),
            out_of_range: out_of_range.iter().map(|s| s.to_string()).collect(),
            residual: None,
        },
    }
}

fn value<'a>(s: &'a DiagnosticStatus, key: &str) -> &'a str {
    &s.values.iter().find(|(k, _)| k == key).unwrap().1
}

#[test]
fn diagnostics_warn_of_a_stale_imu_and_inputs_out_of_range_once() {
    let model = ModelSummary {
        kind: "exact_gp".into(),
        label: "exact GP: rbf".into(),
        training_rows: 1869,
    };
    let settings = LiveSettings::default();
    let mut health = Health::default();
    for k in 1..=200 {
        health.output(&fed(Some(0.01), &[]), f64::from(k) * 1e-5);
    }
    let ok = health.report("n", &model, &settings, Some(0.02));
    assert_eq!(ok.level, 0, "{ok:?}");
    assert_eq!(value(&ok, "latency p50 (ms)"), "1.000");
    assert_eq!(value(&ok, "latency p99 (ms)"), "1.980");
    assert_eq!(value(&ok, "training rows"), "1869");
    assert_eq!(value(&ok, "last input age (s)"), "0.020");

    health.output(&fed(Some(0.8), &["gyro_z"]), 1e-4);
    health.skipped("3 s: no joint `w1`".into());
    let warn = health.report("n", &model, &settings, Some(0.02));
    assert_eq!(warn.level, 1);
    assert!(warn.message.contains("stale IMU"), "{}", warn.message);
    assert!(warn.message.contains("gyro_z"), "{}", warn.message);
    assert_eq!(value(&warn, "inputs not used"), "1");
    // The warnings cover one report's period.
    let again = health.report("n", &model, &settings, Some(0.02));
    assert_eq!(again.level, 0, "{again:?}");
}
