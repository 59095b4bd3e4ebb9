//! The column layout of a rover-log CSV file: which joints it has, the
//! canonical column order, and the mapping between a sample and a row.

use std::path::Path;

use gpodo_traits::{BodyTwist, ImuSample, JointState, ProprioceptiveSample};
use nalgebra::{Isometry3, Quaternion, Vector3};

use super::RoverLog;
use crate::DatasetError;

/// The columns every log has, in canonical order.
pub(super) const FIXED_COLUMNS: [&str; 8] = [
    "time_s", "gt_x_m", "gt_y_m", "gt_z_m", "gt_qw", "gt_qx", "gt_qy", "gt_qz",
];

/// The IMU's columns, after the fixed ones: all eight, or none for a robot
/// without an IMU.
pub(super) const IMU_COLUMNS: [&str; 8] = [
    "roll_rad",
    "pitch_rad",
    "gyro_x_radps",
    "gyro_y_radps",
    "gyro_z_radps",
    "acc_x_mps2",
    "acc_y_mps2",
    "acc_z_mps2",
];

/// Header prefixes of the three joint groups (wheels, steering, bogies).
const JOINT_PREFIXES: [&str; 3] = ["wheel_", "steer_", "bogie_"];
const POS_SUFFIX: &str = "_pos_rad";
const RATE_SUFFIX: &str = "_rate_radps";
const CONTACT_PREFIX: &str = "contact_";
const CONTACT_SUFFIX: &str = "_rad";
const EXTRA_PREFIX: &str = "x_";

/// The robot's own odometry twist (body frame), all six or none.
pub(super) const ODOMETRY_COLUMNS: [&str; 6] = [
    "odom_vx_mps",
    "odom_vy_mps",
    "odom_vz_mps",
    "odom_wx_radps",
    "odom_wy_radps",
    "odom_wz_radps",
];

/// Why `name` cannot be a joint name, if it cannot.
pub(super) fn check_joint_name(name: &str) -> Result<(), &'static str> {
    if name.is_empty() {
        return Err("is empty");
    }
    if name.trim() != name {
        return Err("has surrounding spaces");
    }
    if name.chars().any(|c| c == ',' || c == '"' || c.is_control()) {
        return Err("contains `,`, `\"` or a control character");
    }
    Ok(())
}

/// The joints of a log (names per group, in order) and whether it has
/// an IMU, contact angles and the robot's own odometry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct LogLayout {
    /// Whether the IMU's columns are present.
    imu: bool,
    /// Wheel, steering and bogie names.
    joints: [Vec<String>; 3],
    /// Whether one `contact_<w>_rad` column per wheel is present.
    contact: bool,
    /// Whether the `odom_*` columns are present.
    odometry: bool,
}

impl LogLayout {
    /// The layout of an in-memory log (contact angles as in its first sample).
    pub fn of_log(log: &RoverLog) -> Self {
        Self {
            imu: log.samples.first().is_some_and(|s| s.imu.is_some()),
            joints: [
                log.wheel_names.clone(),
                log.steer_names.clone(),
                log.bogie_names.clone(),
            ],
            contact: log
                .samples
                .first()
                .is_some_and(|s| s.contact_angles_rad.is_some()),
            odometry: log.samples.first().is_some_and(|s| s.odometry.is_some()),
        }
    }

    /// Discovers the layout from a header, rejecting unknown columns.
    /// Columns the layout needs but the header lacks are found later, when
    /// [`Self::column_names`] are looked up.
    pub fn from_header(path: &Path, header: &[String]) -> Result<Self, DatasetError> {
        let mut joints: [Vec<String>; 3] = Default::default();
        let mut contacts = Vec::new();
        let mut odometry = false;
        let mut imu = false;
        for column in header {
            if FIXED_COLUMNS.contains(&column.as_str()) || column.starts_with(EXTRA_PREFIX) {
                continue;
            }
            if IMU_COLUMNS.contains(&column.as_str()) {
                imu = true;
                continue;
            }
            if ODOMETRY_COLUMNS.contains(&column.as_str()) {
                odometry = true;
                continue;
            }
            if let Some((group, name)) = joint_of_column(column) {
                if !joints[group].contains(&name) {
                    joints[group].push(name);
                }
            } else if let Some(wheel) = contact_of_column(column) {
                contacts.push((column, wheel));
            } else {
                return Err(unknown(
                    path,
                    column,
                    "expected a log column or an `x_` extra",
                ));
            }
        }
        if let Some((column, _)) = contacts.iter().find(|(_, w)| !joints[0].contains(w)) {
            return Err(unknown(path, column, "contact columns must name a wheel"));
        }
        Ok(Self {
            imu,
            joints,
            contact: !contacts.is_empty(),
            odometry,
        })
    }

    /// Whether the log has contact angles.
    pub fn has_contact(&self) -> bool {
        self.contact
    }

    /// Whether the log has the robot's own odometry.
    pub fn has_odometry(&self) -> bool {
        self.odometry
    }

    /// Whether the log has an IMU.
    pub fn has_imu(&self) -> bool {
        self.imu
    }

    /// Wheel, steering and bogie names.
    pub fn into_joint_names(self) -> [Vec<String>; 3] {
        self.joints
    }

    /// All column names in canonical order (the order of [`Self::encode`]).
    pub fn column_names(&self) -> Vec<String> {
        let mut names: Vec<String> = FIXED_COLUMNS.iter().map(|c| c.to_string()).collect();
        if self.imu {
            names.extend(IMU_COLUMNS.iter().map(|c| c.to_string()));
        }
        for (prefix, joints) in JOINT_PREFIXES.iter().zip(&self.joints) {
            for joint in joints {
                names.push(format!("{prefix}{joint}{POS_SUFFIX}"));
                names.push(format!("{prefix}{joint}{RATE_SUFFIX}"));
            }
        }
        if self.contact {
            for wheel in &self.joints[0] {
                names.push(format!("{CONTACT_PREFIX}{wheel}{CONTACT_SUFFIX}"));
            }
        }
        if self.odometry {
            names.extend(ODOMETRY_COLUMNS.iter().map(|c| c.to_string()));
        }
        names
    }

    /// The row of a sample and its pose, in [`Self::column_names`] order
    /// (joint vectors written as they are; lengths are checked elsewhere).
    pub fn encode(&self, sample: &ProprioceptiveSample, pose: &Isometry3<f64>) -> Vec<f64> {
        let t = &pose.translation.vector;
        let q = pose.rotation.quaternion();
        let mut row = vec![sample.time_secs, t.x, t.y, t.z, q.w, q.i, q.j, q.k];
        if self.imu {
            let imu = sample.imu.unwrap_or_default();
            let (g, a) = (imu.gyro_radps, imu.accel_mps2);
            row.extend([imu.roll_rad, imu.pitch_rad, g.x, g.y, g.z, a.x, a.y, a.z]);
        }
        for joints in [&sample.wheels, &sample.steering, &sample.bogies] {
            row.extend(joints.iter().flat_map(|j| [j.position_rad, j.rate_radps]));
        }
        if self.contact {
            row.extend(sample.contact_angles_rad.iter().flatten());
        }
        if self.odometry {
            let twist = sample.odometry.unwrap_or_default();
            row.extend(twist.linear_mps.iter().chain(twist.angular_radps.iter()));
        }
        row
    }

    /// The sample, translation and (not yet normalised) quaternion of a row
    /// in [`Self::column_names`] order.
    pub fn decode(&self, row: &[f64]) -> (ProprioceptiveSample, Vector3<f64>, Quaternion<f64>) {
        let mut cells = row.iter().copied();
        let mut next = || cells.next().unwrap_or(f64::NAN);
        let time_secs = next();
        let translation = Vector3::new(next(), next(), next());
        let (w, i, j, k) = (next(), next(), next(), next());
        let imu = self.imu.then(|| ImuSample {
            roll_rad: next(),
            pitch_rad: next(),
            gyro_radps: Vector3::new(next(), next(), next()),
            accel_mps2: Vector3::new(next(), next(), next()),
        });
        let [wheels, steering, bogies] = self.joints.each_ref().map(|names| {
            names
                .iter()
                .map(|_| JointState {
                    position_rad: next(),
                    rate_radps: next(),
                })
                .collect()
        });
        let contact_angles_rad = self
            .contact
            .then(|| self.joints[0].iter().map(|_| next()).collect());
        let odometry = self.odometry.then(|| BodyTwist {
            linear_mps: Vector3::new(next(), next(), next()),
            angular_radps: Vector3::new(next(), next(), next()),
        });
        let sample = ProprioceptiveSample {
            time_secs,
            wheels,
            steering,
            bogies,
            imu,
            attitude_rad: None,
            contact_angles_rad,
            odometry,
        };
        (sample, translation, Quaternion::new(w, i, j, k))
    }
}

/// `(group, joint name)` of a `wheel_/steer_/bogie_<name>_pos_rad|_rate_radps` column.
fn joint_of_column(column: &str) -> Option<(usize, String)> {
    JOINT_PREFIXES
        .iter()
        .enumerate()
        .find_map(|(group, prefix)| {
            let rest = column.strip_prefix(prefix)?;
            let name = rest
                .strip_suffix(POS_SUFFIX)
                .or_else(|| rest.strip_suffix(RATE_SUFFIX))?;
            check_joint_name(name).ok()?;
            Some((group, name.to_string()))
        })
}

/// The wheel name of a `contact_<w>_rad` column.
fn contact_of_column(column: &str) -> Option<String> {
    let name = column
        .strip_prefix(CONTACT_PREFIX)?
        .strip_suffix(CONTACT_SUFFIX)?;
    check_joint_name(name).ok()?;
    Some(name.to_string())
}

/// A [`DatasetError::UnknownColumn`].
fn unknown(path: &Path, column: &str, hint: &str) -> DatasetError {
    DatasetError::UnknownColumn {
        path: path.to_path_buf(),
        column: column.to_string(),
        hint: hint.to_string(),
    }
}
