//! Bounds on the optimiser's coordinates (the logarithm of a positive
//! hyperparameter, or a free coordinate such as an inducing input).
//! Inside `[lower, upper]` the objective is exactly the model's; outside, it
//! is evaluated at the nearest bound plus a quadratic penalty
//! `(u − clamp(u))²` that points back inside.
//! (A logistic squashing of `log θ` would also keep `θ` in bounds, but its
//! gradient vanishes near them, and an early long step parks the optimiser
//! in that flat corner.)

/// Bounds of one hyperparameter, as logarithms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogBounds {
    lo: f64,
    hi: f64,
}

impl LogBounds {
    /// Bounds `[lower, upper]` in natural units (both positive).
    pub fn new([lower, upper]: [f64; 2]) -> Self {
        Self {
            lo: lower.ln(),
            hi: upper.ln(),
        }
    }

    /// No bounds: a free coordinate used as it is.
    pub fn unbounded() -> Self {
        Self {
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        }
    }

    /// The lower bound of `log θ` (−∞ when free).
    pub fn lower(&self) -> f64 {
        self.lo
    }

    /// The upper bound of `log θ` (+∞ when free).
    pub fn upper(&self) -> f64 {
        self.hi
    }

    /// `log θ` used for the optimiser's coordinate `u`: `u` clamped.
    pub fn to_log(&self, u: f64) -> f64 {
        u.clamp(self.lo, self.hi)
    }

    /// The optimiser's coordinate for `log θ` (clamped into the bounds).
    pub fn from_log(&self, log_theta: f64) -> f64 {
        log_theta.clamp(self.lo, self.hi)
    }

    /// `d log θ / du`: 1 inside the bounds, 0 outside.
    pub fn derivative(&self, u: f64) -> f64 {
        if (self.lo..=self.hi).contains(&u) {
            1.0
        } else {
            0.0
        }
    }

    /// The penalty `(u − clamp(u))²` and its derivative.
    pub fn penalty(&self, u: f64) -> (f64, f64) {
        let excess = u - self.to_log(u);
        (excess * excess, 2.0 * excess)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamps_and_penalises_outside_only() {
        let b = LogBounds::new([1e-3, 1e5]);
        assert_eq!(b.to_log(0.5), 0.5);
        assert_eq!(b.penalty(0.5), (0.0, 0.0));
        assert_eq!(b.derivative(0.5), 1.0);
        let above = 1e5f64.ln() + 2.0;
        assert!((b.to_log(above) - 1e5f64.ln()).abs() < 1e-12);
        let (p, g) = b.penalty(above);
        assert!((p - 4.0).abs() < 1e-9 && (g - 4.0).abs() < 1e-9);
        assert_eq!(b.derivative(above), 0.0);
        assert!((b.from_log(-20.0) - 1e-3f64.ln()).abs() < 1e-12);
        let free = LogBounds::unbounded();
        assert_eq!(free.to_log(-1e300), -1e300);
        assert_eq!(free.penalty(7.0), (0.0, 0.0));
    }
}
