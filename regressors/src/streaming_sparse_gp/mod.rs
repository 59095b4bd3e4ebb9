//! The streaming sparse GP (Bui, Nguyen & Turner, NeurIPS 2017): a
//! variational posterior over inducing points updated batch by batch,
//! never revisiting old data. [`bound`]: the collapsed streaming bound and
//! its optimal posterior at given hyperparameters and inducing inputs, and
//! the bound's gradient for learning them; [`model`]: the regressor that
//! learns a stream in batches with them.

pub mod bound;
mod inducing;
pub mod model;
mod objective;
pub mod params;
pub mod state;

pub use bound::{
    InducingSummary, StreamingFit, StreamingProblem, streaming_fit, streaming_objective,
};
pub use model::{BatchTiming, StreamingSparseGp};
pub use params::StreamingSparseGpParams;
pub use state::{SavedSummary, StreamingSparseGpState};
