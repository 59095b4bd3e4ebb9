//! Input rows made live, as the batch pipeline makes them from a log.
//!
//! In a log, step `k` runs from sample `k` to sample `k + 1`, has sample
//! `k`'s inputs and weighs its duration `t_{k+1} − t_k`; a row averages
//! the steps of a window (`gpodo_datasets::residuals::window_rows`). Live,
//! the newest sample's step has not ended yet, so the row in force at
//! sample `n` averages the steps that start in the trailing window
//! `[t_n − w, t_n)`: the same duration weights, over the last `w` seconds
//! instead of a fixed grid of windows. Without a window (models trained on
//! one row per step) the row is the newest sample's own inputs.

use std::collections::VecDeque;

use crate::NodeError;

/// The trailing-window rows of a stream of samples.
#[derive(Debug, Clone)]
pub struct LiveRows {
    window_secs: Option<f64>,
    /// Finished steps that may still be in the window: start time,
    /// duration, inputs.
    steps: VecDeque<(f64, f64, Vec<f64>)>,
    /// The newest sample: time and inputs (its step not finished).
    newest: Option<(f64, Vec<f64>)>,
}

/// The row in force after a sample.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveRow {
    /// The duration-weighted mean inputs.
    pub inputs: Vec<f64>,
    /// Seconds of steps it averages (0 without a window).
    pub covered_secs: f64,
}

impl LiveRows {
    /// Rows averaging `window_secs` (none: one row per sample).
    pub fn new(window_secs: Option<f64>) -> Self {
        Self {
            window_secs,
            steps: VecDeque::new(),
            newest: None,
        }
    }

    /// The window the rows average (s; none: one row per sample).
    pub fn window_secs(&self) -> Option<f64> {
        self.window_secs
    }

    /// Adds the sample at `time_secs` with its `inputs`, and returns the
    /// row in force from then on; `None` while no step has finished (the
    /// first sample of a windowed stream).
    ///
    /// # Errors
    /// As [`LiveRows::peek`]; the stream is left as it was.
    pub fn push(&mut self, time_secs: f64, inputs: Vec<f64>) -> Result<Option<LiveRow>, NodeError> {
        let row = self.peek(time_secs, &inputs)?;
        self.commit(time_secs, inputs);
        Ok(row)
    }

    /// The row [`LiveRows::push`] would return, without adding the sample.
    ///
    /// # Errors
    /// [`NodeError::Sample`] for a time that does not move forward, or
    /// inputs of another length than the earlier samples'.
    pub fn peek(&self, time_secs: f64, inputs: &[f64]) -> Result<Option<LiveRow>, NodeError> {
        let bad = |detail: String| NodeError::Sample { time_secs, detail };
        if !time_secs.is_finite() {
            return Err(bad("its time is not finite".into()));
        }
        if let Some((last, previous)) = &self.newest {
            if time_secs <= *last {
                return Err(bad(format!(
                    "its time is not after the previous sample's ({last} s)"
                )));
            }
            if inputs.len() != previous.len() {
                return Err(bad(format!(
                    "{} inputs, the earlier samples had {}",
                    inputs.len(),
                    previous.len()
                )));
            }
        }
        let Some(window) = self.window_secs else {
            return Ok(Some(LiveRow {
                inputs: inputs.to_vec(),
                covered_secs: 0.0,
            }));
        };
        // The finished steps that start in the window, the newest sample's
        // (which this sample ends) last.
        let finished = self
            .newest
            .as_ref()
            .map(|(start, x)| (*start, time_secs - start, x.as_slice()));
        let in_window = || {
            self.steps
                .iter()
                .map(|(start, dt, x)| (*start, *dt, x.as_slice()))
                .chain(finished)
                .filter(move |(start, _, _)| *start >= time_secs - window)
        };
        let covered: f64 = in_window().map(|(_, dt, _)| dt).sum();
        let Some((_, _, first)) = in_window().next() else {
            return Ok(None);
        };
        let mut mean = vec![0.0; first.len()];
        for (_, dt, x) in in_window() {
            let w = dt / covered;
            for (m, v) in mean.iter_mut().zip(x) {
                *m += w * v;
            }
        }
        Ok(Some(LiveRow {
            inputs: mean,
            covered_secs: covered,
        }))
    }

    /// Adds a sample that [`LiveRows::peek`] accepted.
    pub(crate) fn commit(&mut self, time_secs: f64, inputs: Vec<f64>) {
        let Some(window) = self.window_secs else {
            self.newest = Some((time_secs, inputs));
            return;
        };
        if let Some((start, x)) = self.newest.replace((time_secs, inputs)) {
            self.steps.push_back((start, time_secs - start, x));
        }
        while self
            .steps
            .front()
            .is_some_and(|(start, _, _)| *start < time_secs - window)
        {
            self.steps.pop_front();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_is_the_duration_weighted_mean_of_the_steps_that_start_in_the_window() {
        let mut rows = LiveRows::new(Some(1.0));
        let times = [0.0, 0.1, 0.3, 0.6, 1.0, 1.25, 1.9];
        let x = |k: usize| vec![k as f64, (k * k) as f64];
        assert_eq!(rows.push(times[0], x(0)).unwrap(), None);
        for n in 1..times.len() {
            let row = rows.push(times[n], x(n)).unwrap().unwrap();
            // Steps k < n starting at or after t_n − 1, weighted by their
            // durations, by hand.
            let (mut sum, mut weight) = ([0.0, 0.0], 0.0);
            for k in 0..n {
                if times[k] >= times[n] - 1.0 {
                    let dt = times[k + 1] - times[k];
                    sum[0] += dt * x(k)[0];
                    sum[1] += dt * x(k)[1];
                    weight += dt;
                }
            }
            assert!((row.covered_secs - weight).abs() < 1e-12, "n {n}");
            for (c, (got, s)) in row.inputs.iter().zip(sum).enumerate() {
                let want = s / weight;
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "n {n}, column {c}: {got} vs {want}"
                );
            }
        }
        // At 2 s the window starts at 1 s: the steps from 1, 1.25 and 1.9 s
        // cover it.
        assert!((rows.push(2.0, x(7)).unwrap().unwrap().covered_secs - 1.0).abs() < 1e-12);
    }

    #[test]
    fn without_a_window_a_row_is_the_sample_and_bad_samples_leave_the_stream_as_it_was() {
        let mut rows = LiveRows::new(None);
        let row = rows.push(0.5, vec![1.0, 2.0]).unwrap().unwrap();
        assert_eq!(row.inputs, vec![1.0, 2.0]);
        let e = rows.push(0.5, vec![3.0, 4.0]).unwrap_err().to_string();
        assert!(e.contains("0.5 s") && e.contains("not after"), "{e}");
        let e = rows.push(0.6, vec![3.0]).unwrap_err().to_string();
        assert!(e.contains("1 inputs, the earlier samples had 2"), "{e}");
        let e = rows.push(f64::NAN, vec![3.0, 4.0]).unwrap_err().to_string();
        assert!(e.contains("not finite"), "{e}");
        assert_eq!(
            rows.push(0.6, vec![3.0, 4.0]).unwrap().unwrap().inputs,
            vec![3.0, 4.0]
        );
    }
}
