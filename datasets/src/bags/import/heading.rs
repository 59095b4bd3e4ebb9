//! The heading of a GNSS ground truth: a fix has a position, not an
//! orientation, so the yaw comes from the course over ground (turned by π
//! where the robot reverses), and from the IMU's yaw, less its mean offset
//! to the course, where the track says nothing.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Isometry3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use gpodo_traits::ProprioceptiveSample;

/// Where the heading of a GNSS ground truth comes from (a fix has a
/// position, not an orientation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GnssHeading {
    /// The course over ground: the direction of the GNSS track over
    /// [`COURSE_WINDOW_SECS`] about each row, where the robot moves faster
    /// than [`COURSE_MIN_SPEED_MPS`], turned by π where the robot drives
    /// backwards (decided against the IMU's yaw); elsewhere the IMU's yaw
    /// with its mean offset to the course removed. Roll and pitch from the
    /// IMU. Lateral velocity is then zero by construction while moving.
    #[default]
    Course,
    /// The IMU's orientation as it is (right only when its yaw is
    /// referenced to east-north-up, as an INS's is; most IMUs' yaw is not).
    Imu,
}

/// Course over ground is taken over this window about each row (s).
pub const COURSE_WINDOW_SECS: f64 = 2.0;
/// Below this ground speed the GNSS course is not used (m/s).
pub const COURSE_MIN_SPEED_MPS: f64 = 0.3;

/// How the heading of a GNSS ground truth was made ([`GnssHeading::Course`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeadingReport {
    /// Rows whose heading is the course over ground.
    pub rows_from_course: usize,
    /// Of those, rows driven backwards (course turned by π).
    pub rows_reversed: usize,
    /// Mean offset course − IMU yaw (deg), removed from the IMU's yaw on
    /// the other rows.
    pub imu_offset_deg: f64,
    /// 10th and 90th percentiles of course − IMU yaw − offset (deg): how far
    /// the IMU's yaw wanders from the track.
    pub imu_spread_deg: [f64; 2],
}

impl std::fmt::Display for HeadingReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "GNSS heading: course over ground on {} rows ({} driven backwards), elsewhere \
             the IMU yaw {:+.1}°; course − IMU yaw spans {:+.1}° to {:+.1}° (10–90 %)",
            self.rows_from_course,
            self.rows_reversed,
            self.imu_offset_deg,
            self.imu_spread_deg[0],
            self.imu_spread_deg[1]
        )
    }
}

/// The smallest signed angle equal to `a` modulo 2π.
fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Replaces the yaw of GNSS ground-truth poses (which hold the IMU's
/// orientation) by the course over ground, as [`GnssHeading::Course`] says.
pub(super) fn course_headings(
    samples: &[ProprioceptiveSample],
    ground_truth: &mut [Isometry3<f64>],
) -> HeadingReport {
    let times: Vec<f64> = samples.iter().map(|s| s.time_secs).collect();
    let half = 0.5 * COURSE_WINDOW_SECS;
    let imu_yaw: Vec<f64> = ground_truth
        .iter()
        .map(|p| p.rotation.euler_angles().2)
        .collect();
    // Course where the track over the window is long enough to have one.
    let course: Vec<Option<f64>> = (0..times.len())
        .map(|k| {
            let j = times.partition_point(|&t| t < times[k] - half);
            let l = times.partition_point(|&t| t <= times[k] + half) - 1;
            let span = times[l] - times[j];
            if span < half {
                return None;
            }
            let d = ground_truth[l].translation.vector - ground_truth[j].translation.vector;
            (d.xy().norm() / span >= COURSE_MIN_SPEED_MPS).then(|| d.y.atan2(d.x))
        })
        .collect();
    let diffs: Vec<f64> = course
        .iter()
        .zip(&imu_yaw)
        .filter_map(|(c, y)| c.map(|c| wrap(c - y)))
        .collect();
    // The offset modulo π from the doubled angles (forward and backward
    // driving agree there), then the half turn most rows agree with.
    let (s2, c2) = diffs.iter().fold((0.0, 0.0), |(s, c), d| {
        (s + (2.0 * d).sin(), c + (2.0 * d).cos())
    });
    let mut offset = 0.5 * s2.atan2(c2);
    let forward = diffs
        .iter()
        .filter(|d| wrap(*d - offset).abs() < FRAC_PI_2)
        .count();
    if 2 * forward < diffs.len() {
        offset = wrap(offset + PI);
    }
    let mut reversed = 0;
    let mut spread = Vec::with_capacity(diffs.len());
    for (k, pose) in ground_truth.iter_mut().enumerate() {
        let expected = imu_yaw[k] + offset;
        let heading = match course[k] {
            Some(c) => {
                let mut d = wrap(c - expected);
                let mut c = c;
                if d.abs() > FRAC_PI_2 {
                    reversed += 1;
                    c = wrap(c + PI);
                    d = wrap(c - expected);
                }
                spread.push(d);
                c
            }
            None => expected,
        };
        let (roll, pitch) = samples[k].roll_pitch_rad();
        pose.rotation = UnitQuaternion::from_euler_angles(roll, pitch, heading);
    }
    spread.sort_by(f64::total_cmp);
    let quantile = |q: f64| {
        if spread.is_empty() {
            0.0
        } else {
            spread[((spread.len() - 1) as f64 * q).round() as usize].to_degrees()
        }
    };
    HeadingReport {
        rows_from_course: spread.len(),
        rows_reversed: reversed,
        imu_offset_deg: offset.to_degrees(),
        imu_spread_deg: [quantile(0.1), quantile(0.9)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Translation3;

    #[test]
    fn gnss_heading_is_the_course_turned_for_reversing_and_the_imu_offset_is_removed() {
        // 40 s north at 1 m/s facing north, then 20 s south still facing
        // north (reversing), at 10 Hz; the IMU's yaw reads 40° less than
        // the true heading (90°), and its roll and pitch are kept.
        let (roll, pitch) = (0.01, -0.02);
        let mut samples = Vec::new();
        let mut ground_truth = Vec::new();
        for k in 0..=600 {
            let t = k as f64 * 0.1;
            let y = if t <= 40.0 { t } else { 80.0 - t };
            let mut s = ProprioceptiveSample {
                time_secs: t,
                ..Default::default()
            };
            s.imu.get_or_insert_default().roll_rad = roll;
            s.imu.get_or_insert_default().pitch_rad = pitch;
            samples.push(s);
            let imu = UnitQuaternion::from_euler_angles(roll, pitch, 50f64.to_radians());
            ground_truth.push(Isometry3::from_parts(Translation3::new(0.0, y, 0.0), imu));
        }
        let report = course_headings(&samples, &mut ground_truth);
        assert!((report.imu_offset_deg - 40.0).abs() < 1e-9, "{report:?}");
        // Rows within a second of the turn have too short a net track.
        assert!(report.rows_from_course > 570, "{report:?}");
        assert!((190..=200).contains(&report.rows_reversed), "{report:?}");
        for pose in &ground_truth {
            let (r, p, yaw) = pose.rotation.euler_angles();
            assert!((r - roll).abs() < 1e-12 && (p - pitch).abs() < 1e-12);
            assert!((yaw - FRAC_PI_2).abs() < 1e-9, "{}", yaw.to_degrees());
        }
    }
}
