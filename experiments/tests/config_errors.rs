//! A corpus of malformed experiment files: each error names the file, the
//! line and column of the offending value, and the expected form; every run
//! of a sweep is validated before anything runs.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_experiments::plan::load_plan;

const GOOD: &str = "name: t
dataset: { kind: simulated, preset: exoter-prl, seed: 7 }
regressors:
  - kind: zero
  - kind: exact_gp
    kernel: rbf
";

fn error_of(dir: &Path, file: &str, text: &str) -> String {
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    match load_plan(&path) {
        Ok(plan) => panic!("{file} was accepted ({} runs)", plan.runs.len()),
        Err(e) => e.to_string(),
    }
}

/// Asserts `error` starts with `problem`, names `file:line:column`, and
/// ends with `; expected …` containing `expected`.
fn check(error: &str, problem: &str, file: &str, line: usize, column: usize, expected: &str) {
    assert!(
        error.starts_with(problem),
        "problem `{problem}` in: {error}"
    );
    let at = format!("{file}:{line}:{column}; expected ");
    assert!(
        error.contains(" at ") && error.contains(&at),
        "position `{at}` in: {error}"
    );
    let tail = error.split("; expected ").nth(1).unwrap_or("");
    assert!(tail.contains(expected), "expected `{expected}` in: {error}");
}

#[test]
fn the_good_file_loads_and_is_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.yaml");
    std::fs::write(&path, GOOD).unwrap();
    let plan = load_plan(&path).unwrap();
    assert_eq!(plan.runs.len(), 1);
    assert_eq!(plan.runs[0].key, "base");
}

#[test]
fn an_unknown_regressor_kind_names_its_position_and_the_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let text = GOOD.replace("kind: exact_gp", "kind: exactgp");
    let e = error_of(dir.path(), "paper.yaml", &text);
    let file = dir.path().join("paper.yaml");
    check(
        &e,
        "unknown regressor kind `exactgp`",
        &file.display().to_string(),
        5,
        11,
        "one of zero, exact_gp, sparse_gp, ilgr",
    );
}

#[test]
fn an_unknown_field_names_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = GOOD.replace("regressors:", "regresors:");
    let e = error_of(dir.path(), "x.yaml", &text);
    check(
        &e,
        "unknown field `regresors`",
        "x.yaml",
        3,
        1,
        "one of name,",
    );
    let text = GOOD.replace("    kernel: rbf", "    kernel: rbf\n    restart: 2");
    let e = error_of(dir.path(), "y.yaml", &text);
    check(&e, "unknown field `restart`", "y.yaml", 7, 5, "hyperopt");
}

#[test]
fn a_wrong_type_names_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let text = GOOD.replace("seed: 7", "seed: seven");
    let e = error_of(dir.path(), "x.yaml", &text);
    check(&e, "invalid type: string \"seven\"", "x.yaml", 2, 55, "u64");
}

#[test]
fn a_bad_kernel_expression_names_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let text = GOOD.replace("kernel: rbf", "kernel: rbf + + linear");
    let e = error_of(dir.path(), "x.yaml", &text);
    check(
        &e,
        "kernel expression `rbf + + linear`",
        "x.yaml",
        6,
        13,
        "a kernel name",
    );
}

#[test]
fn an_invalid_value_names_the_field_and_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = GOOD.replace(
        "    kernel: rbf",
        "    kernel: rbf\n    hyperopt:\n      max_iters: 0",
    );
    let e = error_of(dir.path(), "x.yaml", &text);
    check(
        &e,
        "invalid `hyperopt.max_iters` of exact_gp",
        "x.yaml",
        8,
        18,
        "at least 1",
    );
    let text = "name: t\ndataset: { kind: residual_table, path: x.csv, targets: [a], train_fraction: 1.5 }\nregressors: [{ kind: zero }]\n";
    let e = error_of(dir.path(), "y.yaml", text);
    check(
        &e,
        "training fraction 1.5",
        "y.yaml",
        2,
        77,
        "a fraction in (0, 1)",
    );
}

#[test]
fn scoring_windows_must_match_the_training_rows() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{GOOD}residuals: {{ window_secs: 2.0, score_window_secs: 1.0 }}\n");
    let e = error_of(dir.path(), "w.yaml", &text);
    check(
        &e,
        "invalid `residuals.score_window_secs`",
        "w.yaml",
        7,
        51,
        "`window_secs: null`",
    );
    let text = format!(
        "{GOOD}residuals: {{ window_secs: null, score_window_secs: 1.0 }}\nabsolute_regressors: [{{ kind: zero }}]\n"
    );
    let e = error_of(dir.path(), "a.yaml", &text);
    assert!(e.contains("absolute_regressors"), "{e}");
}

#[test]
fn sweeps_are_checked_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Empty sweep, empty list, empty seeds.
    let e = error_of(d, "a.yaml", &format!("{GOOD}sweep: {{}}\n"));
    check(&e, "an empty sweep", "a.yaml", 7, 8, "at least one");
    let e = error_of(
        d,
        "b.yaml",
        &format!("{GOOD}sweep:\n  regressors[1].kernel: []\n"),
    );
    check(
        &e,
        "no values for `regressors[1].kernel`",
        "b.yaml",
        8,
        25,
        "non-empty list",
    );
    let e = error_of(d, "c.yaml", &format!("{GOOD}seeds: []\n"));
    check(
        &e,
        "an empty list of seeds",
        "c.yaml",
        7,
        8,
        "at least one seed",
    );
    // A path past the end of a list.
    let e = error_of(
        d,
        "d.yaml",
        &format!("{GOOD}sweep:\n  regressors[5].kernel: [rbf]\n"),
    );
    check(
        &e,
        "path `regressors[5].kernel`: index 5 is out of range",
        "d.yaml",
        8,
        26,
        "a path",
    );
    // One bad value among good ones: the position is that value's.
    let e = error_of(
        d,
        "e.yaml",
        &format!("{GOOD}sweep:\n  regressors[1].kernel: [rbf, rbf + +, matern52]\n"),
    );
    assert!(e.contains("run `regressors[1].kernel=rbf + +`"), "{e}");
    check(
        &e,
        "kernel expression `rbf + +`",
        "e.yaml",
        8,
        31,
        "a kernel name",
    );
    // A bad value deep in a swept selector.
    let schemes = "schemes:\n  - label: a\n    selector: { kind: fixed_rate, fps: 2.5 }\n";
    let e = error_of(
        d,
        "f.yaml",
        &format!("{GOOD}{schemes}sweep:\n  schemes[0].selector.fps: [1.0, -2.0]\n"),
    );
    check(
        &e,
        "invalid `fps` of selector fixed_rate",
        "f.yaml",
        11,
        34,
        "a positive frame rate",
    );
    // Zip lists of different lengths.
    let e = error_of(
        d,
        "g.yaml",
        &format!(
            "{GOOD}zip:\n  - regressors[1].kernel: [rbf, matern52]\n    regressors[1].hyperopt.restarts: [0]\n"
        ),
    );
    check(
        &e,
        "lists of different lengths",
        "g.yaml",
        8,
        5,
        "one length",
    );
}

#[test]
fn schemes_and_selectors_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let e = error_of(
        d,
        "a.yaml",
        &format!("{GOOD}schemes:\n  - label: a\n    selector: {{ kind: fixed }}\n"),
    );
    check(
        &e,
        "unknown selector kind `fixed`",
        "a.yaml",
        9,
        23,
        "one of fixed_rate, residual_schedule",
    );
    let e = error_of(
        d,
        "b.yaml",
        &format!(
            "{GOOD}schemes:\n  - label: a\n    regressor: exact GP\n    selector: {{ kind: residual_schedule }}\n"
        ),
    );
    check(
        &e,
        "unknown regressor",
        "b.yaml",
        9,
        16,
        "one of `regressors`: `parametric only`, `exact GP: rbf`",
    );
}

/// An online scheme learns one way: in batches of seconds, or refitted
/// every so many targets, and a batch spans a positive time.
#[test]
fn an_online_schemes_batches_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let online = |fields: &str| {
        format!(
            "{GOOD}schemes:\n  - label: a\n    online: {{ regressor: {{ kind: streaming_sparse_gp }}, {fields} }}\n    selector: {{ kind: uncertainty_budget, count_mean: false }}\n"
        )
    };
    let path = dir.path().join("ok.yaml");
    std::fs::write(&path, online("batch_secs: 60.0")).unwrap();
    load_plan(&path).unwrap();
    for (file, fields, problem, expected) in [
        (
            "both.yaml",
            "refit_every: 5, batch_secs: 60.0",
            "both `refit_every` and `batch_secs`",
            "either `refit_every` or `batch_secs`, not both",
        ),
        (
            "zero.yaml",
            "batch_secs: 0.0",
            "a batch of 0 s",
            "a positive, finite number of seconds",
        ),
    ] {
        let text = online(fields);
        let e = error_of(dir.path(), file, &text);
        let line = text.lines().position(|l| l.contains("batch_secs")).unwrap();
        let column =
            text.lines().nth(line).unwrap().find("batch_secs").unwrap() + "batch_secs: ".len();
        check(&e, problem, file, line + 1, column + 1, expected);
    }
    // A regressor that is only refitted cannot learn online.
    let text = online("batch_secs: 60.0").replace("streaming_sparse_gp", "sparse_gp");
    let e = error_of(dir.path(), "batch.yaml", &text);
    let line = text.lines().position(|l| l.contains("sparse_gp")).unwrap();
    let column = text.lines().nth(line).unwrap().find("sparse_gp").unwrap();
    check(
        &e,
        "`sparse_gp`, which cannot learn online",
        "batch.yaml",
        line + 1,
        column + 1,
        "or `refit_every`",
    );
}

/// A scheme's `odometry`: the regressors it names exist in their lists, it
/// does not come with `regressor` or `online`, and a drift budget's
/// explicit `count_mean` agrees with it.
#[test]
fn a_schemes_odometry_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let with_absolute =
        format!("{GOOD}absolute_regressors:\n  - kind: exact_gp\n    kernel: rbf\n");
    let scheme = |odometry: &str, selector: &str| {
        format!(
            "{with_absolute}schemes:\n  - label: a\n    odometry: {odometry}\n    selector: {selector}\n"
        )
    };
    let authors = "{ mean: none, covariance: { absolute: 0 } }";
    // Loads: the authors' odometry with a budget left to follow it, and
    // with one that states the same.
    for selector in [
        "{ kind: uncertainty_budget }",
        "{ kind: uncertainty_budget, count_mean: true }",
    ] {
        let path = d.join("ok.yaml");
        std::fs::write(&path, scheme(authors, selector)).unwrap();
        load_plan(&path).unwrap();
    }
    // The authors' odometry is uncorrected: a budget of the variance alone
    // contradicts it.
    let e = error_of(
        d,
        "c.yaml",
        &scheme(
            authors,
            "{ kind: max_gap, inner: { kind: uncertainty_budget, count_mean: false } }",
        ),
    );
    check(
        &e,
        "invalid `inner.count_mean`",
        "c.yaml",
        13,
        79,
        "true (or no value) for odometry uncorrected, |residual|² covariance",
    );
    // And a corrected odometry with a budget of the uncorrected error.
    let e = error_of(
        d,
        "d.yaml",
        &format!(
            "{GOOD}schemes:\n  - label: a\n    regressor: 1\n    selector: {{ kind: uncertainty_budget, count_mean: true }}\n"
        ),
    );
    check(
        &e,
        "invalid `count_mean`",
        "d.yaml",
        10,
        55,
        "false (or no value)",
    );
    // An absolute index into `regressors`' list is out of range there.
    let e = error_of(
        d,
        "e.yaml",
        &scheme(
            "{ mean: none, covariance: { absolute: 3 } }",
            "{ kind: residual_schedule }",
        ),
    );
    check(
        &e,
        "regressor index 3 out of range",
        "e.yaml",
        12,
        53,
        "an index into `absolute_regressors` (0..1)",
    );
    let e = error_of(
        d,
        "f.yaml",
        &scheme(
            "{ mean: exact GP, covariance: { variance: 1 } }",
            "{ kind: residual_schedule }",
        ),
    );
    check(
        &e,
        "unknown regressor `exact GP`",
        "f.yaml",
        12,
        23,
        "one of `regressors`",
    );
    let e = error_of(
        d,
        "g.yaml",
        &format!(
            "{with_absolute}schemes:\n  - label: a\n    regressor: 1\n    odometry: {authors}\n    selector: {{ kind: residual_schedule }}\n"
        ),
    );
    check(
        &e,
        "both `regressor` and `odometry`",
        "g.yaml",
        13,
        15,
        "either `regressor`",
    );
}

#[test]
fn a_missing_base_and_a_base_chain_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let e = error_of(d, "a.yaml", "base: nowhere.yaml\nname: x\n");
    check(
        &e,
        "base file `nowhere.yaml` not found",
        "a.yaml",
        1,
        7,
        "an experiment file",
    );
    std::fs::write(d.join("good.yaml"), GOOD).unwrap();
    // A file extending a good one inherits everything; its own error is its own.
    let e = error_of(
        d,
        "b.yaml",
        "base: good.yaml\nname: b\nregressors:\n  - kind: zero\n    variance: -1\n",
    );
    check(
        &e,
        "invalid `variance` of zero",
        "b.yaml",
        5,
        15,
        "a positive variance",
    );
    // The base's error positions stay in the base.
    std::fs::write(d.join("bad-base.yaml"), GOOD.replace("seed: 7", "seed: -7")).unwrap();
    let e = error_of(d, "c.yaml", "base: bad-base.yaml\nname: c\n");
    assert!(e.contains("bad-base.yaml:2:"), "{e}");
}

#[test]
fn the_trackers_error_model_and_terrain_fields_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let with_vo = |vo: &str| {
        format!(
            "{GOOD}frontend:\n  vo: {{ kind: simulated, {vo} }}\nschemes:\n  - {{ label: a, selector: {{ kind: fixed_rate, fps: 1.0 }} }}\n"
        )
    };
    let file = dir.path().join("vo.yaml");
    let file = file.display().to_string();
    let e = error_of(dir.path(), "vo.yaml", &with_vo("error_model: sharde"));
    check(
        &e,
        "unknown error_model `sharde`",
        &file,
        8,
        39,
        "shared or independent",
    );
    let e = error_of(dir.path(), "vo.yaml", &with_vo("map_error_share: 1.5"));
    check(
        &e,
        "invalid `vo.map_error_share`",
        &file,
        8,
        43,
        "a fraction in [0, 1]",
    );
    let e = error_of(dir.path(), "vo.yaml", &with_vo("features_per_frame: -3"));
    check(
        &e,
        "invalid `vo.features_per_frame`",
        &file,
        8,
        46,
        "a positive number",
    );
    let e = error_of(
        dir.path(),
        "vo.yaml",
        &with_vo("camera: { exposure_secs: 2.0 }"),
    );
    check(
        &e,
        "invalid `vo.camera.exposure_secs`",
        &file,
        8,
        51,
        "an exposure time in [0, 1] s",
    );
}

#[test]
fn every_shipped_experiment_file_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut loaded = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "yaml") {
            let plan = load_plan(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(!plan.runs.is_empty(), "{}", path.display());
            loaded += 1;
        }
    }
    assert!(loaded >= 15, "{loaded} files");
}

/// `one_at_a_time`: the base, then each value of each parameter alone (its
/// paths set together), every other value as in the base; beside `sweep`
/// it is an error.
#[test]
fn one_parameter_at_a_time_runs_the_base_then_each_value_alone() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("oat.yaml");
    let text = format!(
        "{GOOD}seeds: [1, 2]\none_at_a_time:\n  noise:\n    regressors[1].noise_variance: [0.1, 0.2]\n  kernel:\n    label: [fixed matern]\n    regressors[1].kernel: [matern52]\n    regressors[1].optimize: [false]\n"
    );
    std::fs::write(&path, &text).unwrap();
    let plan = load_plan(&path).unwrap();
    let keys: Vec<&str> = plan.runs.iter().map(|r| r.key.as_str()).collect();
    assert_eq!(
        keys,
        [
            "seed=1",
            "seed=2",
            "kernel=fixed matern, seed=1",
            "kernel=fixed matern, seed=2",
            "noise=0.1, seed=1",
            "noise=0.1, seed=2",
            "noise=0.2, seed=1",
            "noise=0.2, seed=2",
        ]
    );
    let gp = |i: usize| serde_json::to_value(&plan.runs[i].config.regressors[1]).unwrap();
    assert_eq!(gp(0)["kernel"], "rbf");
    assert_eq!(gp(2)["kernel"], "matern52");
    assert_eq!(gp(2)["optimize"], false);
    assert_eq!(gp(2)["noise_variance"], gp(0)["noise_variance"]);
    assert_eq!(gp(4)["noise_variance"], 0.1);
    assert_eq!(gp(4)["kernel"], "rbf");
    // The same seed, the same data in every setting.
    assert_eq!(plan.runs[0].seed, plan.runs[6].seed);
    let e = error_of(
        dir.path(),
        "both.yaml",
        &format!("{text}sweep:\n  regressors[1].kernel: [rbf]\n"),
    );
    check(
        &e,
        "`one_at_a_time` beside `sweep` or `zip`",
        "both.yaml",
        8,
        1,
        "either",
    );
}

#[test]
fn an_optimiser_setting_at_the_top_of_a_gp_names_its_place_in_hyperopt() {
    let dir = tempfile::tempdir().unwrap();
    for (kind, key, value) in [
        ("exact_gp", "max_iters", "30"),
        ("exact_gp", "bounds", "{ variance: [1.0e-3, 10.0] }"),
        ("sparse_gp", "restarts", "2"),
    ] {
        let text = GOOD.replace(
            "  - kind: exact_gp\n    kernel: rbf",
            &format!("  - kind: {kind}\n    kernel: rbf\n    {key}: {value}"),
        );
        let e = error_of(dir.path(), "x.yaml", &text);
        check(
            &e,
            &format!("unknown field `{key}`"),
            "x.yaml",
            7,
            5,
            &format!("hyperopt.{key}"),
        );
    }
    // ILGR has no `hyperopt:` block: its unknown field is only unknown.
    let text = GOOD.replace(
        "kind: exact_gp\n    kernel: rbf",
        "kind: ilgr\n    max_iters: 3",
    );
    let e = error_of(dir.path(), "y.yaml", &text);
    assert!(!e.contains("hyperopt"), "{e}");
    // In the block, the setting is read.
    let text = GOOD.replace(
        "    kernel: rbf",
        "    kernel: rbf\n    hyperopt: { max_iters: 30 }",
    );
    let path = dir.path().join("z.yaml");
    std::fs::write(&path, text).unwrap();
    assert!(load_plan(&path).is_ok());
}

#[test]
fn a_ground_truth_of_the_wrong_shape_names_the_shapes_it_takes() {
    let dir = tempfile::tempdir().unwrap();
    let text = "name: t\ndataset:\n  kind: bags\n  train: [a.mcap]\n  topics:\n    imu: /imu\n    ground_truth: {topic: /mocap/pose}\nregressors: [{ kind: zero }]\n";
    let e = error_of(dir.path(), "x.yaml", text);
    assert!(
        e.contains("x.yaml:")
            && e.contains("ground_truth: /mocap/pose")
            && e.contains("a TF chain"),
        "{e}"
    );
}
