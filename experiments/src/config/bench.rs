//! The `bench:` section of an experiment file: settings of `gpodo bench`.

use serde::{Deserialize, Serialize};

/// The `bench:` section of an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BenchSettings {
    /// Test rows predicted one at a time to time a single query (default
    /// 300; all test rows when there are fewer).
    pub predict_queries: usize,
    /// Learning-curve step of online learners, in training samples
    /// (default 100).
    pub learning_curve_every: usize,
    /// Index (in `regressors`) of the baseline row; omitted, the first
    /// `exact_gp`.
    pub baseline: Option<usize>,
    /// The prequential protocol (omitted: not run): the training stream
    /// cut into `blocks` in time order, the baseline refitted on blocks
    /// 1…k−1 to predict block k, each online learner predicting every
    /// sample before learning it.
    pub prequential: Option<PrequentialSettings>,
}

/// Where the prequential protocol's refits of an exact GP start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RefitStart {
    /// The start policy alone, as a first fit (a cold start).
    Cold,
    /// The previous refit's optimum alone (a warm start); `cold_checks`
    /// refits are also fitted cold, for the record.
    Warm,
    /// Both on every refit, the higher log marginal likelihood kept
    /// (default): the warm start alone keeps to its optimum's basin.
    Best,
}

/// Settings of the prequential protocol.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrequentialSettings {
    /// Blocks the training stream is cut into, in time order (default 10;
    /// blocks 2…K are scored).
    pub blocks: usize,
    /// Where an exact-GP baseline's refits start (default `best`).
    pub refit_start: RefitStart,
    /// With `refit_start: warm`, the refits (evenly spaced, the last
    /// included) beside which a cold fit on the same prefix records whether
    /// the start policy finds a higher log marginal likelihood (default 2).
    pub cold_checks: usize,
}

impl Default for PrequentialSettings {
    fn default() -> Self {
        Self {
            blocks: 10,
            refit_start: RefitStart::Best,
            cold_checks: 2,
        }
    }
}

impl Default for BenchSettings {
    fn default() -> Self {
        Self {
            predict_queries: 300,
            learning_curve_every: 100,
            baseline: None,
            prequential: None,
        }
    }
}

impl BenchSettings {
    /// Checks the fields against the experiment's regressors.
    ///
    /// # Errors
    /// The offending field (under `bench.`) and what it expects.
    pub fn validate(&self, regressors: usize) -> Result<(), (String, String)> {
        if self.predict_queries == 0 {
            return Err(("predict_queries".into(), "at least 1".into()));
        }
        if self.learning_curve_every == 0 {
            return Err(("learning_curve_every".into(), "at least 1".into()));
        }
        if let Some(b) = self.baseline
            && b >= regressors
        {
            return Err((
                "baseline".into(),
                format!("an index into `regressors` (0..{regressors}), found {b}"),
            ));
        }
        if let Some(p) = self.prequential
            && p.blocks < 2
        {
            return Err((
                "prequential.blocks".into(),
                "at least 2 blocks (block 1 is only learned from)".into(),
            ));
        }
        Ok(())
    }
}
