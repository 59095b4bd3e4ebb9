//! Declarative sweeps: an experiment file may extend another (`base:`),
//! vary any value over a list (`sweep:`, Cartesian product), vary several
//! together (`zip:`), and repeat every combination over seeds (`seeds:`).
//! [`load_plan`] reads a file into the list of concrete runs, each a full
//! [`ExperimentConfig`], and validates all of them before anything runs;
//! every error names the file, line and column of the offending value and
//! what was expected.
//!
//! ```yaml
//! name: ablation-kernels
//! base: paper.yaml                 # everything not given here comes from it
//! sweep:                           # one run per combination
//!   regressors[1].kernel: [rbf, matern52, rbf + linear, matern52 + linear]
//! zip:                             # lists varied together
//!   - { regressors[1].hyperopt.restarts: [0, 2], regressors[1].hyperopt.max_iters: [200, 400] }
//! seeds: [1, 2, 3]                 # every combination, three times
//! ```
//!
//! Or, instead of `sweep` and `zip`, one parameter at a time around the
//! base (a sensitivity analysis): the base runs, then each value of each
//! named parameter with everything else as in the base.
//!
//! ```yaml
//! one_at_a_time:
//!   map_error_share: { frontend.vo.map_error_share: [0.0, 1.0] }
//!   camera:                          # paths set together; `label` names
//!     label: [bumblebee2]            # the settings in keys and reports
//!     frontend.vo.camera.focal_px: [838.0]
//!     frontend.vo.search_radius_px: [7.0]
//! ```
//!
//! A run's key names its values (`regressors[1].kernel=rbf, seed=2`); its
//! seed is derived from the sweep's `seed` and the key's seed, so a run's
//! numbers do not depend on which other runs exist or in what order they
//! run, and runs of the same seed share their data (paired comparisons).

//!
//! This is the second stage of the crate: it reads files into
//! [`ExperimentConfig`]s and imports nothing from the stages after it.
//! [`load_plan`] runs its steps in order: `tree::read_tree` (the file and
//! its `base:` chain, with positions), `expand::split_controls`,
//! `expand::dimensions`, `expand::combinations`, then
//! `expand::expand_run` for each combination and seed (set the swept
//! values, deserialise, seed with [`ExperimentConfig::with_seed`],
//! validate).

mod expand;
pub mod gate;
pub mod locate;
mod messages;
pub mod paths;
mod tree;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::config::ExperimentConfig;
use crate::error::ConfigError;
use locate::Position;
use tree::{Provenance, read_tree};

/// What a sweep writes besides `runs.jsonl` and the report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Outputs {
    /// Write each run's detailed report, metrics, trajectories and figures
    /// (default: only when the sweep is a single run, then at the results
    /// folder itself).
    pub run_details: Option<bool>,
    /// Draw the figures (default true).
    pub plots: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Self {
            run_details: None,
            plots: true,
        }
    }
}

/// The sweep controls of a file.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Controls {
    #[serde(default)]
    pub(crate) seed: u64,
    #[serde(default)]
    pub(crate) seeds: Option<Vec<u64>>,
    #[serde(default)]
    pub(crate) sweep: Option<BTreeMap<String, Vec<Value>>>,
    #[serde(default)]
    pub(crate) zip: Option<Vec<BTreeMap<String, Vec<Value>>>>,
    #[serde(default)]
    pub(crate) one_at_a_time: Option<BTreeMap<String, BTreeMap<String, Vec<Value>>>>,
    #[serde(default)]
    pub(crate) outputs: Outputs,
}

/// One swept dimension: a path (or a `zip` group of paths) and its values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dimension {
    /// The name reports use: the path, or the zip group's paths joined by
    /// ` & `.
    pub name: String,
    /// The paths it sets.
    pub paths: Vec<String>,
    /// Its values: one list per setting, one value per path.
    pub values: Vec<Vec<Value>>,
    /// A name per setting for keys and reports (a `one_at_a_time`
    /// parameter's `label:` list); `None`, the values themselves.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub labels: Option<Vec<String>>,
}

/// One concrete run of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSpec {
    /// Position in the plan.
    pub index: usize,
    /// Identity: the swept values and the seed, `path=value, …, seed=s`.
    pub key: String,
    /// The swept values, by dimension name (compact JSON).
    pub assignment: BTreeMap<String, String>,
    /// The replicate seed from `seeds:`, if the sweep has any.
    pub replicate: Option<u64>,
    /// The seed the run's data and visual odometry were given (derived from
    /// the sweep seed and the replicate), if `seeds:` is used.
    pub seed: Option<u64>,
    /// The resolved experiment (every path in it absolute).
    pub config: ExperimentConfig,
}

/// A file expanded into its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPlan {
    /// The experiment file.
    pub file: PathBuf,
    /// The sweep's name (the results folder).
    pub name: String,
    /// The sweep seed.
    pub seed: u64,
    /// The swept dimensions, in product order.
    pub dimensions: Vec<Dimension>,
    /// Whether `seeds:` repeats the runs.
    pub replicates: Vec<u64>,
    /// Outputs.
    pub outputs: Outputs,
    /// The runs, in plan order.
    pub runs: Vec<RunSpec>,
}

/// SplitMix64.
pub fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of replicate `replicate` of a sweep seeded with `sweep_seed`
/// (below 2⁵³, so it survives a round trip through JSON numbers).
pub fn run_seed(sweep_seed: u64, replicate: u64) -> u64 {
    mix(mix(sweep_seed) ^ replicate) >> 11
}

/// Where the values of a file came from, for errors that point at them.
pub(crate) struct Located<'a> {
    file: &'a Path,
    provenance: Provenance,
}

impl Located<'_> {
    /// An error at `path`: the file, line and column that define the value
    /// (or its key, with `prefer_key`).
    pub(crate) fn error(
        &self,
        path: &str,
        problem: String,
        expected: String,
        prefer_key: bool,
    ) -> ConfigError {
        let (f, pos) = self
            .provenance
            .find(path, prefer_key)
            .unwrap_or_else(|| (self.file.to_path_buf(), Position::default()));
        ConfigError::Located {
            file: f,
            line: pos.line,
            column: pos.column,
            path: path.to_string(),
            problem,
            expected,
        }
    }
}

/// Reads `file` and expands it into its runs, all validated.
///
/// # Errors
/// [`ConfigError`] naming the file, line and column of the first problem.
pub fn load_plan(file: &Path) -> Result<SweepPlan, ConfigError> {
    load_plan_with(file, None, None)
}

/// [`load_plan`] with what a caller of the library may change: `text` read
/// as if it were `file` (an experiment given as a Python dict; `file` need
/// not exist, and `base:` and relative paths are resolved from its
/// folder), and `seeds` in place of the file's `seeds:` list.
///
/// # Errors
/// As [`load_plan`]; an error in `text` names `file` and the key's path.
pub fn load_plan_with(
    file: &Path,
    text: Option<&str>,
    seeds: Option<&[u64]>,
) -> Result<SweepPlan, ConfigError> {
    let mut provenance = Provenance::default();
    let mut tree = match text {
        Some(text) => tree::tree_of_text(file, text, 0, &mut provenance)?,
        None => read_tree(file, 0, &mut provenance)?,
    };
    if let (Some(seeds), serde_json::Value::Object(map)) = (seeds, &mut tree) {
        map.insert("seeds".into(), seeds.iter().copied().collect());
    }
    let located = Located { file, provenance };
    let controls = expand::split_controls(&mut tree, &located)?;
    let (mut dimensions, mut value_sources) = expand::dimensions(&controls, &located)?;
    let one_at_a_time = expand::one_at_a_time(&controls, &mut value_sources, &located)?;
    let replicates = controls.seeds.clone().unwrap_or_default();
    if controls.seeds.as_ref().is_some_and(Vec::is_empty) {
        return Err(located.error(
            "seeds",
            "an empty list of seeds".into(),
            "at least one seed, or no `seeds:`".into(),
            false,
        ));
    }
    let seeds: Vec<Option<u64>> = if replicates.is_empty() {
        vec![None]
    } else {
        replicates.iter().copied().map(Some).collect()
    };
    // Each setting: the dimensions it sets and its value index in each.
    let settings: Vec<(Vec<Dimension>, Vec<usize>)> = if one_at_a_time.is_empty() {
        expand::combinations(&dimensions)
            .into_iter()
            .map(|c| (dimensions.clone(), c))
            .collect()
    } else {
        // The base, then each parameter's values alone.
        std::iter::once((Vec::new(), Vec::new()))
            .chain(
                one_at_a_time
                    .iter()
                    .flat_map(|d| (0..d.values.len()).map(move |i| (vec![d.clone()], vec![i]))),
            )
            .collect()
    };
    dimensions.extend(one_at_a_time);
    let base_dir = file
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .to_path_buf();
    let mut runs = Vec::with_capacity(settings.len() * seeds.len());
    for (setting_dimensions, combination) in &settings {
        for &replicate in &seeds {
            let run = expand::expand_run(
                &tree,
                setting_dimensions,
                combination,
                replicate.map(|r| (r, run_seed(controls.seed, r))),
                &value_sources,
                &located,
            )?;
            runs.push(RunSpec {
                index: runs.len(),
                config: run.config.with_paths_resolved(&base_dir),
                ..run
            });
        }
    }
    let name = runs
        .first()
        .map(|r| r.config.name.clone())
        .unwrap_or_default();
    Ok(SweepPlan {
        file: file.to_path_buf(),
        name,
        seed: controls.seed,
        dimensions,
        replicates,
        outputs: controls.outputs,
        runs,
    })
}

impl ExperimentConfig {
    /// Reads and validates an experiment file that describes one run (a
    /// file with `base:` is fine; one with `sweep:` or several `seeds:` is
    /// not).
    ///
    /// # Errors
    /// [`ConfigError`] naming the file, line and column.
    pub fn from_path(path: &Path) -> Result<Self, ConfigError> {
        let plan = load_plan(path)?;
        let runs = plan.runs.len();
        match <[RunSpec; 1]>::try_from(plan.runs) {
            Ok([run]) => Ok(run.config),
            Err(_) => Err(ConfigError::NotSingle {
                path: path.to_path_buf(),
                runs,
            }),
        }
    }
}

/// What `plan.json` holds: enough for `gpodo report` to tell missing and
/// duplicate runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanFile {
    /// The sweep's name.
    pub name: String,
    /// The experiment file.
    pub file: PathBuf,
    /// The sweep seed.
    pub seed: u64,
    /// The swept dimensions.
    pub dimensions: Vec<Dimension>,
    /// The replicate seeds.
    pub replicates: Vec<u64>,
    /// Every run's key, in plan order.
    pub keys: Vec<String>,
    /// How many shards the folder's runs are sliced into, as the first
    /// shard recorded it (none for an unsharded sweep).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shards: Option<usize>,
}

impl PlanFile {
    /// The plan file of `plan`.
    pub fn new(plan: &SweepPlan) -> Self {
        Self {
            name: plan.name.clone(),
            file: plan.file.clone(),
            seed: plan.seed,
            dimensions: plan.dimensions.clone(),
            replicates: plan.replicates.clone(),
            keys: plan.runs.iter().map(|r| r.key.clone()).collect(),
            shards: None,
        }
    }
}
