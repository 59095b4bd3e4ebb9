//! Frames-versus-error curves over seeds (Table II as an experiment, not a
//! single row per policy): the schemes of a run that share a `curve:` name
//! are the points of one policy's curve, each with another value of its
//! knob. Over the seeds of a sweep this module gives every point its mean
//! frames, compute and RMSE with a 95 % bootstrap interval, and two
//! tables:
//!
//! * (a) the frames a curve needs to come within 10 % of the 2.5 fps RMSE
//!   of the same back end (the first crossing of the mean RMSE ratio,
//!   linear in log frames between knob values), with a bootstrap interval;
//! * (b) each curve's RMSE at fixed frame budgets, paired per seed with the
//!   fixed-rate curve of the same back end at the same frames (both
//!   interpolated in log frames), and the 95 % interval of the difference.

use std::collections::BTreeMap;

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::rover_measures::RoverMeasures;

use crate::execute::records::RunRecord;
use crate::report::bootstrap::{Interval, bootstrap, mean_at};

/// How close to the reference "within" means in table (a).
pub const WITHIN: f64 = 1.10;

/// The frame budgets of table (b): about the paper's GP scheme (484) and
/// twice it.
pub const BUDGETS: [f64; 2] = [500.0, 1000.0];

/// One scheme (a knob value) of a curve, on every seed.
#[derive(Debug, Clone, PartialEq)]
pub struct KnobPoint {
    /// The scheme's label.
    pub label: String,
    /// Frames per seed (in [`Curves::seeds`] order).
    pub frames: Vec<f64>,
    /// RMSE per seed (m).
    pub rmse: Vec<f64>,
    /// Compute proxy per seed (s).
    pub compute: Vec<f64>,
    /// A rover team's measures per seed.
    pub rover: Vec<RoverMeasures>,
    /// Tracking losses per seed.
    pub losses: Vec<f64>,
}

/// One policy's curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The `curve:` name.
    pub name: String,
    /// The back end its schemes share.
    pub back_end: String,
    /// Whether every point is a fixed-rate scheme.
    pub fixed_rate: bool,
    /// The points, in experiment order.
    pub points: Vec<KnobPoint>,
    /// Per seed, the 2.5 fps RMSE of the same back end, when the run has
    /// such a scheme.
    pub reference: Option<Vec<f64>>,
    /// Whether its residuals come from the `zero` regressor.
    pub zero_residuals: bool,
    /// The selectors of its points, in order (to find its zero-residual
    /// twin).
    pub selectors: Vec<SelectorSpec>,
}

/// The curves of a set of runs (one per seed) of the same experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Curves {
    /// The seeds, one per run.
    pub seeds: Vec<u64>,
    /// Every curve.
    pub curves: Vec<Curve>,
    /// The experiment's first scheme (the paper's baseline in Table II)
    /// and its RMSE per seed.
    pub baseline: Option<(String, Vec<f64>)>,
}

impl Curve {
    /// The same curve with each point's RMSE replaced by another measure
    /// of the run (per seed), so that every pairing of this module applies
    /// to it.
    #[must_use]
    pub fn with_measure(&self, measure: fn(&RoverMeasures) -> f64) -> Self {
        let mut out = self.clone();
        for p in &mut out.points {
            p.rmse = p.rover.iter().map(measure).collect();
        }
        out
    }

    /// The same curve with each point's RMSE replaced by its tracking
    /// losses per seed.
    #[must_use]
    pub fn with_losses(&self) -> Self {
        let mut out = self.clone();
        for p in &mut out.points {
            p.rmse.clone_from(&p.losses);
        }
        out
    }
}

impl Curves {
    /// The curves of `records` (runs of one setting, one per seed); only
    /// schemes present on every run count. `None` when no scheme names a
    /// curve.
    pub fn of(records: &[&RunRecord]) -> Option<Self> {
        let first = records.first()?;
        let config = &first.config;
        let labels = config.regressor_labels();
        let traverse = first.metrics.schemes.first()?.traverse.clone();
        let metric = |r: &RunRecord, label: &str| {
            r.metrics
                .schemes
                .iter()
                .find(|m| m.label == label && m.traverse == traverse)
                .map(|m| {
                    (
                        m.frames as f64,
                        m.rmse_m,
                        m.compute_s,
                        m.rover,
                        m.tracking_losses as f64,
                    )
                })
        };
        let series = |label: &str| -> Option<KnobPoint> {
            let mut point = KnobPoint {
                label: label.to_string(),
                frames: Vec::new(),
                rmse: Vec::new(),
                compute: Vec::new(),
                rover: Vec::new(),
                losses: Vec::new(),
            };
            for r in records {
                let (f, e, c, m, l) = metric(r, label)?;
                point.losses.push(l);
                point.frames.push(f);
                point.rmse.push(e);
                point.compute.push(c);
                point.rover.push(m);
            }
            Some(point)
        };
        let mut curves: Vec<Curve> = Vec::new();
        for spec in &config.schemes {
            let Some(name) = &spec.curve else { continue };
            let Some(point) = series(&spec.label) else {
                continue;
            };
            let back_end = spec.back_end(config);
            let fixed = matches!(spec.selector, SelectorSpec::FixedRate { .. });
            let zero = spec.online.is_none()
                && spec.odometry.is_none()
                && spec.regressor_index(&labels).is_ok_and(|i| {
                    matches!(
                        config.regressors.get(i),
                        Some(gpodo_regressors::RegressorSpec::Zero { .. })
                    )
                });
            match curves.iter_mut().find(|c| &c.name == name) {
                Some(c) => {
                    c.fixed_rate &= fixed;
                    c.points.push(point);
                    c.selectors.push(spec.selector.clone());
                }
                None => curves.push(Curve {
                    name: name.clone(),
                    back_end: back_end.clone(),
                    fixed_rate: fixed,
                    points: vec![point],
                    reference: None,
                    zero_residuals: zero,
                    selectors: vec![spec.selector.clone()],
                }),
            }
        }
        if curves.is_empty() {
            return None;
        }
        for c in curves.iter_mut() {
            let reference = config.schemes.iter().find(|s| {
                matches!(s.selector, SelectorSpec::FixedRate { fps, phase_secs } if (fps - 2.5).abs() < 1e-9 && phase_secs == 0.0)
                    && s.back_end(config) == c.back_end
            });
            c.reference = reference.and_then(|s| series(&s.label)).map(|p| p.rmse);
        }
        let baseline = config
            .schemes
            .first()
            .and_then(|s| series(&s.label).map(|p| (s.label.clone(), p.rmse)));
        Some(Self {
            baseline,
            seeds: records
                .iter()
                .map(|r| r.replicate.or(r.seed).unwrap_or(r.index as u64))
                .collect(),
            curves,
        })
    }

    /// The same policy with the same knob values on zero residuals and the
    /// same tracking prior, for a curve that is not itself on zero
    /// residuals.
    pub fn zero_twin_of(&self, curve: &Curve) -> Option<&Curve> {
        if curve.zero_residuals || curve.fixed_rate {
            return None;
        }
        let prior = |b: &str| b.rsplit(", ").next().map(str::to_string);
        self.curves.iter().find(|c| {
            c.zero_residuals
                && c.selectors == curve.selectors
                && prior(&c.back_end) == prior(&curve.back_end)
        })
    }

    /// The fixed-rate curve with `back_end`, if any.
    pub fn fixed_rate_of(&self, back_end: &str) -> Option<&Curve> {
        self.curves
            .iter()
            .find(|c| c.fixed_rate && c.back_end == back_end)
    }
}

/// A point's mean frames, mean compute and mean RMSE with its interval.
#[derive(Debug, Clone, PartialEq)]
pub struct PointSummary {
    /// The scheme's label.
    pub label: String,
    /// Mean frames over seeds.
    pub frames: f64,
    /// Mean compute proxy (s).
    pub compute: f64,
    /// Mean RMSE (m) and its interval.
    pub rmse: Interval,
    /// Mean 95th percentile of the drift since the last look (m).
    pub drift_since_look_p95_m: f64,
    /// Mean relative pose error over 1 m (m).
    pub rpe_1m_m: f64,
    /// Mean compute model per metre (ms/m).
    pub cpu_ms_per_m: f64,
}

/// Every point of `curve`, summarised over seeds.
pub fn summarise(curve: &Curve, seed: u64) -> Vec<PointSummary> {
    curve
        .points
        .iter()
        .filter_map(|p| {
            let n = p.rmse.len();
            let rmse = bootstrap(n, seed, |ix| Some(mean_at(&p.rmse, ix)))?;
            let rover_mean =
                |f: fn(&RoverMeasures) -> f64| p.rover.iter().map(f).sum::<f64>() / n as f64;
            Some(PointSummary {
                drift_since_look_p95_m: rover_mean(|m| m.drift_since_look_p95_m),
                rpe_1m_m: rover_mean(|m| m.rpe_1m_m),
                cpu_ms_per_m: rover_mean(|m| m.cpu_ms_per_m),
                label: p.label.clone(),
                frames: p.frames.iter().sum::<f64>() / n as f64,
                compute: p.compute.iter().sum::<f64>() / n as f64,
                rmse,
            })
        })
        .collect()
}

/// What table (a) found for one curve.
#[derive(Debug, Clone, PartialEq)]
pub enum FramesToReach {
    /// The curve's mean crosses the threshold at these frames.
    Crosses(Interval),
    /// Already within at its fewest frames (mean frames of that point).
    AtMost(f64),
    /// Never within; the best mean ratio and the mean frames where it is.
    Never {
        /// Best mean RMSE ratio to the reference.
        best_ratio: f64,
        /// Mean frames at the best point.
        frames: f64,
    },
}

/// The mean frames at which the seeds `ix` of `curve` first come within
/// [`WITHIN`] of `reference` (mean of per-seed ratios), scanning the points
/// by increasing mean frames.
fn crossing(curve: &Curve, reference: &[f64], ix: &[usize]) -> FramesToReach {
    let mut points: Vec<(f64, f64)> = curve
        .points
        .iter()
        .map(|p| {
            let frames = mean_at(&p.frames, ix);
            let ratio = ix.iter().map(|&i| p.rmse[i] / reference[i]).sum::<f64>() / ix.len() as f64;
            (frames, ratio)
        })
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some(&first) = points.first() else {
        return FramesToReach::Never {
            best_ratio: f64::NAN,
            frames: f64::NAN,
        };
    };
    if first.1 <= WITHIN {
        return FramesToReach::AtMost(first.0);
    }
    for w in points.windows(2) {
        let ((f0, r0), (f1, r1)) = (w[0], w[1]);
        if r1 <= WITHIN {
            let t = (r0 - WITHIN) / (r0 - r1);
            let frames = (f0.ln() + t * (f1.ln() - f0.ln())).exp();
            return FramesToReach::Crosses(Interval {
                estimate: frames,
                low: f64::NAN,
                high: f64::NAN,
                defined: 1.0,
            });
        }
    }
    let best = points
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or(first);
    FramesToReach::Never {
        best_ratio: best.1,
        frames: best.0,
    }
}

/// Table (a) for `curve` against `reference` (per-seed RMSE: the 2.5 fps
/// RMSE of its back end, or the paper's baseline).
pub fn frames_to_reach(curve: &Curve, reference: &[f64], seed: u64) -> FramesToReach {
    let n = reference.len();
    let all: Vec<usize> = (0..n).collect();
    match crossing(curve, reference, &all) {
        FramesToReach::Crosses(_) => {
            let frames = |ix: &[usize]| match crossing(curve, reference, ix) {
                FramesToReach::Crosses(i) => Some(i.estimate),
                FramesToReach::AtMost(f) => Some(f),
                FramesToReach::Never { .. } => None,
            };
            bootstrap(n, seed, frames).map_or(
                FramesToReach::Never {
                    best_ratio: f64::NAN,
                    frames: f64::NAN,
                },
                FramesToReach::Crosses,
            )
        }
        other => other,
    }
}

/// Groups `records` into sets of seeds of the same setting (swept values
/// other than the seed), in first-seen order.
pub fn by_setting(records: &[RunRecord]) -> Vec<(String, Vec<&RunRecord>)> {
    let mut groups: BTreeMap<String, Vec<&RunRecord>> = BTreeMap::new();
    let mut order = Vec::new();
    for r in records {
        let key = r
            .assignment
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(", ");
        if !groups.contains_key(&key) {
            order.push(key.clone());
        }
        groups.entry(key).or_default().push(r);
    }
    order
        .into_iter()
        .filter_map(|k| groups.remove(&k).map(|v| (k, v)))
        .collect()
}

#[cfg(test)]
pub(crate) mod fixtures {
    //! Curves for the report's unit tests.
    use super::*;

    pub(crate) fn point(label: &str, frames: &[f64], rmse: &[f64]) -> KnobPoint {
        KnobPoint {
            label: label.into(),
            frames: frames.to_vec(),
            rmse: rmse.to_vec(),
            compute: frames.to_vec(),
            rover: vec![RoverMeasures::default(); frames.len()],
            losses: vec![0.0; frames.len()],
        }
    }

    pub(crate) fn curve(
        points: Vec<KnobPoint>,
        fixed_rate: bool,
        reference: Option<Vec<f64>>,
    ) -> Curve {
        Curve {
            name: "c".into(),
            back_end: "b".into(),
            fixed_rate,
            points,
            reference,
            zero_residuals: false,
            selectors: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::curves::fixtures::{curve, point};

    #[test]
    fn the_crossing_is_interpolated_in_log_frames() {
        // Two seeds with the same curve: ratio 1.3 at 100 frames, 1.0 at
        // 1000; 1.1 is two thirds of the way in log frames.
        let c = curve(
            vec![
                point("a", &[100.0, 100.0], &[0.13, 0.26]),
                point("b", &[1000.0, 1000.0], &[0.10, 0.20]),
            ],
            false,
            Some(vec![0.1, 0.2]),
        );
        let FramesToReach::Crosses(i) = frames_to_reach(&c, &[0.1, 0.2], 3) else {
            panic!("expected a crossing");
        };
        let expected = 10f64.powf(2.0 + 2.0 / 3.0);
        assert!((i.estimate - expected).abs() < 1e-9 * expected, "{i:?}");
        // Identical seeds: every resample gives the same crossing.
        assert!((i.low - expected).abs() < 1e-9 * expected);
        assert!((i.high - expected).abs() < 1e-9 * expected);
    }

    #[test]
    fn never_within_and_within_from_the_start_are_reported_as_such() {
        let never = curve(
            vec![point("a", &[100.0], &[0.5]), point("b", &[300.0], &[0.3])],
            false,
            Some(vec![0.1]),
        );
        assert!(matches!(
            frames_to_reach(&never, &[0.1], 1),
            FramesToReach::Never { best_ratio, frames } if (best_ratio - 3.0).abs() < 1e-12 && frames == 300.0
        ));
        let early = curve(vec![point("a", &[100.0], &[0.1])], false, Some(vec![0.1]));
        assert_eq!(
            frames_to_reach(&early, &[0.1], 1),
            FramesToReach::AtMost(100.0)
        );
    }
}
