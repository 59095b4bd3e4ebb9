//! The residual targets an online learner learns from visual odometry
//! (§VI), formed one way for the offline schemes ([`crate::run`]) and the
//! live node: over an interval between two poses the VO tracked, the VO's
//! displacement minus the parametric odometry's, per second, in the frame
//! of the interval's start, with the regressor inputs averaged over the
//! interval by time.
//!
//! A [`TargetInterval`] is opened at a tracked pose, takes the parametric
//! odometry of every stretch driven since ([`TargetInterval::add`]), and
//! is closed at a later tracked pose once it spans
//! [`OnlineTargetParams::min_interval_secs`]; an interval longer than
//! [`OnlineTargetParams::max_interval_secs`], or with no regressor inputs,
//! gives no target.

use nalgebra::{Isometry3, Vector3};

use crate::params::OnlineTargetParams;

/// One residual target.
#[derive(Debug, Clone, PartialEq)]
pub struct VoTarget {
    /// The regressor inputs, averaged over the interval by time.
    pub inputs: Vec<f64>,
    /// The residual (m/s): the VO's displacement minus the parametric
    /// odometry's, in the frame of the interval's start, over its length.
    pub residual: Vector3<f64>,
    /// The interval's end (s).
    pub time_secs: f64,
    /// The interval's length (s).
    pub duration_secs: f64,
}

/// Why a closed interval gave no target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoTarget {
    /// The interval is shorter than the least a target spans: keep
    /// accumulating.
    TooShort,
    /// The interval is longer than the most a target spans (a loss in
    /// between).
    TooLong,
    /// No stretch of it had regressor inputs.
    NoInputs,
    /// Its start or end pose is unknown (not tracked).
    Untracked,
}

/// An open interval: from a tracked pose, the parametric odometry since.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetInterval {
    start_secs: f64,
    start_pose: Option<Isometry3<f64>>,
    raw_relative: Isometry3<f64>,
    inputs_sum: Vec<f64>,
    inputs_secs: f64,
}

impl TargetInterval {
    /// Opens an interval at `time_secs`, at the VO's pose `start_pose`
    /// (`None` when the VO did not place that frame).
    pub fn open(time_secs: f64, start_pose: Option<Isometry3<f64>>) -> Self {
        Self {
            start_secs: time_secs,
            start_pose,
            raw_relative: Isometry3::identity(),
            inputs_sum: Vec::new(),
            inputs_secs: 0.0,
        }
    }

    /// When the interval opened (s).
    pub fn start_secs(&self) -> f64 {
        self.start_secs
    }

    /// Adds a stretch driven since: its parametric odometry
    /// (`start_from_end`, no residual correction), the time-weighted mean
    /// of its regressor inputs if it had any, and its length (s). A change
    /// in the inputs' width restarts their average.
    pub fn add(
        &mut self,
        raw_relative: &Isometry3<f64>,
        mean_inputs: Option<&[f64]>,
        duration_secs: f64,
    ) {
        self.raw_relative *= raw_relative;
        if let Some(x) = mean_inputs {
            if self.inputs_sum.len() != x.len() {
                self.inputs_sum = vec![0.0; x.len()];
                self.inputs_secs = 0.0;
            }
            for (acc, v) in self.inputs_sum.iter_mut().zip(x) {
                *acc += v * duration_secs;
            }
            self.inputs_secs += duration_secs;
        }
    }

    /// Whether the interval, closed at `time_secs`, spans enough to give a
    /// target.
    pub fn is_ready(&self, time_secs: f64, limits: &OnlineTargetParams) -> bool {
        time_secs - self.start_secs >= limits.min_interval_secs
    }

    /// Closes the interval at `time_secs`, at the VO's pose `end_pose`.
    ///
    /// # Errors
    /// [`NoTarget`] says why the interval gives no target;
    /// [`NoTarget::TooShort`] leaves the interval to be continued (the
    /// caller checks [`Self::is_ready`] first).
    pub fn close(
        &self,
        time_secs: f64,
        end_pose: Option<&Isometry3<f64>>,
        limits: &OnlineTargetParams,
    ) -> Result<VoTarget, NoTarget> {
        let mut target = self.close_without_inputs(time_secs, end_pose, limits)?;
        if self.inputs_secs <= 0.0 {
            return Err(NoTarget::NoInputs);
        }
        target.inputs = self
            .inputs_sum
            .iter()
            .map(|v| v / self.inputs_secs)
            .collect();
        Ok(target)
    }

    /// [`Self::close`] for a caller that attributes the regressor inputs
    /// itself, once it knows them: the target's inputs are left empty, and
    /// an interval driven without inputs is not refused for it.
    ///
    /// # Errors
    /// As [`Self::close`], but never [`NoTarget::NoInputs`].
    pub fn close_without_inputs(
        &self,
        time_secs: f64,
        end_pose: Option<&Isometry3<f64>>,
        limits: &OnlineTargetParams,
    ) -> Result<VoTarget, NoTarget> {
        let duration = time_secs - self.start_secs;
        if !self.is_ready(time_secs, limits) {
            return Err(NoTarget::TooShort);
        }
        let (Some(a), Some(b)) = (self.start_pose.as_ref(), end_pose) else {
            return Err(NoTarget::Untracked);
        };
        if duration > limits.max_interval_secs {
            return Err(NoTarget::TooLong);
        }
        let visual = a.inverse() * b;
        Ok(VoTarget {
            inputs: Vec::new(),
            residual: (visual.translation.vector - self.raw_relative.translation.vector) / duration,
            time_secs,
            duration_secs: duration,
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;

    fn limits() -> OnlineTargetParams {
        OnlineTargetParams {
            min_interval_secs: 4.0,
            max_interval_secs: 12.0,
        }
    }

    #[test]
    fn a_target_is_the_displacement_difference_per_second_in_the_start_frame() {
        // The start pose is turned a quarter turn about z: a displacement
        // of 1 m along the world's y is 1 m along the start frame's x.
        let start = Isometry3::from_parts(
            Translation3::new(5.0, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let end = Isometry3::from_parts(
            Translation3::new(5.0, 1.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let mut interval = TargetInterval::open(10.0, Some(start));
        // Two stretches of the parametric odometry: 0.45 m then 0.35 m
        // ahead, inputs 1 for 1 s and 4 for 3 s.
        interval.add(&Isometry3::translation(0.45, 0.0, 0.0), Some(&[1.0]), 1.0);
        interval.add(&Isometry3::translation(0.35, 0.0, 0.0), Some(&[4.0]), 3.0);
        let target = interval.close(15.0, Some(&end), &limits()).unwrap();
        assert!((target.residual - Vector3::new(0.2 / 5.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((target.inputs[0] - 13.0 / 4.0).abs() < 1e-15);
        assert_eq!((target.time_secs, target.duration_secs), (15.0, 5.0));
    }

    #[test]
    fn intervals_outside_the_limits_or_untracked_give_no_target() {
        let pose = Isometry3::identity();
        let mut interval = TargetInterval::open(0.0, Some(pose));
        interval.add(&pose, Some(&[0.0]), 1.0);
        let l = limits();
        assert_eq!(
            interval.close(3.0, Some(&pose), &l),
            Err(NoTarget::TooShort)
        );
        assert!(!interval.is_ready(3.9, &l) && interval.is_ready(4.0, &l));
        assert_eq!(
            interval.close(12.5, Some(&pose), &l),
            Err(NoTarget::TooLong)
        );
        assert_eq!(interval.close(6.0, None, &l), Err(NoTarget::Untracked));
        let without_inputs = TargetInterval::open(0.0, Some(pose));
        assert_eq!(
            without_inputs.close(6.0, Some(&pose), &l),
            Err(NoTarget::NoInputs)
        );
        assert!(interval.close(6.0, Some(&pose), &l).is_ok());
    }
}
