//! The rover description: chassis geometry read from YAML.
//!
//! The default, [`RoverDescription::exoter`], is the ExoTeR-like rover of the
//! paper, shipped as `kinematics/rovers/exoter.yaml` (documented there, field
//! by field). Joint vectors in [`gpodo_traits::ProprioceptiveSample`] follow
//! the orders defined here: `bogies` in file order, `steering` over the
//! steerable wheels in wheel order, `wheels` in file order.

use std::path::Path;

use nalgebra::{Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::KinematicsError;

/// The ExoTeR-like description shipped with gpodo.
const EXOTER_YAML: &str = include_str!("../rovers/exoter.yaml");

/// A passive bogie: a revolute joint between the body and its wheels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BogieSpec {
    /// Joint name (e.g. `left`).
    pub name: String,
    /// Pivot position in the body frame (m).
    pub pivot_m: [f64; 3],
    /// Rotation axis in the body frame (normalised on use).
    pub axis: [f64; 3],
}

/// A wheel: carried by a bogie (or mounted rigidly on the body), optionally
/// steerable about the vertical axis through its centre, rolling about its
/// own y axis; a mecanum wheel's rollers let its contact point move freely
/// in one direction of the ground plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelSpec {
    /// Wheel name (e.g. `fl`).
    pub name: String,
    /// Name of the bogie that carries the wheel; omitted, the wheel is
    /// mounted rigidly on the body (a differential-drive, skid-steer or
    /// mecanum chassis).
    #[serde(default)]
    pub bogie: Option<String>,
    /// Whether a steering joint turns the wheel.
    pub steerable: bool,
    /// Wheel centre in the body frame with all joints at zero (m).
    pub center_m: [f64; 3],
    /// A mecanum wheel: the angle of its rollers' axes to the wheel's axle
    /// (deg, typically ±45). Its contact point then moves freely along the
    /// ground direction perpendicular to the roller axis, one unknown roller
    /// rate per wheel. Omitted: an ordinary wheel.
    #[serde(default)]
    pub roller_angle_deg: Option<f64>,
}

/// Chassis geometry of a wheeled rover with passive bogies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoverDescription {
    /// Rover name.
    pub name: String,
    /// Wheel radius (m).
    pub wheel_radius_m: f64,
    /// Centre of mass in the body frame (m).
    pub center_of_mass_m: [f64; 3],
    /// Passive bogies.
    pub bogies: Vec<BogieSpec>,
    /// Wheels.
    pub wheels: Vec<WheelSpec>,
}

impl Default for RoverDescription {
    fn default() -> Self {
        Self::exoter()
    }
}

impl RoverDescription {
    /// The ExoTeR-like rover: 6 wheels of radius 0.07 m on three bogies,
    /// 4 steerable corner wheels (see `kinematics/rovers/exoter.yaml`).
    pub fn exoter() -> Self {
        // The embedded file is checked by a unit test; parsing cannot fail at
        // run time unless that test fails too.
        match Self::from_yaml_str(EXOTER_YAML, "<embedded exoter.yaml>") {
            Ok(d) => d,
            Err(e) => unreachable!("embedded rover description is invalid: {e}"),
        }
    }

    /// Parses and validates a description.
    ///
    /// # Errors
    /// [`KinematicsError::Yaml`] with line and column, or
    /// [`KinematicsError::InvalidDescription`] naming the field.
    pub fn from_yaml_str(yaml: &str, source_name: &str) -> Result<Self, KinematicsError> {
        let d: Self = serde_saphyr::from_str(yaml).map_err(|e| KinematicsError::Yaml {
            source_name: source_name.to_string(),
            detail: e.to_string(),
        })?;
        d.validate()?;
        Ok(d)
    }

    /// Reads a description from a YAML file.
    ///
    /// # Errors
    /// As [`RoverDescription::from_yaml_str`], plus unreadable files.
    pub fn from_path(path: &Path) -> Result<Self, KinematicsError> {
        let text = std::fs::read_to_string(path).map_err(|e| KinematicsError::Yaml {
            source_name: path.display().to_string(),
            detail: e.to_string(),
        })?;
        Self::from_yaml_str(&text, &path.display().to_string())
    }

    /// Checks every field; the error names the first bad one.
    ///
    /// # Errors
    /// [`KinematicsError::InvalidDescription`].
    pub fn validate(&self) -> Result<(), KinematicsError> {
        let bad = |field: String, expected: &str| KinematicsError::InvalidDescription {
            field,
            expected: expected.to_string(),
        };
        if !(self.wheel_radius_m.is_finite() && self.wheel_radius_m > 0.0) {
            return Err(bad("wheel_radius_m".into(), "a positive number of metres"));
        }
        if self.center_of_mass_m.iter().any(|v| !v.is_finite()) {
            return Err(bad("center_of_mass_m".into(), "three finite numbers"));
        }
        if self.wheels.is_empty() {
            return Err(bad("wheels".into(), "at least one wheel"));
        }
        for (k, b) in self.bogies.iter().enumerate() {
            if b.pivot_m.iter().any(|v| !v.is_finite()) {
                return Err(bad(format!("bogies[{k}].pivot_m"), "three finite numbers"));
            }
            let axis = Vector3::from(b.axis);
            if !axis.iter().all(|v| v.is_finite()) || axis.norm() < 1e-9 {
                return Err(bad(format!("bogies[{k}].axis"), "a non-zero finite vector"));
            }
            if self.bogies[..k].iter().any(|o| o.name == b.name) {
                return Err(bad(format!("bogies[{k}].name"), "a unique bogie name"));
            }
        }
        for (i, w) in self.wheels.iter().enumerate() {
            if w.center_m.iter().any(|v| !v.is_finite()) {
                return Err(bad(format!("wheels[{i}].center_m"), "three finite numbers"));
            }
            if let Some(bogie) = &w.bogie
                && self.bogie_index(bogie).is_none()
            {
                let names: Vec<&str> = self.bogies.iter().map(|b| b.name.as_str()).collect();
                return Err(bad(
                    format!("wheels[{i}].bogie"),
                    &format!("one of the bogie names {names:?}, found `{bogie}`"),
                ));
            }
            if let Some(angle) = w.roller_angle_deg
                && !(angle.is_finite() && angle.abs() > 1.0 && angle.abs() < 89.0)
            {
                return Err(bad(
                    format!("wheels[{i}].roller_angle_deg"),
                    "a roller angle in degrees, between 1 and 89 in magnitude",
                ));
            }
            if self.wheels[..i].iter().any(|o| o.name == w.name) {
                return Err(bad(format!("wheels[{i}].name"), "a unique wheel name"));
            }
        }
        Ok(())
    }

    fn bogie_index(&self, name: &str) -> Option<usize> {
        self.bogies.iter().position(|b| b.name == name)
    }

    /// Wheel names in order.
    pub fn wheel_names(&self) -> Vec<String> {
        self.wheels.iter().map(|w| w.name.clone()).collect()
    }

    /// Names of the steering joints (the steerable wheels, in wheel order).
    pub fn steer_names(&self) -> Vec<String> {
        self.wheels
            .iter()
            .filter(|w| w.steerable)
            .map(|w| w.name.clone())
            .collect()
    }

    /// Bogie names in order.
    pub fn bogie_names(&self) -> Vec<String> {
        self.bogies.iter().map(|b| b.name.clone()).collect()
    }

    /// Resolved per-wheel chain: bogie index and steering joint index.
    pub fn chains(&self) -> Vec<WheelChain> {
        let mut steer = 0;
        self.wheels
            .iter()
            .map(|w| {
                let steer_index = w.steerable.then(|| {
                    steer += 1;
                    steer - 1
                });
                let bogie_index = w.bogie.as_deref().and_then(|b| self.bogie_index(b));
                // A rigidly mounted wheel: a bogie joint that never moves.
                let (pivot, axis) = bogie_index.map_or(([0.0; 3], [0.0, 1.0, 0.0]), |k| {
                    (self.bogies[k].pivot_m, self.bogies[k].axis)
                });
                WheelChain {
                    bogie_index,
                    steer_index,
                    bogie_pivot: Point3::from(pivot),
                    bogie_axis: Unit::new_normalize(Vector3::from(axis)),
                    center: Point3::from(w.center_m),
                    roller_angle_rad: w.roller_angle_deg.map(f64::to_radians),
                }
            })
            .collect()
    }
}

/// The resolved kinematic chain body → bogie → steer → wheel of one wheel.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelChain {
    /// Index of the wheel's bogie in the bogie joint vector; `None` for a
    /// wheel mounted rigidly on the body.
    pub bogie_index: Option<usize>,
    /// Index of the wheel's steering joint, if steerable.
    pub steer_index: Option<usize>,
    /// Bogie pivot (body frame, m).
    pub bogie_pivot: Point3<f64>,
    /// Bogie axis (body frame).
    pub bogie_axis: Unit<Vector3<f64>>,
    /// Wheel centre with all joints at zero (body frame, m).
    pub center: Point3<f64>,
    /// A mecanum wheel's roller angle to the axle (rad).
    pub roller_angle_rad: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_exoter_description_is_valid() {
        let d = RoverDescription::from_yaml_str(EXOTER_YAML, "exoter.yaml").unwrap();
        assert_eq!(d.wheel_radius_m, 0.07);
        assert_eq!(d.wheel_names(), ["fl", "fr", "ml", "mr", "rl", "rr"]);
        assert_eq!(d.steer_names(), ["fl", "fr", "rl", "rr"]);
        assert_eq!(d.bogie_names(), ["left", "right", "rear"]);
        let chains = d.chains();
        assert_eq!(chains[4].steer_index, Some(2));
        assert_eq!(chains[3].steer_index, None);
        assert_eq!(chains[5].bogie_index, Some(2));
    }

    #[test]
    fn unknown_bogie_is_named_in_the_error() {
        let yaml = EXOTER_YAML.replace(
            "bogie: rear, steerable: true, center_m: [-0.29, -0.28",
            "bogie: back, steerable: true, center_m: [-0.29, -0.28",
        );
        let err = RoverDescription::from_yaml_str(&yaml, "x.yaml").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("wheels[5].bogie") && msg.contains("back"),
            "{msg}"
        );
    }

    #[test]
    fn unknown_field_gives_a_yaml_error_with_position() {
        let yaml = EXOTER_YAML.replace("wheel_radius_m: 0.07", "wheel_radius: 0.07");
        let err = RoverDescription::from_yaml_str(&yaml, "x.yaml").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("x.yaml") && msg.contains("wheel_radius"),
            "{msg}"
        );
    }

    #[test]
    fn non_positive_radius_is_rejected() {
        let yaml = EXOTER_YAML.replace("wheel_radius_m: 0.07", "wheel_radius_m: -0.07");
        let err = RoverDescription::from_yaml_str(&yaml, "x.yaml").unwrap_err();
        assert!(err.to_string().contains("wheel_radius_m"), "{err}");
    }
}
