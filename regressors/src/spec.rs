//! The regressor kinds an experiment may name in YAML, as a closed enum
//! (`kind: zero`, ...). A spec is validated when the configuration is read
//! and then built into a runtime `Box<dyn ResidualRegressor>`.

use gpodo_traits::ResidualRegressor;
use serde::{Deserialize, Serialize};

use crate::exact_gp::{ExactGp, ExactGpParams, OutputSharing};
use crate::external::{ExternalParams, ExternalRegressor};
use crate::ilgr::{Ilgr, IlgrParams};
use crate::knn::{Knn, KnnParams};
use crate::sparse_gp::{Approximation, SparseGp, SparseGpParams};
use crate::sparse_spectrum::{SparseSpectrumGp, SparseSpectrumParams};
use crate::streaming_sparse_gp::{StreamingSparseGp, StreamingSparseGpParams};
use crate::{RegressorError, ZeroResidual};

/// A regressor as written in an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RegressorSpec {
    /// "Parametric model only": zero residual.
    Zero {
        /// Fixed predictive variance per output ((m/s)²); omitted, the
        /// training residuals' mean square per output.
        #[serde(default)]
        variance: Option<f64>,
    },
    /// The exact Gaussian process (§IV-A) with a kernel expression.
    ExactGp(ExactGpParams),
    /// The sparse GP (VFE or FITC) with a kernel expression.
    SparseGp(SparseGpParams),
    /// Incremental local Gaussian regression (§VI), learning online.
    Ilgr(IlgrParams),
    /// The sparse-spectrum GP learned online (I-SSGP): random Fourier
    /// features of a stationary kernel, exact rank-one updates.
    SparseSpectrum(SparseSpectrumParams),
    /// The streaming sparse GP (Bui, Nguyen & Turner 2017), learning
    /// online in batches from a variational posterior over inducing points.
    StreamingSparseGp(StreamingSparseGpParams),
    /// k-nearest-neighbour regression (the worked example of adding a
    /// regressor).
    Knn(KnnParams),
    /// A model in another language, run as a child process speaking the
    /// protocol of `plugins/PROTOCOL.md`; its extra fields are the
    /// plugin's `options`.
    External(ExternalParams),
}

impl RegressorSpec {
    /// A short label for reports: the kind, its kernel and approximation,
    /// then every other setting that differs from its default
    /// in name order (`ILGR [forgetting=1.0, passes=3]`), so that two rows of a table never
    /// share a label unless they share their settings.
    pub fn label(&self) -> String {
        let (base, shown, params, defaults) = match self {
            Self::Zero { variance } => {
                let base = "parametric only".to_string();
                return match variance {
                    Some(v) => format!("{base} [variance={v}]"),
                    None => base,
                };
            }
            Self::ExactGp(p) => {
                let base = match p.outputs {
                    OutputSharing::Shared => format!("exact GP: {}", p.kernel),
                    OutputSharing::Independent => format!("exact GP: {} (per output)", p.kernel),
                };
                (
                    base,
                    &["kernel", "outputs"][..],
                    to_json(p),
                    to_json(&ExactGpParams::default()),
                )
            }
            Self::SparseGp(p) => {
                let method = match p.approximation {
                    Approximation::Vfe => "VFE",
                    Approximation::Fitc => "FITC",
                };
                let base = format!("sparse GP ({method}, m={}): {}", p.inducing.count, p.kernel);
                let shown = &["kernel", "approximation", "inducing.count"][..];
                (base, shown, to_json(p), to_json(&SparseGpParams::default()))
            }
            Self::SparseSpectrum(p) => (
                format!("sparse spectrum (D={}): {}", p.features, p.kernel),
                &["kernel", "features"][..],
                to_json(p),
                to_json(&SparseSpectrumParams::default()),
            ),
            Self::StreamingSparseGp(p) => (
                format!(
                    "streaming sparse GP (m={}, batch={}): {}",
                    p.inducing.count, p.batch_rows, p.kernel
                ),
                &["kernel", "inducing.count", "batch_rows"][..],
                to_json(p),
                to_json(&StreamingSparseGpParams::default()),
            ),
            Self::Ilgr(p) => (
                "ILGR".to_string(),
                &[][..],
                to_json(p),
                to_json(&IlgrParams::default()),
            ),
            Self::Knn(p) => (
                format!("k-NN (k={})", p.k),
                &["k"][..],
                to_json(p),
                to_json(&KnnParams::default()),
            ),
            Self::External(p) => (
                p.base_label(),
                &["command", "label", "timeout_secs"][..],
                to_json(p),
                to_json(&ExternalParams::new(p.command.clone())),
            ),
        };
        let mut changed = Vec::new();
        non_default_settings("", &params, &defaults, &mut changed);
        changed.retain(|(path, _)| !shown.contains(&path.as_str()));
        if changed.is_empty() {
            base
        } else {
            let details: Vec<String> = changed
                .into_iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            format!("{base} [{}]", details.join(", "))
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), RegressorError> {
        match self {
            Self::Zero { variance: Some(v) } if !(v.is_finite() && *v > 0.0) => {
                Err(RegressorError::InvalidSpec {
                    regressor: "zero".into(),
                    field: "variance".into(),
                    expected: "a positive variance in (m/s)²".into(),
                })
            }
            Self::Zero { .. } => Ok(()),
            Self::ExactGp(p) => p.check(),
            Self::SparseGp(p) => p.check(),
            Self::Ilgr(p) => p.check(),
            Self::SparseSpectrum(p) => p.check(),
            Self::StreamingSparseGp(p) => p.check(),
            Self::Knn(p) => p.check(),
            Self::External(p) => p.check(),
        }
    }

    /// The memory a fit on `n` rows of `d` inputs and `p` outputs will
    /// need at its peak (bytes), for the models whose need grows with the
    /// data (`None` for the others): an exact GP holds about five `n × n`
    /// matrices (the Gram matrix, its Cholesky factor, its inverse and the
    /// gradient's scratch), three when it can only solve iteratively
    /// (`solver: iterative`, or `auto` above its small-noise dense limit),
    /// a sparse GP about eight `m × n` ones and its
    /// `m × m` factors, with `m` the inducing points it will use; a
    /// sparse-spectrum GP its warm-up GP's and its `D × D` factor.
    pub fn fit_memory_bytes(&self, n: usize, d: usize, p: usize) -> Option<u64> {
        let f64s = |count: u128| u64::try_from(count.saturating_mul(8)).unwrap_or(u64::MAX);
        let (n, d, p) = (n as u128, d as u128, p as u128);
        match self {
            Self::ExactGp(e)
                if !e
                    .solver
                    .may_be_dense(usize::try_from(n).unwrap_or(usize::MAX)) =>
            {
                // K, W and the gradient's scratch while learning (the
                // posterior then needs K alone); the preconditioner and
                // the CG blocks are n × (k + p + t), the variances' Krylov
                // basis three n × r blocks.
                let k = e.iterative.preconditioner_rank as u128;
                let t = e.iterative.probes as u128;
                let r = e.iterative.variance_rank as u128;
                Some(f64s(
                    3 * n * n + 6 * n * (k + p + t) + 3 * n * r + 4 * n * (d + p),
                ))
            }
            Self::ExactGp(_) => Some(f64s(5 * n * n + 4 * n * (d + p))),
            Self::SparseGp(s) => {
                let m = (s.inducing.count as u128).min(n);
                Some(f64s(8 * m * n + 6 * m * m + 4 * n * (d + p)))
            }
            // The warm-up GP's five w × w matrices and the D × D factor.
            Self::SparseSpectrum(s) => {
                let w = (s.warmup_rows as u128).min(n);
                let features = s.features as u128;
                Some(f64s(
                    5 * w * w + features * (features + p) + 4 * n * (d + p),
                ))
            }
            // Its first batch's sparse GP, and one batch's at a time after.
            Self::StreamingSparseGp(s) => {
                let w = (s.warmup_rows.max(s.batch_rows) as u128).min(n);
                let m = s.inducing.count as u128;
                Some(f64s(8 * m * w + 10 * m * m + 4 * n * (d + p)))
            }
            Self::Zero { .. } | Self::Ilgr(_) | Self::Knn(_) | Self::External(_) => None,
        }
    }

    /// A rough relative cost of fitting on `n` rows, to start the longest
    /// fits of a sweep first: `n³` per exact-GP fit times the kernel's
    /// additive terms (a sum needs about twice the evaluations of one
    /// kernel; `kernel: auto` fits every candidate); `n m²` for a sparse
    /// GP; the warm-up GP's `w³` plus `n D²` for a sparse-spectrum GP; `n³`
    /// for a plug-in, which may be anything and so starts early; `n` for
    /// the models that pass over the data once.
    pub fn fit_cost(&self, n: usize) -> f64 {
        let n_rows = n as f64;
        match self {
            Self::ExactGp(p) => {
                let fits: usize = match p.kernel.expr() {
                    Some(k) => k.additive_terms(),
                    None => p.kernel_candidates.iter().map(|k| k.additive_terms()).sum(),
                };
                n_rows.powi(3) * fits as f64
            }
            Self::SparseGp(p) => n_rows * (p.inducing.count.min(n) as f64).powi(2),
            Self::SparseSpectrum(p) => {
                (p.warmup_rows.min(n) as f64).powi(3) + n_rows * (p.features as f64).powi(2)
            }
            Self::StreamingSparseGp(p) => n_rows * (p.inducing.count as f64).powi(2),
            Self::External(_) => n_rows.powi(3),
            Self::Zero { .. } | Self::Ilgr(_) | Self::Knn(_) => n_rows,
        }
    }

    /// Builds the runtime regressor.
    ///
    /// # Errors
    /// As [`RegressorSpec::validate`].
    pub fn build(&self) -> Result<Box<dyn ResidualRegressor>, RegressorError> {
        self.validate()?;
        Ok(match self {
            Self::Zero { variance } => Box::new(ZeroResidual::new(*variance)),
            Self::ExactGp(p) => Box::new(ExactGp::new(p.clone())?),
            Self::SparseGp(p) => Box::new(SparseGp::new(p.clone())?),
            Self::Ilgr(p) => Box::new(Ilgr::new(p.clone())?),
            Self::SparseSpectrum(p) => Box::new(SparseSpectrumGp::new(p.clone())?),
            Self::StreamingSparseGp(p) => Box::new(StreamingSparseGp::new(p.clone())?),
            Self::Knn(p) => Box::new(Knn::new(p.clone())?),
            Self::External(p) => Box::new(ExternalRegressor::new(p.clone())?),
        })
    }
}

fn to_json<T: Serialize>(value: &T) -> serde_json::Value {
    serde_json::to_value(value).unwrap_or(serde_json::Value::Null)
}

/// The settings of `value` that differ from `default`, as dotted paths
/// (`inducing.fixed`) with compact values, in name order.
fn non_default_settings(
    prefix: &str,
    value: &serde_json::Value,
    default: &serde_json::Value,
    out: &mut Vec<(String, String)>,
) {
    use serde_json::Value;
    match (value, default) {
        (Value::Object(fields), Value::Object(defaults)) => {
            for (key, v) in fields {
                let path = if prefix.is_empty() {
                    key.clone()
                } else {
                    format!("{prefix}.{key}")
                };
                match defaults.get(key) {
                    Some(d) => non_default_settings(&path, v, d, out),
                    None => out.push((path, compact(v))),
                }
            }
        }
        _ if value != default => out.push((prefix.to_string(), compact(value))),
        _ => {}
    }
}

fn compact(value: &serde_json::Value) -> String {
    match value {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<RegressorSpec, serde_json::Error> {
        serde_json::from_str(json)
    }

    #[test]
    fn exact_gp_reads_its_kernel_expression_and_defaults() {
        let spec = parse(
            r#"{"kind": "exact_gp", "kernel": "matern52 + linear", "hyperopt": {"restarts": 2}}"#,
        )
        .unwrap();
        let RegressorSpec::ExactGp(p) = &spec else {
            panic!("not an exact GP: {spec:?}")
        };
        assert_eq!(p.kernel.to_string(), "matern52 + linear");
        assert_eq!(p.hyperopt.restarts, 2);
        assert_eq!(
            p.hyperopt.max_iters,
            ExactGpParams::default().hyperopt.max_iters
        );
        assert_eq!(
            spec.label(),
            "exact GP: matern52 + linear [hyperopt.restarts=2]"
        );
        assert!(spec.build().is_ok());
    }

    #[test]
    fn an_exact_gp_on_twenty_thousand_rows_needs_gigabytes() {
        let exact = parse(r#"{"kind": "exact_gp"}"#).unwrap();
        // Five 20 000 × 20 000 matrices of f64: 16 GB.
        let need = exact.fit_memory_bytes(20_000, 28, 3).unwrap();
        assert!((16.0e9..16.1e9).contains(&(need as f64)), "{need}");
        // `solver: auto` can only solve iteratively above its small-noise
        // dense limit: three matrices there, five (dense) at or below it.
        let auto = parse(r#"{"kind": "exact_gp", "solver": "auto"}"#).unwrap();
        let need = auto.fit_memory_bytes(20_000, 28, 3).unwrap();
        assert!((9.6e9..10.2e9).contains(&(need as f64)), "{need}");
        let at = crate::exact_gp::Solver::AUTO_SMALL_NOISE_DENSE_UP_TO_ROWS;
        assert_eq!(
            auto.fit_memory_bytes(at, 28, 3),
            exact.fit_memory_bytes(at, 28, 3)
        );
        assert_eq!(
            crate::exact_gp::Solver::Auto.resolve(at + 1),
            crate::exact_gp::Solver::Iterative
        );
        let sparse = parse(r#"{"kind": "sparse_gp", "inducing": {"count": 1000000000}}"#).unwrap();
        // The inducing points it will use are the rows.
        assert_eq!(
            sparse.fit_memory_bytes(100, 2, 1),
            Some(8 * (8 * 100 * 100 + 6 * 100 * 100 + 4 * 100 * 3))
        );
        assert_eq!(
            parse(r#"{"kind": "ilgr"}"#)
                .unwrap()
                .fit_memory_bytes(10, 2, 1),
            None
        );
    }

    #[test]
    fn sparse_gp_reads_its_inducing_settings() {
        let spec = parse(
            r#"{"kind": "sparse_gp", "approximation": "fitc", "inducing": {"count": 50, "init": "random_subset"}}"#,
        )
        .unwrap();
        assert_eq!(
            spec.label(),
            "sparse GP (FITC, m=50): rbf [inducing.init=random_subset]"
        );
        assert!(spec.build().is_ok());
        let err = parse(r#"{"kind": "sparse_gp", "inducing": {"cnt": 5}}"#).unwrap_err();
        assert!(err.to_string().contains("cnt"), "{err}");
        let spec = parse(r#"{"kind": "sparse_gp", "inducing": {"count": 0}}"#).unwrap();
        assert!(
            spec.validate()
                .unwrap_err()
                .to_string()
                .contains("inducing.count")
        );
    }

    #[test]
    fn unknown_fields_and_bad_kernels_are_rejected() {
        let err = parse(r#"{"kind": "exact_gp", "kernal": "rbf"}"#).unwrap_err();
        assert!(err.to_string().contains("kernal"), "{err}");
        let err = parse(r#"{"kind": "exact_gp", "kernel": "rbf + lin"}"#).unwrap_err();
        assert!(err.to_string().contains("found `lin`"), "{err}");
        let spec = parse(r#"{"kind": "exact_gp", "noise_variance": 0.0}"#).unwrap();
        assert!(
            spec.validate()
                .unwrap_err()
                .to_string()
                .contains("noise_variance")
        );
    }

    #[test]
    fn ilgr_reads_its_fields_and_defaults() {
        let spec = parse(r#"{"kind": "ilgr", "w_gen": 0.4, "max_models": 50}"#).unwrap();
        let RegressorSpec::Ilgr(p) = &spec else {
            panic!("not an ILGR: {spec:?}")
        };
        assert_eq!(p.w_gen, 0.4);
        assert_eq!(p.max_models, 50);
        assert_eq!(p.forgetting, IlgrParams::default().forgetting);
        assert_eq!(spec.label(), "ILGR [max_models=50, w_gen=0.4]");
        let model = spec.build().unwrap();
        assert_eq!(model.name(), "ilgr");
        assert!(model.supports_online_update());
        let spec = parse(r#"{"kind": "ilgr"}"#).unwrap();
        assert_eq!(spec.label(), "ILGR");
        let spec = parse(r#"{"kind": "ilgr", "forgetting": 1.0, "passes": 3}"#).unwrap();
        assert_eq!(spec.label(), "ILGR [forgetting=1.0, passes=3]");
    }

    #[test]
    fn ilgr_rejects_unknown_fields_and_bad_values() {
        let err = parse(r#"{"kind": "ilgr", "wgen": 0.4}"#).unwrap_err();
        assert!(err.to_string().contains("wgen"), "{err}");
        let spec = parse(r#"{"kind": "ilgr", "forgetting": 1.5}"#).unwrap();
        let err = spec.build().err().unwrap();
        assert!(err.to_string().contains("forgetting"), "{err}");
    }
}
