//! The experiment file: what data, which motion model, how residuals are
//! formed, which regressors, which SLAM schemes. Unknown fields are errors,
//! and every error names the file, line and column (the loader in
//! [`crate::plan`] turns an [`Issue`]'s path into a position).
//!
//! ```yaml
//! name: paper
//! dataset: { kind: simulated, preset: exoter-prl, seed: 7 }
//! motion_model: { kind: weighted_jacobian }
//! residuals: { window_secs: 1.0 }
//! regressors:
//!   - kind: zero
//! ```
//!
//! This is the first stage of the crate: it imports no other module of it
//! but the error types.

pub mod bench;
pub mod gate;
pub mod paths;
pub mod schemes;
mod validate;
pub mod verdict;

use std::path::PathBuf;

use gpodo_datasets::residuals::ResidualConfig;
use gpodo_frontends::FrontendParams;
use gpodo_frontends::params::VoSpec;
pub use gpodo_kinematics::spec::{AttitudeWithoutImu, MotionModelSpec};
use gpodo_regressors::RegressorSpec;
use gpodo_testbed::sim::preset::Preset;
use serde::{Deserialize, Serialize};

pub use bench::{BenchSettings, PrequentialSettings, RefitStart};
pub use schemes::SchemeSpec;
pub use validate::Issue;
pub use verdict::{Comparison, Margins, Measure, VerdictRules};

/// A whole experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentConfig {
    /// Name; results go to `results/<name>/` unless told otherwise.
    pub name: String,
    /// Free text shown at the top of the report.
    #[serde(default)]
    pub description: Option<String>,
    /// Where the data come from.
    pub dataset: DatasetSpec,
    /// The parametric motion model (ignored for residual tables).
    #[serde(default)]
    pub motion_model: MotionModelSpec,
    /// How log steps become residual rows (ignored for residual tables).
    #[serde(default)]
    pub residuals: ResidualConfig,
    /// Regressors to train and evaluate, in report order.
    pub regressors: Vec<RegressorSpec>,
    /// Regressors trained on |residual| targets (the authors' GP), whose
    /// prediction a scheme's `odometry.covariance` may take as the
    /// odometry's standard deviation. Labelled `|residual| <label>`; scored
    /// against |residual| on the test rows, outside Table I.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub absolute_regressors: Vec<RegressorSpec>,
    /// A residual table (e.g. the authors' real ExoTeR data) whose
    /// statistics the report shows beside this experiment's, to judge how
    /// close a simulated testbed is to the real rover. Skipped with a warning
    /// when the file is missing.
    #[serde(default)]
    pub compare_with: Option<ReferenceTable>,
    /// Settings of `gpodo bench` (ignored by `gpodo run`).
    #[serde(default)]
    pub bench: BenchSettings,
    /// The visual front end of Table II (visual odometry, keyframes, back
    /// end); every field has a default.
    #[serde(default)]
    pub frontend: FrontendParams,
    /// The SLAM schemes of Table II, run on every test run (needs rover
    /// logs: `simulated` or `logs` data).
    #[serde(default)]
    pub schemes: Vec<SchemeSpec>,
    /// The margin ε of the verdict "equivalent" (m): a paired Δ RMSE whose
    /// 95 % interval lies within ±ε, across zero, is equivalent to its
    /// comparison. Committed before the runs it judges; without it the
    /// verdict has no "equivalent".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equivalence_margin_m: Option<f64>,
    /// The rules of Table II's verdict (policies judged, primary and
    /// secondary comparisons, margins), committed before the runs they
    /// judge; the sweep report applies them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<VerdictRules>,
}

/// A reference residual table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceTable {
    /// CSV file (relative to the experiment file).
    pub path: PathBuf,
    /// Its target columns.
    pub targets: Vec<String>,
}

/// Where the data come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DatasetSpec {
    /// The built-in simulated testbed.
    Simulated {
        /// Preset (`exoter-prl`).
        preset: Preset,
        /// Seed of every random draw.
        seed: u64,
        /// Override of the preset's number of training runs.
        #[serde(default)]
        training_runs: Option<usize>,
        /// Override of the preset's training run duration (s).
        #[serde(default)]
        training_run_secs: Option<f64>,
        /// Override of the longest the test traverse may take (s); a shorter
        /// value cuts the traverse (quick runs, tests).
        #[serde(default)]
        test_max_secs: Option<f64>,
        /// The test traverse's route: `paper` (the fixed 42.3 m route,
        /// default), `random` (drawn per seed with the same length and
        /// terrain statistics) or `sandy_slopes` (drawn per seed with the
        /// same length and a quarter of it or more on sand at 5° or more).
        #[serde(default)]
        route: gpodo_testbed::sim::route::Route,
        /// Slip bursts on loose ground (`testbed/src/sim/slip/bursts.rs`;
        /// `{}` takes every default); none when unset.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        slip_bursts: Option<gpodo_testbed::sim::slip::SlipBursts>,
        /// Override of the preset's motion-capture jitter per frame (m), the
        /// white noise of the ground-truth positions: differenced over one
        /// 80-ms step it is most of a per-step residual's noise, over a 1-s
        /// window a twelfth of it.
        #[serde(default)]
        mocap_jitter_m: Option<f64>,
        /// Override of the preset's camera rate (Hz; 10): the stream every
        /// scheme picks its frames from. The authors' adaptive SLAM read a
        /// 2.5 Hz stream; a rendered camera renders each frame a scheme
        /// picks, so the image files use it.
        #[serde(default)]
        camera_rate_hz: Option<f64>,
    },
    /// Rover logs in gpodo's trajectory CSV format (paths relative to the
    /// experiment file).
    Logs {
        /// Training runs.
        train: Vec<PathBuf>,
        /// Test runs.
        test: Vec<PathBuf>,
    },
    /// ROS bags (MCAP or ROS 1; paths relative to the experiment file),
    /// each turned into a rover log through the topic map as `gpodo
    /// import` does (`datasets/README.md`, "ROS bags").
    Bags {
        /// Training recordings.
        train: Vec<PathBuf>,
        /// Test recordings (may be empty when `train_fraction` holds out
        /// the end of each training recording).
        #[serde(default)]
        test: Vec<PathBuf>,
        /// Cut every training recording in time: the first fraction of it
        /// trains, the rest is a test run.
        #[serde(default)]
        train_fraction: Option<f64>,
        /// Which topic plays which role, the clock rate and the longest gap
        /// bridged.
        topics: Box<gpodo_datasets::bags::import::TopicMap>,
    },
    /// A residual table (features and targets already computed), split in
    /// time order.
    ResidualTable {
        /// CSV file (relative to the experiment file).
        path: PathBuf,
        /// Input columns; omitted, every column that is not a target.
        #[serde(default)]
        inputs: Option<Vec<String>>,
        /// Target columns.
        targets: Vec<String>,
        /// Fraction of rows (the first ones) used for training.
        train_fraction: f64,
    },
}

impl ExperimentConfig {
    /// The same experiment with a replicate's seed given to every random
    /// draw it configures: the simulated testbed and the simulated visual
    /// odometry (data read from files keep theirs).
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        if let DatasetSpec::Simulated { seed: s, .. } = &mut self.dataset {
            *s = seed;
        }
        if let VoSpec::Simulated(p) = &mut self.frontend.vo {
            p.seed = seed;
        }
        self
    }

    /// The A/A pairs among the schemes: each fixed rate with a phase
    /// (`phase_secs > 0`) and the first scheme of the same rate without
    /// one and of the same back end, as (unshifted, shifted) indices. Both
    /// process as many frames, none in common: what separates them is the
    /// comparison's floor.
    pub fn phase_pairs(&self) -> Vec<(usize, usize)> {
        let rate = |s: &SchemeSpec| match s.selector {
            gpodo_frontends::SelectorSpec::FixedRate { fps, phase_secs } => Some((fps, phase_secs)),
            _ => None,
        };
        let mut pairs = Vec::new();
        for (shifted, spec) in self.schemes.iter().enumerate() {
            let Some((fps, phase)) = rate(spec) else {
                continue;
            };
            if phase <= 0.0 {
                continue;
            }
            let back_end = spec.back_end(self);
            let unshifted = self.schemes.iter().position(|other| {
                rate(other) == Some((fps, 0.0)) && other.back_end(self) == back_end
            });
            if let Some(unshifted) = unshifted {
                pairs.push((unshifted, shifted));
            }
        }
        pairs
    }

    /// The labels of the regressors, as reports print them.
    pub fn regressor_labels(&self) -> Vec<String> {
        self.regressors.iter().map(RegressorSpec::label).collect()
    }

    /// The labels of the |residual| regressors, as reports print them.
    pub fn absolute_regressor_labels(&self) -> Vec<String> {
        self.absolute_regressors
            .iter()
            .map(schemes::absolute_label)
            .collect()
    }
}
