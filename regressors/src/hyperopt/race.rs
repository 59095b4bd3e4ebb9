//! The start race: every named base start and the best-scored candidates
//! run a few optimiser iterations (the worse half stopping early when the
//! policy halves the race), and only the leader goes on to convergence,
//! with the seeded restarts. The highest optimum wins, and every
//! candidate keeps a record of where it started and ended.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use gpodo_traits::{FitProgress, StartRecord};

use super::run::Run;
use super::starts::{Candidate, StartPoint, StartPolicy, best, score_all};
use super::{
    Coordinates, LogBounds, Maximized, Objective, OptimizerSettings, ProgressSink, clamped,
    maximize,
};
use crate::RegressorError;

/// Scores a candidate start by the objective alone (no gradient).
pub type Score<'a> = &'a dyn Fn(&[f64]) -> Result<f64, RegressorError>;

/// One objective to race on: its optimiser coordinates, how to score a
/// start, and how to run the optimiser.
pub struct StartRace<'a> {
    /// The objective (with its gradient) to maximise.
    pub objective: &'a dyn Objective,
    /// The objective without its gradient, for scoring candidates.
    pub score: Score<'a>,
    /// One bound per coordinate.
    pub bounds: &'a [LogBounds],
    /// Which coordinates the restarts perturb.
    pub perturb: &'a [bool],
    /// Normalises the objective (e.g. `1/(n·p)`), so that the tolerances
    /// mean the same at any data size.
    pub value_scale: f64,
    /// How each optimiser run goes.
    pub settings: OptimizerSettings,
    /// Where the runs report their iterations (and may be told to stop).
    pub progress: &'a ProgressSink,
}

/// A candidate's index among the scored ones, and where its run starts.
type Entrant = (usize, Vec<f64>);

/// A racer: the candidate's index, its run and its progress sink.
type Racer<'a> = (usize, Run<'a>, Option<Arc<dyn FitProgress>>);

impl StartRace<'_> {
    /// Scores `candidates`, races the optimiser from every named base and
    /// the best `policy.optimize_best` of them for `policy.race_iterations`
    /// (only the better half after `policy.halve_after`, when set), then
    /// runs [`maximize`] from the leader's best point alone to convergence,
    /// with `settings.restarts` extra perturbed runs, and returns the
    /// highest optimum with every candidate's record (restarts appended as
    /// records of their own). Evaluations and iterations are summed over
    /// all runs.
    ///
    /// # Errors
    /// [`RegressorError::Stopped`] when the progress asked to stop; the
    /// last optimiser error when no run produced a finite objective, or
    /// [`RegressorError::Optimizer`] when no candidate could be scored.
    pub fn maximize_best(
        &self,
        candidates: Vec<StartPoint>,
        policy: &StartPolicy,
    ) -> Result<(Maximized, Vec<StartRecord>), RegressorError> {
        let scored = score_all(candidates, self.score);
        let mut tally = Tally::new(&scored);
        let mut entrants: Vec<Entrant> = entrants(&scored, policy.optimize_best)
            .into_iter()
            .map(|i| (i, scored[i].coords.clone()))
            .collect();
        if entrants.len() > 1 && policy.race_iterations > 0 {
            entrants = self.race(entrants, policy, &mut tally)?;
        }
        for (rank, (i, start)) in entrants.into_iter().enumerate() {
            self.converge(i, start, rank == 0, &scored[i].label, &mut tally)?;
        }
        tally.finish(&self.settings)
    }

    /// Runs every entrant `policy.race_iterations` (halving as the policy
    /// says) and returns the leader, to be continued from its best point.
    fn race(
        &self,
        entrants: Vec<Entrant>,
        policy: &StartPolicy,
        tally: &mut Tally,
    ) -> Result<Vec<Entrant>, RegressorError> {
        let short = OptimizerSettings {
            max_iters: policy.race_iterations,
            restarts: 0,
            ..self.settings
        };
        let mut racers = Vec::with_capacity(entrants.len());
        for (i, start) in entrants {
            let u = clamped(&start, self.bounds);
            let sink = tally.next_sink(self.progress, 1);
            match Run::start(self.objective, self.bounds, u, self.value_scale, &short) {
                Ok(run) => racers.push((i, run, sink)),
                Err(e) => tally.last_error = Some(e),
            }
        }
        advance_race(&mut racers, policy);
        tally.check_stopped()?;
        let mut leader: Option<(usize, Vec<f64>, f64)> = None;
        for (i, run, _) in racers {
            let out = run.finish();
            tally.record_race(i, &out);
            if leader.as_ref().is_none_or(|l| out.value > l.2) {
                leader = Some((i, out.coords.clone(), out.value));
            }
            tally.offer(out);
        }
        Ok(leader.map(|(i, c, _)| vec![(i, c)]).unwrap_or_default())
    }

    /// Runs candidate `i` from `start` to convergence, with the restarts
    /// when it is the `first` run to converge.
    fn converge(
        &self,
        i: usize,
        start: Vec<f64>,
        first: bool,
        label: &str,
        tally: &mut Tally,
    ) -> Result<(), RegressorError> {
        let mut settings = self.settings;
        if !first {
            settings.restarts = 0;
        }
        let coords = Coordinates {
            start,
            bounds: self.bounds.to_vec(),
            perturb: self.perturb.to_vec(),
        };
        let sink = tally.next_sink(self.progress, 1 + settings.restarts);
        let result = maximize(
            self.objective,
            &coords,
            self.value_scale,
            &settings,
            sink.as_ref(),
        );
        tally.check_stopped()?;
        match result {
            Ok(out) => {
                tally.record_converged(i, label, &out);
                tally.offer(out);
            }
            Err(e) => tally.last_error = Some(e),
        }
        Ok(())
    }
}

/// The candidates that race: every named base, then the best-scored
/// others (the objective at a start predicts its optimum poorly: on the
/// ExoTeR table a perturbed start scores above GPy's unit lengthscales and
/// ends 350 nats below them), leaving out those that could not be scored.
fn entrants(scored: &[Candidate], optimize_best: usize) -> Vec<usize> {
    let mut chosen: Vec<usize> = (0..scored.len()).filter(|&i| scored[i].base).collect();
    for i in best(scored, optimize_best) {
        if !chosen.contains(&i) {
            chosen.push(i);
        }
    }
    chosen.retain(|&i| scored[i].value.is_some());
    chosen
}

/// What the runs of one race have produced so far.
struct Tally {
    records: Vec<StartRecord>,
    best: Option<Maximized>,
    evaluations: usize,
    iterations: u64,
    last_error: Option<RegressorError>,
    /// The number the next optimiser run reports its progress under.
    run_number: usize,
    /// Set once the progress asked the fit to stop.
    stopped: Arc<AtomicBool>,
}

impl Tally {
    fn new(scored: &[Candidate]) -> Self {
        let records = scored
            .iter()
            .map(|c| StartRecord {
                label: c.label.clone(),
                start_objective: c.value,
                ..StartRecord::default()
            })
            .collect();
        Self {
            records,
            best: None,
            evaluations: 0,
            iterations: 0,
            last_error: None,
            run_number: 0,
            stopped: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The progress sink of the next `runs` optimiser runs, numbered after
    /// the runs before them.
    fn next_sink(&mut self, progress: &ProgressSink, runs: usize) -> Option<Arc<dyn FitProgress>> {
        let first = self.run_number;
        self.run_number += runs;
        progress.0.as_ref().map(|inner| {
            Arc::new(Numbered {
                inner: Arc::clone(inner),
                first,
                stopped: Arc::clone(&self.stopped),
            }) as Arc<dyn FitProgress>
        })
    }

    /// [`RegressorError::Stopped`] once the fit's progress asked to stop.
    fn check_stopped(&self) -> Result<(), RegressorError> {
        if self.stopped.load(Ordering::Relaxed) {
            Err(RegressorError::Stopped)
        } else {
            Ok(())
        }
    }

    /// Records a racer's run as candidate `i`'s.
    fn record_race(&mut self, i: usize, out: &Maximized) {
        self.evaluations += out.evaluations;
        self.iterations += out.iterations;
        let record = &mut self.records[i];
        record.final_objective = Some(out.value);
        record.evaluations = Some(out.evaluations);
        record.iterations = Some(out.iterations);
    }

    /// Adds a converged run (and its restarts) to candidate `i`'s record.
    fn record_converged(&mut self, i: usize, label: &str, out: &Maximized) {
        self.evaluations += out.evaluations;
        self.iterations += out.iterations;
        let record = &mut self.records[i];
        record.final_objective = out.start_values.first().copied();
        record.evaluations = Some(record.evaluations.unwrap_or(0) + out.evaluations);
        record.iterations = Some(record.iterations.unwrap_or(0) + out.iterations);
        for (k, v) in out.start_values.iter().enumerate().skip(1) {
            self.records.push(StartRecord {
                label: format!("{label}, restart #{k}"),
                final_objective: Some(*v),
                ..StartRecord::default()
            });
        }
    }

    /// Keeps `out` when it is the best run so far.
    fn offer(&mut self, out: Maximized) {
        if self.best.as_ref().is_none_or(|b| out.value > b.value) {
            self.best = Some(out);
        }
    }

    /// The best run with the totals of all runs, and every record.
    fn finish(
        self,
        settings: &OptimizerSettings,
    ) -> Result<(Maximized, Vec<StartRecord>), RegressorError> {
        let Some(mut out) = self.best else {
            return Err(self
                .last_error
                .unwrap_or_else(|| RegressorError::Optimizer {
                    optimizer: format!("{:?}", settings.optimizer),
                    detail: "no candidate start could be evaluated".into(),
                }));
        };
        out.evaluations = self.evaluations;
        out.iterations = self.iterations;
        Ok((out, self.records))
    }
}

/// Reports a run's starts to the fit's progress under numbers that follow
/// the runs before it, so that every optimiser run of a fit has its own;
/// once the progress asks to stop, every run of the fit stops.
struct Numbered {
    inner: Arc<dyn FitProgress>,
    first: usize,
    stopped: Arc<AtomicBool>,
}

impl FitProgress for Numbered {
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

    fn stop_requested(&self) -> bool {
        let stop = self.stopped.load(Ordering::Relaxed) || self.inner.stop_requested();
        if stop {
            self.stopped.store(true, Ordering::Relaxed);
        }
        stop
    }
}

/// Advances every racer to `policy.halve_after` iterations (unset or 0:
/// `policy.race_iterations`), then only the better half of them (rounded
/// up; ranked by their best value so far, ties to the earlier candidate,
/// among those that can still go on: a racer that converged keeps its
/// value without taking a place) on to `policy.race_iterations`. Each run
/// is resumed where it paused, so a racer that goes on ends exactly where
/// an uninterrupted race of `race_iterations` would have left it: halving
/// only spares the iterations of the racers that trail.
fn advance_race(racers: &mut [Racer<'_>], policy: &StartPolicy) {
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
            optimizer: crate::hyperopt::Optimizer::Lbfgs,
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
            let score = |c: &[f64]| Bumps.evaluate(c).map(|(v, _)| v);
            let race = StartRace {
                objective: &Bumps,
                score: &score,
                bounds: &bounds,
                perturb: &[true, true],
                value_scale: 1.0,
                settings,
                progress: &ProgressSink::default(),
            };
            race.maximize_best(candidates.clone(), &policy).unwrap()
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
}
