//! Processes exactly the frames of a precomputed plan (by time stamp): the
//! offline oracle's choice, or a schedule recorded elsewhere.

use gpodo_traits::{FrameContext, FrameDecision, FrameSelector};

use super::TIME_TOLERANCE_SECS;

/// A fixed plan of frame times.
#[derive(Debug, Clone, PartialEq)]
pub struct Planned {
    times_secs: Vec<f64>,
    next: usize,
    name: String,
}

impl Planned {
    /// Processes the frames at `times_secs` (sorted on construction).
    pub fn new(name: impl Into<String>, mut times_secs: Vec<f64>) -> Self {
        times_secs.sort_by(f64::total_cmp);
        Self {
            times_secs,
            next: 0,
            name: name.into(),
        }
    }

    /// The planned times.
    pub fn times_secs(&self) -> &[f64] {
        &self.times_secs
    }
}

impl FrameSelector for Planned {
    fn name(&self) -> &str {
        &self.name
    }

    fn decide(&mut self, ctx: &FrameContext) -> FrameDecision {
        while self
            .times_secs
            .get(self.next)
            .is_some_and(|t| *t < ctx.time_secs - TIME_TOLERANCE_SECS)
        {
            self.next += 1;
        }
        match self.times_secs.get(self.next) {
            Some(t) if (t - ctx.time_secs).abs() <= TIME_TOLERANCE_SECS => {
                self.next += 1;
                FrameDecision::PROCESS
            }
            _ => FrameDecision::Skip,
        }
    }

    fn reset(&mut self) {
        self.next = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::run;
    use super::*;

    #[test]
    fn processes_exactly_the_plan() {
        let plan = vec![3.0, 0.0, 0.5, 7.2];
        let mut s = Planned::new("oracle", plan);
        let times = run(&mut s, 10.0, |_| 0.0);
        assert_eq!(times.len(), 4);
        for (a, b) in times.iter().zip([0.0, 0.5, 3.0, 7.2]) {
            assert!((a - b).abs() < 1e-9, "{times:?}");
        }
        s.reset();
        assert_eq!(run(&mut s, 1.0, |_| 0.0).len(), 2);
    }
}
