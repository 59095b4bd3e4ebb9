//! Wheel odometry between processed frames: the parametric model's twists,
//! corrected by the predicted residual mean where the scheme's odometry
//! mode says so (eq. 12: `g + f`; [`crate::odometry_mode`]), integrated
//! from the last processed frame, with the covariance the mode's variance
//! implies, and the quantities a gating policy reads (distance, rotation,
//! accumulated drift).
//!
//! The residual prediction is constant over a regressor window, so its
//! error is fully correlated within the window: a window that contributes
//! the body-frame displacement matrix `D_w = Σ_k R_k τ_k` (rotations of the
//! step frames into the interval's start frame, times the step durations)
//! adds `D_w diag(σ²_w) D_wᵀ` to the translation covariance, and
//! `e_w τ_w²` to a drift (the expected squared displacement error over the
//! `τ_w` seconds spent in the window, `e_w` the expected squared velocity
//! error: `Σ σ²_w` of the odometry as corrected, or `E[r²]` of the
//! uncorrected odometry). A floor `q_t τ` (translation) and a random walk
//! `q_r τ` (rotation, gyro noise) are added per second, and a gyro bias `b`
//! held over the whole interval adds `σ_b² τ²` to each rotation axis (it
//! grows with the square of the gap, not linearly).

use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Matrix3, Matrix6};
use serde::{Deserialize, Serialize};

use crate::odometry_mode::WindowOdometry;

/// Variance added to every diagonal entry of an interval's covariance
/// (rad², m²): 1 µm, 1 µrad.
pub const COVARIANCE_FLOOR: f64 = 1e-12;

/// Noise of the odometry beyond the predicted residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OdometryNoise {
    /// Translation variance per second of driving, each axis (m²/s;
    /// default 1e-7: 0.3 mm after one second), for what the residual model
    /// does not describe.
    pub translation_m2_per_s: f64,
    /// Rotation variance per second, each axis (rad²/s; default 1e-6:
    /// 1 mrad after one second, a gyro's angle random walk).
    pub rotation_rad2_per_s: f64,
    /// Standard deviation σ_b of the gyro's bias, each axis (rad/s): adds
    /// `σ_b² τ²` over an interval of `τ` seconds. Default null: derived
    /// from the simulator's sensor noise on simulated data
    /// (`SensorNoise::gyro_bias_sigma_radps`, 6e-4 rad/s), 0 otherwise;
    /// set it from the IMU's datasheet for a recording.
    pub rotation_bias_radps: Option<f64>,
}

impl Default for OdometryNoise {
    fn default() -> Self {
        Self {
            translation_m2_per_s: 1e-7,
            rotation_rad2_per_s: 1e-6,
            rotation_bias_radps: None,
        }
    }
}

/// The odometry over one interval between processed frames.
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryInterval {
    /// Corrected odometry: `start_from_end`.
    pub relative: Isometry3<f64>,
    /// The parametric model alone (no residual correction): `start_from_end`.
    pub raw_relative: Isometry3<f64>,
    /// Covariance of `relative` as a right perturbation
    /// (`relative · Exp(δ)`, `δ = [rotation; translation]`, the order
    /// factrs uses), end-frame coordinates.
    pub covariance: Matrix6<f64>,
    /// Duration (s).
    pub duration_secs: f64,
    /// Path length of the corrected odometry (m).
    pub distance_m: f64,
    /// Rotation angle integrated from the angular rates (rad).
    pub rotation_rad: f64,
    /// Expected squared displacement error of the uncorrected odometry
    /// (m²), see the module documentation.
    pub drift_m2: f64,

    /// Duration-weighted mean of the regressor inputs of the windows the
    /// interval's steps belong to (`None` if no step was in a window).
    pub mean_inputs: Option<Vec<f64>>,
}

/// Integrates odometry since the last processed frame.
#[derive(Debug, Clone)]
pub struct OdometryIntegrator {
    noise: OdometryNoise,
    relative: Isometry3<f64>,
    raw_relative: Isometry3<f64>,
    translation_cov: Matrix3<f64>,
    rotation_var: f64,
    duration: f64,
    distance: f64,
    rotation: f64,
    drift: f64,
    drift_variance: f64,
    /// The window odometry in force and the displacement matrix / time
    /// spent under it since it took over (or since the interval started).
    epoch: Option<(usize, WindowOdometry)>,
    epoch_matrix: Matrix3<f64>,
    epoch_secs: f64,
    inputs_sum: Vec<f64>,
    inputs_secs: f64,
}

impl OdometryIntegrator {
    /// An integrator at the start of an interval.
    pub fn new(noise: OdometryNoise) -> Self {
        Self {
            noise,
            relative: Isometry3::identity(),
            raw_relative: Isometry3::identity(),
            translation_cov: Matrix3::zeros(),
            rotation_var: 0.0,
            duration: 0.0,
            distance: 0.0,
            rotation: 0.0,
            drift: 0.0,
            drift_variance: 0.0,
            epoch: None,
            epoch_matrix: Matrix3::zeros(),
            epoch_secs: 0.0,
            inputs_sum: Vec::new(),
            inputs_secs: 0.0,
        }
    }

    fn flush_epoch(&mut self) {
        if let Some((_, p)) = self.epoch {
            let d = self.epoch_matrix;
            self.translation_cov += d * Matrix3::from_diagonal(&p.variance) * d.transpose();
            self.drift += p.uncorrected_sq_error * self.epoch_secs * self.epoch_secs;
            self.drift_variance += p.variance.sum() * self.epoch_secs * self.epoch_secs;
        }
        self.epoch_matrix = Matrix3::zeros();
        self.epoch_secs = 0.0;
    }

    /// Drives `dt_secs` with the model's `twist` under window odometry
    /// number `epoch` (a new number starts a new fully correlated block)
    /// and the regressor inputs of the step's window, if any.
    pub fn advance(
        &mut self,
        twist: &BodyTwist,
        dt_secs: f64,
        epoch: usize,
        window: &WindowOdometry,
        inputs: Option<&[f64]>,
    ) {
        if dt_secs <= 0.0 {
            return;
        }
        if self.epoch.map(|(e, _)| e) != Some(epoch) {
            self.flush_epoch();
            self.epoch = Some((epoch, *window));
        }
        let corrected = BodyTwist {
            linear_mps: twist.linear_mps + window.correction,
            angular_radps: twist.angular_radps,
        };
        self.epoch_matrix += self.relative.rotation.to_rotation_matrix().matrix() * dt_secs;
        self.epoch_secs += dt_secs;
        self.relative *= corrected.pose_delta(dt_secs);
        self.raw_relative *= twist.pose_delta(dt_secs);
        self.translation_cov += Matrix3::identity() * (self.noise.translation_m2_per_s * dt_secs);
        self.rotation_var += self.noise.rotation_rad2_per_s * dt_secs;
        self.duration += dt_secs;
        self.distance += corrected.linear_mps.norm() * dt_secs;
        self.rotation += twist.angular_radps.norm() * dt_secs;
        if let Some(x) = inputs {
            if self.inputs_sum.len() != x.len() {
                self.inputs_sum = vec![0.0; x.len()];
                self.inputs_secs = 0.0;
            }
            for (acc, v) in self.inputs_sum.iter_mut().zip(x) {
                *acc += v * dt_secs;
            }
            self.inputs_secs += dt_secs;
        }
    }

    /// Corrected odometry since the interval started: `start_from_now`.
    pub fn relative(&self) -> &Isometry3<f64> {
        &self.relative
    }

    /// Path length since the interval started (m).
    pub fn distance_m(&self) -> f64 {
        self.distance
    }

    /// Integrated rotation since the interval started (rad).
    pub fn rotation_rad(&self) -> f64 {
        self.rotation
    }

    /// Time since the interval started (s).
    pub fn duration_secs(&self) -> f64 {
        self.duration
    }

    /// Expected squared displacement error since the interval started
    /// (m²), including the block in progress.
    pub fn drift_m2(&self) -> f64 {
        let partial = self.epoch.map_or(0.0, |(_, p)| {
            p.uncorrected_sq_error * self.epoch_secs * self.epoch_secs
        });
        self.drift + partial
    }

    /// The same for the odometry as corrected, from its variance alone
    /// (m²).
    pub fn drift_variance_m2(&self) -> f64 {
        let partial = self.epoch.map_or(0.0, |(_, p)| {
            p.variance.sum() * self.epoch_secs * self.epoch_secs
        });
        self.drift_variance + partial
    }

    /// Ends the interval: returns it and starts the next one at the same
    /// prediction epoch.
    pub fn take(&mut self) -> OdometryInterval {
        self.flush_epoch();
        let r = self.relative.rotation.to_rotation_matrix().into_inner();
        // Start-frame translation covariance → end-frame right perturbation.
        let translation = r.transpose() * self.translation_cov * r;
        let mut covariance = Matrix6::zeros();
        let bias = self.noise.rotation_bias_radps.unwrap_or(0.0) * self.duration;
        covariance
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * (self.rotation_var + bias * bias)));
        covariance
            .fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(0.5 * (translation + translation.transpose())));
        // A floor keeps the edge of a zero-length interval (a frame at the
        // previous node's time) well defined.
        covariance += Matrix6::identity() * COVARIANCE_FLOOR;
        let mean_inputs = (self.inputs_secs > 0.0).then(|| {
            self.inputs_sum
                .iter()
                .map(|v| v / self.inputs_secs)
                .collect()
        });
        let out = OdometryInterval {
            relative: self.relative,
            raw_relative: self.raw_relative,
            covariance,
            duration_secs: self.duration,
            distance_m: self.distance,
            rotation_rad: self.rotation,
            drift_m2: self.drift,
            mean_inputs,
        };
        let epoch = self.epoch;
        *self = Self::new(self.noise);
        self.epoch = epoch;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn twist(vx: f64, wz: f64) -> BodyTwist {
        BodyTwist {
            linear_mps: Vector3::new(vx, 0.0, 0.0),
            angular_radps: Vector3::new(0.0, 0.0, wz),
        }
    }

    fn prediction(mean_x: f64, var: f64) -> WindowOdometry {
        WindowOdometry {
            correction: Vector3::new(mean_x, 0.0, 0.0),
            variance: Vector3::repeat(var),
            uncorrected_sq_error: mean_x * mean_x + 3.0 * var,
        }
    }

    #[test]
    fn the_residual_mean_corrects_the_velocity() {
        let mut odo = OdometryIntegrator::new(OdometryNoise::default());
        let p = prediction(0.01, 0.0);
        for _ in 0..10 {
            odo.advance(&twist(0.04, 0.0), 0.1, 0, &p, None);
        }
        let out = odo.take();
        assert!((out.relative.translation.vector.x - 0.05).abs() < 1e-12);
        assert!((out.raw_relative.translation.vector.x - 0.04).abs() < 1e-12);
        assert!((out.distance_m - 0.05).abs() < 1e-12);
        assert!((out.duration_secs - 1.0).abs() < 1e-12);
    }

    #[test]
    fn one_window_is_fully_correlated_and_windows_add_independently() {
        let noise = OdometryNoise {
            translation_m2_per_s: 0.0,
            rotation_rad2_per_s: 0.0,
            rotation_bias_radps: None,
        };
        let p = prediction(0.0, 4e-6);
        // Two seconds under one prediction: σ_x = 2 s · 2 mm/s = 4 mm.
        let mut odo = OdometryIntegrator::new(noise);
        for _ in 0..20 {
            odo.advance(&twist(0.04, 0.0), 0.1, 0, &p, None);
        }
        let one = odo.take();
        assert!((one.covariance[(3, 3)] - 16e-6).abs() < 2e-12);
        assert!((one.drift_m2 - 3.0 * 4e-6 * 4.0).abs() < 1e-15);
        // A residual mean counts in the drift, not in the variance drift.
        let mut odo = OdometryIntegrator::new(noise);
        let biased = prediction(0.003, 4e-6);
        for _ in 0..10 {
            odo.advance(&twist(0.04, 0.0), 0.1, 0, &biased, None);
        }
        assert!((odo.drift_m2() - (9e-6 + 12e-6)).abs() < 1e-15);
        assert!((odo.drift_variance_m2() - 12e-6).abs() < 1e-15);
        // Two seconds under two predictions: 2 · (1 s · 2 mm/s)² = 8e-6.
        let mut odo = OdometryIntegrator::new(noise);
        for k in 0..20 {
            odo.advance(&twist(0.04, 0.0), 0.1, k / 10, &p, None);
        }
        let two = odo.take();
        assert!((two.covariance[(3, 3)] - 8e-6).abs() < 2e-12);
    }

    #[test]
    fn covariance_is_expressed_in_the_end_frame() {
        let noise = OdometryNoise {
            translation_m2_per_s: 0.0,
            rotation_rad2_per_s: 1e-6,
            rotation_bias_radps: None,
        };
        // Drive 1 s along x, then turn 90° in place: the x uncertainty of
        // the start frame is the end frame's −y uncertainty.
        let p = WindowOdometry {
            correction: Vector3::zeros(),
            variance: Vector3::new(1e-6, 0.0, 0.0),
            uncorrected_sq_error: 1e-6,
        };
        let mut odo = OdometryIntegrator::new(noise);
        odo.advance(&twist(0.04, 0.0), 1.0, 0, &p, None);
        let steps = 100;
        for _ in 0..steps {
            odo.advance(
                &twist(0.0, std::f64::consts::FRAC_PI_2),
                1.0 / steps as f64,
                1,
                &prediction(0.0, 0.0),
                None,
            );
        }
        let out = odo.take();
        assert!(
            (out.covariance[(4, 4)] - 1e-6).abs() < 1e-12,
            "{}",
            out.covariance
        );
        assert!(out.covariance[(3, 3)].abs() < 1e-11);
        assert!((out.covariance[(0, 0)] - 2e-6).abs() < 2e-12);
        assert!((out.rotation_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }

    #[test]
    fn mean_inputs_weight_steps_by_duration() {
        let mut odo = OdometryIntegrator::new(OdometryNoise::default());
        let p = prediction(0.0, 0.0);
        odo.advance(&twist(0.0, 0.0), 0.3, 0, &p, Some(&[1.0, 0.0]));
        odo.advance(&twist(0.0, 0.0), 0.1, 0, &p, Some(&[5.0, 4.0]));
        odo.advance(&twist(0.0, 0.0), 0.1, 0, &p, None);
        let out = odo.take();
        let m = out.mean_inputs.unwrap();
        assert!((m[0] - 2.0).abs() < 1e-12 && (m[1] - 1.0).abs() < 1e-12);
        assert!(odo.take().mean_inputs.is_none());
    }

    #[test]
    fn a_gyro_bias_grows_the_rotation_variance_with_the_square_of_the_gap() {
        let noise = OdometryNoise {
            rotation_bias_radps: Some(6e-4),
            ..OdometryNoise::default()
        };
        let rotation_variance = |secs: f64| {
            let mut odo = OdometryIntegrator::new(noise);
            for _ in 0..100 {
                odo.advance(
                    &twist(0.0, 0.0),
                    secs / 100.0,
                    0,
                    &prediction(0.0, 0.0),
                    None,
                );
            }
            odo.take().covariance[(2, 2)]
        };
        for secs in [1.0f64, 3.0, 10.0] {
            // q_r τ + σ_b² τ² + the floor.
            let expected = 1e-6 * secs + (6e-4 * secs).powi(2) + COVARIANCE_FLOOR;
            let got = rotation_variance(secs);
            assert!(
                (got / expected - 1.0).abs() < 1e-9,
                "{secs} s: {got} vs {expected}"
            );
        }
        // Beyond (q_r / σ_b²) ≈ 2.8 s the bias term dominates.
        assert!((6e-4f64 * 3.0).powi(2) > 1e-6 * 3.0);
        assert!((6e-4f64 * 2.0).powi(2) < 1e-6 * 2.0);
    }
}
