//! Trajectories in the TUM RGB-D format, one pose per line:
//! `timestamp tx ty tz qx qy qz qw` (seconds, metres, unit quaternion with
//! w last), `#` comments allowed — what `evo` and the TUM tools read.
//! Numbers are written in the shortest form that reads back to the same
//! `f64`, so writing and reading is lossless.

use std::fmt::Write as _;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use crate::FrontendError;

/// One stamped pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Time stamp (s).
    pub time_secs: f64,
    /// `world_from_body` (or whatever frame the file describes).
    pub pose: Isometry3<f64>,
}

/// Formats poses as TUM text, with a comment line first.
pub fn format_tum(comment: &str, poses: &[StampedPose]) -> String {
    let mut out = String::with_capacity(64 * poses.len() + 64);
    for line in comment.lines() {
        let _ = writeln!(out, "# {line}");
    }
    for p in poses {
        let t = p.pose.translation.vector;
        let q = p.pose.rotation.quaternion();
        let _ = writeln!(
            out,
            "{} {} {} {} {} {} {} {}",
            p.time_secs, t.x, t.y, t.z, q.i, q.j, q.k, q.w
        );
    }
    out
}

/// Parses TUM text; `path` names the file in errors.
///
/// # Errors
/// [`FrontendError::Parse`] with the line: a line without 8 numbers, a
/// non-finite number, a quaternion whose norm is not 1 within 1e-3, or time
/// stamps that do not increase.
pub fn parse_tum(text: &str, path: &str) -> Result<Vec<StampedPose>, FrontendError> {
    let mut poses: Vec<StampedPose> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |detail: String| FrontendError::Parse {
            path: path.to_string(),
            line: i + 1,
            detail,
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.len() != 8 {
            return Err(bad(format!(
                "expected 8 numbers `timestamp tx ty tz qx qy qz qw`, found {} fields",
                fields.len()
            )));
        }
        let mut v = [0.0; 8];
        for (k, (slot, field)) in v.iter_mut().zip(&fields).enumerate() {
            *slot = field
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "field {}: expected a finite number, found `{field}`",
                        k + 1
                    ))
                })?;
        }
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        if (q.norm() - 1.0).abs() > 1e-3 {
            return Err(bad(format!("quaternion norm {} is not 1", q.norm())));
        }
        if let Some(last) = poses.last()
            && v[0] <= last.time_secs
        {
            return Err(bad(format!(
                "time stamp {} does not increase (previous {})",
                v[0], last.time_secs
            )));
        }
        poses.push(StampedPose {
            time_secs: v[0],
            pose: Isometry3::from_parts(
                Translation3::new(v[1], v[2], v[3]),
                UnitQuaternion::from_quaternion(q),
            ),
        });
    }
    Ok(poses)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn poses_round_trip_bit_for_bit() {
        let poses: Vec<StampedPose> = (0..20)
            .map(|k| StampedPose {
                time_secs: 0.1 * k as f64 + 1e-9,
                pose: Isometry3::from_parts(
                    Translation3::new(0.3 * k as f64, -1.0 / 3.0, 2.0_f64.sqrt()),
                    UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.2, 0.05 * k as f64)),
                ),
            })
            .collect();
        let text = format_tum("estimated\nsecond line", &poses);
        assert!(text.starts_with("# estimated\n# second line\n"));
        let back = parse_tum(&text, "t.txt").unwrap();
        assert_eq!(back.len(), poses.len());
        for (a, b) in poses.iter().zip(&back) {
            assert_eq!(a.time_secs, b.time_secs);
            assert_eq!(a.pose.translation, b.pose.translation);
            assert!(a.pose.rotation.angle_to(&b.pose.rotation) < 1e-15);
        }
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let err = parse_tum("# c\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0\n", "traj.txt").unwrap_err();
        assert!(err.to_string().starts_with("traj.txt:3:"), "{err}");
        let err = parse_tum("0 0 0 0 0 0 0 2\n", "t").unwrap_err();
        assert!(err.to_string().contains("norm"), "{err}");
        let err = parse_tum("0 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n", "t").unwrap_err();
        assert!(
            err.to_string().contains("t:2") && err.to_string().contains("increase"),
            "{err}"
        );
        let err = parse_tum("0 0 nan 0 0 0 0 1\n", "t").unwrap_err();
        assert!(err.to_string().contains("field 3"), "{err}");
    }
}
