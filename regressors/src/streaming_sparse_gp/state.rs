//! What a streaming sparse GP saves: its settings, scaling, hyperparameters,
//! the summary the next batch starts from and the rows of its unfinished
//! batch.

use gpodo_traits::{SampleMatrix, Standardizer};
use serde::{Deserialize, Serialize};

use super::bound::InducingSummary;
use super::params::StreamingSparseGpParams;
use crate::dense::{from_faer, to_faer};
use crate::kernels::Kernel;

/// The old batches' summary as saved: what they told the function at their
/// inducing inputs ([`InducingSummary`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedSummary {
    /// Inducing inputs `Z_a` (`M × d`, standardised units).
    pub inducing: SampleMatrix,
    /// `K'_aa` under the hyperparameters it was computed with.
    pub prior_covariance: SampleMatrix,
    /// `Λ_a` (`M × M`).
    pub data_precision: SampleMatrix,
    /// `η_a` (`M × p`).
    pub natural_mean: SampleMatrix,
}

/// Everything needed to predict and go on learning, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StreamingSparseGpState {
    /// The settings.
    pub params: StreamingSparseGpParams,
    /// Input column names.
    pub input_names: Vec<String>,
    /// Output column names.
    pub target_names: Vec<String>,
    /// The first batch's input scaling (None when `standardize` is off or
    /// the inputs came z-scored).
    pub input_scaler: Option<Standardizer>,
    /// The first batch's target scaling.
    pub output_scaler: Option<Standardizer>,
    /// Kernel with the last batch's hyperparameters (standardised units).
    pub kernel: Kernel,
    /// The last batch's noise variance (standardised units).
    pub noise_variance: f64,
    /// The summary the next batch starts from.
    pub summary: SavedSummary,
    /// The posterior's weights `β` (`M × p`), as the sparse GP's.
    pub weights: SampleMatrix,
    /// The posterior's `P` (`M × M`), as the sparse GP's.
    pub variance_matrix: SampleMatrix,
    /// The last batch's bound.
    pub objective: f64,
    /// Batches learned.
    pub batches: usize,
    /// Rows learned.
    pub rows_seen: usize,
    /// Rows of the batch not yet complete (raw units), learned with it.
    pub pending: Vec<(Vec<f64>, Vec<f64>)>,
}

pub(super) fn summary_to_saved(s: &InducingSummary) -> SavedSummary {
    SavedSummary {
        inducing: from_faer(s.inducing.as_ref()),
        prior_covariance: from_faer(s.prior_covariance.as_ref()),
        data_precision: from_faer(s.data_precision.as_ref()),
        natural_mean: from_faer(s.natural_mean.as_ref()),
    }
}

pub(super) fn saved_to_summary(s: &SavedSummary) -> InducingSummary {
    InducingSummary {
        inducing: to_faer(&s.inducing),
        prior_covariance: to_faer(&s.prior_covariance),
        data_precision: to_faer(&s.data_precision),
        natural_mean: to_faer(&s.natural_mean),
    }
}
