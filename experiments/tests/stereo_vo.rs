//! The stereo VO on rendered sequences of ExoTeR's mast camera at
//! 512 × 384, against ground truth: relative pose errors at three gaps
//! (and a 20 % scale error that the bound catches), loss of track that
//! comes from the images (longer gaps, turning in place), fewer inliers on
//! loose sand than on gravel and under motion blur, and the same numbers
//! from run to run and at any thread count.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;

use gpodo_frontends::vo::stereo::{
    LocalMapPlacement, OverlapDenominator, StereoFrames, StereoVo, StereoVoParams,
};
use gpodo_frontends::vo::{
    FrameRef, TrackOutcome, TrackPurpose, TrackRequest, VisualOdometry, VoMeasurement,
};
use gpodo_testbed::camera::{FramePose, RenderedFrames};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector6};

const FPS: f64 = 2.5;

/// Poses at `FPS` along an arc at `speed` (m/s) turning at `turn`
/// (rad/s), from (1.5, 3) on a flat 9 × 9 m patch, heading +x.
fn drive(frames: usize, speed: f64, turn: f64) -> Vec<FramePose> {
    (0..frames)
        .map(|k| {
            let t = k as f64 / FPS;
            let yaw = turn * t;
            let (x, y) = if turn.abs() < 1e-12 {
                (speed * t, 0.0)
            } else {
                (speed / turn * yaw.sin(), speed / turn * (1.0 - yaw.cos()))
            };
            FramePose {
                world_from_body: Isometry3::from_parts(
                    Translation3::new(1.5 + x, 3.0 + y, 0.25),
                    UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
                ),
                exposure_motion: Isometry3::identity(),
            }
        })
        .collect()
}

fn vo(soil: Soil, poses: &[FramePose]) -> StereoVo {
    vo_with(soil, poses, StereoVoParams::default())
}

fn vo_with(soil: Soil, poses: &[FramePose], params: StereoVoParams) -> StereoVo {
    let frames = frames(soil, poses, &params);
    StereoVo::new(params, frames).unwrap()
}

/// The rendered frames at `poses` with `params`' ORB settings, to share
/// between VOs.
fn frames(soil: Soil, poses: &[FramePose], params: &StereoVoParams) -> Arc<StereoFrames> {
    let ground = GroundMaps::build(
        &Terrain::flat(9.0).unwrap(),
        &SoilMap::uniform(soil, 9.0).unwrap(),
        &SceneSpec::default(),
        11,
    )
    .unwrap();
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let source = RenderedFrames::new(
        Arc::new(ground),
        camera,
        SensorSpec::default(),
        11,
        poses.to_vec(),
    );
    let orb = params.orb(&camera);
    // The true poses, for the local map's ground-truth placement control.
    let true_poses = source.true_camera_poses();
    Arc::new(
        StereoFrames::with_orb(camera, Arc::new(source), orb).with_true_camera_poses(true_poses),
    )
}

fn frame(k: usize) -> FrameRef {
    FrameRef {
        index: k,
        time_secs: k as f64 / FPS,
    }
}

/// Tracks frame `k + gap` against frame `k` with a wheel-odometry-like
/// prior (5 % short, 0.2° off in yaw).
fn track(vo: &mut StereoVo, poses: &[FramePose], k: usize, gap: usize) -> TrackOutcome {
    let truth = truth(poses, k, gap);
    let prior = Isometry3::from_parts(
        Translation3::from(truth.translation.vector * 0.95),
        truth.rotation * UnitQuaternion::from_euler_angles(0.0, 0.0, 0.0035),
    );
    vo.track(&TrackRequest {
        reference: frame(k),
        current: frame(k + gap),
        prior: Some(prior),
        purpose: TrackPurpose::Tracking,
    })
}

fn truth(poses: &[FramePose], k: usize, gap: usize) -> Isometry3<f64> {
    poses[k].world_from_body.inverse() * poses[k + gap].world_from_body
}

/// `(δ_rotation, δ_translation)` with `truth = estimate · Exp(δ)`.
fn error(estimate: &Isometry3<f64>, truth: &Isometry3<f64>) -> Vector6<f64> {
    let d = estimate.inverse() * truth;
    let r = d.rotation.scaled_axis();
    let t = d.translation.vector;
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The bound a gap's median errors are held to: translation within
/// `max(t_floor, 3 %)` of the median displacement, rotation within
/// `r_limit` degrees.
fn within_bound(
    (translation_m, rotation_deg): (f64, f64),
    displacement_m: f64,
    (t_floor, r_limit): (f64, f64),
) -> bool {
    translation_m <= t_floor.max(0.03 * displacement_m) && rotation_deg <= r_limit
}

/// Median errors at gaps of 0.4, 2 and 4.8 s within `bound` (and a 20 %
/// scale error outside it), the NEES printed.
fn check_relative_poses(label: &str, params: StereoVoParams, bound: (f64, f64)) {
    let poses = drive(220, 0.03, 0.01);
    let mut vo = vo_with(Soil::compact(), &poses, params);
    for gap in [1usize, 5, 12] {
        let pairs = poses.len() - gap;
        let mut rows: Vec<(VoMeasurement, Isometry3<f64>)> = Vec::new();
        for k in 0..pairs {
            if let TrackOutcome::Tracked(m) = track(&mut vo, &poses, k, gap) {
                rows.push((m, truth(&poses, k, gap)));
            }
        }
        assert!(
            rows.len() >= 200,
            "{label}, gap {gap}: {} of {pairs} tracked",
            rows.len()
        );
        let medians = |scale: f64| {
            let errors: Vec<Vector6<f64>> = rows
                .iter()
                .map(|(m, t)| {
                    let scaled = Isometry3::from_parts(
                        Translation3::from(m.relative.translation.vector * scale),
                        m.relative.rotation,
                    );
                    error(&scaled, t)
                })
                .collect();
            (
                median(errors.iter().map(|e| e.fixed_rows::<3>(3).norm()).collect()),
                median(
                    errors
                        .iter()
                        .map(|e| e.fixed_rows::<3>(0).norm().to_degrees())
                        .collect(),
                ),
            )
        };
        let (t, r) = medians(1.0);
        let d = median(
            rows.iter()
                .map(|(_, t)| t.translation.vector.norm())
                .collect(),
        );
        let nees: Vec<f64> = rows
            .iter()
            .map(|(m, t)| {
                let e = error(&m.relative, t);
                (e.transpose() * m.covariance.try_inverse().unwrap() * e)[0]
            })
            .collect();
        eprintln!(
            "{label}, gap {:.1} s: {} of {pairs} tracked; median errors {:.3} mm of {:.1} mm and {:.4}°; overlap {:.2}; NEES mean {:.1}, median {:.1}",
            gap as f64 / FPS,
            rows.len(),
            t * 1e3,
            d * 1e3,
            r,
            median(rows.iter().map(|(m, _)| m.overlap).collect()),
            nees.iter().sum::<f64>() / nees.len() as f64,
            median(nees.clone()),
        );
        assert!(
            within_bound((t, r), d, bound),
            "{label}, gap {gap}: {t} m, {r}° of {d} m"
        );
        // The bound has the power to see a 20 % scale error.
        assert!(
            !within_bound(medians(1.2), d, bound),
            "{label}, gap {gap}: a 20 % scale error passes"
        );
    }
}

#[test]
fn relative_poses_on_compact_soil_are_within_two_millimetres_or_three_percent() {
    // ExoTeR's ORB settings: 750 features at 512 × 384, FAST 20 then 7.
    check_relative_poses("ExoTeR's ORB", StereoVoParams::default(), (0.002, 0.1));
    // Strong corners only, up to 1500: the weak corners of the second
    // threshold are what costs the default its accuracy.
    let strong = StereoVoParams {
        features: Some(1500),
        fast_min_threshold: 20,
        ..StereoVoParams::default()
    };
    check_relative_poses("strong corners", strong, (0.0015, 0.04));
}

/// The share of `pairs` starting frames whose frame `gap` later is lost.
fn lost_share(vo: &mut StereoVo, poses: &[FramePose], gap: usize, pairs: usize) -> f64 {
    let lost = (0..pairs)
        .filter(|&k| matches!(track(vo, poses, k, gap), TrackOutcome::Lost))
        .count();
    lost as f64 / pairs as f64
}

#[test]
fn tracks_are_lost_more_often_with_longer_gaps_and_turning_in_place() {
    // Turning in place at 0.15 rad/s: frames 0.4 s apart share most of the
    // view, frames 4 s apart (34°) about half of the 63° field of view,
    // frames 8 s apart (69°) none.
    let turning = drive(60, 0.0, 0.15);
    let mut vo = vo(Soil::gravel(), &turning);
    let shares: Vec<f64> = [1usize, 10, 20]
        .iter()
        .map(|&gap| lost_share(&mut vo, &turning, gap, 30))
        .collect();
    eprintln!("turning in place, lost at gaps 0.4, 4, 8 s: {shares:?}");
    assert!(shares[0] < 0.1, "{shares:?}");
    assert!(
        shares[0] <= shares[1] && shares[1] <= shares[2],
        "{shares:?}"
    );
    assert!(shares[2] > 0.9, "{shares:?}");
    // Driving straight at 0.1 m/s, 0.4 s to 20 s apart (2 m: the near
    // ground has left the view).
    let straight = drive(80, 0.1, 0.0);
    let mut vo = self::vo(Soil::compact(), &straight);
    let shares: Vec<f64> = [1usize, 10, 30, 50]
        .iter()
        .map(|&gap| lost_share(&mut vo, &straight, gap, 30))
        .collect();
    eprintln!("straight at 0.1 m/s, lost at gaps 0.4, 4, 12, 20 s: {shares:?}");
    assert!(shares.windows(2).all(|w| w[0] <= w[1]), "{shares:?}");
    assert!(shares[3] > shares[0], "{shares:?}");
}

/// The median number of map points found again (inliers) in the next
/// frame (0 when lost).
fn median_inliers(vo: &mut StereoVo, poses: &[FramePose]) -> f64 {
    let found: Vec<f64> = (0..poses.len() - 1)
        .map(|k| match track(vo, poses, k, 1) {
            TrackOutcome::Tracked(_) => vo.tracked_inliers(frame(k + 1)).unwrap() as f64,
            TrackOutcome::Lost => 0.0,
        })
        .collect();
    median(found)
}

#[test]
fn loose_sand_and_blur_leave_fewer_inliers_than_gravel_and_a_still_camera() {
    let poses = drive(10, 0.03, 0.01);
    let sand = median_inliers(&mut vo(Soil::loose_sand(), &poses), &poses);
    let gravel = median_inliers(&mut vo(Soil::gravel(), &poses), &poses);
    // The same drive with the mast turning at 3 rad/s while a 10 ms
    // shutter is open: a smear of about 13 px at 512 × 384.
    let blurred: Vec<FramePose> = poses
        .iter()
        .map(|p| FramePose {
            exposure_motion: Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_euler_angles(0.0, 0.0, 0.03),
            ),
            ..*p
        })
        .collect();
    let smeared = median_inliers(&mut vo(Soil::gravel(), &blurred), &blurred);
    eprintln!("inliers: loose sand {sand:.0}, gravel {gravel:.0}, gravel blurred {smeared:.0}");
    assert!(sand < gravel, "sand {sand}, gravel {gravel}");
    assert!(smeared < gravel, "blurred {smeared}, sharp {gravel}");
}

#[test]
fn the_same_frames_give_the_same_numbers_at_any_thread_count() {
    let poses = drive(6, 0.03, 0.01);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut vo = vo(Soil::compact(), &poses);
            (0..5)
                .map(|k| match track(&mut vo, &poses, k, 1) {
                    TrackOutcome::Tracked(m) => Some((m.relative, m.covariance, m.overlap)),
                    TrackOutcome::Lost => None,
                })
                .collect::<Vec<_>>()
        })
    };
    let one = run(1);
    assert!(one.iter().all(Option::is_some));
    assert_eq!(one, run(2));
    assert_eq!(one, run(2));
}

/// Pooled correlation of paired error components, each series centred.
fn correlation(pairs: &[(f64, f64)]) -> f64 {
    let n = pairs.len() as f64;
    let (ma, mb) = (
        pairs.iter().map(|p| p.0).sum::<f64>() / n,
        pairs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (a, b) in pairs {
        ab += (a - ma) * (b - mb);
        aa += (a - ma) * (a - ma);
        bb += (b - mb) * (b - mb);
    }
    ab / (aa * bb).sqrt()
}

#[test]
fn frames_tracked_against_one_keyframe_share_its_map_error() {
    // Keyframes every 6 frames; each tracked by the 5 frames after it
    // (0.4 to 2 s). The statistical tracker's `map_error_share` is the
    // correlation of two such frames' errors; frames of different
    // keyframes (disjoint frames) are the control.
    let poses = drive(220, 0.03, 0.01);
    let mut vo = vo(Soil::compact(), &poses);
    let keyframes: Vec<usize> = (0..poses.len() - 6).step_by(6).collect();
    let errors: Vec<Vec<Vector6<f64>>> = keyframes
        .iter()
        .map(|&k| {
            (1..=5)
                .filter_map(|g| match track(&mut vo, &poses, k, g) {
                    TrackOutcome::Tracked(m) => Some(error(&m.relative, &truth(&poses, k, g))),
                    TrackOutcome::Lost => None,
                })
                .collect()
        })
        .collect();
    let mut report = Vec::new();
    for (name, range) in [("rotation", 0..3), ("translation", 3..6)] {
        let (mut same, mut other) = (Vec::new(), Vec::new());
        for (i, e) in errors.iter().enumerate() {
            for a in 0..e.len() {
                for b in a + 1..e.len() {
                    for c in range.clone() {
                        same.push((e[a][c], e[b][c]));
                    }
                }
                if let Some(next) = errors.get(i + 1) {
                    for f in next {
                        for c in range.clone() {
                            other.push((e[a][c], f[c]));
                        }
                    }
                }
            }
        }
        let (rho, control) = (correlation(&same), correlation(&other));
        report.push(format!("{name}: {rho:.2} (control {control:.2})"));
        assert!(rho > control + 0.1, "{name}: {rho} against {control}");
    }
    eprintln!(
        "map-error share, one keyframe's frames: {}",
        report.join("; ")
    );
}

#[test]
fn the_keyframe_ratio_falls_below_three_quarters_as_tracked_points_are_lost() {
    // ExoTeR's drive (3 cm/s, a slow turn) on compact soil at 2.5 fps:
    // frames 0.4 to 20 s after frame 0 tracked against it in turn.
    // ORB-SLAM2 (stereo) inserts a keyframe when the inliers fall below
    // 0.75 of the reference's points seen again.
    let poses = drive(51, 0.03, 0.01);
    let mut vo = vo(Soil::compact(), &poses);
    let gaps = [1usize, 5, 12, 25, 50];
    let mut inliers = Vec::new();
    let ratios: Vec<f64> = gaps
        .iter()
        .map(|&gap| match track(&mut vo, &poses, 0, gap) {
            TrackOutcome::Tracked(m) => {
                inliers.push(vo.tracked_inliers(frame(gap)).unwrap());
                m.overlap
            }
            TrackOutcome::Lost => {
                inliers.push(0);
                0.0
            }
        })
        .collect();
    eprintln!("inliers at 0.4, 2, 4.8, 10, 20 s: {inliers:?}; keyframe ratio {ratios:.2?}");
    // The first frame tracked against a keyframe scores 1; each later one
    // its inliers over the most any frame had.
    assert_eq!(ratios[0], 1.0);
    let most = *inliers.iter().max().unwrap();
    for (r, n) in ratios.iter().zip(&inliers).skip(1) {
        assert!(
            (r - *n as f64 / most as f64).abs() < 1e-12,
            "{ratios:?} {inliers:?}"
        );
    }
    // A frame 20 s (0.6 m) later asks for a keyframe; the ratio never
    // rises with the gap by more than draw-to-draw noise.
    assert!(ratios[4] < 0.75, "{ratios:?}");
    assert!(ratios.windows(2).all(|w| w[1] <= w[0] + 0.05), "{ratios:?}");
}

#[test]
fn tracking_the_local_map_finds_the_older_keyframes_points_again() {
    // The drive above: frame 12 (4.8 s), tracked against frame 0, is the
    // reference of frames 13 to 50, which are tracked against its points
    // alone and with frame 0's as a local map (ORB-SLAM2's
    // `TrackLocalMap`). Frame 0's points reach the current frame only
    // through the pose chain 0 → 12 → current: a wrong link would place
    // them where no keypoint matches them.
    let poses = drive(51, 0.03, 0.01);
    let params = StereoVoParams::default();
    let shared = frames(Soil::compact(), &poses, &params);
    let gaps = [1usize, 5, 12, 25, 38];
    let run = |local_map_keyframes: usize| {
        let params = StereoVoParams {
            local_map_keyframes,
            ..params.clone()
        };
        let mut vo = StereoVo::new(params, Arc::clone(&shared)).unwrap();
        assert!(matches!(
            track(&mut vo, &poses, 0, 12),
            TrackOutcome::Tracked(_)
        ));
        gaps.iter()
            .map(|&gap| match track(&mut vo, &poses, 12, gap) {
                TrackOutcome::Tracked(m) => {
                    let e = error(&m.relative, &truth(&poses, 12, gap));
                    (
                        vo.tracked_inliers(frame(12 + gap)).unwrap(),
                        m.overlap,
                        Vector6::new(0.0, 0.0, 0.0, e[3], e[4], e[5]).norm(),
                    )
                }
                TrackOutcome::Lost => panic!("lost at gap {gap}"),
            })
            .collect::<Vec<(usize, f64, f64)>>()
    };
    let (alone, local) = (run(0), run(1));
    eprintln!("reference only (inliers, ratio, error m): {alone:.4?}");
    eprintln!("with the local map: {local:.4?}");
    // More inliers at every gap, 20 more a frame on average; the keyframe
    // ratio higher at 2 and 4.8 s, before either falls below 0.75.
    for (a, l) in alone.iter().zip(&local) {
        assert!(l.0 >= a.0, "{alone:?} {local:?}");
    }
    let gained: usize = alone.iter().zip(&local).map(|(a, l)| l.0 - a.0).sum();
    assert!(gained >= 20 * gaps.len(), "{alone:?} {local:?}");
    for g in [1, 2] {
        assert!(local[g].1 > alone[g].1, "{alone:?} {local:?}");
    }
    // The older points are placed right: the poses err by millimetres as
    // the reference's alone do.
    let mean_error = |r: &[(usize, f64, f64)]| r.iter().map(|e| e.2).sum::<f64>() / r.len() as f64;
    assert!(
        mean_error(&local) < 1.5 * mean_error(&alone),
        "{alone:?} {local:?}"
    );
}

#[test]
fn the_local_maps_older_keyframes_are_placed_by_a_chain_that_drifts() {
    // Keyframes every 12 frames (4.8 s) along the drive, each tracked
    // against the one before; the local map of the last places the ten
    // before it by chaining those relative poses. Each link's error adds
    // to the chain's, so the older keyframes' points are placed worse, and
    // their error enters the pose refined on them. The control that sees
    // ground truth places them exactly.
    let poses = drive(121, 0.03, 0.01);
    let shared = frames(Soil::compact(), &poses, &StereoVoParams::default());
    let local_map = |local_map_placement| {
        let params = StereoVoParams {
            local_map_keyframes: 10,
            local_map_placement,
            ..StereoVoParams::default()
        };
        let mut vo = StereoVo::new(params, Arc::clone(&shared)).unwrap();
        for k in (0..120).step_by(12) {
            assert!(matches!(
                track(&mut vo, &poses, k, 12),
                TrackOutcome::Tracked(_)
            ));
        }
        vo.local_keyframes(frame(120))
    };
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let body_from_camera = camera.body_from_camera();
    // Where a local map puts each keyframe's camera against where it was:
    // its error, and a point 2 m ahead of it seen from the reference.
    let errors = |keyframes: &[(FrameRef, Isometry3<f64>)]| -> Vec<(f64, f64)> {
        assert_eq!(keyframes.len(), 10);
        keyframes
            .iter()
            .map(|(keyframe, reference_from_keyframe)| {
                let truth = (poses[120].world_from_body * body_from_camera).inverse()
                    * poses[keyframe.index].world_from_body
                    * body_from_camera;
                let d = reference_from_keyframe.inverse() * truth;
                let ahead = nalgebra::Point3::new(0.0, 0.0, 2.0);
                let shift = (reference_from_keyframe * ahead - truth * ahead).norm();
                (d.rotation.angle().to_degrees(), shift)
            })
            .collect()
    };
    let chained = errors(&local_map(LocalMapPlacement::Chained));
    eprintln!(
        "chained keyframes, nearest first (rotation error °, a point 2 m ahead off by m): {chained:.4?}"
    );
    // The chain's error grows with its length: the five oldest keyframes
    // are placed worse than the five nearest.
    let mean = |e: &[(f64, f64)]| e.iter().map(|e| e.1).sum::<f64>() / e.len() as f64;
    assert!(mean(&chained[5..]) > mean(&chained[..5]), "{chained:?}");
    for (_, shift) in errors(&local_map(LocalMapPlacement::GroundTruth)) {
        assert!(shift < 1e-9, "{shift}");
    }
}

#[test]
fn the_shared_points_are_the_references_points_the_keyframe_behind_it_sees() {
    // ORB-SLAM2's keyframe rule divides a frame's inliers by the reference
    // keyframe's points that a second keyframe sees too. Frame `gap`,
    // tracked against keyframe 0, counts those keyframe 0 sees: fewer the
    // farther it has driven, about as many as keyframe 0's points it
    // tracked. Keyframe 0, with none behind it, counts all its points.
    let poses = drive(51, 0.03, 0.01);
    let shared = frames(Soil::compact(), &poses, &StereoVoParams::default());
    let vo_of = |overlap_denominator| {
        let params = StereoVoParams {
            overlap_denominator,
            ..StereoVoParams::default()
        };
        StereoVo::new(params, Arc::clone(&shared)).unwrap()
    };
    let mut vo = vo_of(OverlapDenominator::SharedPoints);
    assert_eq!(
        vo.shared_point_count(frame(0)),
        vo.map_point_count(frame(0))
    );
    let counts: Vec<(usize, usize, usize)> = [1usize, 5, 12, 25, 38]
        .iter()
        .map(|&gap| {
            assert!(matches!(
                track(&mut vo, &poses, 0, gap),
                TrackOutcome::Tracked(_)
            ));
            let current = frame(gap);
            (
                vo.shared_point_count(current),
                vo.tracked_inliers(current).unwrap(),
                vo.map_point_count(current),
            )
        })
        .collect();
    eprintln!("(shared points, inliers against keyframe 0, map points): {counts:?}");
    for &(shared, inliers, points) in &counts {
        assert!(shared <= points, "{counts:?}");
        assert!(
            (shared as f64) > 0.7 * inliers as f64 && (shared as f64) < 1.5 * inliers as f64,
            "{counts:?}"
        );
    }
    assert!(counts[4].0 < counts[0].0, "{counts:?}");
    // Frames tracked against frame 12 as the reference: the same inliers
    // over the shared points, a ratio at least the most-inliers one.
    let ratios = |vo: &mut StereoVo| -> Vec<f64> {
        assert!(matches!(track(vo, &poses, 0, 12), TrackOutcome::Tracked(_)));
        [1usize, 5, 12, 25, 38]
            .iter()
            .map(|&gap| match track(vo, &poses, 12, gap) {
                TrackOutcome::Tracked(m) => m.overlap,
                TrackOutcome::Lost => panic!("lost at gap {gap}"),
            })
            .collect()
    };
    let most = ratios(&mut vo_of(OverlapDenominator::MostInliers));
    let orb_slam = ratios(&mut vo_of(OverlapDenominator::SharedPoints));
    eprintln!("keyframe ratios, most inliers: {most:.3?}; shared points: {orb_slam:.3?}");
    for (m, o) in most.iter().zip(&orb_slam) {
        assert!(o >= m, "{most:?} {orb_slam:?}");
    }
}

#[test]
fn too_few_close_points_tracked_call_for_a_keyframe() {
    // ORB-SLAM2's stereo trigger: fewer than 100 close points tracked
    // while more than 70 go untracked. A frame's close points are its map
    // points, and its close inliers at most its inliers, so fewer than 100
    // inliers with more than 70 other close points must call; the call
    // never comes with 70 or fewer close points in all. Off, it never
    // calls.
    let poses = drive(51, 0.03, 0.01);
    let shared = frames(Soil::compact(), &poses, &StereoVoParams::default());
    let calls = |close_points_keyframe| {
        let params = StereoVoParams {
            close_points_keyframe,
            ..StereoVoParams::default()
        };
        let mut vo = StereoVo::new(params, Arc::clone(&shared)).unwrap();
        [1usize, 5, 12, 25, 38]
            .iter()
            .map(|&gap| match track(&mut vo, &poses, 0, gap) {
                TrackOutcome::Tracked(m) => (
                    m.needs_keyframe,
                    vo.tracked_inliers(frame(gap)).unwrap(),
                    vo.map_point_count(frame(gap)),
                ),
                TrackOutcome::Lost => panic!("lost at gap {gap}"),
            })
            .collect::<Vec<(bool, usize, usize)>>()
    };
    let orb_slam = calls(Some([100, 70]));
    eprintln!("(calls, inliers, close points): {orb_slam:?}");
    for &(call, inliers, close) in &orb_slam {
        if inliers < 100 && close - inliers.min(close) > 70 {
            assert!(call, "{orb_slam:?}");
        }
        if call {
            assert!(close > 70, "{orb_slam:?}");
        }
    }
    // At 512 × 384 a quarter or more of a frame's inliers have no stereo
    // match of their own: ORB-SLAM2's counts, set for ExoTeR's
    // 1024 × 768, call at every gap (130 inliers at 0.4 s). Halved, they
    // call only once the view has moved on.
    assert!(orb_slam.iter().all(|c| c.0), "{orb_slam:?}");
    let halved = calls(Some([50, 35]));
    eprintln!("at [50, 35]: {halved:?}");
    assert!(!halved[0].0 && halved[4].0, "{halved:?}");
    assert!(calls(None).iter().all(|c| !c.0));
}
