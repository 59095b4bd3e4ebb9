//! Paths into a configuration tree, as sweeps name the values they vary:
//! `regressors[1].kernel`, `frontend.vo.seed`, `schemes[3].selector`.
//! Keys are field names; `[i]` indexes a list, `[*]` is every element of
//! it (`schemes[*].motion_prior` sets every scheme's).

use serde_json::Value;

/// One step of a path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    /// A mapping key.
    Key(String),
    /// A list index.
    Index(usize),
    /// Every element of a list.
    All,
}

/// Parses `a.b[2].c`.
///
/// # Errors
/// A message naming what is malformed.
pub fn parse_path(path: &str) -> Result<Vec<Segment>, String> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if name.is_empty() && out.is_empty() {
            return Err(format!("path `{path}`: expected a field name first"));
        }
        if !name.is_empty() {
            if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(format!(
                    "path `{path}`: `{name}` is not a field name (letters, digits, `_`)"
                ));
            }
            out.push(Segment::Key(name.to_string()));
        } else if part.is_empty() {
            return Err(format!("path `{path}`: empty field name"));
        }
        while !rest.is_empty() {
            let close = rest
                .find(']')
                .ok_or_else(|| format!("path `{path}`: `[` without `]`"))?;
            let inside = &rest[1..close];
            if inside == "*" {
                out.push(Segment::All);
            } else {
                let index: usize = inside
                    .parse()
                    .map_err(|_| format!("path `{path}`: `{inside}` is not a list index or `*`"))?;
                out.push(Segment::Index(index));
            }
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(format!("path `{path}`: expected `.` or `[` after `]`"));
            }
        }
    }
    Ok(out)
}

/// Sets the value at `path` in `root`, creating missing mapping keys (a
/// misspelt field then fails as an unknown field where it is read).
///
/// # Errors
/// A message when the path runs through a scalar or past the end of a
/// list.
pub fn set_path(root: &mut Value, path: &str, value: Value) -> Result<(), String> {
    let segments = parse_path(path)?;
    if segments.is_empty() {
        return Err(format!("path `{path}`: empty path"));
    }
    set_at(root, &segments, &value, path)
}

/// Sets `value` at `segments` below `node` (`path` for messages).
fn set_at(node: &mut Value, segments: &[Segment], value: &Value, path: &str) -> Result<(), String> {
    let Some((segment, rest)) = segments.split_first() else {
        *node = value.clone();
        return Ok(());
    };
    match segment {
        Segment::Key(k) => {
            if node.is_null() {
                *node = Value::Object(Default::default());
            }
            let Value::Object(map) = node else {
                return Err(format!(
                    "path `{path}`: `{k}` is a field of a mapping, but the value there is not one"
                ));
            };
            set_at(
                map.entry(k.clone()).or_insert(Value::Null),
                rest,
                value,
                path,
            )
        }
        Segment::Index(idx) => {
            let Value::Array(list) = node else {
                return Err(format!(
                    "path `{path}`: [{idx}] indexes a list, but the value there is not one"
                ));
            };
            let len = list.len();
            let item = list.get_mut(*idx).ok_or_else(|| {
                format!("path `{path}`: index {idx} is out of range (the list has {len} entries)")
            })?;
            set_at(item, rest, value, path)
        }
        Segment::All => {
            let Value::Array(list) = node else {
                return Err(format!(
                    "path `{path}`: [*] takes every element of a list, but the value there is not one"
                ));
            };
            list.iter_mut()
                .try_for_each(|item| set_at(item, rest, value, path))
        }
    }
}

/// Overlays `top` on `base`: mappings are merged key by key (recursively),
/// anything else in `top` replaces what `base` has.
pub fn merge(base: &mut Value, top: Value) {
    match (base, top) {
        (Value::Object(b), Value::Object(t)) => {
            for (k, v) in t {
                match b.get_mut(&k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (slot, t) => *slot = t,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn paths_parse_keys_and_indices() {
        assert_eq!(
            parse_path("schemes[3].selector.inner[0][1]").unwrap(),
            vec![
                Segment::Key("schemes".into()),
                Segment::Index(3),
                Segment::Key("selector".into()),
                Segment::Key("inner".into()),
                Segment::Index(0),
                Segment::Index(1),
            ]
        );
        for bad in ["", ".a", "a..b", "a[x]", "a[1", "a b", "a[1]b"] {
            assert!(parse_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn set_replaces_values_and_reports_bad_paths() {
        let mut v = json!({"regressors": [{"kind": "zero"}, {"kind": "exact_gp"}]});
        set_path(&mut v, "regressors[1].kernel", json!("matern52")).unwrap();
        set_path(&mut v, "frontend.vo.seed", json!(3)).unwrap();
        assert_eq!(v["regressors"][1]["kernel"], json!("matern52"));
        assert_eq!(v["frontend"]["vo"]["seed"], json!(3));
        let err = set_path(&mut v, "regressors[5].kernel", json!("rbf")).unwrap_err();
        assert!(
            err.contains("out of range (the list has 2 entries)"),
            "{err}"
        );
        let err = set_path(&mut v, "regressors[0].kind.x", json!(1)).unwrap_err();
        assert!(err.contains("not one"), "{err}");
        // `[*]`: every element.
        set_path(&mut v, "regressors[*].outputs", json!("shared")).unwrap();
        assert_eq!(v["regressors"][0]["outputs"], json!("shared"));
        assert_eq!(v["regressors"][1]["outputs"], json!("shared"));
        assert_eq!(v["regressors"][1]["kernel"], json!("matern52"));
        assert_eq!(
            parse_path("schemes[*].odometry").unwrap(),
            vec![
                Segment::Key("schemes".into()),
                Segment::All,
                Segment::Key("odometry".into())
            ]
        );
    }

    #[test]
    fn merge_overlays_mappings_and_replaces_the_rest() {
        let mut base = json!({"name": "paper", "dataset": {"kind": "simulated", "seed": 7}, "regressors": [1, 2]});
        merge(
            &mut base,
            json!({"name": "ablation", "dataset": {"seed": 3}, "regressors": [9]}),
        );
        assert_eq!(
            base,
            json!({"name": "ablation", "dataset": {"kind": "simulated", "seed": 3}, "regressors": [9]})
        );
    }
}
