//! The regressors that go on learning after they are saved and loaded
//! (ILGR, the sparse-spectrum GP, the streaming sparse GP) as one type, so
//! that a learner running live can be checkpointed and resumed: built
//! fresh from its spec or from a saved state, and saved again.

use gpodo_traits::{
    Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
};

use crate::model_file::SavedState;
use crate::{Ilgr, RegressorError, RegressorSpec, SparseSpectrumGp, StreamingSparseGp};

/// A regressor that learns online and can be saved at any point.
#[derive(Debug, Clone)]
pub enum OnlineModel {
    /// Incremental local Gaussian regression.
    Ilgr(Box<Ilgr>),
    /// The sparse-spectrum GP (I-SSGP).
    SparseSpectrum(Box<SparseSpectrumGp>),
    /// The streaming sparse GP.
    StreamingSparseGp(Box<StreamingSparseGp>),
}

/// The kinds [`OnlineModel`] takes, as specs and checkpoints name them.
pub const ONLINE_KINDS: [&str; 3] = ["ilgr", "sparse_spectrum", "streaming_sparse_gp"];

impl OnlineModel {
    /// A fresh model of `spec`.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] for a kind that does not learn
    /// online, or what its constructor reports.
    pub fn from_spec(spec: &RegressorSpec) -> Result<Self, RegressorError> {
        Ok(match spec {
            RegressorSpec::Ilgr(p) => Self::Ilgr(Box::new(Ilgr::new(p.clone())?)),
            RegressorSpec::SparseSpectrum(p) => {
                Self::SparseSpectrum(Box::new(SparseSpectrumGp::new(p.clone())?))
            }
            RegressorSpec::StreamingSparseGp(p) => {
                Self::StreamingSparseGp(Box::new(StreamingSparseGp::new(p.clone())?))
            }
            other => return Err(not_online(&other.label())),
        })
    }

    /// The model a saved state rebuilds.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] for a kind that does not learn
    /// online; what rebuilding the state reports.
    pub fn from_state(state: &SavedState) -> Result<Self, RegressorError> {
        Ok(match state {
            SavedState::Ilgr(s) => Self::Ilgr(Box::new(Ilgr::from_state(s.clone())?)),
            SavedState::SparseSpectrum(s) => {
                Self::SparseSpectrum(Box::new(SparseSpectrumGp::from_state(s.as_ref().clone())?))
            }
            SavedState::StreamingSparseGp(s) => Self::StreamingSparseGp(Box::new(
                StreamingSparseGp::from_state(s.as_ref().clone())?,
            )),
            SavedState::ExactGp(_) => return Err(not_online("exact_gp")),
            SavedState::SparseGp(_) => return Err(not_online("sparse_gp")),
        })
    }

    /// The kind of a saved state, if it is one of the online kinds (without
    /// rebuilding it).
    pub fn kind_of(state: &SavedState) -> Option<&'static str> {
        match state {
            SavedState::Ilgr(_) => Some(ONLINE_KINDS[0]),
            SavedState::SparseSpectrum(_) => Some(ONLINE_KINDS[1]),
            SavedState::StreamingSparseGp(_) => Some(ONLINE_KINDS[2]),
            SavedState::ExactGp(_) | SavedState::SparseGp(_) => None,
        }
    }

    /// Its kind, as specs and checkpoints name it.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Ilgr(_) => ONLINE_KINDS[0],
            Self::SparseSpectrum(_) => ONLINE_KINDS[1],
            Self::StreamingSparseGp(_) => ONLINE_KINDS[2],
        }
    }

    /// Its learned state, to save; `None` before it has learned anything.
    pub fn saved_state(&self) -> Option<SavedState> {
        match self {
            Self::Ilgr(m) => m.state().cloned().map(SavedState::Ilgr),
            Self::SparseSpectrum(m) => m
                .state()
                .cloned()
                .map(|s| SavedState::SparseSpectrum(Box::new(s))),
            Self::StreamingSparseGp(m) => m
                .state()
                .cloned()
                .map(|s| SavedState::StreamingSparseGp(Box::new(s))),
        }
    }

    fn inner(&self) -> &dyn ResidualRegressor {
        match self {
            Self::Ilgr(m) => m.as_ref(),
            Self::SparseSpectrum(m) => m.as_ref(),
            Self::StreamingSparseGp(m) => m.as_ref(),
        }
    }

    fn inner_mut(&mut self) -> &mut dyn ResidualRegressor {
        match self {
            Self::Ilgr(m) => m.as_mut(),
            Self::SparseSpectrum(m) => m.as_mut(),
            Self::StreamingSparseGp(m) => m.as_mut(),
        }
    }
}

fn not_online(kind: &str) -> RegressorError {
    RegressorError::InvalidSpec {
        regressor: kind.to_string(),
        field: "kind".into(),
        expected: format!(
            "a regressor that learns online: one of {}",
            ONLINE_KINDS.join(", ")
        ),
    }
}

impl ResidualRegressor for OnlineModel {
    fn name(&self) -> &str {
        self.inner().name()
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        self.inner_mut().fit(data)
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        self.inner().predict(inputs)
    }

    fn supports_online_update(&self) -> bool {
        self.inner().supports_online_update()
    }

    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        self.inner_mut().update(inputs, targets)
    }

    fn update_batch(&mut self, data: &ResidualDataset) -> Result<(), Error> {
        self.inner_mut().update_batch(data)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn a_learner_saved_midway_and_rebuilt_predicts_as_the_one_that_went_on() {
        let spec: RegressorSpec = serde_json::from_str(r#"{"kind": "ilgr"}"#).unwrap();
        let mut model = OnlineModel::from_spec(&spec).unwrap();
        assert!(model.saved_state().is_none());
        let row = |i: usize| [(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()];
        let target = |x: [f64; 2]| [0.01 * x[0], -0.004 * x[1], 0.001];
        for i in 0..50 {
            model.update(&row(i), &target(row(i))).unwrap();
        }
        let mut resumed = OnlineModel::from_state(&model.saved_state().unwrap()).unwrap();
        for i in 50..80 {
            model.update(&row(i), &target(row(i))).unwrap();
            resumed.update(&row(i), &target(row(i))).unwrap();
        }
        let x = SampleMatrix::from_row_major(1, 2, vec![0.3, -0.2]).unwrap();
        let (a, b) = (model.predict(&x).unwrap(), resumed.predict(&x).unwrap());
        assert_eq!(a.mean, b.mean);
        assert_eq!(a.variance, b.variance);
    }

    #[test]
    fn kinds_that_do_not_learn_online_are_refused_by_name() {
        let spec: RegressorSpec =
            serde_json::from_str(r#"{"kind": "exact_gp", "kernel": "rbf"}"#).unwrap();
        let Err(RegressorError::InvalidSpec { expected, .. }) = OnlineModel::from_spec(&spec)
        else {
            panic!("an exact GP accepted as an online learner");
        };
        assert!(expected.contains("ilgr"), "{expected}");
    }
}
