//! The gate driven along the outputs' steps, lazily up to each pair's
//! stamp, with the predictions put in force on the session's clock: at
//! each step's end (the sample clock) or at each window's end after the
//! targets waiting for that window (the window clock).

use gpodo_frontends::FrontendError;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_traits::BodyTwist;
use nalgebra::Vector3;

use super::GateSession;
use crate::gate::windows::GridWindows;
use crate::pipeline::LiveOutput;

/// An output, as the step from it needs it.
pub(super) struct Sample {
    pub(super) time_secs: f64,
    /// The motion model's twist.
    pub(super) twist: BodyTwist,
    /// The learner's inputs: of its row on the sample clock, its own on
    /// the window clock.
    pub(super) inputs: Option<Vec<f64>>,
}

/// A step between two outputs, known once the second has come.
pub(super) struct Step {
    pub(super) start_secs: f64,
    pub(super) end_secs: f64,
    pub(super) twist: BodyTwist,
    /// The learner's inputs the gate is driven with (the sample clock).
    pub(super) inputs: Option<Vec<f64>>,
    /// Its window (the window clock).
    pub(super) window: Option<i64>,
    /// The prediction put in force at its end (the sample clock).
    pub(super) then_predict: Option<ResidualPrediction>,
}

impl<T> GateSession<T> {
    /// One odometry output, of the joint state stamped `stamp_ns`: the
    /// step since the output before it is known. The gate is driven to
    /// that output (the step before is finished), and along the new step
    /// as pairs are decided. The first output sets the gate's clock: the
    /// outputs' own, so a pair stamped as a joint state is at its time.
    ///
    /// # Errors
    /// A prediction the gate's odometry cannot use, or the learner's
    /// failure on a window's row.
    pub fn output(&mut self, out: &LiveOutput, stamp_ns: i64) -> Result<(), FrontendError> {
        let on_row = out.residual.map(|(mean, variance)| ResidualPrediction {
            mean: Vector3::from(mean),
            variance: Vector3::from(variance),
            absolute: None,
        });
        let prediction = match &self.windows {
            None => on_row,
            Some(_) => {
                if self.learner.is_none() {
                    self.saved = on_row;
                }
                None
            }
        };
        let inputs = match &self.windows {
            Some(_) => Some(self.learner_row(&out.inputs)),
            None => out
                .row
                .as_deref()
                .filter(|_| self.learner.is_some())
                .map(|row| self.learner_row(row)),
        };
        let previous = self.previous.replace(Sample {
            time_secs: out.time_secs,
            twist: out.uncorrected,
            inputs,
        });
        if let Some(step) = &self.step {
            self.drive_to(step.end_secs)?;
        }
        match previous {
            None => {
                self.gate
                    .set_origin_ns(stamp_ns - (out.time_secs * 1e9).round() as i64);
                if let Some(windows) = self.windows.as_mut() {
                    windows.index_at(out.time_secs);
                }
                self.driven_secs = out.time_secs;
                if let Some(p) = prediction {
                    self.gate.predict(p)?;
                }
            }
            Some(Sample {
                time_secs: time,
                twist,
                inputs,
            }) => {
                let dt = out.time_secs - time;
                let (inputs, window) = match self.windows.as_mut() {
                    Some(windows) => (
                        None,
                        Some(windows.step(time, dt, inputs.unwrap_or_default())),
                    ),
                    None => (inputs, None),
                };
                self.step = Some(Step {
                    start_secs: time,
                    end_secs: out.time_secs,
                    twist,
                    inputs,
                    window,
                    then_predict: prediction,
                });
            }
        }
        Ok(())
    }

    /// Drives the gate along the step known up to `time_secs` (no further
    /// than the step's end), putting predictions in force where they are
    /// due: at the step's end on the sample clock, at each window's end on
    /// the window clock, after the targets waiting for that window.
    pub(super) fn drive_to(&mut self, time_secs: f64) -> Result<(), FrontendError> {
        let Some(step) = self.step.as_mut() else {
            return Ok(());
        };
        let target = time_secs.min(step.end_secs);
        loop {
            self.close_windows()?;
            let Some(step) = self.step.as_mut() else {
                return Ok(());
            };
            if self.driven_secs >= target {
                break;
            }
            let mut end = target;
            if let Some(next) = self.windows.as_ref().and_then(GridWindows::next_end)
                && next > self.driven_secs
            {
                end = end.min(next);
            }
            let from = self.driven_secs.max(step.start_secs);
            self.gate
                .drive(&step.twist, end - from, step.inputs.as_deref());
            if let (Some(windows), Some(w)) = (self.windows.as_mut(), step.window) {
                windows.driven(from, end, w);
            }
            self.driven_secs = end;
        }
        if let Some(step) = self.step.as_mut()
            && self.driven_secs >= step.end_secs
            && let Some(p) = step.then_predict.take()
        {
            self.gate.predict(p)?;
        }
        Ok(())
    }

    /// Closes the windows that have ended by now: the targets waiting for
    /// them are learned, then each window's prediction is put in force.
    fn close_windows(&mut self) -> Result<(), FrontendError> {
        loop {
            let Some(closed) = self
                .windows
                .as_mut()
                .and_then(|w| w.close_until(self.driven_secs))
            else {
                return Ok(());
            };
            self.learn_waiting();
            let prediction = match (closed.row, self.learner.as_ref()) {
                (Some(row), Some(learner)) => Some(learner.predict(&row)?),
                (Some(_), None) => self.saved,
                (None, _) => None,
            };
            if let Some(p) = prediction {
                self.gate.predict(p)?;
            }
        }
    }

    /// Learns the waiting targets whose windows have all closed, in the
    /// order they were formed; a target none of whose stretches had a
    /// row is dropped, as offline.
    pub(super) fn learn_waiting(&mut self) {
        let Some(windows) = self.windows.as_mut() else {
            return;
        };
        while let Some(target) = self.waiting.front() {
            let start = target.time_secs - target.duration_secs;
            let Some(inputs) = windows.inputs_over(start, target.time_secs) else {
                break;
            };
            let Some(mut target) = self.waiting.pop_front() else {
                break;
            };
            if let Some(inputs) = inputs {
                target.inputs = inputs;
                if let Some(learner) = self.learner.as_mut()
                    && learner.learn(target).is_err()
                {
                    self.faults.learn_errors += 1;
                }
            }
        }
        let oldest = self
            .waiting
            .front()
            .map_or(self.driven_secs, |t| t.time_secs - t.duration_secs);
        let span = self.gate.settings().targets.max_interval_secs;
        windows.forget_before(oldest.min(self.driven_secs - span));
    }
}
