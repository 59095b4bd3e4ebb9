//! One role's messages as a stream on its own clock, interpolated onto the
//! common clock without bridging gaps, and the clock itself: message times
//! as seconds after a whole-second base, in integer nanoseconds.

use super::{StreamReport, TimeSource};
use crate::bags::topic::Stamped;

/// A stream on its own clock: time (s since the epoch) and values.
pub(super) struct Stream {
    pub(super) report: StreamReport,
    pub(super) times: Vec<f64>,
    pub(super) values: Vec<Vec<f64>>,
    /// Index ranges of values that are quaternions `[x, y, z, w]`.
    pub(super) quaternions: Vec<usize>,
}

impl Stream {
    pub(super) fn new(
        role: &str,
        topic: &str,
        mut samples: Vec<(f64, Vec<f64>)>,
        messages: usize,
        unusable: usize,
        quaternions: Vec<usize>,
    ) -> Self {
        let mut report = StreamReport {
            role: role.into(),
            topic: topic.into(),
            messages,
            unusable,
            ..StreamReport::default()
        };
        report.out_of_order = samples.windows(2).filter(|w| w[1].0 < w[0].0).count();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let before = samples.len();
        samples.dedup_by(|b, a| b.0 == a.0);
        report.duplicates = before - samples.len();
        let (times, values) = samples.into_iter().unzip();
        Self {
            report,
            times,
            values,
            quaternions,
        }
    }

    /// The values at `t`, interpolated between the messages around it, or
    /// `None` when they are more than `max_gap` apart (or `t` is outside).
    pub(super) fn at(&mut self, t: f64, max_gap: f64) -> Option<Vec<f64>> {
        let k = self.times.partition_point(|&s| s <= t);
        if k == 0 {
            return None;
        }
        let i = k - 1;
        if self.times[i] == t {
            return Some(self.values[i].clone());
        }
        let j = k;
        if j >= self.times.len() {
            return None;
        }
        let gap = self.times[j] - self.times[i];
        if gap > max_gap {
            self.report.rows_in_gaps += 1;
            return None;
        }
        self.report.max_gap_bridged_secs = self.report.max_gap_bridged_secs.max(gap);
        let u = (t - self.times[i]) / gap;
        let (a, b) = (&self.values[i], &self.values[j]);
        let mut v: Vec<f64> = a.iter().zip(b).map(|(a, b)| a + u * (b - a)).collect();
        for &q in &self.quaternions {
            // The shorter way round, then back onto the unit sphere.
            let dot: f64 = (0..4).map(|c| a[q + c] * b[q + c]).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            let mut n = 0.0;
            for c in 0..4 {
                v[q + c] = a[q + c] + u * (sign * b[q + c] - a[q + c]);
                n += v[q + c] * v[q + c];
            }
            let n = n.sqrt();
            for c in 0..4 {
                v[q + c] /= n;
            }
        }
        Some(v)
    }
}

/// Message times as seconds after a whole-second base near the recording's
/// start, subtracted in integer nanoseconds: seconds since the Unix epoch
/// held in an `f64` would keep only a quarter of a microsecond.
pub(super) struct Clock {
    pub(super) source: TimeSource,
    pub(super) base_ns: i64,
}

impl Clock {
    /// The clock whose base is the whole second at or before the first
    /// message's time.
    pub(super) fn new(source: TimeSource, first: Option<(&Stamped, i64)>) -> Self {
        let mut clock = Self { source, base_ns: 0 };
        if let Some((s, header_ns)) = first {
            let ns = clock.ns(s, header_ns);
            clock.base_ns = ns - ns.rem_euclid(1_000_000_000);
        }
        clock
    }

    pub(super) fn ns(&self, s: &Stamped, header_ns: i64) -> i64 {
        match self.source {
            TimeSource::Header => header_ns,
            TimeSource::Receive => i64::try_from(s.log_time_ns).unwrap_or(i64::MAX),
        }
    }

    /// Seconds after the base.
    pub(super) fn at(&self, s: &Stamped, header_ns: i64) -> f64 {
        (self.ns(s, header_ns) - self.base_ns) as f64 * 1e-9
    }
}

/// The span every stream covers, `(latest first time, earliest last
/// time)`; each stream's report says how late it starts and how early it
/// stops against the others.
pub(super) fn common_span(streams: &mut [&mut Stream]) -> (f64, f64) {
    let firsts: Vec<f64> = streams
        .iter()
        .filter_map(|s| s.times.first().copied())
        .collect();
    let lasts: Vec<f64> = streams
        .iter()
        .filter_map(|s| s.times.last().copied())
        .collect();
    let start = firsts.iter().copied().fold(f64::MIN, f64::max);
    let end = lasts.iter().copied().fold(f64::MAX, f64::min);
    let earliest = firsts.iter().copied().fold(f64::MAX, f64::min);
    let latest = lasts.iter().copied().fold(f64::MIN, f64::max);
    for s in streams.iter_mut() {
        if let (Some(first), Some(last)) = (s.times.first(), s.times.last()) {
            s.report.starts_late_secs = first - earliest;
            s.report.stops_early_secs = latest - last;
        }
    }
    (start, end)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_stops_at_gaps_and_takes_the_short_way_round() {
        let q0 = [0.0, 0.0, 0.0, 1.0];
        let q1 = [0.0, 0.0, -0.0, -1.0]; // the same rotation, other sign
        let mut s = Stream::new(
            "t",
            "/t",
            vec![
                (0.0, [vec![0.0], q0.to_vec()].concat()),
                (1.0, [vec![2.0], q1.to_vec()].concat()),
                (5.0, [vec![4.0], q0.to_vec()].concat()),
            ],
            3,
            0,
            vec![1],
        );
        let v = s.at(0.25, 1.5).unwrap();
        assert!((v[0] - 0.5).abs() < 1e-12);
        assert!(
            (v[4].abs() - 1.0).abs() < 1e-12,
            "no collapse through zero: {v:?}"
        );
        assert!(s.at(3.0, 1.5).is_none());
        assert_eq!(s.report.rows_in_gaps, 1);
        assert_eq!(s.report.max_gap_bridged_secs, 1.0);
        assert!(s.at(-1.0, 1.5).is_none() && s.at(6.0, 1.5).is_none());
    }

    #[test]
    fn a_stream_that_stops_part_way_ends_the_log_and_says_so() {
        let stream = |role: &str, from: f64, to: f64| {
            let samples = (0..=((to - from) * 10.0).round() as usize)
                .map(|k| (from + k as f64 * 0.1, vec![0.0]))
                .collect();
            Stream::new(role, "/t", samples, 0, 0, vec![])
        };
        let (mut imu, mut gt, mut odom) = (
            stream("imu", 0.0, 100.0),
            stream("ground_truth", 2.0, 100.0),
            stream("odometry", 0.0, 40.0),
        );
        let (start, end) = common_span(&mut [&mut imu, &mut gt, &mut odom]);
        assert_eq!((start, end), (2.0, 40.0));
        assert_eq!(odom.report.stops_early_secs, 60.0);
        assert_eq!(gt.report.starts_late_secs, 2.0);
        assert_eq!(
            (imu.report.starts_late_secs, imu.report.stops_early_secs),
            (0.0, 0.0)
        );
    }

    #[test]
    fn duplicates_and_out_of_order_stamps_are_counted() {
        let s = Stream::new(
            "t",
            "/t",
            vec![
                (1.0, vec![1.0]),
                (0.0, vec![0.0]),
                (1.0, vec![9.0]),
                (2.0, vec![2.0]),
            ],
            4,
            0,
            vec![],
        );
        assert_eq!((s.report.out_of_order, s.report.duplicates), (1, 1));
        assert_eq!(s.times, vec![0.0, 1.0, 2.0]);
    }
}
