//! A rover log seen by the rendered camera: the body's true pose and its
//! motion over the exposure at any time of the log, frame times at a
//! rate, and the log's frames as a stream a bag writer records.

use nalgebra::{Isometry3, Translation3};

use super::StereoRenderer;
use gpodo_datasets::bags::write_camera::CameraStream;
use gpodo_datasets::log::RoverLog;

/// The ground-truth `world_from_body` of `log` at `time_secs`,
/// interpolated between its samples (linearly in position, by slerp in
/// rotation) and held beyond its ends; `None` for an empty log.
pub fn pose_at(log: &RoverLog, time_secs: f64) -> Option<Isometry3<f64>> {
    let samples = &log.samples;
    let k = samples.partition_point(|s| s.time_secs <= time_secs);
    let truth = &log.ground_truth;
    match k {
        0 => truth.first().copied(),
        k if k >= samples.len() => truth.last().copied(),
        k => {
            let (t0, t1) = (samples[k - 1].time_secs, samples[k].time_secs);
            let s = ((time_secs - t0) / (t1 - t0)).clamp(0.0, 1.0);
            let (a, b) = (&truth[k - 1], &truth[k]);
            let translation = a.translation.vector.lerp(&b.translation.vector, s);
            let rotation = a.rotation.slerp(&b.rotation, s);
            Some(Isometry3::from_parts(
                Translation3::from(translation),
                rotation,
            ))
        }
    }
}

/// The body's motion while a shutter of `exposure_secs` centred at
/// `time_secs` is open: `body_start_from_body_end`.
pub fn exposure_motion(log: &RoverLog, time_secs: f64, exposure_secs: f64) -> Isometry3<f64> {
    let half = 0.5 * exposure_secs;
    match (
        pose_at(log, time_secs - half),
        pose_at(log, time_secs + half),
    ) {
        (Some(start), Some(end)) => start.inverse() * end,
        _ => Isometry3::identity(),
    }
}

/// Frame times at `fps` from the log's first sample to its last.
pub fn frame_times(log: &RoverLog, fps: f64) -> Vec<f64> {
    let (Some(first), Some(last)) = (log.samples.first(), log.samples.last()) else {
        return Vec::new();
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Vec::new();
    }
    let count = ((last.time_secs - first.time_secs) * fps).floor() as usize + 1;
    (0..count)
        .map(|k| first.time_secs + k as f64 / fps)
        .collect()
}

/// The frames of `log` at `fps` through `renderer`, as a stream for
/// [`gpodo_datasets::bags::write::write_mcap_with_camera`]: frame `k`'s noise is
/// drawn from the renderer's seed and `k`.
pub fn camera_stream<'a>(
    renderer: &'a StereoRenderer<'a>,
    log: &'a RoverLog,
    fps: f64,
) -> CameraStream<'a> {
    let camera = *renderer.camera();
    CameraStream {
        camera,
        times_secs: frame_times(log, fps),
        frames: Box::new(move |k, t| {
            let pose = pose_at(log, t).unwrap_or_else(Isometry3::identity);
            let motion = exposure_motion(log, t, camera.exposure_secs);
            let frame = renderer.render(&pose, &motion, k as u64);
            Ok((frame.left, frame.right))
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gpodo_datasets::log::RoverLog;
    use gpodo_traits::ProprioceptiveSample;
    use nalgebra::Vector3;

    fn log() -> RoverLog {
        let samples: Vec<ProprioceptiveSample> = (0..3)
            .map(|k| ProprioceptiveSample {
                time_secs: k as f64,
                ..Default::default()
            })
            .collect();
        RoverLog {
            name: "t".into(),
            wheel_names: Vec::new(),
            steer_names: Vec::new(),
            bogie_names: Vec::new(),
            samples,
            ground_truth: vec![
                Isometry3::identity(),
                Isometry3::new(Vector3::new(1.0, 0.0, 0.0), Vector3::z() * 0.2),
                Isometry3::new(Vector3::new(2.0, 0.0, 0.0), Vector3::z() * 0.4),
            ],
            camera_times_secs: Vec::new(),
        }
    }

    #[test]
    fn poses_interpolate_between_samples_and_hold_beyond_the_ends() {
        let log = log();
        let mid = pose_at(&log, 0.5).unwrap();
        assert!((mid.translation.vector - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-12);
        assert!((mid.rotation.angle() - 0.1).abs() < 1e-12);
        assert_eq!(pose_at(&log, -1.0), Some(log.ground_truth[0]));
        assert_eq!(pose_at(&log, 9.0), Some(log.ground_truth[2]));
        // 0.1 s centred at 1.5 s: 0.1 m forward and 0.02 rad of yaw.
        let motion = exposure_motion(&log, 1.5, 0.1);
        assert!((motion.rotation.angle() - 0.02).abs() < 1e-12);
        assert!((motion.translation.vector.norm() - 0.1).abs() < 1e-3);
        assert_eq!(frame_times(&log, 2.5).len(), 6);
    }
}
