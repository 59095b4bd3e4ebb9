//! One processed stereo frame of the stereo VO at 512 × 384 on one core:
//! ORB features of both images and their row matches, then tracking the
//! frame against a reference keyframe whose features are cached; the pair
//! is rendered (gravel, ExoTeR's mast camera) outside the timed closures.
//! And what a keyframe adds: the loop-closure query of a new keyframe
//! against 80 earlier ones (half the keyframes of a 0.5 fps route),
//! features cached, as the front end makes it for every keyframe.
//!
//! ```text
//! cargo bench -p gpodo-experiments --bench stereo_vo
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use gpodo_frontends::vo::stereo::{StereoFrames, StereoVo, StereoVoParams};
use gpodo_frontends::vo::{FrameRef, TrackPurpose, TrackRequest, VisualOdometry};
use gpodo_testbed::camera::{FramePose, RenderedFrames};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use gpodo_vision::orb::OrbParams;
use gpodo_vision::stereo::stereo_features;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// A flat 6-m patch of gravel, the ground of every bench here.
fn gravel_ground() -> Arc<GroundMaps> {
    Arc::new(
        GroundMaps::build(
            &Terrain::flat(6.0).unwrap(),
            &SoilMap::uniform(Soil::gravel(), 6.0).unwrap(),
            &SceneSpec::default(),
            7,
        )
        .unwrap(),
    )
}

fn stereo_frame(c: &mut Criterion) {
    let ground = gravel_ground();
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let poses: Vec<FramePose> = (0..2)
        .map(|k| FramePose {
            world_from_body: Isometry3::from_parts(
                Translation3::new(1.0 + 0.012 * k as f64, 3.0, 0.25),
                UnitQuaternion::from_euler_angles(0.0, 0.0, 0.004 * k as f64),
            ),
            exposure_motion: Isometry3::identity(),
        })
        .collect();
    let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 7).unwrap();
    let pair = renderer.render(&poses[1].world_from_body, &Isometry3::identity(), 1);
    let orb = OrbParams::exoter_for_size(512, 384);
    let source = RenderedFrames::new(
        Arc::clone(&ground),
        camera,
        SensorSpec::default(),
        7,
        poses.clone(),
    );
    let mut vo = StereoVo::new(
        StereoVoParams::default(),
        Arc::new(StereoFrames::new(camera, Arc::new(source))),
    )
    .unwrap();
    let frame = |k: usize| FrameRef {
        index: k,
        time_secs: k as f64 / 2.5,
    };
    let request = TrackRequest {
        reference: frame(0),
        current: frame(1),
        prior: Some(poses[0].world_from_body.inverse() * poses[1].world_from_body),
        purpose: TrackPurpose::Tracking,
    };
    // Both frames' features are cached by the first call.
    vo.track(&request);

    let mut group = c.benchmark_group("stereo_vo");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(8));
    group.bench_function("features_512x384", |b| {
        b.iter(|| stereo_features(&pair.left, &pair.right, &orb, camera.focal_px).unwrap())
    });
    group.bench_function("track_cached_512x384", |b| b.iter(|| vo.track(&request)));
    group.finish();
}

/// The loop-closure query of a keyframe against `KEYFRAMES` earlier ones
/// around a 2-m circle on gravel, each 4.5° and 16 cm on.
fn keyframe_query(c: &mut Criterion) {
    const KEYFRAMES: usize = 80;
    let ground = gravel_ground();
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let poses: Vec<FramePose> = (0..=KEYFRAMES)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / KEYFRAMES as f64;
            FramePose {
                world_from_body: Isometry3::from_parts(
                    Translation3::new(3.0 + 2.0 * a.cos(), 3.0 + 2.0 * a.sin(), 0.25),
                    UnitQuaternion::from_euler_angles(0.0, 0.0, a + std::f64::consts::FRAC_PI_2),
                ),
                exposure_motion: Isometry3::identity(),
            }
        })
        .collect();
    let source = RenderedFrames::new(ground, camera, SensorSpec::default(), 7, poses);
    let vo = StereoVo::new(
        StereoVoParams::default(),
        Arc::new(StereoFrames::new(camera, Arc::new(source))),
    )
    .unwrap();
    let frame = |k: usize| FrameRef {
        index: k,
        time_secs: k as f64 * 2.0,
    };
    let keyframes: Vec<FrameRef> = (0..KEYFRAMES).map(frame).collect();
    let current = frame(KEYFRAMES);
    // Renders every frame and caches its features.
    let found = vo.recognise(current, &keyframes);
    println!(
        "keyframe query: {} of {KEYFRAMES} keyframes recognised",
        found.len()
    );
    let mut group = c.benchmark_group("stereo_vo");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(8));
    group.bench_function("keyframe_query_80", |b| {
        b.iter(|| vo.recognise(current, &keyframes))
    });
    group.finish();
}

criterion_group!(benches, stereo_frame, keyframe_query);
criterion_main!(benches);
