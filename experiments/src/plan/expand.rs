//! The steps of expanding a file's tree into runs: the sweep controls
//! taken out of the experiment, the swept dimensions, their Cartesian
//! product, and each combination (and replicate seed) made into a
//! validated [`RunSpec`].

use std::collections::{BTreeMap, HashMap};

use serde_json::Value;

use crate::config::{ExperimentConfig, Issue};
use crate::error::ConfigError;
use crate::plan::messages::{refine_path, split_serde_message, with_run};
use crate::plan::paths::{self, set_path};
use crate::plan::{Controls, Dimension, Located, RunSpec};

/// Keys of an experiment file that steer the sweep rather than describe an
/// experiment.
const CONTROL_KEYS: [&str; 6] = ["seed", "seeds", "sweep", "zip", "one_at_a_time", "outputs"];

/// Where each swept value is written in the file: (path, value index) →
/// the value's own path (`sweep.regressors[1].kernel[2]`).
pub(crate) type ValueSources = HashMap<(String, usize), String>;

/// Takes the sweep controls (`seed`, `seeds`, `sweep`, `zip`,
/// `one_at_a_time`, `outputs`) out of `tree`, leaving the experiment.
///
/// # Errors
/// [`ConfigError::Located`] for a malformed control.
pub(crate) fn split_controls(
    tree: &mut Value,
    located: &Located<'_>,
) -> Result<Controls, ConfigError> {
    let mut controls = serde_json::Map::new();
    if let Value::Object(map) = tree {
        for key in CONTROL_KEYS {
            if let Some(v) = map.remove(key) {
                controls.insert(key.to_string(), v);
            }
        }
    }
    serde_path_to_error::deserialize(Value::Object(controls)).map_err(|e| {
        let path = e.path().to_string();
        let (problem, expected) = split_serde_message(&e.inner().to_string(), &path);
        located.error(&path, problem, expected, false)
    })
}

/// The swept dimensions: each `sweep:` path, then each `zip:` group; and
/// where each of their values is written.
///
/// # Errors
/// [`ConfigError::Located`] for an empty sweep or group, lists of unequal
/// length in a group, or a malformed path.
pub(crate) fn dimensions(
    controls: &Controls,
    located: &Located<'_>,
) -> Result<(Vec<Dimension>, ValueSources), ConfigError> {
    let mut dimensions = Vec::new();
    let mut value_sources = ValueSources::new();
    let bad_path = |at: &str, e: String| {
        located.error(at, e, "a path such as `regressors[1].kernel`".into(), true)
    };
    if let Some(sweep) = &controls.sweep {
        if sweep.is_empty() {
            return Err(located.error(
                "sweep",
                "an empty sweep".into(),
                "at least one `path: [values]`".into(),
                false,
            ));
        }
        for (path, values) in sweep {
            let at = format!("sweep.{path}");
            if values.is_empty() {
                return Err(located.error(
                    &at,
                    format!("no values for `{path}`"),
                    "a non-empty list of values".into(),
                    false,
                ));
            }
            paths::parse_path(path).map_err(|e| bad_path(&at, e))?;
            for i in 0..values.len() {
                value_sources.insert((path.clone(), i), format!("{at}[{i}]"));
            }
            dimensions.push(Dimension {
                name: path.clone(),
                paths: vec![path.clone()],
                values: values.iter().map(|v| vec![v.clone()]).collect(),
                labels: None,
            });
        }
    }
    for (g, group) in controls.zip.iter().flatten().enumerate() {
        let name = group.keys().cloned().collect::<Vec<_>>().join(" & ");
        dimensions.push(group_dimension(
            name,
            &format!("zip[{g}]"),
            group,
            &mut value_sources,
            located,
        )?);
    }
    Ok((dimensions, value_sources))
}

/// The parameters of `one_at_a_time:`, each a dimension named by its
/// parameter (its paths varied together, element by element), and where
/// each of their values is written.
///
/// # Errors
/// [`ConfigError::Located`] for an empty parameter, lists of unequal
/// length, a malformed path, or `one_at_a_time` beside `sweep` or `zip`.
pub(crate) fn one_at_a_time(
    controls: &Controls,
    value_sources: &mut ValueSources,
    located: &Located<'_>,
) -> Result<Vec<Dimension>, ConfigError> {
    let Some(parameters) = &controls.one_at_a_time else {
        return Ok(Vec::new());
    };
    if controls.sweep.is_some() || controls.zip.is_some() {
        return Err(located.error(
            "one_at_a_time",
            "`one_at_a_time` beside `sweep` or `zip`".into(),
            "either a product of dimensions (`sweep`, `zip`) or one parameter at a time around the base"
                .into(),
            true,
        ));
    }
    if parameters.is_empty() {
        return Err(located.error(
            "one_at_a_time",
            "no parameter".into(),
            "at least one `name: {path: [values]}`".into(),
            false,
        ));
    }
    parameters
        .iter()
        .map(|(name, group)| {
            let at = format!("one_at_a_time.{name}");
            let mut paths = group.clone();
            let labels = paths.remove("label");
            let mut dimension = group_dimension(name.clone(), &at, &paths, value_sources, located)?;
            if let Some(labels) = labels {
                let names: Option<Vec<String>> = labels
                    .iter()
                    .map(|v| v.as_str().map(str::to_string))
                    .collect();
                match names {
                    Some(names) if names.len() == dimension.values.len() => {
                        dimension.labels = Some(names);
                    }
                    _ => {
                        return Err(located.error(
                            &format!("{at}.label"),
                            "labels that do not name the settings".into(),
                            format!(
                                "a list of {} strings, one per value",
                                dimension.values.len()
                            ),
                            false,
                        ));
                    }
                }
            }
            Ok(dimension)
        })
        .collect()
}

/// A dimension of paths varied together, element by element (a `zip`
/// group or a `one_at_a_time` parameter written at `at`).
fn group_dimension(
    name: String,
    at: &str,
    group: &BTreeMap<String, Vec<Value>>,
    value_sources: &mut ValueSources,
    located: &Located<'_>,
) -> Result<Dimension, ConfigError> {
    let lengths: Vec<usize> = group.values().map(Vec::len).collect();
    if group.is_empty() || lengths.contains(&0) {
        return Err(located.error(
            at,
            "an empty group".into(),
            "paths with non-empty lists of values".into(),
            false,
        ));
    }
    if lengths.iter().any(|&l| l != lengths[0]) {
        return Err(located.error(
            at,
            format!("lists of different lengths {lengths:?}"),
            "lists of one length (they are paired element by element)".into(),
            false,
        ));
    }
    for path in group.keys() {
        paths::parse_path(path).map_err(|e| {
            located.error(
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
    Ok(Dimension {
        name,
        paths: group.keys().cloned().collect(),
        values: (0..lengths[0])
            .map(|i| group.values().map(|list| list[i].clone()).collect())
            .collect(),
        labels: None,
    })
}

/// The Cartesian product of the dimensions' value indices, first dimension
/// outermost.
pub(crate) fn combinations(dimensions: &[Dimension]) -> Vec<Vec<usize>> {
    let mut combinations: Vec<Vec<usize>> = vec![Vec::new()];
    for d in dimensions {
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
    combinations
}

/// A key of `assignment` values: compact JSON, strings bare.
fn show(value: &Value) -> String {
    match value {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// One run: `tree` with the values of `combination` set, deserialised,
/// given the replicate's seed (`(replicate, derived seed)`) and validated.
/// Its `index` is left 0 for the caller to set.
///
/// # Errors
/// [`ConfigError::Located`] at the swept value or the file position of the
/// first problem.
pub(crate) fn expand_run(
    tree: &Value,
    dimensions: &[Dimension],
    combination: &[usize],
    seed: Option<(u64, u64)>,
    value_sources: &ValueSources,
    located: &Located<'_>,
) -> Result<RunSpec, ConfigError> {
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
                located.error(
                    &source,
                    e,
                    "a path to a value of the experiment".into(),
                    false,
                )
            })?;
            set_by.push((path.clone(), source));
        }
        let shown = match d.labels.as_ref().and_then(|l| l.get(i)) {
            Some(label) => label.clone(),
            None => d.values[i].iter().map(show).collect::<Vec<_>>().join(" & "),
        };
        key_parts.push(format!("{}={shown}", d.name));
        assignment.insert(d.name.clone(), shown);
    }
    if let Some((replicate, _)) = seed {
        key_parts.push(format!("seed={replicate}"));
    }
    let key = if key_parts.is_empty() {
        "base".to_string()
    } else {
        key_parts.join(", ")
    };
    let single = dimensions.is_empty() && seed.is_none();
    // The position of a path: the swept value that set it (or set a parent
    // of it), else where the files define it.
    let locate = |path: &str, problem: String, expected: String, prefer_key: bool| {
        let swept = set_by.iter().find(|(p, _)| {
            path == p || path.starts_with(&format!("{p}.")) || path.starts_with(&format!("{p}["))
        });
        let problem = with_run(problem, &key, single);
        match swept {
            Some((_, source)) => located.error(source, problem, expected, false),
            None => located.error(path, problem, expected, prefer_key),
        }
    };
    let snapshot = value.clone();
    let mut config: ExperimentConfig = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = refine_path(&snapshot, &e.path().to_string(), &e.inner().to_string());
        let message = e.inner().to_string();
        let unknown_field = message.starts_with("unknown field");
        let (problem, expected) = split_serde_message(&message, &path);
        // An unknown field's path ends at the field itself.
        locate(&path, problem, expected, unknown_field)
    })?;
    if let Some((_, s)) = seed {
        config = config.with_seed(s);
    }
    config.validate().map_err(
        |Issue {
             path,
             problem,
             expected,
         }| locate(&path, problem, expected, false),
    )?;
    Ok(RunSpec {
        index: 0,
        key,
        assignment,
        replicate: seed.map(|(r, _)| r),
        seed: seed.map(|(_, s)| s),
        config,
    })
}
