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
//!   - { regressors[1].restarts: [0, 2], regressors[1].max_iters: [200, 400] }
//! seeds: [1, 2, 3]                 # every combination, three times
//! ```
//!
//! A run's key names its values (`regressors[1].kernel=rbf, seed=2`); its
//! seed is derived from the sweep's `seed` and the key's seed, so a run's
//! numbers do not depend on which other runs exist or in what order they
//! run, and runs of the same seed share their data (paired comparisons).

pub mod locate;
pub mod paths;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::config::{ConfigError, ExperimentConfig, Issue};
use locate::{Locator, Position, join_key};
use paths::{merge, set_path};

/// Keys of an experiment file that steer the sweep rather than describe an
/// experiment.
const CONTROL_KEYS: [&str; 5] = ["seed", "seeds", "sweep", "zip", "outputs"];

/// Longest chain of `base:` files.
const MAX_BASE_DEPTH: usize = 8;

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
struct Controls {
    #[serde(default)]
    seed: u64,
    #[serde(default)]
    seeds: Option<Vec<u64>>,
    #[serde(default)]
    sweep: Option<BTreeMap<String, Vec<Value>>>,
    #[serde(default)]
    zip: Option<Vec<BTreeMap<String, Vec<Value>>>>,
    #[serde(default)]
    outputs: Outputs,
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
    /// The resolved experiment.
    pub config: ExperimentConfig,
}

/// A file expanded into its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPlan {
    /// The experiment file.
    pub file: PathBuf,
    /// Its folder: relative paths in every run are resolved against it.
    pub base_dir: PathBuf,
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

/// Where the values of the merged tree came from.
#[derive(Debug, Default)]
struct Provenance {
    files: Vec<PathBuf>,
    values: HashMap<String, (usize, Position)>,
    keys: HashMap<String, (usize, Position)>,
}

impl Provenance {
    fn add_file(&mut self, file: &Path, locator: &Locator, shadowed: &[String]) {
        let index = self.files.len();
        self.files.push(file.to_path_buf());
        // Lists and scalars of the new file replace the base's entirely.
        for prefix in shadowed {
            let (dot, bracket) = (format!("{prefix}."), format!("{prefix}["));
            self.values
                .retain(|k, _| !(k.starts_with(&dot) || k.starts_with(&bracket)));
            self.keys
                .retain(|k, _| !(k.starts_with(&dot) || k.starts_with(&bracket)));
        }
        for (path, pos) in locator.values() {
            self.values.insert(path.clone(), (index, *pos));
        }
        for (path, pos) in locator.keys() {
            self.keys.insert(path.clone(), (index, *pos));
        }
    }

    /// The file and position of `path` (or of the nearest parent known).
    fn find(&self, path: &str, prefer_key: bool) -> Option<(PathBuf, Position)> {
        let mut p = path.to_string();
        let first = if prefer_key { self.keys.get(&p) } else { None };
        if let Some((f, pos)) = first {
            return Some((self.files[*f].clone(), *pos));
        }
        loop {
            if let Some((f, pos)) = self.values.get(&p).or_else(|| self.keys.get(&p)) {
                return Some((self.files[*f].clone(), *pos));
            }
            let cut = p.rfind(['.', '['])?;
            p.truncate(cut);
        }
    }
}

/// Paths of the non-mapping values of `value` (the ones that replace a
/// base's wholesale when overlaid).
fn replaced_paths(value: &Value, prefix: &str, out: &mut Vec<String>) {
    if let Value::Object(map) = value {
        for (k, v) in map {
            let path = join_key(prefix, k);
            if v.is_object() {
                replaced_paths(v, &path, out);
            } else {
                out.push(path);
            }
        }
    }
}

fn read_tree(file: &Path, depth: usize, provenance: &mut Provenance) -> Result<Value, ConfigError> {
    let text = std::fs::read_to_string(file).map_err(|source| ConfigError::Io {
        path: file.to_path_buf(),
        source,
    })?;
    let mut value: Value = serde_saphyr::from_str(&text).map_err(|e| ConfigError::Parse {
        path: file.to_path_buf(),
        detail: e.to_string(),
    })?;
    let locator = Locator::new(&text);
    let located = |path: &str, problem: String, expected: String| {
        let pos = locator.find(path).unwrap_or_default();
        ConfigError::Located {
            file: file.to_path_buf(),
            line: pos.line,
            column: pos.column,
            path: path.to_string(),
            problem,
            expected,
        }
    };
    let Value::Object(map) = &mut value else {
        return Err(located(
            "",
            "the file is not a mapping".into(),
            "an experiment: `name:`, `dataset:`, `regressors:` …".into(),
        ));
    };
    let base = map.remove("base");
    let mut merged = match base {
        None => Value::Object(Default::default()),
        Some(Value::String(b)) => {
            if depth >= MAX_BASE_DEPTH {
                return Err(located(
                    "base",
                    format!("more than {MAX_BASE_DEPTH} `base:` files in a chain"),
                    "a shorter chain (a file extending itself?)".into(),
                ));
            }
            let dir = file.parent().unwrap_or_else(|| Path::new("."));
            let base_file = dir.join(&b);
            if !base_file.is_file() {
                return Err(located(
                    "base",
                    format!("base file `{b}` not found"),
                    format!("an experiment file (relative to {})", dir.display()),
                ));
            }
            read_tree(&base_file, depth + 1, provenance)?
        }
        Some(other) => {
            return Err(located(
                "base",
                format!("`base: {other}`"),
                "the path of the experiment file this one extends".into(),
            ));
        }
    };
    let mut shadowed = Vec::new();
    replaced_paths(&value, "", &mut shadowed);
    provenance.add_file(file, &locator, &shadowed);
    merge(&mut merged, value);
    Ok(merged)
}

/// Turns a serde message into (problem, expected): `unknown variant `x`,
/// expected one of `a`, `b`` → (`unknown <what> `x``, `one of a, b`).
fn split_serde_message(message: &str, path: &str) -> (String, String) {
    let message = message.trim();
    let (problem, expected) = match message.split_once(", expected ") {
        Some((p, e)) => (p.to_string(), e.replace('`', "")),
        None => match message.split_once(" expected ") {
            Some((p, e)) => (
                p.trim_end_matches([',', ':', ';']).to_string(),
                e.replace('`', ""),
            ),
            None => (
                message.to_string(),
                "a value of the documented form (experiments/README.md)".to_string(),
            ),
        },
    };
    let what =
        if path.ends_with("selector") || path.contains("selector.") || path.ends_with("inner") {
            "selector kind"
        } else if path.starts_with("regressors") || path.contains(".regressor") {
            "regressor kind"
        } else if path.starts_with("dataset") {
            "dataset kind"
        } else if path.contains("vo") {
            "visual odometry kind"
        } else if path.starts_with("motion_model") {
            "motion model kind"
        } else {
            "variant"
        };
    let problem = problem.replace("unknown variant", &format!("unknown {what}"));
    (problem, expected)
}

/// A key of `assignment` values: compact JSON, strings bare.
fn show(value: &Value) -> String {
    match value {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Reads `file` and expands it into its runs, all validated.
///
/// # Errors
/// [`ConfigError`] naming the file, line and column of the first problem.
pub fn load_plan(file: &Path) -> Result<SweepPlan, ConfigError> {
    let mut provenance = Provenance::default();
    let mut tree = read_tree(file, 0, &mut provenance)?;
    let located = |path: &str, problem: String, expected: String, prefer_key: bool| {
        let (f, pos) = provenance
            .find(path, prefer_key)
            .unwrap_or_else(|| (file.to_path_buf(), Position::default()));
        ConfigError::Located {
            file: f,
            line: pos.line,
            column: pos.column,
            path: path.to_string(),
            problem,
            expected,
        }
    };
    // Separate the sweep controls from the experiment.
    let mut controls_value = serde_json::Map::new();
    if let Value::Object(map) = &mut tree {
        for key in CONTROL_KEYS {
            if let Some(v) = map.remove(key) {
                controls_value.insert(key.to_string(), v);
            }
        }
    }
    let controls: Controls = serde_path_to_error::deserialize(Value::Object(controls_value))
        .map_err(|e| {
            let path = e.path().to_string();
            let (problem, expected) = split_serde_message(&e.inner().to_string(), &path);
            located(&path, problem, expected, false)
        })?;
    // Dimensions: each `sweep:` path, then each `zip:` group.
    let mut dimensions = Vec::new();
    // Where each swept value is written: (path, value index) → sweep path.
    let mut value_sources: HashMap<(String, usize), String> = HashMap::new();
    if let Some(sweep) = &controls.sweep {
        if sweep.is_empty() {
            return Err(located(
                "sweep",
                "an empty sweep".into(),
                "at least one `path: [values]`".into(),
                false,
            ));
        }
        for (path, values) in sweep {
            let at = format!("sweep.{path}");
            if values.is_empty() {
                return Err(located(
                    &at,
                    format!("no values for `{path}`"),
                    "a non-empty list of values".into(),
                    false,
                ));
            }
            paths::parse_path(path).map_err(|e| {
                located(&at, e, "a path such as `regressors[1].kernel`".into(), true)
            })?;
            for i in 0..values.len() {
                value_sources.insert((path.clone(), i), format!("{at}[{i}]"));
            }
            dimensions.push(Dimension {
                name: path.clone(),
                paths: vec![path.clone()],
                values: values.iter().map(|v| vec![v.clone()]).collect(),
            });
        }
    }
    if let Some(groups) = &controls.zip {
        for (g, group) in groups.iter().enumerate() {
            let at = format!("zip[{g}]");
            let lengths: Vec<usize> = group.values().map(Vec::len).collect();
            if group.is_empty() || lengths.contains(&0) {
                return Err(located(
                    &at,
                    "an empty zip group".into(),
                    "paths with non-empty lists of values".into(),
                    false,
                ));
            }
            if lengths.iter().any(|&l| l != lengths[0]) {
                return Err(located(
                    &at,
                    format!("lists of different lengths {lengths:?}"),
                    "lists of one length (they are paired element by element)".into(),
                    false,
                ));
            }
            for path in group.keys() {
                paths::parse_path(path).map_err(|e| {
                    located(
                        &format!("{at}.{path}"),
                        e,
                        "a path such as `regressors[1].kernel`".into(),
                        true,
                    )
                })?;
                for i in 0..lengths[0] {
                    value_sources.insert((path.clone(), i), format!("{at}.{path}[{i}]"));
                }
            }
            dimensions.push(Dimension {
                name: group.keys().cloned().collect::<Vec<_>>().join(" & "),
                paths: group.keys().cloned().collect(),
                values: (0..lengths[0])
                    .map(|i| group.values().map(|list| list[i].clone()).collect())
                    .collect(),
            });
        }
    }
    let replicates = controls.seeds.clone().unwrap_or_default();
    if controls.seeds.as_ref().is_some_and(Vec::is_empty) {
        return Err(located(
            "seeds",
            "an empty list of seeds".into(),
            "at least one seed, or no `seeds:`".into(),
            false,
        ));
    }
    // The Cartesian product, first dimension outermost, seeds innermost.
    let mut combinations: Vec<Vec<usize>> = vec![Vec::new()];
    for d in &dimensions {
        combinations = combinations
            .into_iter()
            .flat_map(|c| {
                (0..d.values.len()).map(move |i| {
                    let mut next = c.clone();
                    next.push(i);
                    next
                })
            })
            .collect();
    }
    let seeds: Vec<Option<u64>> = if replicates.is_empty() {
        vec![None]
    } else {
        replicates.iter().copied().map(Some).collect()
    };
    let base_dir = file
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .to_path_buf();
    let mut runs = Vec::with_capacity(combinations.len() * seeds.len());
    for combination in &combinations {
        for &replicate in &seeds {
            let mut value = tree.clone();
            let mut assignment = BTreeMap::new();
            let mut key_parts = Vec::new();
            // Which swept path set which value (for error positions).
            let mut set_by: Vec<(String, String)> = Vec::new();
            for (d, &i) in dimensions.iter().zip(combination) {
                for (path, v) in d.paths.iter().zip(&d.values[i]) {
                    let source = value_sources
                        .get(&(path.clone(), i))
                        .cloned()
                        .unwrap_or_else(|| format!("sweep.{path}"));
                    set_path(&mut value, path, v.clone()).map_err(|e| {
                        located(
                            &source,
                            e,
                            "a path to a value of the experiment".into(),
                            false,
                        )
                    })?;
                    set_by.push((path.clone(), source));
                }
                let shown: Vec<String> = d.values[i].iter().map(show).collect();
                assignment.insert(d.name.clone(), shown.join(" & "));
                key_parts.push(format!("{}={}", d.name, shown.join(" & ")));
            }
            let seed = replicate.map(|r| run_seed(controls.seed, r));
            if let Some(s) = seed {
                apply_seed(&mut value, s);
                key_parts.push(format!("seed={}", replicate.unwrap_or_default()));
            }
            let key = if key_parts.is_empty() {
                "base".to_string()
            } else {
                key_parts.join(", ")
            };
            // The position of a path: the swept value that set it (or set a
            // parent of it), else where the files define it.
            let locate = |path: &str, problem: String, expected: String, prefer_key: bool| {
                let swept = set_by.iter().find(|(p, _)| {
                    path == p
                        || path.starts_with(&format!("{p}."))
                        || path.starts_with(&format!("{p}["))
                });
                match swept {
                    Some((_, source)) => located(source, problem, expected, false),
                    None => located(path, problem, expected, prefer_key),
                }
            };
            let snapshot = value.clone();
            let config: ExperimentConfig =
                serde_path_to_error::deserialize(value).map_err(|e| {
                    let path =
                        refine_path(&snapshot, &e.path().to_string(), &e.inner().to_string());
                    let message = e.inner().to_string();
                    let unknown_field = message.starts_with("unknown field");
                    let (problem, expected) = split_serde_message(&message, &path);
                    // An unknown field's path ends at the field itself.
                    locate(
                        &path,
                        with_run(problem, &key, dimensions.is_empty() && seed.is_none()),
                        expected,
                        unknown_field,
                    )
                })?;
            config.validate().map_err(
                |Issue {
                     path,
                     problem,
                     expected,
                 }| {
                    locate(
                        &path,
                        with_run(problem, &key, dimensions.is_empty() && seed.is_none()),
                        expected,
                        false,
                    )
                },
            )?;
            runs.push(RunSpec {
                index: runs.len(),
                key,
                assignment,
                replicate,
                seed,
                config,
            });
        }
    }
    let name = runs
        .first()
        .map(|r| r.config.name.clone())
        .unwrap_or_default();
    Ok(SweepPlan {
        file: file.to_path_buf(),
        base_dir,
        name,
        seed: controls.seed,
        dimensions,
        replicates,
        outputs: controls.outputs,
        runs,
    })
}

/// The value at `path` in `root`.
fn value_at<'a>(root: &'a Value, path: &str) -> Option<&'a Value> {
    let mut node = root;
    for segment in paths::parse_path(path).ok()? {
        node = match segment {
            paths::Segment::Key(k) => node.get(&k)?,
            paths::Segment::Index(i) => node.get(i)?,
        };
    }
    Some(node)
}

/// Serde stops its path at an internally tagged enum (it buffers the
/// variant's fields): when the message quotes one of the fields' values
/// (`` `rbf + + linear` ``, `"seven"`), the path of that field.
fn refine_path(root: &Value, path: &str, message: &str) -> String {
    fn search(node: &Value, path: &str, message: &str, depth: usize) -> Option<String> {
        let Value::Object(map) = node else {
            return None;
        };
        for (k, v) in map {
            let here = join_key(path, k);
            let quoted = match v {
                Value::String(s) => [format!("`{s}`"), format!("\"{s}\"")]
                    .iter()
                    .any(|q| message.contains(q.as_str())),
                Value::Number(n) => message.contains(&format!("`{n}`")),
                _ => false,
            };
            if quoted && k != "kind" {
                return Some(here);
            }
            if depth > 0
                && let Some(found) = search(v, &here, message, depth - 1)
            {
                return Some(found);
            }
        }
        None
    }
    if let Some(field) = message
        .strip_prefix("unknown field `")
        .and_then(|rest| rest.split('`').next())
        && value_at(root, path).is_some_and(|node| node.get(field).is_some())
    {
        return join_key(path, field);
    }
    value_at(root, path)
        .and_then(|node| search(node, path, message, 2))
        .unwrap_or_else(|| path.to_string())
}

/// Names the run in a problem when the file has several.
fn with_run(problem: String, key: &str, single: bool) -> String {
    if single {
        problem
    } else {
        format!("{problem} (run `{key}`)")
    }
}

/// Gives a replicate's seed to the simulated data and visual odometry.
fn apply_seed(value: &mut Value, seed: u64) {
    let Value::Object(root) = value else {
        return;
    };
    if let Some(Value::Object(dataset)) = root.get_mut("dataset")
        && dataset.get("kind").and_then(Value::as_str) == Some("simulated")
    {
        dataset.insert("seed".into(), Value::from(seed));
    }
    let frontend = root
        .entry("frontend")
        .or_insert_with(|| Value::Object(Default::default()));
    if let Value::Object(frontend) = frontend {
        let vo = frontend
            .entry("vo")
            .or_insert_with(|| serde_json::json!({"kind": "simulated"}));
        if let Value::Object(vo) = vo
            && vo.get("kind").and_then(Value::as_str) == Some("simulated")
        {
            vo.insert("seed".into(), Value::from(seed));
        }
    }
}
