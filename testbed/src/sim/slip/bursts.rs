//! Slip bursts: short spells in which the wheels lose much more grip than
//! the slope and the soil's mean slip explain, as on loose sand when a wheel
//! breaks through a crust or digs into a ripple.
//!
//! On a soil named in [`SlipBursts::soils`] a burst starts with probability
//! `1 − exp(−rate_per_m · Δs)` per step, `Δs` the commanded distance of the
//! step (bursts come per metre driven, not per second: a standing rover
//! does not slip), unless one is under way. It lasts `duration_secs`, and
//! while it does the longitudinal slip ratio gains
//! `extra_slip · e^{slope_rate_per_rad · θ}` (`θ` the uphill angle, 0 on
//! level ground or downhill) before the slip model's clamp.
//!
//! The defaults rest on ExoTeR's real residuals
//! (`../shared/data/exoter_gp_train_1s.csv`, 1-s means): in steady
//! straight driving 0.29 excursions per metre of wheel travel exceed five
//! robust standard deviations of the running residual, almost all single
//! 1-s rows, carrying 0.16–0.47 of extra slip over the local median, the
//! extra growing from 0.29 on 0–3° of tilt to 0.74 above 10°. The table has
//! no soil label, so the rate is the lab's (mostly loose sand), applied
//! here to sand alone; the slope growth `e^{3θ}` (×1.7 at 10°) is fitted by
//! eye to four tilt bins. Mars rovers report rarer and larger events
//! (Opportunity's 44.5 % on one 5-m segment two sols after a 2.5 % drive),
//! which a user sets with a smaller rate and a larger extra slip.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::error::require;
use crate::sim::soil::Soil;

/// Settings of the burst process; see the module docs. Every field has a
/// default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlipBursts {
    /// Bursts per metre of commanded travel on a bursting soil (default 0.3).
    pub rate_per_m: f64,
    /// Extra longitudinal slip ratio of a burst on level ground (default
    /// 0.3).
    pub extra_slip: f64,
    /// How long a burst lasts (s; default 1).
    pub duration_secs: f64,
    /// Growth rate of the extra slip with the uphill angle (1/rad; default
    /// 3, half the slip model's slope rate).
    pub slope_rate_per_rad: f64,
    /// The soils, by name, on which bursts happen (default
    /// `["loose_sand"]`).
    pub soils: Vec<String>,
}

impl Default for SlipBursts {
    fn default() -> Self {
        Self {
            rate_per_m: 0.3,
            extra_slip: 0.3,
            duration_secs: 1.0,
            slope_rate_per_rad: 3.0,
            soils: vec!["loose_sand".to_owned()],
        }
    }
}

impl SlipBursts {
    /// Checks every field, naming the first bad one (`slip.bursts.…`).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        require(
            non_negative(self.rate_per_m),
            "slip.bursts.rate_per_m",
            "a finite value >= 0",
        )?;
        require(
            self.extra_slip.is_finite() && (0.0..1.0).contains(&self.extra_slip),
            "slip.bursts.extra_slip",
            "a value in [0, 1)",
        )?;
        require(
            self.duration_secs.is_finite() && self.duration_secs > 0.0,
            "slip.bursts.duration_secs",
            "a finite value > 0",
        )?;
        require(
            non_negative(self.slope_rate_per_rad),
            "slip.bursts.slope_rate_per_rad",
            "a finite value >= 0",
        )
    }

    /// Whether bursts happen on `soil`.
    pub fn bursts_on(&self, soil: &Soil) -> bool {
        self.soils.contains(&soil.name)
    }

    /// The extra slip ratio of a burst at uphill angle `uphill_rad`.
    pub fn extra_at(&self, uphill_rad: f64) -> f64 {
        self.extra_slip * (self.slope_rate_per_rad * uphill_rad.max(0.0)).exp()
    }
}

/// The state of the burst process along one run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BurstProcess {
    /// Time left in the burst under way (s; 0 when none is).
    remaining_secs: f64,
    /// Bursts started so far.
    started: usize,
}

impl BurstProcess {
    /// Advances one step of `dt_secs` over `commanded_distance_m` on `soil`;
    /// returns whether a burst acts during this step. Draws one uniform
    /// number from `rng` per step on a bursting soil outside a burst, and
    /// none otherwise.
    pub fn step<R: Rng + ?Sized>(
        &mut self,
        bursts: &SlipBursts,
        soil: &Soil,
        commanded_distance_m: f64,
        dt_secs: f64,
        rng: &mut R,
    ) -> bool {
        if self.remaining_secs > 0.0 {
            self.remaining_secs -= dt_secs;
            return true;
        }
        if !(bursts.bursts_on(soil) && commanded_distance_m > 0.0) {
            return false;
        }
        let p = 1.0 - (-bursts.rate_per_m * commanded_distance_m).exp();
        if rng.random::<f64>() < p {
            self.started += 1;
            self.remaining_secs = bursts.duration_secs - dt_secs;
            return true;
        }
        false
    }

    /// Bursts started so far.
    pub fn started(&self) -> usize {
        self.started
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Steps of 0.08 s at 0.04 m/s over `metres` on `soil`: (bursts
    /// started, steps in a burst).
    fn drive(bursts: &SlipBursts, soil: &Soil, metres: f64, seed: u64) -> (usize, usize) {
        let (dt, speed) = (0.08, 0.04);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut process = BurstProcess::default();
        let steps = (metres / (speed * dt)).round() as usize;
        let active = (0..steps)
            .filter(|_| process.step(bursts, soil, speed * dt, dt, &mut rng))
            .count();
        (process.started(), active)
    }

    #[test]
    fn bursts_come_at_their_rate_per_metre_and_last_their_duration() {
        let bursts = SlipBursts::default();
        let metres = 2000.0;
        let (started, active) = drive(&bursts, &Soil::loose_sand(), metres, 3);
        // The process is renewal: a burst of duration d at speed v blocks
        // v·d metres, so the rate of starts is r / (1 + r·v·d).
        let expected = metres * bursts.rate_per_m / (1.0 + bursts.rate_per_m * 0.04 * 1.0);
        let sd = expected.sqrt();
        assert!(
            (started as f64 - expected).abs() < 4.0 * sd,
            "{started} bursts, expected {expected:.0} ± {sd:.0}"
        );
        // Each lasts 1 s: 12.5 steps of 0.08 s, rounded up to 13.
        assert_eq!(active, started * 13);
    }

    #[test]
    fn other_soils_and_a_standing_rover_never_burst() {
        let bursts = SlipBursts::default();
        assert_eq!(drive(&bursts, &Soil::compact(), 500.0, 1), (0, 0));
        assert_eq!(drive(&bursts, &Soil::gravel(), 500.0, 1), (0, 0));
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let mut process = BurstProcess::default();
        assert!((0..10_000).all(|_| !process.step(
            &bursts,
            &Soil::loose_sand(),
            0.0,
            0.08,
            &mut rng
        )));
    }

    #[test]
    fn the_extra_slip_grows_with_the_uphill_angle_only() {
        let bursts = SlipBursts::default();
        assert_eq!(bursts.extra_at(0.0), 0.3);
        assert_eq!(bursts.extra_at(-0.2), 0.3);
        let ten = 10f64.to_radians();
        assert!((bursts.extra_at(ten) - 0.3 * (3.0 * ten).exp()).abs() < 1e-15);
        assert!((bursts.extra_at(ten) / 0.3 - 1.688).abs() < 1e-3);
    }

    #[test]
    fn bad_settings_are_refused_by_name() {
        for (bad, field) in [
            (
                SlipBursts {
                    rate_per_m: -1.0,
                    ..SlipBursts::default()
                },
                "slip.bursts.rate_per_m",
            ),
            (
                SlipBursts {
                    extra_slip: 1.0,
                    ..SlipBursts::default()
                },
                "slip.bursts.extra_slip",
            ),
            (
                SlipBursts {
                    duration_secs: 0.0,
                    ..SlipBursts::default()
                },
                "slip.bursts.duration_secs",
            ),
        ] {
            let err = bad.validate().unwrap_err();
            assert!(err.to_string().contains(field), "{err}");
        }
    }
}
