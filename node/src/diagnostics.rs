//! The node's health, as `/diagnostics` carries it: the model, the
//! latency of each output (p50, p99 over the last outputs), the last
//! input's age, and warnings for a stale IMU and for inputs outside the
//! training range.

use std::collections::{BTreeSet, VecDeque};

use gpodo_datasets::bags::write::DiagnosticStatus;

use crate::feed::Fed;
use crate::pipeline::{LiveSettings, ModelSummary};

/// Outputs whose latencies the percentiles are taken over.
pub const LATENCY_WINDOW: usize = 1000;

/// `diagnostic_msgs/DiagnosticStatus` levels.
pub(crate) const OK: u8 = 0;
pub(crate) const WARN: u8 = 1;

/// What the node saw since it started, and since the last report.
#[derive(Debug, Clone, Default)]
pub struct Health {
    latencies_secs: VecDeque<f64>,
    outputs: usize,
    skipped: usize,
    last_skip: Option<String>,
    /// Since the last report: inputs seen outside the training range, and
    /// the oldest IMU reading a joint state got (s).
    out_of_range: BTreeSet<String>,
    oldest_imu_secs: Option<f64>,
}

/// The p-th percentile (0–100) of `values`, by the nearest rank.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    Some(sorted[rank.clamp(1, sorted.len()) - 1])
}

impl Health {
    /// Records one output and the seconds from taking its input to
    /// publishing it.
    pub fn output(&mut self, fed: &Fed, latency_secs: f64) {
        self.outputs += 1;
        if self.latencies_secs.len() == LATENCY_WINDOW {
            self.latencies_secs.pop_front();
        }
        self.latencies_secs.push_back(latency_secs);
        self.out_of_range
            .extend(fed.output.out_of_range.iter().cloned());
        if let Some(age) = fed.imu_age_secs {
            self.oldest_imu_secs = Some(self.oldest_imu_secs.map_or(age, |a| a.max(age)));
        }
    }

    /// Records an input that gave no output, and why.
    pub fn skipped(&mut self, reason: String) {
        self.skipped += 1;
        self.last_skip = Some(reason);
    }

    /// Outputs so far.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// Why the last input that gave no output gave none.
    pub fn last_skip(&self) -> Option<&str> {
        self.last_skip.as_deref()
    }

    /// Inputs that gave no output so far.
    pub fn skipped_count(&self) -> usize {
        self.skipped
    }

    /// The latency's p50 and p99 over the last [`LATENCY_WINDOW`] outputs (s).
    pub fn latency_secs(&self) -> Option<(f64, f64)> {
        let (a, b) = self.latencies_secs.as_slices();
        let all = [a, b].concat();
        Some((percentile(&all, 50.0)?, percentile(&all, 99.0)?))
    }

    /// The status to publish, given the last input's age (s) and the
    /// settings; the warnings cover what was seen since the last report,
    /// which this starts afresh.
    pub fn report(
        &mut self,
        name: &str,
        model: &ModelSummary,
        settings: &LiveSettings,
        last_input_age_secs: Option<f64>,
    ) -> DiagnosticStatus {
        let mut warnings = Vec::new();
        if let Some(age) = self
            .oldest_imu_secs
            .filter(|a| *a > settings.stale_imu_secs)
        {
            warnings.push(format!(
                "stale IMU: a reading {age:.3} s old was used (limit {} s)",
                settings.stale_imu_secs
            ));
        }
        if !self.out_of_range.is_empty() {
            warnings.push(format!(
                "outside the training range (|z| > {}): {}",
                settings.out_of_range_z,
                self.out_of_range
                    .iter()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        let ms = |s: f64| format!("{:.3}", s * 1e3);
        let (p50, p99) = self
            .latency_secs()
            .map_or(("".into(), "".into()), |(a, b)| (ms(a), ms(b)));
        let values = vec![
            ("model kind".into(), model.kind.clone()),
            ("model".into(), model.label.clone()),
            ("training rows".into(), model.training_rows.to_string()),
            ("latency p50 (ms)".into(), p50),
            ("latency p99 (ms)".into(), p99),
            (
                "last input age (s)".into(),
                last_input_age_secs.map_or_else(String::new, |a| format!("{a:.3}")),
            ),
            ("outputs".into(), self.outputs.to_string()),
            ("inputs not used".into(), self.skipped.to_string()),
            (
                "last input not used".into(),
                self.last_skip.clone().unwrap_or_default(),
            ),
        ];
        self.out_of_range.clear();
        self.oldest_imu_secs = None;
        DiagnosticStatus {
            level: if warnings.is_empty() { OK } else { WARN },
            name: name.into(),
            message: if warnings.is_empty() {
                "ok".into()
            } else {
                warnings.join("; ")
            },
            hardware_id: String::new(),
            values,
        }
    }
}
