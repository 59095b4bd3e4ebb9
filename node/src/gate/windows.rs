//! The regressor windows of the offline front end, kept live: the gate's
//! predictions at window ends, each from its window's row, and a target's
//! inputs attributed once the windows its interval spans have closed.
//!
//! Offline (`gpodo_datasets::residuals::window_rows`), windows are a grid
//! of `window_secs` from the first sample; a step belongs to the window it
//! starts in, weighs its duration, and a window whose steps cover less than
//! half its length is dropped. The front end drives each step with its
//! window's mean inputs and puts the window's prediction in force at the
//! window's end. Live, a window's row is known once its last step has
//! ended, so the gate is driven without inputs, and a target's inputs are
//! the duration-weighted mean, over the stretches driven in its interval,
//! of the inputs of the windows they belong to, attributed when the last
//! of those windows closes.

use std::collections::{BTreeMap, VecDeque};

/// A window the gate has reached the end of.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedWindow {
    /// Its end (s), where its prediction is put in force.
    pub end_secs: f64,
    /// Its duration-weighted mean inputs (`None`: its steps covered less
    /// than half of it, so it has no row).
    pub row: Option<Vec<f64>>,
}

/// The grid of windows over a stream of steps.
#[derive(Debug, Clone)]
pub struct GridWindows {
    window_secs: f64,
    /// The first sample's time: the grid's origin.
    origin_secs: Option<f64>,
    /// Per window not yet closed, its steps: duration and inputs.
    open: BTreeMap<i64, Vec<(f64, Vec<f64>)>>,
    /// Closed windows' rows, while a stretch driven in them may still be
    /// part of a target.
    rows: BTreeMap<i64, Option<Vec<f64>>>,
    /// The stretches driven, oldest first: start, end, their step's window.
    stretches: VecDeque<(f64, f64, i64)>,
}

impl GridWindows {
    /// Windows of `window_secs`.
    pub fn new(window_secs: f64) -> Self {
        Self {
            window_secs,
            origin_secs: None,
            open: BTreeMap::new(),
            rows: BTreeMap::new(),
            stretches: VecDeque::new(),
        }
    }

    /// The window a step starting at `time_secs` belongs to (the first
    /// sample's time is the grid's origin).
    pub fn index_at(&mut self, time_secs: f64) -> i64 {
        let origin = *self.origin_secs.get_or_insert(time_secs);
        ((time_secs - origin) / self.window_secs).floor() as i64
    }

    /// The end of window `index` (s).
    fn end_of(&self, index: i64) -> f64 {
        self.origin_secs.unwrap_or(0.0) + (index as f64 + 1.0) * self.window_secs
    }

    /// A step starting at `start_secs`, lasting `dt_secs`, with the inputs
    /// of its first sample; returns its window.
    pub fn step(&mut self, start_secs: f64, dt_secs: f64, inputs: Vec<f64>) -> i64 {
        let index = self.index_at(start_secs);
        self.open.entry(index).or_default().push((dt_secs, inputs));
        index
    }

    /// The end of the oldest window not yet closed, if any.
    pub fn next_end(&self) -> Option<f64> {
        self.open.keys().next().map(|&w| self.end_of(w))
    }

    /// Closes the oldest window not yet closed, if it ends at or before
    /// `time_secs`.
    pub fn close_until(&mut self, time_secs: f64) -> Option<ClosedWindow> {
        let (&index, _) = self.open.iter().next()?;
        let end_secs = self.end_of(index);
        if end_secs > time_secs {
            return None;
        }
        let steps = self.open.remove(&index).unwrap_or_default();
        let covered: f64 = steps.iter().map(|(dt, _)| dt).sum();
        let row = (covered >= 0.5 * self.window_secs).then(|| {
            let mut x = vec![0.0; steps[0].1.len()];
            for (dt, inputs) in &steps {
                let w = dt / covered;
                for (acc, v) in x.iter_mut().zip(inputs) {
                    *acc += w * v;
                }
            }
            x
        });
        self.rows.insert(index, row.clone());
        Some(ClosedWindow { end_secs, row })
    }

    /// Closes every window still open, whatever its end (the stream has
    /// ended); the rows of those that have one.
    pub fn close_all(&mut self) -> Vec<ClosedWindow> {
        std::iter::from_fn(|| self.close_until(f64::INFINITY)).collect()
    }

    /// The gate drove from `start_secs` to `end_secs` within a step of
    /// window `index`.
    pub fn driven(&mut self, start_secs: f64, end_secs: f64, index: i64) {
        if end_secs > start_secs {
            self.stretches.push_back((start_secs, end_secs, index));
        }
    }

    /// The inputs of the interval from `start_secs` to `end_secs`: `None`
    /// while a window it spans is open; then the duration-weighted mean
    /// over its stretches of their windows' rows, `Some(None)` when none
    /// of them has a row.
    pub fn inputs_over(&self, start_secs: f64, end_secs: f64) -> Option<Option<Vec<f64>>> {
        let mut sum: Vec<f64> = Vec::new();
        let mut secs = 0.0;
        for &(a, b, index) in &self.stretches {
            let (a, b) = (a.max(start_secs), b.min(end_secs));
            if b <= a {
                continue;
            }
            let row = self.rows.get(&index)?;
            if let Some(row) = row {
                if sum.len() != row.len() {
                    sum = vec![0.0; row.len()];
                }
                for (acc, v) in sum.iter_mut().zip(row) {
                    *acc += v * (b - a);
                }
                secs += b - a;
            }
        }
        Some((secs > 0.0).then(|| sum.iter().map(|v| v / secs).collect()))
    }

    /// Forgets the stretches ending before `time_secs`, and the rows no
    /// stretch left belongs to.
    pub fn forget_before(&mut self, time_secs: f64) {
        while self.stretches.front().is_some_and(|s| s.1 < time_secs) {
            self.stretches.pop_front();
        }
        let oldest = self.stretches.front().map(|s| s.2);
        self.rows
            .retain(|&index, _| oldest.is_some_and(|oldest| index >= oldest));
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn a_window_closes_at_its_end_with_its_duration_weighted_row() {
        let mut g = GridWindows::new(1.0);
        // Steps of 0.3 s from 10 s: 10.0, 10.3, 10.6, 10.9 start in the
        // first window (the last ends at 11.2), 11.2 in the second.
        for (k, x) in [1.0, 2.0, 3.0, 4.0, 5.0].iter().enumerate() {
            let index = g.step(10.0 + 0.3 * k as f64, 0.3, vec![*x]);
            assert_eq!(index, i64::from(k >= 4));
        }
        assert_eq!(g.next_end(), Some(11.0));
        assert!(g.close_until(10.99).is_none());
        let w = g.close_until(11.0).unwrap();
        assert_eq!(w.end_secs, 11.0);
        assert!((w.row.unwrap()[0] - 2.5).abs() < 1e-15);
        // 0.3 s of a 1-s window: less than half, no row.
        let w = g.close_until(12.0).unwrap();
        assert_eq!(w.row, None);
        assert!(g.close_until(100.0).is_none());
    }

    #[test]
    fn a_targets_inputs_wait_for_its_windows_and_weigh_the_stretches() {
        let mut g = GridWindows::new(1.0);
        let a = g.step(0.0, 0.9, vec![2.0]);
        let b = g.step(0.9, 0.6, vec![4.0]);
        let c = g.step(1.5, 0.6, vec![8.0]);
        // The step from 0.9 to 1.5 is the first window's: 0.9·2 + 0.6·4
        // over 1.5 s. The step from 1.5 is the second's.
        assert_eq!((a, b, c), (0, 0, 1));
        g.driven(0.0, 0.9, a);
        g.driven(0.9, 1.0, b);
        g.driven(1.0, 1.5, b);
        g.driven(1.5, 1.8, c);
        assert_eq!(g.inputs_over(0.5, 1.8), None, "no window has closed");
        g.close_until(1.0).unwrap();
        assert_eq!(g.inputs_over(0.5, 1.8), None, "the second is open");
        let first = (0.9 * 2.0 + 0.6 * 4.0) / 1.5;
        let only_first = g.inputs_over(0.5, 1.5).unwrap().unwrap();
        assert!((only_first[0] - first).abs() < 1e-15);
        g.close_until(2.0).unwrap();
        let both = g.inputs_over(0.5, 1.8).unwrap().unwrap();
        assert!((both[0] - (first * 1.0 + 8.0 * 0.3) / 1.3).abs() < 1e-14);
        g.forget_before(1.2);
        assert_eq!(g.stretches.len(), 2);
        assert_eq!(g.rows.len(), 2);
        g.forget_before(1.9);
        assert!(g.stretches.is_empty() && g.rows.is_empty());
    }
}
