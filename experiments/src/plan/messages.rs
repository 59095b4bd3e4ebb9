//! Serde's messages and paths turned into the loader's (problem, expected)
//! pairs and the path of the value at fault.

use serde_json::Value;

use crate::plan::locate::join_key;
use crate::plan::paths;

/// Turns a serde message into (problem, expected): `unknown variant `x`,
/// expected one of `a`, `b`` → (`unknown <what> `x``, `one of a, b`).
pub(crate) fn split_serde_message(message: &str, path: &str) -> (String, String) {
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
    let field = path.rsplit('.').next().unwrap_or(path);
    let what =
        if path.ends_with("selector") || path.contains("selector.") || path.ends_with("inner") {
            "selector kind"
        } else if path.starts_with("regressors") || path.contains(".regressor") {
            "regressor kind"
        } else if path.starts_with("dataset") {
            "dataset kind"
        } else if path.ends_with(".vo") || path.ends_with(".vo.kind") {
            "visual odometry kind"
        } else if path.starts_with("motion_model") {
            "motion model kind"
        } else if !field.is_empty() && field.chars().all(|c| c.is_ascii_lowercase() || c == '_') {
            field
        } else {
            "variant"
        };
    let problem = problem.replace("unknown variant", &format!("unknown {what}"));
    (
        problem.clone(),
        moved_setting(&problem, &expected).unwrap_or(expected),
    )
}

/// For an unknown GP field that is one of the optimiser's settings (the
/// fields the message expects include `hyperopt`), where it belongs now.
fn moved_setting(problem: &str, expected: &str) -> Option<String> {
    let field = problem.strip_prefix("unknown field `")?.split('`').next()?;
    let listed = |name: &str| expected.split([',', ' ']).any(|f| f == name);
    if !listed("hyperopt") {
        return None;
    }
    let place = gpodo_regressors::hyperopt::moved_to_hyperopt(field)?;
    Some(format!(
        "`{place}`: the optimiser's settings are in the model's `hyperopt:` block"
    ))
}

/// The value at `path` in `root`.
fn value_at<'a>(root: &'a Value, path: &str) -> Option<&'a Value> {
    let mut node = root;
    for segment in paths::parse_path(path).ok()? {
        node = match segment {
            paths::Segment::Key(k) => node.get(&k)?,
            paths::Segment::Index(i) => node.get(i)?,
            paths::Segment::All => node.get(0)?,
        };
    }
    Some(node)
}

/// Serde stops its path at an internally tagged enum (it buffers the
/// variant's fields): when the message quotes one of the fields' values
/// (`` `rbf + + linear` ``, `"seven"`), the path of that field.
pub(crate) fn refine_path(root: &Value, path: &str, message: &str) -> String {
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
pub(crate) fn with_run(problem: String, key: &str, single: bool) -> String {
    if single {
        problem
    } else {
        format!("{problem} (run `{key}`)")
    }
}
