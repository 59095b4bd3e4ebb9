//! The rules of Table II's verdict, committed in the experiment file
//! before the runs they judge (`verdict:`): which policies are judged,
//! the one primary comparison, the secondary ones, the error rate and
//! the margin of "equivalent" for each measure. The report applies them
//! (`report::verdict_section`); this module only holds and checks them.
//!
//! ```yaml
//! verdict:
//!   policies: ["authors' schedule (GP)", "drift budget + turn guard (GP)"]
//!   primary: { measure: rmse, frames: 500 }
//!   secondary:
//!     - { measure: rmse, frames: 1000 }
//!     - { measure: losses, frames: 500 }
//!   margins: { rmse_m: 0.015, losses: 0.5, drift_since_look_m: 0.002, cpu_ms_per_m: 17.0 }
//! ```

use serde::{Deserialize, Serialize};

use super::validate::Issue;

/// The verdict's rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerdictRules {
    /// The policies judged, by `curve:` name; each is compared with the
    /// fixed-rate curve of its own back end at equal frames.
    pub policies: Vec<String>,
    /// The primary comparison, tested at level `alpha` for each policy
    /// (the paper's: RMSE at about 500 frames).
    pub primary: Comparison,
    /// Secondary comparisons: their p-values over every policy of a
    /// regime are corrected together by Holm's step-down rule at level
    /// `alpha`.
    #[serde(default)]
    pub secondary: Vec<Comparison>,
    /// The error rate of each family (default 0.05).
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// The margin ε of "equivalent", per measure.
    pub margins: Margins,
}

fn default_alpha() -> f64 {
    0.05
}

/// One comparison: a measure at a frame budget.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Comparison {
    /// What is compared.
    pub measure: Measure,
    /// At how many processed frames (each route's curve interpolated in
    /// log frames, never extrapolated).
    pub frames: f64,
}

/// A measure of a scheme's run on one route.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// The trajectory's RMSE against the ground truth (m).
    Rmse,
    /// Tracking losses (a count; judged by an exact test).
    Losses,
    /// The 95th percentile of the drift since the last look (m).
    DriftSinceLook,
    /// The compute model's cost per metre driven (ms/m).
    CpuPerMetre,
}

impl Measure {
    /// The measure's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rmse => "RMSE [m]",
            Self::Losses => "losses per route",
            Self::DriftSinceLook => "drift since look, p95 [mm]",
            Self::CpuPerMetre => "compute [ms/m]",
        }
    }

    /// The factor from the measure's unit (m, count, ms/m) to the unit of
    /// its name: 1000 for the drift, shown in mm.
    pub fn display_scale(self) -> f64 {
        match self {
            Self::DriftSinceLook => 1000.0,
            _ => 1.0,
        }
    }

    /// Its key in YAML and CSV.
    pub fn key(self) -> &'static str {
        match self {
            Self::Rmse => "rmse",
            Self::Losses => "losses",
            Self::DriftSinceLook => "drift_since_look",
            Self::CpuPerMetre => "cpu_per_metre",
        }
    }

    /// Whether it counts events (an exact test) rather than measures a
    /// quantity (a bootstrap).
    pub fn is_count(self) -> bool {
        matches!(self, Self::Losses)
    }
}

/// The margin ε of "equivalent" for each measure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Margins {
    /// RMSE (m).
    pub rmse_m: f64,
    /// Tracking losses per route.
    pub losses: f64,
    /// Drift since the last look, p95 (m).
    pub drift_since_look_m: f64,
    /// Compute per metre (ms/m).
    pub cpu_ms_per_m: f64,
}

impl Margins {
    /// The margin of `measure`.
    pub fn of(&self, measure: Measure) -> f64 {
        match measure {
            Measure::Rmse => self.rmse_m,
            Measure::Losses => self.losses,
            Measure::DriftSinceLook => self.drift_since_look_m,
            Measure::CpuPerMetre => self.cpu_ms_per_m,
        }
    }
}

impl VerdictRules {
    /// The primary comparison, then the secondary ones.
    pub fn comparisons(&self) -> impl Iterator<Item = (bool, Comparison)> + '_ {
        std::iter::once((true, self.primary)).chain(self.secondary.iter().map(|c| (false, *c)))
    }

    /// Checks the rules against the file's curves: `curves` are the
    /// `curve:` names with whether each is a fixed rate and its back end.
    ///
    /// # Errors
    /// An [`Issue`] under `verdict.`.
    pub fn validate(&self, curves: &[(String, bool, String)]) -> Result<(), Issue> {
        if !(self.alpha > 0.0 && self.alpha < 0.5) {
            return Err(Issue::new(
                "verdict.alpha",
                format!("invalid error rate {}", self.alpha),
                "a rate in (0, 0.5), such as 0.05",
            ));
        }
        for (field, v) in [
            ("rmse_m", self.margins.rmse_m),
            ("losses", self.margins.losses),
            ("drift_since_look_m", self.margins.drift_since_look_m),
            ("cpu_ms_per_m", self.margins.cpu_ms_per_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Issue::new(
                    &format!("verdict.margins.{field}"),
                    format!("invalid margin {v}"),
                    "a positive margin in the measure's unit",
                ));
            }
        }
        let frames = |at: &str, c: &Comparison| {
            if c.frames.is_finite() && c.frames > 0.0 {
                Ok(())
            } else {
                Err(Issue::new(
                    &format!("{at}.frames"),
                    format!("invalid frame budget {}", c.frames),
                    "a positive number of processed frames",
                ))
            }
        };
        frames("verdict.primary", &self.primary)?;
        for (i, c) in self.secondary.iter().enumerate() {
            frames(&format!("verdict.secondary[{i}]"), c)?;
            if *c == self.primary || self.secondary[..i].contains(c) {
                return Err(Issue::new(
                    &format!("verdict.secondary[{i}]"),
                    "a comparison listed twice",
                    "each comparison once, the primary not among the secondary ones",
                ));
            }
        }
        if self.policies.is_empty() {
            return Err(Issue::new(
                "verdict.policies",
                "no policy to judge",
                "the `curve:` names of the policies judged",
            ));
        }
        for (i, policy) in self.policies.iter().enumerate() {
            let at = format!("verdict.policies[{i}]");
            let Some((_, fixed, back_end)) = curves.iter().find(|(name, ..)| name == policy) else {
                return Err(Issue::new(
                    &at,
                    format!("no curve named `{policy}`"),
                    "the `curve:` name of a scheme of this file",
                ));
            };
            if *fixed {
                return Err(Issue::new(
                    &at,
                    format!("`{policy}` is a fixed-rate curve"),
                    "a gating policy's curve; fixed rates are what it is judged against",
                ));
            }
            if !curves.iter().any(|(_, f, b)| *f && b == back_end) {
                return Err(Issue::new(
                    &at,
                    format!("`{policy}` has no fixed-rate curve of its back end ({back_end})"),
                    "a `curve:` of fixed-rate schemes with the policy's regressor, odometry and prior",
                ));
            }
        }
        Ok(())
    }
}
