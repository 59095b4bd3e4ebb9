//! The multi-start policy shared by the GP regressors: the log marginal
//! likelihood in 20–30 lengthscales is multimodal, and a single start can
//! land in an optimum hundreds of nats below another
//! (`bench/peers/README.md`, "From the same start", compares the starts on
//! the ExoTeR table). So a
//! handful of deterministic candidate starts — named base points and seeded
//! perturbations of them — is scored by the objective alone (no gradient,
//! one factorisation each), the optimiser runs from the best few, and the
//! best optimum wins. Every candidate's starting value (and final value, for
//! those optimised) is kept, so a report can show how multimodal a problem
//! was.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use faer::MatRef;

use super::{LogBounds, clamped, perturbed};
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
                field: "hyperopt.start.optimize_best".into(),
                expected: "at least 1".into(),
            });
        }
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
