//! Logged rover runs ([`RoverLog`]) and their CSV file format.
//!
//! A log holds what the residual of the paper's eq. 12 (§IV-C) is built
//! from: the proprioceptive samples `u̇(k)` and IMU readings a motion model
//! turns into odometry (eq. 11), the ground-truth pose `s(k)` at each sample,
//! and the camera frame times at which the visual front end may run (§V-B).
//! [`read_log_csv`] and [`write_log_csv`] move logs to and from the format
//! below; the section can be pasted into a README as it is.
//!
//! ## Rover log CSV format
//!
//! A run called `NAME` is two files in one directory:
//!
//! * `NAME.csv`: one header row, then one row per proprioceptive sample in
//!   time order;
//! * `NAME.camera.csv` (optional): the camera frame times, a header row
//!   `time_s` then one strictly increasing time per row. When the file is
//!   absent the run has no camera frames.
//!
//! Both are comma separated UTF-8 text. The run's name is the file stem.
//!
//! ### Columns of `NAME.csv`
//!
//! Frames: the world frame has z up; the body frame has x forward, y left,
//! z up. The pose is `world_from_body`, so `p_world = world_from_body · p_body`.
//!
//! | columns | meaning | unit |
//! | --- | --- | --- |
//! | `time_s` | sample time, strictly increasing | s |
//! | `gt_x_m, gt_y_m, gt_z_m` | ground-truth position of the body origin in the world frame | m |
//! | `gt_qw, gt_qx, gt_qy, gt_qz` | ground-truth orientation `world_from_body`, unit quaternion (w first) | – |
//! | `roll_rad, pitch_rad` | attitude from the IMU filter | rad |
//! | `gyro_x_radps, gyro_y_radps, gyro_z_radps` | angular rate, body frame | rad/s |
//! | `acc_x_mps2, acc_y_mps2, acc_z_mps2` | specific force, body frame (+9.81 on z at rest) | m/s² |
//! | `wheel_<w>_pos_rad, wheel_<w>_rate_radps` | for each wheel `<w>`: angle and rate of the rolling joint | rad, rad/s |
//! | `steer_<s>_pos_rad, steer_<s>_rate_radps` | for each steering joint `<s>` | rad, rad/s |
//! | `bogie_<b>_pos_rad, bogie_<b>_rate_radps` | for each passive bogie joint `<b>` | rad, rad/s |
//! | `contact_<w>_rad` | optional: wheel–terrain contact angle of each wheel `<w>` (all wheels or none) | rad |
//! | `odom_vx_mps, odom_vy_mps, odom_vz_mps, odom_wx_radps, odom_wy_radps, odom_wz_radps` | optional (all six or none): the robot's own odometry twist in the body frame, as its drive controller reports it | m/s, rad/s |
//! | `x_...` | optional user extras, ignored | – |
//!
//! The writer puts the columns in this order, with joints in the log's
//! order (for the ExoTeR-like rover: wheels `fl fr ml mr rl rr`, steering
//! `fl fr rl rr`, bogies `left right rear`).
//!
//! ### Rules the reader applies
//!
//! * Columns are found by name, so their order does not matter; spaces
//!   around fields are ignored; blank lines are skipped.
//! * Joint names are discovered from the header, in header order, from the
//!   `wheel_`, `steer_`, `bogie_` prefixes and `_pos_rad`, `_rate_radps`
//!   suffixes, so a rover with other joints needs no code change. Each joint
//!   needs both its columns.
//! * Columns starting with `x_` are ignored; any other unknown column is an
//!   error (it is usually a typo). Duplicate names are an error.
//! * Every cell is a finite decimal number (`1.5`, `-0`, `2.5e-7`); NaN and
//!   infinities are rejected. Every row has as many fields as the header.
//! * A quaternion whose norm differs from 1 by more than `1e-3` is an error;
//!   one within `1e-3` is normalised (one within `1e-12`, i.e. unit up to
//!   rounding, is kept bit for bit).
//! * A file needs a header and at least one sample.
//! * Errors name the file, the line (the header is line 1) and the column.
//!
//! The writer prints every number in the shortest decimal form that reads
//! back to the same `f64`, so writing and reading a log is lossless, and it
//! replaces each file atomically (a temporary file in the same directory,
//! then a rename): an interrupted or failed write never leaves a
//! half-written file.

mod columns;
mod read;
pub(crate) mod write;

use gpodo_traits::{JointState, ProprioceptiveSample};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::DatasetError;

use columns::{LogLayout, check_joint_name};
pub use read::read_log_csv;
pub use write::{log_table, write_log_csv};

/// Largest `|‖q‖ − 1|` accepted for a ground-truth quaternion.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// Stride of [`RoverLog::path_length_m`] (s).
pub const PATH_STRIDE_SECS: f64 = 1.0;

/// One rover run: proprioceptive samples at the sensor rate, the
/// ground-truth pose at each sample, and camera frame times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoverLog {
    /// The run's name (the file stem of its CSV file).
    pub name: String,
    /// Wheel names, in the order of each sample's `wheels` (e.g. `fl fr ml mr rl rr`).
    pub wheel_names: Vec<String>,
    /// Steering joint names, in the order of each sample's `steering` (e.g. `fl fr rl rr`).
    pub steer_names: Vec<String>,
    /// Bogie joint names, in the order of each sample's `bogies` (e.g. `left right rear`).
    pub bogie_names: Vec<String>,
    /// Proprioceptive samples, strictly increasing in time.
    pub samples: Vec<ProprioceptiveSample>,
    /// Ground-truth `world_from_body` at each sample (same length as `samples`).
    pub ground_truth: Vec<Isometry3<f64>>,
    /// Camera frame times (s), strictly increasing; empty when the run has no camera.
    pub camera_times_secs: Vec<f64>,
}

/// Positions in `have` of each name of `want`, or an error naming the first
/// missing one.
fn permutation(
    log: &str,
    kind: &str,
    have: &[String],
    want: &[String],
) -> Result<Vec<usize>, DatasetError> {
    if have.len() != want.len() {
        return Err(DatasetError::InvalidLog {
            log: log.to_string(),
            sample: None,
            detail: format!("the rover has {kind} joints {want:?}, the log {have:?}"),
        });
    }
    want.iter()
        .map(|name| {
            have.iter()
                .position(|h| h == name)
                .ok_or_else(|| DatasetError::InvalidLog {
                    log: log.to_string(),
                    sample: None,
                    detail: format!("no {kind} joint `{name}` (the log has {have:?})"),
                })
        })
        .collect()
}

impl RoverLog {
    /// The same log with its joints in the given orders, matched by name:
    /// motion models read joints by position, so a log whose columns come
    /// in another order (or from a logger with its own conventions) is
    /// brought into the rover description's order first.
    ///
    /// # Errors
    /// [`DatasetError::InvalidLog`] naming a joint the log lacks, or when the
    /// joint counts differ.
    pub fn with_joint_order(
        &self,
        wheels: &[String],
        steering: &[String],
        bogies: &[String],
    ) -> Result<RoverLog, DatasetError> {
        let pw = permutation(&self.name, "wheel", &self.wheel_names, wheels)?;
        let ps = permutation(&self.name, "steering", &self.steer_names, steering)?;
        let pb = permutation(&self.name, "bogie", &self.bogie_names, bogies)?;
        let pick = |v: &[JointState], p: &[usize]| -> Vec<JointState> {
            p.iter().map(|&i| v[i]).collect()
        };
        let mut samples = Vec::with_capacity(self.samples.len());
        for (k, s) in self.samples.iter().enumerate() {
            let lengths_ok = s.wheels.len() == pw.len()
                && s.steering.len() == ps.len()
                && s.bogies.len() == pb.len()
                && s.contact_angles_rad
                    .as_ref()
                    .is_none_or(|c| c.len() == pw.len());
            if !lengths_ok {
                return Err(DatasetError::InvalidLog {
                    log: self.name.clone(),
                    sample: Some(k),
                    detail: "joint vectors do not match the log's joint names".into(),
                });
            }
            let mut s = s.clone();
            s.wheels = pick(&s.wheels, &pw);
            s.steering = pick(&s.steering, &ps);
            s.bogies = pick(&s.bogies, &pb);
            s.contact_angles_rad = s
                .contact_angles_rad
                .map(|c| pw.iter().map(|&i| c[i]).collect());
            samples.push(s);
        }
        Ok(RoverLog {
            name: self.name.clone(),
            wheel_names: wheels.to_vec(),
            steer_names: steering.to_vec(),
            bogie_names: bogies.to_vec(),
            samples,
            ground_truth: self.ground_truth.clone(),
            camera_times_secs: self.camera_times_secs.clone(),
        })
    }

    /// Checks that the log is consistent and can be written as CSV: joint
    /// names non-empty, distinct within their group and free of `,`, `"`,
    /// control characters and surrounding spaces; at least one sample; one
    /// pose per sample; joint vectors as long as their name lists; contact
    /// angles present in all samples (one per wheel) or in none; every number
    /// finite; quaternions unit within [`QUATERNION_NORM_TOLERANCE`]; sample
    /// and camera times strictly increasing.
    ///
    /// # Errors
    /// [`DatasetError::InvalidLog`] naming the sample and what is wrong.
    pub fn validate(&self) -> Result<(), DatasetError> {
        self.check_names()?;
        if self.samples.is_empty() {
            return Err(self.invalid(None, "no samples".to_string()));
        }
        if self.ground_truth.len() != self.samples.len() {
            return Err(self.invalid(
                None,
                format!(
                    "{} ground-truth poses for {} samples",
                    self.ground_truth.len(),
                    self.samples.len()
                ),
            ));
        }
        let layout = LogLayout::of_log(self);
        for i in 0..self.samples.len() {
            self.check_sample(&layout, i)?;
        }
        self.check_times()
    }

    /// Time from the first to the last sample (s); 0 for fewer than two.
    pub fn duration_secs(&self) -> f64 {
        match (self.samples.first(), self.samples.last()) {
            (Some(first), Some(last)) => last.time_secs - first.time_secs,
            _ => 0.0,
        }
    }

    /// Length of the ground-truth path (m): the sum of the distances between
    /// ground-truth positions [`PATH_STRIDE_SECS`] apart (and the last one).
    pub fn path_length_m(&self) -> f64 {
        // Summed over strides of at least `PATH_STRIDE_SECS`, so that the
        // motion-capture jitter of consecutive samples (sub-millimetre, but
        // at 12.5 Hz comparable to the motion itself) does not inflate it.
        let mut length = 0.0;
        let mut last = 0;
        for k in 1..self.ground_truth.len() {
            let elapsed = self.samples[k].time_secs - self.samples[last].time_secs;
            if elapsed >= PATH_STRIDE_SECS || k + 1 == self.ground_truth.len() {
                length += (self.ground_truth[k].translation.vector
                    - self.ground_truth[last].translation.vector)
                    .norm();
                last = k;
            }
        }
        length
    }

    /// Joint names valid and distinct within each group.
    fn check_names(&self) -> Result<(), DatasetError> {
        let groups = [
            ("wheel", &self.wheel_names),
            ("steer", &self.steer_names),
            ("bogie", &self.bogie_names),
        ];
        for (group, names) in groups {
            for (k, name) in names.iter().enumerate() {
                check_joint_name(name)
                    .map_err(|why| self.invalid(None, format!("{group} name `{name}` {why}")))?;
                if names[..k].contains(name) {
                    return Err(self.invalid(None, format!("{group} name `{name}` repeated")));
                }
            }
        }
        Ok(())
    }

    /// Lengths, contact presence, finiteness and quaternion norm of sample `i`.
    fn check_sample(&self, layout: &LogLayout, i: usize) -> Result<(), DatasetError> {
        let sample = &self.samples[i];
        let lengths = [
            ("wheel", sample.wheels.len(), self.wheel_names.len()),
            ("steering", sample.steering.len(), self.steer_names.len()),
            ("bogie", sample.bogies.len(), self.bogie_names.len()),
        ];
        for (what, found, expected) in lengths {
            if found != expected {
                let detail = format!("{found} {what} joints, {expected} {what} names");
                return Err(self.invalid(Some(i), detail));
            }
        }
        match (&sample.contact_angles_rad, layout.has_contact()) {
            (Some(c), true) if c.len() != self.wheel_names.len() => {
                let detail = format!(
                    "{} contact angles for {} wheels",
                    c.len(),
                    self.wheel_names.len()
                );
                return Err(self.invalid(Some(i), detail));
            }
            (Some(_), false) | (None, true) => {
                let detail = "contact angles must be given in every sample or in none".to_string();
                return Err(self.invalid(Some(i), detail));
            }
            _ => {}
        }
        if sample.imu.is_some() != layout.has_imu() {
            let detail = "the IMU must be given in every sample or in none".to_string();
            return Err(self.invalid(Some(i), detail));
        }
        if sample.odometry.is_some() != layout.has_odometry() {
            let detail = "odometry must be given in every sample or in none".to_string();
            return Err(self.invalid(Some(i), detail));
        }
        let values = layout.encode(sample, &self.ground_truth[i]);
        if let Some((column, _)) = layout
            .column_names()
            .into_iter()
            .zip(values)
            .find(|(_, v)| !v.is_finite())
        {
            return Err(self.invalid(Some(i), format!("`{column}` is not finite")));
        }
        let norm = self.ground_truth[i].rotation.quaternion().norm();
        if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(self.invalid(Some(i), format!("ground-truth quaternion norm {norm}")));
        }
        Ok(())
    }

    /// Sample and camera times strictly increasing, camera times finite.
    fn check_times(&self) -> Result<(), DatasetError> {
        for i in 1..self.samples.len() {
            let (previous, found) = (self.samples[i - 1].time_secs, self.samples[i].time_secs);
            if found <= previous {
                let detail =
                    format!("time {found} s does not increase on the previous {previous} s");
                return Err(self.invalid(Some(i), detail));
            }
        }
        let camera = &self.camera_times_secs;
        for (k, &t) in camera.iter().enumerate() {
            let increasing = k == 0 || t > camera[k - 1];
            if !t.is_finite() || !increasing {
                let detail = format!("camera frame {k}: time {t} s is not finite and increasing");
                return Err(self.invalid(None, detail));
            }
        }
        Ok(())
    }

    /// A [`DatasetError::InvalidLog`] for this log.
    /// The log cut in time: the samples before `fraction` of its duration
    /// (named `<name>-train`) and the rest (`<name>-test`), camera frames
    /// with their samples; the way to hold out the end of one recording.
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] for a fraction outside (0, 1), and
    /// [`DatasetError::InvalidLog`] when a part would have fewer than two
    /// samples.
    pub fn split_in_time(&self, fraction: f64) -> Result<(RoverLog, RoverLog), DatasetError> {
        if !(fraction > 0.0 && fraction < 1.0) {
            return Err(DatasetError::InvalidConfig {
                field: "train_fraction".into(),
                expected: format!("a fraction in (0, 1), found {fraction}"),
            });
        }
        let t0 = self.samples.first().map_or(0.0, |s| s.time_secs);
        let cut_time = t0 + fraction * self.duration_secs();
        let cut = self.samples.partition_point(|s| s.time_secs < cut_time);
        if cut < 2 || self.samples.len() - cut < 2 {
            return Err(self.invalid(
                None,
                format!(
                    "cutting at {:.0} % leaves {} and {} samples; each part needs two",
                    100.0 * fraction,
                    cut,
                    self.samples.len() - cut
                ),
            ));
        }
        let part = |suffix: &str, range: std::ops::Range<usize>| {
            let (from, to) = (
                self.samples[range.start].time_secs,
                self.samples[range.end - 1].time_secs,
            );
            RoverLog {
                name: format!("{}-{suffix}", self.name),
                samples: self.samples[range.clone()].to_vec(),
                ground_truth: self.ground_truth[range].to_vec(),
                camera_times_secs: self
                    .camera_times_secs
                    .iter()
                    .copied()
                    .filter(|&t| t >= from && t <= to)
                    .collect(),
                ..self.clone_names()
            }
        };
        Ok((part("train", 0..cut), part("test", cut..self.samples.len())))
    }

    /// A log with this log's name and joints and nothing else.
    fn clone_names(&self) -> RoverLog {
        RoverLog {
            name: self.name.clone(),
            wheel_names: self.wheel_names.clone(),
            steer_names: self.steer_names.clone(),
            bogie_names: self.bogie_names.clone(),
            samples: Vec::new(),
            ground_truth: Vec::new(),
            camera_times_secs: Vec::new(),
        }
    }

    fn invalid(&self, sample: Option<usize>, detail: String) -> DatasetError {
        DatasetError::InvalidLog {
            log: self.name.clone(),
            sample,
            detail,
        }
    }
}

#[cfg(test)]
mod tests;
