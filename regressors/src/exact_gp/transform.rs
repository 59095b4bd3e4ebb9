//! The bounded log transform the optimiser works in: an unconstrained `u`
//! maps to `log θ = a + (b − a)·σ(u)` with `[a, b] = [log lower, log upper]`
//! and `σ` the logistic function — log space in the interior, smooth, and
//! never outside the bounds (GPy's `Logistic` constraint, on `log θ`).

/// Bounds of one hyperparameter, as logarithms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedLog {
    lo: f64,
    hi: f64,
}

fn sigmoid(u: f64) -> f64 {
    1.0 / (1.0 + (-u).exp())
}

impl BoundedLog {
    /// Bounds `[lower, upper]` in natural units (both positive).
    pub fn new([lower, upper]: [f64; 2]) -> Self {
        Self {
            lo: lower.ln(),
            hi: upper.ln(),
        }
    }

    /// `log θ` from `u`.
    pub fn to_log(&self, u: f64) -> f64 {
        (self.lo + (self.hi - self.lo) * sigmoid(u)).clamp(self.lo, self.hi)
    }

    /// `u` from `log θ` (clamped just inside the bounds).
    pub fn from_log(&self, log_theta: f64) -> f64 {
        let t = ((log_theta - self.lo) / (self.hi - self.lo)).clamp(1e-9, 1.0 - 1e-9);
        (t / (1.0 - t)).ln()
    }

    /// `d log θ / du`.
    pub fn derivative(&self, u: f64) -> f64 {
        let s = sigmoid(u);
        (self.hi - self.lo) * s * (1.0 - s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_differentiates() {
        let t = BoundedLog::new([1e-3, 1e5]);
        for log_theta in [-6.0, -1.0, 0.0, 2.5, 11.0] {
            assert!((t.to_log(t.from_log(log_theta)) - log_theta).abs() < 1e-9);
        }
        let u = 0.3;
        let h = 1e-6;
        let fd = (t.to_log(u + h) - t.to_log(u - h)) / (2.0 * h);
        assert!((fd - t.derivative(u)).abs() < 1e-8);
        assert!(t.to_log(-50.0) >= 1e-3f64.ln() && t.to_log(50.0) <= 1e5f64.ln());
    }
}
