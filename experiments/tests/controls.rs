//! The control rows of `paper.yaml` (issue: Table II as a sound
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
fn back_end(config: &ExperimentConfig, s: &SchemeSpec) -> (MotionPrior, String) {
    let prior = s.motion_prior.unwrap_or(config.frontend.motion_prior);
    let source = match &s.online {
        Some(online) => format!(
            "online {}",
            serde_json::to_string(online).unwrap_or_default()
        ),
        None => {
            let labels = config.regressor_labels();
            let i = s.regressor_index(&labels).unwrap_or(usize::MAX);
            serde_json::to_string(&config.regressors[i]).unwrap_or_default()
        }
    };
    (prior, source)
}

fn fps(s: &SchemeSpec) -> Option<f64> {
    match s.selector {
        SelectorSpec::FixedRate { fps } => Some(fps),
        _ => None,
    }
}

fn uses_zero(config: &ExperimentConfig, s: &SchemeSpec) -> bool {
    let labels = config.regressor_labels();
    s.online.is_none()
        && s.regressor_index(&labels)
            .is_ok_and(|i| matches!(config.regressors[i], RegressorSpec::Zero { .. }))
}

#[test]
fn every_gated_scheme_has_fixed_rate_and_zero_residual_controls() {
    let config = paper();
    let gated: Vec<&SchemeSpec> = config
        .schemes
        .iter()
        .filter(|s| fps(s).is_none() && s.selector.oracle().is_none())
        .collect();
    assert!(gated.len() >= 8, "{} gated schemes", gated.len());
    for s in gated {
        let rates: Vec<f64> = config
            .schemes
            .iter()
            .filter(|f| back_end(&config, f) == back_end(&config, s))
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
        let prior = back_end(&config, s).0;
        let control = config.schemes.iter().find(|c| {
            uses_zero(&config, c) && c.selector == s.selector && back_end(&config, c).0 == prior
        });
        assert!(
            control.is_some(),
            "`{}`: no row with its selector and prior on zero residuals",
            s.label
        );
    }
}
