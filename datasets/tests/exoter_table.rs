//! Loads the authors' real ExoTeR GP training table (shared/data, see its
//! README) and checks the figures the README states. The file is part of the
//! repository's contract: if it is missing, this test fails.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_datasets::table::{TableSpec, read_residual_table, split_fraction, summarize_abs};

const TABLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/exoter_gp_train_1s.csv"
);

fn load() -> gpodo_traits::ResidualDataset {
    let path = Path::new(TABLE);
    assert!(
        path.is_file(),
        "the real ExoTeR table is missing at {TABLE}; it ships in shared/data beside the workspace"
    );
    let spec = TableSpec {
        inputs: None,
        targets: vec![
            "abs_err_vx".into(),
            "abs_err_vy".into(),
            "abs_err_vz".into(),
        ],
    };
    match read_residual_table(path, &spec) {
        Ok(data) => data,
        Err(e) => panic!("loading {TABLE}: {e}"),
    }
}

#[test]
fn loads_all_rows_inputs_and_targets() {
    let data = load();
    assert_eq!(data.len(), 2337);
    assert_eq!(data.inputs.ncols(), 28);
    assert_eq!(data.targets.ncols(), 3);
    assert_eq!(data.input_names[0], "roll");
    assert_eq!(data.input_names[27], "gyro_z");
}

#[test]
fn keeps_the_steering_logging_outlier() {
    let data = load();
    let j = data
        .input_names
        .iter()
        .position(|n| n == "pos_fl_steer")
        .unwrap();
    let max = data.inputs.column(j).into_iter().fold(f64::MIN, f64::max);
    assert!((max - 12.7).abs() < 0.05, "max pos_fl_steer = {max}");
}

#[test]
fn mean_abs_residuals_match_the_readme() {
    let data = load();
    let summary = summarize_abs(&data);
    let readme_mm_s = [4.1, 2.3, 2.0];
    for (s, expected) in summary.iter().zip(readme_mm_s) {
        println!(
            "{}: mean |y| = {:.3} mm/s, p95 |y| = {:.3} mm/s",
            s.name,
            s.mean_abs * 1e3,
            s.p95_abs * 1e3
        );
        assert!(
            (s.mean_abs - expected * 1e-3).abs() < 0.06e-3,
            "{}: mean |y| = {} m/s, README says {expected} mm/s",
            s.name,
            s.mean_abs
        );
    }
}

#[test]
fn standard_split_is_1869_train_and_468_test() {
    let data = load();
    let (train, test) = split_fraction(&data, 0.8).unwrap();
    assert_eq!((train.len(), test.len()), (1869, 468));
}

#[test]
fn simulated_residual_inputs_have_the_real_tables_columns() {
    // The residual dataset built from the ExoTeR-like rover's logs uses the
    // authors' column names, in their order, so a regressor trained on one
    // can be run on the other.
    let config = gpodo_testbed::sim::preset::SimulatorConfig {
        training_runs: 1,
        training_run_secs: 5.0,
        test_max_secs: 5.0,
        ..Default::default()
    };
    let testbed = config.simulate().unwrap();
    let names = gpodo_datasets::residuals::feature_names(&testbed.train[0]);
    assert_eq!(names, load().input_names);
}
