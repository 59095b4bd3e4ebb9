//! The front end's view of a test run ([`build_traverse`]) and a trained
//! regressor's predictions on its windows ([`window_predictions`]).

use gpodo_datasets::log::RoverLog;
use gpodo_datasets::residuals::{log_steps, window_rows};
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_traits::Standardizer;
use gpodo_traits::{MotionModel, ResidualRegressor, SampleMatrix};
use nalgebra::Vector3;

use crate::error::PipelineError;

/// Builds the front end's view of a test run: the motion model's twist per
/// step, the regressor windows with inputs standardised like the training
/// rows, the camera frames.
///
/// # Errors
/// [`PipelineError`] when the model fails or the run is inconsistent.
pub fn build_traverse(
    log: &RoverLog,
    model: &dyn MotionModel,
    wheel_radius_m: f64,
    window_secs: f64,
    scaler: &Standardizer,
) -> Result<Traverse, PipelineError> {
    let steps = log_steps(log, model, wheel_radius_m)?;
    let rows = window_rows(&steps, window_secs);
    let d = rows.first().map_or(0, |r| r.inputs.len());
    let raw = SampleMatrix::from_row_major(
        rows.len(),
        d,
        rows.iter().flat_map(|r| r.inputs.iter().copied()).collect(),
    )?;
    let standardised = if rows.is_empty() {
        raw
    } else {
        scaler.transform(&raw)?
    };
    let windows = rows
        .into_iter()
        .enumerate()
        .map(|(i, r)| TraverseWindow {
            start_secs: r.start_secs,
            end_secs: r.end_secs,
            steps: r.steps,
            inputs: standardised.row(i).to_vec(),
            true_residual: r.residual,
        })
        .collect();
    Ok(Traverse::new(
        log.name.clone(),
        log.samples.iter().map(|s| s.time_secs).collect(),
        log.ground_truth.clone(),
        steps.iter().map(|s| s.twist).collect(),
        windows,
        log.camera_times_secs.clone(),
    )?
    .with_standardized_inputs(true))
}

/// A trained regressor's predictions on every window of a traverse.
///
/// # Errors
/// [`PipelineError::Model`] when prediction fails.
pub fn window_predictions(
    model: &dyn ResidualRegressor,
    traverse: &Traverse,
) -> Result<Vec<ResidualPrediction>, PipelineError> {
    let windows = traverse.windows();
    if windows.is_empty() {
        return Ok(Vec::new());
    }
    let d = windows[0].inputs.len();
    let x = SampleMatrix::from_row_major(
        windows.len(),
        d,
        windows
            .iter()
            .flat_map(|w| w.inputs.iter().copied())
            .collect(),
    )?;
    let p = model.predict(&x)?;
    Ok((0..windows.len())
        .map(|i| ResidualPrediction {
            mean: Vector3::from_iterator(p.mean.row(i).iter().copied()),
            variance: Vector3::from_iterator(p.variance.row(i).iter().copied()),
            absolute: None,
        })
        .collect())
}
