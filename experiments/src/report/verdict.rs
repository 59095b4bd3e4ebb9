//! The verdict on one paired difference of the curves tables: lower,
//! higher, equivalent within the experiment's margin, or not resolved.

use crate::report::bootstrap::Interval;

/// Fewest seeds for a verdict on a paired difference.
pub const MIN_SEEDS_FOR_VERDICT: usize = 5;

/// The verdict on a paired Δ over `seeds` seeds: lower or higher when its
/// interval excludes zero; equivalent when it crosses zero within ±ε
/// (`margin`, the experiment's `equivalence_margin_m`); else not resolved.
pub fn verdict(d: &Interval, seeds: usize, margin: Option<f64>) -> String {
    if seeds < MIN_SEEDS_FOR_VERDICT {
        "too few seeds".into()
    } else if d.high < 0.0 {
        "lower, 95 %".into()
    } else if d.low > 0.0 {
        "higher, 95 %".into()
    } else if let Some(e) = margin.filter(|e| -e < d.low && d.high < *e) {
        format!("equivalent (within ±{e:.3} m)")
    } else {
        "not resolved".into()
    }
}
