//! Noise processes of the simulated testbed.
//!
//! Two building blocks drive every random perturbation of the simulator:
//!
//! - [`OrnsteinUhlenbeck`]: mean-reverting, time-correlated Gaussian noise with
//!   a stationary standard deviation `σ` and a correlation time `τ`. The
//!   simulator draws the slip perturbations of [`super::slip`] from it, so a
//!   patch of bad traction lasts a few seconds instead of flickering at the
//!   sensor rate. Its autocorrelation at lag `t` is `exp(-|t|/τ)`.
//! - [`RandomWalk`]: an integrated white noise (Brownian motion) whose standard
//!   deviation grows as `σ·sqrt(t)`; it models slowly wandering biases such as a
//!   gyroscope bias or the drift of the motion-capture reference.
//!
//! Both processes are stepped with their exact discretisation, so the
//! statistics do not depend on the step length.

use rand::Rng;
use rand_distr::StandardNormal;

use crate::TestbedError;
use crate::error::require;

/// Mean-reverting Gaussian noise (an Ornstein–Uhlenbeck process).
///
/// Stepped with the exact discretisation
/// `x ← x·e^{−dt/τ} + σ·sqrt(1 − e^{−2dt/τ})·N(0, 1)`, so its stationary
/// standard deviation is `σ` and its lag-`t` autocorrelation is `e^{−t/τ}` for
/// any step length. [`OrnsteinUhlenbeck::new`] starts the process at 0 (the
/// first samples are then smaller than stationary for about `τ`);
/// [`OrnsteinUhlenbeck::new_stationary`] starts it from a stationary draw.
#[derive(Clone, Debug, PartialEq)]
pub struct OrnsteinUhlenbeck {
    sigma: f64,
    correlation_time_secs: f64,
    value: f64,
}

impl OrnsteinUhlenbeck {
    /// A process with stationary standard deviation `sigma` (≥ 0, in the units
    /// of the noise) and correlation time `correlation_time_secs` (> 0), started
    /// at 0.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming `sigma` or
    /// `correlation_time_secs` when it is negative, zero (for the time) or not
    /// finite.
    pub fn new(sigma: f64, correlation_time_secs: f64) -> Result<Self, TestbedError> {
        require(
            sigma.is_finite() && sigma >= 0.0,
            "sigma",
            "a finite value >= 0",
        )?;
        require(
            correlation_time_secs.is_finite() && correlation_time_secs > 0.0,
            "correlation_time_secs",
            "a finite value > 0",
        )?;
        Ok(Self {
            sigma,
            correlation_time_secs,
            value: 0.0,
        })
    }

    /// Like [`OrnsteinUhlenbeck::new`], but started from a draw of the
    /// stationary distribution `N(0, σ²)`.
    ///
    /// # Errors
    /// As [`OrnsteinUhlenbeck::new`].
    pub fn new_stationary<R: Rng + ?Sized>(
        sigma: f64,
        correlation_time_secs: f64,
        rng: &mut R,
    ) -> Result<Self, TestbedError> {
        let mut process = Self::new(sigma, correlation_time_secs)?;
        process.value = sigma * standard_normal(rng);
        Ok(process)
    }

    /// Advances the process by `dt_secs` and returns the new value. A
    /// non-positive or non-finite `dt_secs` leaves the value unchanged (and
    /// draws nothing from `rng`).
    pub fn step<R: Rng + ?Sized>(&mut self, dt_secs: f64, rng: &mut R) -> f64 {
        if !(dt_secs.is_finite() && dt_secs > 0.0) {
            return self.value;
        }
        let decay = (-dt_secs / self.correlation_time_secs).exp();
        let innovation_std = self.sigma * (1.0 - decay * decay).max(0.0).sqrt();
        self.value = self.value * decay + innovation_std * standard_normal(rng);
        self.value
    }

    /// The current value.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The stationary standard deviation `σ`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The correlation time `τ`, in seconds.
    pub fn correlation_time_secs(&self) -> f64 {
        self.correlation_time_secs
    }
}

/// A Gaussian random walk (Brownian motion), for slowly drifting biases.
///
/// Each step adds `intensity·sqrt(dt)·N(0, 1)`, so after a time `t` the
/// standard deviation of the change is `intensity·sqrt(t)`. The intensity has
/// the units of the value per square-root second (e.g. rad/s/√s for a gyro
/// bias, m/√s for a motion-capture drift).
#[derive(Clone, Debug, PartialEq)]
pub struct RandomWalk {
    intensity_per_sqrt_sec: f64,
    value: f64,
}

impl RandomWalk {
    /// A walk of the given intensity (≥ 0, units per √s) starting at
    /// `initial`.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming `intensity_per_sqrt_sec` or
    /// `initial` when it is not finite (or the intensity is negative).
    pub fn new(intensity_per_sqrt_sec: f64, initial: f64) -> Result<Self, TestbedError> {
        require(
            intensity_per_sqrt_sec.is_finite() && intensity_per_sqrt_sec >= 0.0,
            "intensity_per_sqrt_sec",
            "a finite value >= 0",
        )?;
        require(initial.is_finite(), "initial", "a finite value")?;
        Ok(Self {
            intensity_per_sqrt_sec,
            value: initial,
        })
    }

    /// Advances the walk by `dt_secs` and returns the new value. A
    /// non-positive or non-finite `dt_secs` leaves the value unchanged.
    pub fn step<R: Rng + ?Sized>(&mut self, dt_secs: f64, rng: &mut R) -> f64 {
        if dt_secs.is_finite() && dt_secs > 0.0 {
            self.value += self.intensity_per_sqrt_sec * dt_secs.sqrt() * standard_normal(rng);
        }
        self.value
    }

    /// The current value.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The intensity, in units per √s.
    pub fn intensity_per_sqrt_sec(&self) -> f64 {
        self.intensity_per_sqrt_sec
    }
}

/// One draw of `N(0, 1)`.
pub(crate) fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    rng.sample::<f64, _>(StandardNormal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn ou_samples(sigma: f64, tau: f64, dt: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut ou = OrnsteinUhlenbeck::new_stationary(sigma, tau, &mut rng).unwrap();
        (0..n).map(|_| ou.step(dt, &mut rng)).collect()
    }

    fn mean(xs: &[f64]) -> f64 {
        xs.iter().sum::<f64>() / xs.len() as f64
    }

    fn std(xs: &[f64]) -> f64 {
        let m = mean(xs);
        (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / xs.len() as f64).sqrt()
    }

    #[test]
    fn ou_long_run_std_matches_sigma_within_five_percent() {
        let xs = ou_samples(0.7, 2.0, 0.08, 400_000, 1);
        let s = std(&xs);
        assert!((s / 0.7 - 1.0).abs() < 0.05, "std {s}");
    }

    #[test]
    fn ou_autocorrelation_at_lag_tau_is_one_over_e() {
        let (tau, dt) = (2.0, 0.08);
        let xs = ou_samples(1.0, tau, dt, 400_000, 2);
        let lag = (tau / dt).round() as usize;
        let m = mean(&xs);
        let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>();
        let cov = xs
            .iter()
            .zip(&xs[lag..])
            .map(|(a, b)| (a - m) * (b - m))
            .sum::<f64>();
        let rho = cov / var;
        assert!((rho - (-1.0f64).exp()).abs() < 0.03, "rho {rho}");
    }

    #[test]
    fn ou_statistics_do_not_depend_on_step_length() {
        let coarse = ou_samples(1.0, 1.0, 0.5, 100_000, 3);
        assert!((std(&coarse) - 1.0).abs() < 0.05);
    }

    #[test]
    fn ou_started_with_new_is_at_zero_and_zero_step_keeps_value() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut ou = OrnsteinUhlenbeck::new(1.0, 1.0).unwrap();
        assert_eq!(ou.value(), 0.0);
        let v = ou.step(0.1, &mut rng);
        assert_eq!(ou.step(0.0, &mut rng), v);
        assert_eq!(ou.step(f64::NAN, &mut rng), v);
    }

    #[test]
    fn ou_rejects_non_positive_correlation_time_by_name() {
        let err = OrnsteinUhlenbeck::new(1.0, 0.0).unwrap_err();
        assert!(
            matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "correlation_time_secs")
        );
        let err = OrnsteinUhlenbeck::new(-1.0, 1.0).unwrap_err();
        assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "sigma"));
    }

    #[test]
    fn random_walk_spread_grows_with_square_root_of_time() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (intensity, dt, steps) = (0.3, 0.08, 125);
        let finals: Vec<f64> = (0..4000)
            .map(|_| {
                let mut walk = RandomWalk::new(intensity, 0.0).unwrap();
                (0..steps).fold(0.0, |_, _| walk.step(dt, &mut rng))
            })
            .collect();
        let expected = intensity * (dt * steps as f64).sqrt();
        assert!((std(&finals) / expected - 1.0).abs() < 0.05);
    }

    #[test]
    fn random_walk_rejects_negative_intensity_by_name() {
        let err = RandomWalk::new(-0.1, 0.0).unwrap_err();
        assert!(
            matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "intensity_per_sqrt_sec")
        );
    }
}
