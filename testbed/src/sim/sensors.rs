//! The rover's sensors and the motion-capture system, with their noise.
//!
//! Sensors run at 12.5 Hz as on ExoTeR: wheel encoders (angle and rate),
//! steering encoders, bogie potentiometers, an IMU (gyros with a slowly
//! drifting bias and white noise, accelerometers reading specific force,
//! gravity included, plus vibration on rough soils) and an attitude filter
//! (roll, pitch with a slowly varying error). Ground truth is a Vicon-like
//! motion-capture system: a slowly varying calibration error of about 1 cm
//! and 0.2° plus sub-millimetre jitter.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::error::require;
use crate::sim::noise::{OrnsteinUhlenbeck, RandomWalk, standard_normal};

/// Noise levels of every sensor (standard deviations unless said otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorNoise {
    /// Gyro white noise per sample (rad/s). Default 5e-4.
    pub gyro_noise_radps: f64,
    /// Gyro bias random-walk intensity (rad/s/√s). Default 2e-5.
    pub gyro_bias_walk: f64,
    /// Accelerometer white noise (m/s²). Default 0.02.
    pub accel_noise_mps2: f64,
    /// Attitude (roll, pitch) error, slowly varying (rad). Default 0.003.
    pub attitude_error_rad: f64,
    /// Correlation time of the attitude error (s). Default 20.
    pub attitude_error_secs: f64,
    /// Wheel rate noise (rad/s). Default 0.003.
    pub wheel_rate_noise_radps: f64,
    /// Steering and bogie angle noise (rad). Default 0.002.
    pub joint_angle_noise_rad: f64,
    /// Steering and bogie rate noise (rad/s). Default 0.004.
    pub joint_rate_noise_radps: f64,
    /// Motion-capture position calibration error, slowly varying (m). Default 0.008.
    pub mocap_position_error_m: f64,
    /// Motion-capture orientation calibration error (rad). Default 0.0035 (0.2°).
    pub mocap_orientation_error_rad: f64,
    /// Correlation time of the motion-capture errors (s). Default 60.
    pub mocap_error_secs: f64,
    /// Motion-capture jitter per frame (m). Default 3e-4.
    pub mocap_jitter_m: f64,
}

impl Default for SensorNoise {
    fn default() -> Self {
        Self {
            gyro_noise_radps: 5e-4,
            gyro_bias_walk: 2e-5,
            accel_noise_mps2: 0.02,
            attitude_error_rad: 0.003,
            attitude_error_secs: 20.0,
            wheel_rate_noise_radps: 0.003,
            joint_angle_noise_rad: 0.002,
            joint_rate_noise_radps: 0.004,
            mocap_position_error_m: 0.008,
            mocap_orientation_error_rad: 0.0035,
            mocap_error_secs: 60.0,
            mocap_jitter_m: 3e-4,
        }
    }
}

impl SensorNoise {
    /// Standard deviation of each gyro axis' bias at the start of a run
    /// (rad/s): the stationary draw the simulator starts the bias random
    /// walk from, `30 s^½ × gyro_bias_walk` (6e-4 rad/s by default). What an
    /// odometry covariance should allow for a bias held over an interval.
    pub fn gyro_bias_sigma_radps(&self) -> f64 {
        self.gyro_bias_walk * 30.0
    }

    /// Checks that every level is finite and non-negative and every time
    /// positive.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming the field (`sensors.<name>`).
    pub fn validate(&self) -> Result<(), TestbedError> {
        let levels = [
            ("gyro_noise_radps", self.gyro_noise_radps),
            ("gyro_bias_walk", self.gyro_bias_walk),
            ("accel_noise_mps2", self.accel_noise_mps2),
            ("attitude_error_rad", self.attitude_error_rad),
            ("wheel_rate_noise_radps", self.wheel_rate_noise_radps),
            ("joint_angle_noise_rad", self.joint_angle_noise_rad),
            ("joint_rate_noise_radps", self.joint_rate_noise_radps),
            ("mocap_position_error_m", self.mocap_position_error_m),
            (
                "mocap_orientation_error_rad",
                self.mocap_orientation_error_rad,
            ),
            ("mocap_jitter_m", self.mocap_jitter_m),
        ];
        for (name, v) in levels {
            require(
                v.is_finite() && v >= 0.0,
                &format!("sensors.{name}"),
                "a finite value >= 0",
            )?;
        }
        for (name, v) in [
            ("attitude_error_secs", self.attitude_error_secs),
            ("mocap_error_secs", self.mocap_error_secs),
        ] {
            require(
                v.is_finite() && v > 0.0,
                &format!("sensors.{name}"),
                "a positive time in s",
            )?;
        }
        Ok(())
    }

    /// Every level zero: ideal sensors and ground truth.
    pub fn none() -> Self {
        Self {
            gyro_noise_radps: 0.0,
            gyro_bias_walk: 0.0,
            accel_noise_mps2: 0.0,
            attitude_error_rad: 0.0,
            wheel_rate_noise_radps: 0.0,
            joint_angle_noise_rad: 0.0,
            joint_rate_noise_radps: 0.0,
            mocap_position_error_m: 0.0,
            mocap_orientation_error_rad: 0.0,
            mocap_jitter_m: 0.0,
            ..Self::default()
        }
    }
}

/// A zero-mean normal draw with standard deviation `sigma`.
pub fn normal<R: Rng + ?Sized>(rng: &mut R, sigma: f64) -> f64 {
    if sigma == 0.0 {
        return 0.0;
    }
    sigma * standard_normal(rng)
}

/// The time-correlated parts of the sensor errors of one run.
#[derive(Debug, Clone)]
pub struct SensorErrors {
    noise: SensorNoise,
    gyro_bias: [RandomWalk; 3],
    attitude: [OrnsteinUhlenbeck; 2],
    mocap_position: [OrnsteinUhlenbeck; 3],
    mocap_orientation: [OrnsteinUhlenbeck; 3],
}

impl SensorErrors {
    /// Fresh error processes (biases start from stationary draws).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] for negative levels or times.
    pub fn new<R: Rng + ?Sized>(noise: SensorNoise, rng: &mut R) -> Result<Self, TestbedError> {
        noise.validate()?;
        let walk = |rng: &mut R| {
            RandomWalk::new(
                noise.gyro_bias_walk,
                normal(rng, noise.gyro_bias_sigma_radps()),
            )
        };
        let ou = |sigma: f64, secs: f64, rng: &mut R| {
            OrnsteinUhlenbeck::new_stationary(sigma, secs, rng)
        };
        Ok(Self {
            noise,
            gyro_bias: [walk(rng)?, walk(rng)?, walk(rng)?],
            attitude: [
                ou(noise.attitude_error_rad, noise.attitude_error_secs, rng)?,
                ou(noise.attitude_error_rad, noise.attitude_error_secs, rng)?,
            ],
            mocap_position: [
                ou(noise.mocap_position_error_m, noise.mocap_error_secs, rng)?,
                ou(noise.mocap_position_error_m, noise.mocap_error_secs, rng)?,
                ou(noise.mocap_position_error_m, noise.mocap_error_secs, rng)?,
            ],
            mocap_orientation: [
                ou(
                    noise.mocap_orientation_error_rad,
                    noise.mocap_error_secs,
                    rng,
                )?,
                ou(
                    noise.mocap_orientation_error_rad,
                    noise.mocap_error_secs,
                    rng,
                )?,
                ou(
                    noise.mocap_orientation_error_rad,
                    noise.mocap_error_secs,
                    rng,
                )?,
            ],
        })
    }

    /// The noise levels.
    pub fn levels(&self) -> &SensorNoise {
        &self.noise
    }

    /// Advances every correlated error by one step.
    pub fn step<R: Rng + ?Sized>(&mut self, dt_secs: f64, rng: &mut R) {
        for p in &mut self.gyro_bias {
            p.step(dt_secs, rng);
        }
        for p in self
            .attitude
            .iter_mut()
            .chain(&mut self.mocap_position)
            .chain(&mut self.mocap_orientation)
        {
            p.step(dt_secs, rng);
        }
    }

    /// Gyro reading for a true body rate.
    pub fn gyro<R: Rng + ?Sized>(&self, true_radps: &Vector3<f64>, rng: &mut R) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            true_radps[i] + self.gyro_bias[i].value() + normal(rng, self.noise.gyro_noise_radps)
        })
    }

    /// Accelerometer reading for a true specific force plus vibration.
    pub fn accel<R: Rng + ?Sized>(
        &self,
        true_mps2: &Vector3<f64>,
        vibration_mps2: f64,
        rng: &mut R,
    ) -> Vector3<f64> {
        let sigma = self.noise.accel_noise_mps2.hypot(vibration_mps2);
        Vector3::from_fn(|i, _| true_mps2[i] + normal(rng, sigma))
    }

    /// Attitude filter output `(roll, pitch)`.
    pub fn attitude(&self, roll_rad: f64, pitch_rad: f64) -> (f64, f64) {
        (
            roll_rad + self.attitude[0].value(),
            pitch_rad + self.attitude[1].value(),
        )
    }

    /// What the motion-capture system reports for a true pose.
    pub fn mocap<R: Rng + ?Sized>(&self, truth: &Isometry3<f64>, rng: &mut R) -> Isometry3<f64> {
        let jitter = self.noise.mocap_jitter_m;
        let dp = Vector3::from_fn(|i, _| self.mocap_position[i].value() + normal(rng, jitter));
        let dr = Vector3::from_fn(|i, _| self.mocap_orientation[i].value());
        Isometry3::from_parts(
            Translation3::from(truth.translation.vector + dp),
            UnitQuaternion::from_scaled_axis(dr) * truth.rotation,
        )
    }
}
