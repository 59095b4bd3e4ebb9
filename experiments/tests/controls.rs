//! The control rows of `paper.yaml` (what makes Table II a sound
//! experiment) share everything with the row they control but the named
//! difference, asserted from the resolved configuration.

use std::path::Path;

use gpodo_experiments::config::{ExperimentConfig, SchemeSpec};
use gpodo_frontends::SelectorSpec;
use gpodo_frontends::params::MotionPrior;
use gpodo_regressors::RegressorSpec;

fn paper() -> ExperimentConfig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("paper.yaml");
    match ExperimentConfig::from_path(&path) {
        Ok(c) => c,
        Err(e) => panic!("{e}"),
    }
}

/// A scheme's back end: its resolved tracking prior and its residual
/// source (the trained regressor's spec, or the online learner's).
fn back_end_of(config: &ExperimentConfig, s: &SchemeSpec) -> (MotionPrior, String) {
    let prior = s.motion_prior.unwrap_or(config.frontend.motion_prior);
    let source = match (&s.online, &s.odometry) {
        (Some(online), _) => format!(
            "online {}",
            serde_json::to_string(online).unwrap_or_default()
        ),
        (None, Some(odometry)) => format!(
            "odometry {}",
            serde_json::to_string(odometry).unwrap_or_default()
        ),
        (None, None) => {
            let labels = config.regressor_labels();
            let i = s.regressor_index(&labels).unwrap_or(usize::MAX);
            serde_json::to_string(&config.regressors[i]).unwrap_or_default()
        }
    };
    (prior, source)
}

fn fps(s: &SchemeSpec) -> Option<f64> {
    match s.selector {
        SelectorSpec::FixedRate { fps, .. } => Some(fps),
        _ => None,
    }
}

fn uses_zero(config: &ExperimentConfig, s: &SchemeSpec) -> bool {
    let labels = config.regressor_labels();
    s.online.is_none()
        && s.odometry.is_none()
        && s.regressor_index(&labels)
            .is_ok_and(|i| matches!(config.regressors[i], RegressorSpec::Zero { .. }))
}

#[test]
fn every_gated_scheme_has_fixed_rate_and_zero_residual_controls() {
    let config = paper();
    let gated: Vec<&SchemeSpec> = config
        .schemes
        .iter()
        .filter(|s| fps(s).is_none() && s.selector.same_as().is_none())
        .collect();
    assert!(gated.len() >= 8, "{} gated schemes", gated.len());
    for s in gated {
        let rates: Vec<f64> = config
            .schemes
            .iter()
            .filter(|f| back_end_of(&config, f) == back_end_of(&config, s))
            .filter_map(fps)
            .collect();
        for want in [2.5, 1.0, 0.5] {
            assert!(
                rates.contains(&want),
                "`{}`: no {want} fps row with its back end (has {rates:?})",
                s.label
            );
        }
        if uses_zero(&config, s) {
            continue;
        }
        let prior = back_end_of(&config, s).0;
        let control = config.schemes.iter().find(|c| {
            uses_zero(&config, c) && c.selector == s.selector && back_end_of(&config, c).0 == prior
        });
        assert!(
            control.is_some(),
            "`{}`: no row with its selector and prior on zero residuals",
            s.label
        );
    }
}

/// The curves of `table2-curves.yaml`: every curve is one back end with
/// one knob varied, every gated curve has a fixed-rate curve of its back
/// end reaching 2.5 fps (the reference of table (a)), every gated policy on
/// the GP has the same policies on zero residuals, and all runs share one
/// configuration but the seed.
#[test]
fn the_curves_file_pairs_each_policy_with_its_controls() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("table2-curves.yaml");
    let plan = match gpodo_experiments::plan::load_plan(&path) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    };
    assert!(plan.runs.len() >= 20, "{} seeds", plan.runs.len());
    let config = &plan.runs[0].config;
    for run in &plan.runs {
        let reseeded = run.config.clone().with_seed(0);
        assert_eq!(reseeded, config.clone().with_seed(0), "{}", run.key);
    }
    // The A/A control: each back end's fixed rate at 0.5 fps and at the
    // rate nearest 1000 frames against itself at a phase, outside the
    // curves.
    let pairs = config.phase_pairs();
    assert_eq!(pairs.len(), 4, "{pairs:?}");
    let in_pair = |i: usize| pairs.iter().any(|&(a, b)| a == i || b == i);
    let mut curves: Vec<(&str, Vec<&SchemeSpec>)> = Vec::new();
    for (i, s) in config.schemes.iter().enumerate() {
        let Some(name) = s.curve.as_deref() else {
            assert!(in_pair(i), "`{}` is on no curve", s.label);
            continue;
        };
        match curves.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.push(s),
            None => curves.push((name, vec![s])),
        }
    }
    assert!(curves.len() >= 8, "{} curves", curves.len());
    for (name, schemes) in &curves {
        assert!(schemes.len() >= 4, "`{name}`: {} points", schemes.len());
        let back_end = schemes[0].back_end(config);
        for s in schemes {
            assert_eq!(s.back_end(config), back_end, "`{}`", s.label);
            assert_eq!(back_end_of(config, s), back_end_of(config, schemes[0]));
        }
        let fixed: Vec<f64> = config
            .schemes
            .iter()
            .filter(|f| f.back_end(config) == back_end)
            .filter_map(fps)
            .collect();
        assert!(
            fixed.contains(&2.5),
            "`{name}`: no 2.5 fps with its back end"
        );
        let all_fixed = schemes.iter().all(|s| fps(s).is_some());
        if all_fixed {
            continue;
        }
        assert!(
            fixed.len() >= 5 && fixed.iter().any(|f| *f <= 0.2),
            "`{name}`: its back end's fixed rates {fixed:?} do not span 0.2–2.5 fps"
        );
        // The surrogate planner is the mechanism's bound, not a policy
        // whose regressor is under test: it has no zero-residual twin.
        let on_gp = schemes
            .iter()
            .all(|s| s.online.is_none() && !uses_zero(config, s) && s.selector.oracle().is_none());
        if on_gp {
            for s in schemes {
                let control = config
                    .schemes
                    .iter()
                    .find(|c| uses_zero(config, c) && c.selector == s.selector);
                assert!(control.is_some(), "`{}`: no zero-residual twin", s.label);
            }
        }
    }
}

/// The controls differ from their rows in frame selection only: the
/// paper's fixed-rate baselines track with the odometry prior, as the
/// authors' code did (the constant-velocity rows are extras and say so);
/// while lost, gated policies look every 0.4 s and fixed rates keep
/// theirs; no curve rescales keyframe thresholds.
#[test]
fn the_baselines_track_as_the_authors_did_and_differ_in_selection_only() {
    for file in ["paper.yaml", "table2-curves.yaml"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let plan = match gpodo_experiments::plan::load_plan(&path) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let config = &plan.runs[0].config;
        assert_eq!(config.frontend.lost_frame_period_secs, Some(0.4), "{file}");
        for s in &config.schemes {
            let prior = s.motion_prior.unwrap_or(config.frontend.motion_prior);
            let says_cv = s.label.contains("constant-velocity prior");
            assert_eq!(
                prior == MotionPrior::ConstantVelocity,
                says_cv,
                "{file}: `{}` tracks with {prior:?}",
                s.label
            );
            if s.label.starts_with("ORB-SLAM") && fps(s).is_some() && !says_cv {
                assert_eq!(prior, MotionPrior::Odometry, "{file}: `{}`", s.label);
            }
            if file == "table2-curves.yaml" {
                match &s.selector {
                    SelectorSpec::ResidualSchedule(p) => {
                        assert!(!p.scale_keyframes, "{file}: `{}` rescales", s.label);
                    }
                    SelectorSpec::Hysteresis {
                        alert_keyframe_scale,
                        ..
                    } => assert_eq!(*alert_keyframe_scale, 1.0, "{file}: `{}`", s.label),
                    _ => {}
                }
            }
        }
        // The report divides by the first scheme: the authors' baseline.
        assert_eq!(config.schemes[0].label, "ORB-SLAM 2.5 fps", "{file}");
        assert_eq!(fps(&config.schemes[0]), Some(2.5));
    }
}

/// The seeds and curves files drive a route per seed; the paper's run
/// keeps the paper's route.
#[test]
fn the_seeds_and_curves_files_draw_a_route_per_seed() {
    use gpodo_experiments::config::DatasetSpec;
    use gpodo_testbed::sim::route::Route;
    for (file, want) in [
        ("paper.yaml", Route::Paper),
        ("paper-seeds.yaml", Route::Random),
        ("table2-curves.yaml", Route::Random),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let plan = match gpodo_experiments::plan::load_plan(&path) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        for run in &plan.runs {
            match &run.config.dataset {
                DatasetSpec::Simulated { route, .. } => assert_eq!(*route, want, "{file}"),
                other => panic!("{file}: {other:?}"),
            }
        }
    }
}

/// The online learner's control: a front-loaded fixed schedule (dense
/// early, sparse late) with the learner's frames and its back end.
#[test]
fn the_online_learner_has_a_front_loaded_control_with_its_frames() {
    let config = paper();
    let learners: Vec<&SchemeSpec> = config
        .schemes
        .iter()
        .filter(|s| s.online.is_some() && fps(s).is_none() && s.selector.same_as().is_none())
        .collect();
    assert!(!learners.is_empty());
    for learner in learners {
        let control = config.schemes.iter().find(
            |c| matches!(&c.selector, SelectorSpec::FrontLoaded(p) if p.same_as == learner.label),
        );
        let Some(control) = control else {
            panic!("`{}`: no front-loaded control", learner.label);
        };
        assert_eq!(
            back_end_of(&config, control),
            back_end_of(&config, learner),
            "`{}`",
            control.label
        );
    }
}

/// The budget inside a selector, if any.
fn budget_of(spec: &SelectorSpec) -> Option<gpodo_frontends::gating::UncertaintyBudgetParams> {
    match spec {
        SelectorSpec::UncertaintyBudget(p) => Some(*p),
        SelectorSpec::MaxGap { inner, .. } | SelectorSpec::Hysteresis { inner, .. } => {
            budget_of(inner)
        }
        _ => None,
    }
}

/// Each scheme's odometry as `paper.yaml` resolves it: the authors' row
/// runs uncorrected with the |residual| GP's covariance, and every drift
/// budget counts the drift of the odometry its scheme's graph uses (the
/// corrected odometry's variance on gpodo's odometry).
#[test]
fn the_drift_budgets_count_the_odometry_the_graph_uses() {
    use gpodo_frontends::odometry_mode::OdometryMode;
    let config = paper();
    let labels = config.regressor_labels();
    let absolute = config.absolute_regressor_labels();
    let mode = |s: &SchemeSpec| {
        s.resolve_odometry(&labels, &absolute)
            .unwrap_or_else(|e| panic!("{}: {e:?}", s.label))
            .map(|r| r.mode)
            .unwrap_or_default()
    };
    let authors: Vec<&SchemeSpec> = config
        .schemes
        .iter()
        .filter(|s| mode(s) == OdometryMode::AUTHORS)
        .collect();
    assert!(
        authors.iter().any(|s| fps(s).is_none()),
        "no gated scheme on the authors' odometry"
    );
    let mut budgets = 0;
    for s in &config.schemes {
        let resolved = s.selector.for_odometry(&mode(s)).unwrap();
        if let Some(b) = budget_of(&resolved) {
            budgets += 1;
            assert_eq!(b.count_mean, Some(!mode(s).correct_mean), "{}", s.label);
        }
    }
    assert!(budgets >= 5, "{budgets} budgets");
}
