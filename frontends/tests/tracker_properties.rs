//! Properties of the simulated tracker a SLAM reader expects of an
//! ORB-SLAM-class front end, checked over random motions:
//!
//! * the view overlap falls as the camera turns further or drives further;
//! * tracking success (with an exact prior, and without one) never rises
//!   as the gap to the reference keyframe grows, by turning or driving;
//! * the expected measurement error never falls as that gap grows.
//!
//! What many frames tracked against one keyframe are worth together is
//! not a property of one measurement: see `map_error.rs`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_frontends::vo::camera::CameraParams;
use gpodo_frontends::vo::{FrameRef, SimulatedVo, SimulatedVoParams, TrackPurpose, TrackRequest};
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;

const DT: f64 = 0.08;

/// A traverse of `secs` at constant body speed `v` (m/s) and yaw rate `w`
/// (rad/s), camera on every sensor sample.
fn steady(secs: f64, v: f64, w: f64) -> Traverse {
    let n = (secs / DT).round() as usize + 1;
    let times: Vec<f64> = (0..n).map(|k| k as f64 * DT).collect();
    let mut pose = Isometry3::identity();
    let step = Isometry3::from_parts(
        Translation3::new(v * DT, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, w * DT),
    );
    let gt: Vec<Isometry3<f64>> = times
        .iter()
        .map(|_| {
            let p = pose;
            pose *= step;
            p
        })
        .collect();
    let twists = vec![
        BodyTwist {
            linear_mps: Vector3::new(v, 0.0, 0.0),
            angular_radps: Vector3::new(0.0, 0.0, w),
        };
        n - 1
    ];
    let per = (1.0 / DT).round() as usize;
    let windows = (0..(n - 1) / per)
        .map(|i| TraverseWindow {
            start_secs: times[i * per],
            end_secs: times[(i + 1) * per],
            steps: i * per..(i + 1) * per,
            inputs: vec![0.0],
            true_residual: Vector3::zeros(),
        })
        .collect();
    let camera = times[..n - 1].to_vec();
    Traverse::new("steady", times, gt, twists, windows, camera).unwrap()
}

fn request(t: &Traverse, current: usize, prior: bool) -> TrackRequest {
    let frame = |index: usize| FrameRef {
        index,
        time_secs: t.camera_times_secs()[index],
    };
    let truth = t.ground_truth()[0].inverse() * t.ground_truth()[current];
    TrackRequest {
        reference: frame(0),
        current: frame(current),
        prior: prior.then_some(truth),
        purpose: TrackPurpose::Tracking,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn overlap_falls_as_the_camera_turns_or_drives_further(
        a in 0.0..1.5f64,
        b in 0.0..1.5f64,
        heading in -std::f64::consts::PI..std::f64::consts::PI,
    ) {
        let (near, far) = if a <= b { (a, b) } else { (b, a) };
        let cam = CameraParams::default();
        let turn = |yaw: f64| Isometry3::rotation(Vector3::z() * yaw);
        prop_assert!(cam.body_overlap(&turn(far)) <= cam.body_overlap(&turn(near)) + 1e-12);
        let direction = Vector3::new(heading.cos(), heading.sin(), 0.0);
        let drive = |d: f64| Isometry3::translation(d * direction.x, d * direction.y, 0.0);
        prop_assert!(cam.body_overlap(&drive(far)) <= cam.body_overlap(&drive(near)) + 1e-12);
    }

    #[test]
    fn success_never_rises_and_error_never_falls_as_the_gap_grows(
        speed in 0.0..0.1f64,
        yaw_rate in -0.3..0.3f64,
        i in 1usize..120,
        j in 1usize..120,
        seed in 0u64..1000,
    ) {
        let t = steady(12.0, speed, yaw_rate);
        let vo = SimulatedVo::new(SimulatedVoParams { seed, ..SimulatedVoParams::default() }, &t).unwrap();
        let (near, far) = if i <= j { (i, j) } else { (j, i) };
        for prior in [true, false] {
            let (p_near, o_near) = vo.success_and_overlap(&request(&t, near, prior)).unwrap();
            let (p_far, o_far) = vo.success_and_overlap(&request(&t, far, prior)).unwrap();
            prop_assert!(o_far <= o_near + 1e-12, "overlap {o_far} > {o_near}");
            prop_assert!(p_far <= p_near + 1e-12, "success {p_far} > {p_near} (prior {prior})");
        }
        let sigmas = |k: usize| {
            let truth = t.ground_truth()[0].inverse() * t.ground_truth()[k];
            let (_, overlap) = vo.success_and_overlap(&request(&t, k, true)).unwrap();
            vo.error_sigmas(&truth, overlap)
        };
        let ((r_near, t_near), (r_far, t_far)) = (sigmas(near), sigmas(far));
        prop_assert!(r_far >= r_near - 1e-15 && t_far >= t_near - 1e-15);
    }
}
