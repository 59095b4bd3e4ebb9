//! The multi-start policy shared by the GP regressors: the log marginal
//! likelihood in 20–30 lengthscales is multimodal, and a single start can
//! land in an optimum hundreds of nats below another (`bench/README.md`
//! compares the starts on the ExoTeR table). So a
//! handful of deterministic candidate starts — named base points and seeded
//! perturbations of them — is scored by the objective alone (no gradient,
//! one factorisation each), the optimiser runs from the best few, and the
//! best optimum wins. Every candidate's starting value (and final value, for
//! those optimised) is kept, so a report can show how multimodal a problem
//! was.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use faer::MatRef;
use gpodo_traits::StartRecord;

use super::run::Run;
use super::{
    Coordinates, LogBounds, Maximized, Objective, OptimizerSettings, ProgressSink, clamped,
    maximize, perturbed,
};
use crate::RegressorError;
use crate::kernels::{KernelExpr, KernelInit, ParamKind, median_pairwise_distance};

/// How the GP regressors choose where their optimiser starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartPolicy {
    /// Seeded perturbations (one standard normal per `log θ`) scored beside
    /// each base candidate (default 2).
    pub perturbations: usize,
    /// How many of the best-scored candidates race beside the named bases
    /// (default 2).
    pub optimize_best: usize,
    /// Iterations of the race: every named base and the `optimize_best`
    /// best-scored candidates run up to this many (see `halve_after`), and
    /// only the leader goes on to convergence (default 15; 0 runs every one
    /// of them to convergence).
    pub race_iterations: u64,
    /// Iterations after which only the better half of the race (rounded
    /// up, by LML so far) goes on to `race_iterations`, resumed exactly
    /// where it paused, so the leader and its optimum are unchanged
    /// whenever it is in that half; 0 races every candidate the whole way.
    /// Unset, each model's own default: 7 for the exact GP
    /// ([`EXACT_GP_HALVE_AFTER`]), none for the sparse GP, where halving
    /// changed which start continued (`bench/README.md`, "Halving the
    /// start race").
    pub halve_after: Option<u64>,
}

impl Default for StartPolicy {
    fn default() -> Self {
        Self {
            perturbations: 2,
            optimize_best: 2,
            race_iterations: 15,
            halve_after: None,
        }
    }
}

/// The exact GP's default for [`StartPolicy::halve_after`]: starts from
/// unit lengthscales climb slowly at first, so a ranking after fewer
/// iterations drops the eventual leader (the racers' ranks by iteration are
/// in `bench/README.md`, "Halving the start race").
pub const EXACT_GP_HALVE_AFTER: u64 = 7;

impl StartPolicy {
    /// This policy with `halve_after` set to `default` when it is unset.
    pub fn with_default_halve_after(self, default: u64) -> Self {
        Self {
            halve_after: Some(self.halve_after.unwrap_or(default)),
            ..self
        }
    }

    /// Checks the fields, naming the bad one for `regressor`.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] when `optimize_best` is 0.
    pub fn check(&self, regressor: &str) -> Result<(), RegressorError> {
        if self.optimize_best == 0 {
            return Err(RegressorError::InvalidSpec {
                regressor: regressor.into(),
                field: "start.optimize_best".into(),
                expected: "at least 1".into(),
            });
        }
        Ok(())
    }
}

/// Reports a run's starts to the fit's progress under numbers that follow
/// the runs before it, so that every optimiser run of a fit has its own;
/// once the progress asks to stop, every run of the fit stops.
struct Numbered {
    inner: std::sync::Arc<dyn gpodo_traits::FitProgress>,
    first: usize,
    stopped: std::sync::Arc<AtomicBool>,
}

impl gpodo_traits::FitProgress for Numbered {
    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> ControlFlow<()> {
        if self.stopped.load(Ordering::Relaxed) {
            return ControlFlow::Break(());
        }
        let flow = self
            .inner
            .iteration(self.first + start, iteration, objective);
        if flow.is_break() {
            self.stopped.store(true, Ordering::Relaxed);
        }
        flow
    }
}

/// The progress sink of the run that is numbered `first`, which sets
/// `stopped` when the fit is to stop.
fn numbered(
    progress: &ProgressSink,
    first: usize,
    stopped: &std::sync::Arc<AtomicBool>,
) -> Option<std::sync::Arc<dyn gpodo_traits::FitProgress>> {
    progress.0.as_ref().map(|inner| {
        std::sync::Arc::new(Numbered {
            inner: std::sync::Arc::clone(inner),
            first,
            stopped: std::sync::Arc::clone(stopped),
        }) as std::sync::Arc<dyn gpodo_traits::FitProgress>
    })
}

/// [`RegressorError::Stopped`] once the fit's progress has asked to stop.
fn check_stopped(stopped: &AtomicBool) -> Result<(), RegressorError> {
    if stopped.load(Ordering::Relaxed) {
        Err(RegressorError::Stopped)
    } else {
        Ok(())
    }
}

/// What a candidate start is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartKind {
    /// A named base start: it always races.
    Base,
    /// Seeded perturbation number `number` (from 1) of the base before it:
    /// it races only when it scores among the best.
    Perturbation {
        /// Which perturbation of its base.
        number: usize,
    },
}

/// A candidate start before it is scored.
#[derive(Debug, Clone, PartialEq)]
pub struct StartPoint {
    /// What the start is, e.g. `lengthscale 1` or `√D, perturbed #2`.
    pub label: String,
    /// Its kind.
    pub kind: StartKind,
    /// The optimiser's coordinates there.
    pub coords: Vec<f64>,
}

impl StartPoint {
    /// A named base start.
    pub fn base(label: impl Into<String>, coords: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            kind: StartKind::Base,
            coords,
        }
    }
}

/// One candidate start.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// What the start is, e.g. `lengthscale 1` or `√D, perturbed #2`.
    pub label: String,
    /// The optimiser's coordinates there (inside the bounds).
    pub coords: Vec<f64>,
    /// The objective there; `None` when it could not be evaluated.
    pub value: Option<f64>,
    /// A named base start (not a perturbation).
    pub base: bool,
}

/// The base candidates and `perturbations` seeded perturbations of each
/// (seed `seed`; a perturbation moves every coordinate with `perturb[i]` by
/// one standard normal and clamps it into its bounds), in a fixed order:
/// each base, then its perturbations.
pub fn with_perturbations(
    bases: Vec<(String, Vec<f64>)>,
    bounds: &[LogBounds],
    perturb: &[bool],
    perturbations: usize,
    seed: u64,
) -> Vec<StartPoint> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(bases.len() * (1 + perturbations));
    for (label, base) in bases {
        let base = clamped(&base, bounds);
        for number in 1..=perturbations {
            out.push(StartPoint {
                label: format!("{label}, perturbed #{number}"),
                kind: StartKind::Perturbation { number },
                coords: perturbed(&base, bounds, perturb, &mut rng),
            });
        }
        out.insert(out.len() - perturbations, StartPoint::base(label, base));
    }
    out
}

/// Scores every candidate with `score` and returns them all, in their
/// given order, with their values (a failed evaluation scores `None`).
pub fn score_all(
    candidates: Vec<StartPoint>,
    score: impl Fn(&[f64]) -> Result<f64, RegressorError>,
) -> Vec<Candidate> {
    candidates
        .into_iter()
        .map(|start| {
            let value = score(&start.coords).ok().filter(|v| v.is_finite());
            Candidate {
                base: start.kind == StartKind::Base,
                label: start.label,
                coords: start.coords,
                value,
            }
        })
        .collect()
}

/// The indices of the `k` best-scored candidates, best first (ties keep
/// the earlier candidate first; unscored candidates are never chosen).
pub fn best(candidates: &[Candidate], k: usize) -> Vec<usize> {
    let mut scored: Vec<(usize, f64)> = candidates
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.value.map(|v| (i, v)))
        .collect();
    scored.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    scored.into_iter().take(k).map(|(i, _)| i).collect()
}

/// The base candidate starts of a GP with kernel `expr` on standardised
/// inputs `x`, as `log θ` followed by `log σ_n²`: the user's `init.lengthscale` alone when it
/// is set, otherwise lengthscale 1 (GPy's default in standardised units),
/// `√D` and the median distance between training inputs (the kernels
/// without lengthscales have one base). Duplicates are dropped.
pub fn kernel_bases(
    expr: &KernelExpr,
    init: &KernelInit,
    x: MatRef<'_, f64>,
    noise_variance: f64,
) -> Vec<(String, Vec<f64>)> {
    let d = x.ncols();
    let mut lengthscales: Vec<(String, Option<f64>)> = match init.lengthscale {
        Some(l) => vec![(format!("init (lengthscale {l})"), Some(l))],
        None => {
            let mut v = vec![
                ("lengthscale 1".to_string(), Some(1.0)),
                ("lengthscale √D".to_string(), Some((d.max(1) as f64).sqrt())),
            ];
            if let Some(m) = median_pairwise_distance(x) {
                v.push(("lengthscale = median distance".to_string(), Some(m)));
            }
            v
        }
    };
    let has_lengthscales = expr
        .build(d, init)
        .param_kinds()
        .contains(&ParamKind::Lengthscale);
    if !has_lengthscales {
        lengthscales.truncate(1);
        lengthscales[0] = ("init".to_string(), init.lengthscale);
    }
    let mut bases: Vec<(String, Vec<f64>)> = Vec::new();
    for (label, lengthscale) in lengthscales {
        let init = KernelInit {
            lengthscale,
            ..*init
        };
        let mut coords = expr.build(d, &init).log_params();
        coords.push(noise_variance.ln());
        if !bases.iter().any(|(_, c)| *c == coords) {
            bases.push((label, coords));
        }
    }
    bases
}

/// Scores `candidates` with `score` (the objective without its gradient),
/// races the optimiser from every named base and the best
/// `policy.optimize_best` of them for `policy.race_iterations` (only the
/// better half after `policy.halve_after`, when set), then runs
/// [`maximize`] from the leader's best point alone to convergence, with
/// `settings.restarts` extra perturbed runs, and
/// returns the highest optimum, with every candidate's record
/// (restarts appended as records of their own). Evaluations and iterations
/// are summed over all runs.
///
/// # Errors
/// The last optimiser error when no run produced a finite objective, or
/// [`RegressorError::Optimizer`] when no candidate could be scored.
#[allow(clippy::too_many_arguments)]
pub fn maximize_best(
    objective: &dyn Objective,
    candidates: Vec<StartPoint>,
    score: impl Fn(&[f64]) -> Result<f64, RegressorError>,
    bounds: &[LogBounds],
    perturb: &[bool],
    policy: &StartPolicy,
    value_scale: f64,
    settings: &OptimizerSettings,
    progress: &ProgressSink,
) -> Result<(Maximized, Vec<StartRecord>), RegressorError> {
    let scored = score_all(candidates, score);
    let mut records: Vec<StartRecord> = scored
        .iter()
        .map(|c| StartRecord {
            label: c.label.clone(),
            start_objective: c.value,
            ..StartRecord::default()
        })
        .collect();
    let (mut best_run, mut evaluations, mut iterations) = (None::<Maximized>, 0, 0);
    let mut last_error = None;
    let mut run_number = 0;
    let stopped = std::sync::Arc::new(AtomicBool::new(false));
    // Every named base races, with the best-scored others: the objective
    // at a start predicts its optimum poorly (on the ExoTeR table a
    // perturbed start scores above GPy's unit lengthscales and ends 350
    // nats below them).
    let mut chosen: Vec<usize> = (0..scored.len()).filter(|&i| scored[i].base).collect();
    for i in best(&scored, policy.optimize_best) {
        if !chosen.contains(&i) {
            chosen.push(i);
        }
    }
    chosen.retain(|&i| scored[i].value.is_some());
    let mut runs: Vec<(usize, Vec<f64>)> = chosen
        .iter()
        .map(|&i| (i, scored[i].coords.clone()))
        .collect();
    if chosen.len() > 1 && policy.race_iterations > 0 {
        // The race: every chosen candidate runs a few iterations, and only
        // the leader goes on, restarted from its best point.
        let short = OptimizerSettings {
            max_iters: policy.race_iterations,
            restarts: 0,
            ..*settings
        };
        let mut racers = Vec::with_capacity(runs.len());
        for (i, start) in runs {
            let u = clamped(&start, bounds);
            let sink = numbered(progress, run_number, &stopped);
            run_number += 1;
            match Run::start(objective, bounds, u, value_scale, &short) {
                Ok(run) => racers.push((i, run, sink)),
                Err(e) => last_error = Some(e),
            }
        }
        race(&mut racers, policy);
        check_stopped(&stopped)?;
        let mut leader: Option<(usize, Vec<f64>, f64)> = None;
        for (i, run, _) in racers {
            let out = run.finish();
            evaluations += out.evaluations;
            iterations += out.iterations;
            records[i].final_objective = Some(out.value);
            records[i].evaluations = Some(out.evaluations);
            records[i].iterations = Some(out.iterations);
            if leader.as_ref().is_none_or(|l| out.value > l.2) {
                leader = Some((i, out.coords.clone(), out.value));
            }
            if best_run.as_ref().is_none_or(|b| out.value > b.value) {
                best_run = Some(out);
            }
        }
        runs = leader.map(|(i, c, _)| vec![(i, c)]).unwrap_or_default();
    }
    for (rank, (i, start)) in runs.into_iter().enumerate() {
        let mut settings = *settings;
        if rank > 0 {
            settings.restarts = 0;
        }
        let coords = Coordinates {
            start,
            bounds: bounds.to_vec(),
            perturb: perturb.to_vec(),
        };
        let sink = numbered(progress, run_number, &stopped);
        run_number += 1 + settings.restarts;
        let result = maximize(objective, &coords, value_scale, &settings, sink.as_ref());
        check_stopped(&stopped)?;
        match result {
            Ok(out) => {
                let record = &mut records[i];
                record.final_objective = out.start_values.first().copied();
                record.evaluations = Some(record.evaluations.unwrap_or(0) + out.evaluations);
                record.iterations = Some(record.iterations.unwrap_or(0) + out.iterations);
                for (k, v) in out.start_values.iter().enumerate().skip(1) {
                    records.push(StartRecord {
                        label: format!("{}, restart #{k}", scored[i].label),
                        final_objective: Some(*v),
                        ..StartRecord::default()
                    });
                }
                evaluations += out.evaluations;
                iterations += out.iterations;
                if best_run.as_ref().is_none_or(|b| out.value > b.value) {
                    best_run = Some(out);
                }
            }
            Err(e) => last_error = Some(e),
        }
    }
    let Some(mut out) = best_run else {
        return Err(last_error.unwrap_or_else(|| RegressorError::Optimizer {
            optimizer: format!("{:?}", settings.optimizer),
            detail: "no candidate start could be evaluated".into(),
        }));
    };
    out.evaluations = evaluations;
    out.iterations = iterations;
    Ok((out, records))
}

/// A racer: the candidate's index, its run and its progress sink.
type Racer<'a> = (
    usize,
    Run<'a>,
    Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
);

/// Advances every racer to `policy.halve_after` iterations (unset or 0:
/// `policy.race_iterations`), then only the better half of them (rounded
/// up; ranked by their best value so far, ties to the earlier candidate,
/// among those that can still go on: a racer that converged keeps its
/// value without taking a place) on to `policy.race_iterations`. Each run
/// is resumed where it paused, so a racer that goes on ends exactly where
/// an uninterrupted race of `race_iterations` would have left it: halving
/// only spares the iterations of the racers that trail.
fn race(racers: &mut [Racer<'_>], policy: &StartPolicy) {
    let first = match policy.halve_after.unwrap_or(0) {
        0 => policy.race_iterations,
        h => h.min(policy.race_iterations),
    };
    for (_, run, sink) in racers.iter_mut() {
        run.advance(first, sink.as_ref().map(|s| (s, 0)));
    }
    if first >= policy.race_iterations {
        return;
    }
    let places = racers.len().div_ceil(2);
    let mut order: Vec<usize> = (0..racers.len())
        .filter(|&k| racers[k].1.can_go_on())
        .collect();
    order.sort_by(|&a, &b| {
        let value = |k: usize| racers[k].1.best_value();
        value(b).total_cmp(&value(a)).then(a.cmp(&b))
    });
    for &k in order.iter().take(places) {
        let (_, run, sink) = &mut racers[k];
        run.advance(policy.race_iterations, sink.as_ref().map(|s| (s, 0)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perturbations_follow_their_base_and_stay_in_bounds() {
        let bounds = [LogBounds::new([0.5, 2.0]), LogBounds::unbounded()];
        let bases = vec![
            ("a".to_string(), vec![0.0, 1.0]),
            ("b".into(), vec![5.0, 2.0]),
        ];
        let all = with_perturbations(bases.clone(), &bounds, &[true, false], 2, 7);
        let labels: Vec<&str> = all.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "a",
                "a, perturbed #1",
                "a, perturbed #2",
                "b",
                "b, perturbed #1",
                "b, perturbed #2"
            ]
        );
        assert_eq!(all[0].kind, StartKind::Base);
        assert_eq!(all[2].kind, StartKind::Perturbation { number: 2 });
        // Base b was clamped into its bound; unperturbed coordinates stay.
        assert_eq!(all[3].coords, vec![2.0f64.ln(), 2.0]);
        for s in &all {
            assert!(s.coords[0] >= 0.5f64.ln() - 1e-15 && s.coords[0] <= 2.0f64.ln() + 1e-15);
        }
        assert_eq!(all[1].coords[1], 1.0);
        // Deterministic: the same seed gives the same candidates.
        assert_eq!(
            all,
            with_perturbations(bases, &bounds, &[true, false], 2, 7)
        );
    }

    #[test]
    fn picks_the_highest_scored_candidates_and_skips_failures() {
        let candidates = vec![
            StartPoint::base("low", vec![0.0]),
            StartPoint::base("fails", vec![1.0]),
            StartPoint::base("high", vec![2.0]),
            StartPoint::base("tie", vec![3.0]),
            StartPoint::base("high again", vec![4.0]),
        ];
        let scored = score_all(candidates, |c| match c[0] as i32 {
            0 => Ok(-10.0),
            1 => Err(RegressorError::InvalidData {
                detail: "nope".into(),
            }),
            3 => Ok(-10.0),
            _ => Ok(-1.0),
        });
        assert_eq!(scored[1].value, None);
        assert_eq!(best(&scored, 2), vec![2, 4]);
        assert_eq!(best(&scored, 10), vec![2, 4, 0, 3]);
    }

    /// Five Gaussian bumps of different heights in the plane.
    struct Bumps;

    const PEAKS: [([f64; 2], f64); 5] = [
        ([0.0, 0.0], 1.0),
        ([4.0, 0.0], 2.0),
        ([0.0, 4.0], 1.5),
        ([4.0, 4.0], 0.5),
        ([8.0, 0.0], 1.2),
    ];

    impl Objective for Bumps {
        fn evaluate(&self, c: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
            let (mut value, mut grad) = (0.0, vec![0.0; 2]);
            for (t, w) in PEAKS {
                let e = w * (-0.5 * ((c[0] - t[0]).powi(2) + (c[1] - t[1]).powi(2))).exp();
                value += e;
                grad[0] -= e * (c[0] - t[0]);
                grad[1] -= e * (c[1] - t[1]);
            }
            Ok((value, grad))
        }
    }

    #[test]
    fn halving_the_race_spares_only_the_trailing_racers() {
        // One named start near each bump: all five race.
        let candidates: Vec<StartPoint> = PEAKS
            .iter()
            .enumerate()
            .map(|(k, (t, _))| StartPoint::base(format!("near {k}"), vec![t[0] + 1.2, t[1] - 0.9]))
            .collect();
        let bounds = vec![LogBounds::unbounded(); 2];
        let settings = OptimizerSettings {
            optimizer: super::super::Optimizer::Lbfgs,
            max_iters: 200,
            restarts: 0,
            seed: 0,
            gradient_tolerance: 1e-12,
            relative_cost_tolerance: 0.0,
            lbfgs_memory: 5,
        };
        let fit = |halve_after| {
            let policy = StartPolicy {
                perturbations: 0,
                optimize_best: 1,
                race_iterations: 6,
                halve_after: Some(halve_after),
            };
            maximize_best(
                &Bumps,
                candidates.clone(),
                |c| Bumps.evaluate(c).map(|(v, _)| v),
                &bounds,
                &[true, true],
                &policy,
                1.0,
                &settings,
                &ProgressSink::default(),
            )
            .unwrap()
        };
        let (whole, whole_records) = fit(0);
        let (halved, halved_records) = fit(2);
        // The same leader, continued to the same optimum: the highest bump.
        assert_eq!(halved.coords, whole.coords);
        assert_eq!(halved.value, whole.value);
        assert!((whole.coords[0] - 4.0).abs() < 0.01 && whole.coords[1].abs() < 0.01);
        assert!(halved.evaluations < whole.evaluations);
        // After 2 iterations the racers near the three highest bumps (1, 2
        // and 4: half of five, rounded up) lead: they go on exactly as in
        // the whole race; the other two stop.
        let iterations: Vec<Option<u64>> = halved_records.iter().map(|r| r.iterations).collect();
        assert_eq!(iterations[0], Some(2));
        assert_eq!(iterations[3], Some(2));
        for k in [1, 2, 4] {
            assert_eq!(halved_records[k], whole_records[k], "racer {k}");
        }
        for k in [0, 3] {
            let (cut, whole) = (&halved_records[k], &whole_records[k]);
            assert!(cut.evaluations < whole.evaluations, "racer {k}");
            assert!(cut.final_objective <= whole.final_objective, "racer {k}");
        }
    }

    #[test]
    fn halve_after_is_unset_unless_given_and_each_model_fills_its_default() {
        let parse = |text: &str| serde_saphyr::from_str::<StartPolicy>(text).unwrap();
        let omitted = parse("perturbations: 1");
        assert_eq!(omitted.halve_after, None);
        assert_eq!(omitted.perturbations, 1);
        assert_eq!(parse("halve_after: 0").halve_after, Some(0));
        assert_eq!(
            omitted
                .with_default_halve_after(EXACT_GP_HALVE_AFTER)
                .halve_after,
            Some(EXACT_GP_HALVE_AFTER)
        );
        // A value the user gave, 0 (no halving) included, is kept.
        assert_eq!(
            parse("halve_after: 0")
                .with_default_halve_after(EXACT_GP_HALVE_AFTER)
                .halve_after,
            Some(0)
        );
        assert!(serde_saphyr::from_str::<StartPolicy>("halve_after_typo: 3").is_err());
    }
}
