//! One rendered stereo pair of the testbed's gravel (its stones and
//! shadows are the most work for the rays) from ExoTeR's Bumblebee2, at
//! 512 × 384 (scale 0.5) and at its full 1024 × 768, on a ground map built
//! outside the timed closure; beside them, building the ground maps of a
//! 3 × 3 m patch; and the first hits of one 512 × 384 view's rays, cast
//! four at a time on vectors (as the renderer does) against one at a time.
//!
//! ```text
//! cargo bench -p gpodo-testbed --bench camera
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use nalgebra::{Isometry3, Point3, Vector3};

fn stereo_pair(c: &mut Criterion) {
    let spec = SceneSpec::default();
    let ground = GroundMaps::build(
        &Terrain::flat(6.0).unwrap(),
        &SoilMap::uniform(Soil::gravel(), 6.0).unwrap(),
        &spec,
        7,
    )
    .unwrap();
    let body = Isometry3::new(Vector3::new(1.0, 3.0, 0.25), Vector3::zeros());
    let mut group = c.benchmark_group("camera");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(8));
    for scale in [0.5, 1.0] {
        let camera = CameraParams::exoter_bumblebee2().scaled(scale);
        let [w, h] = camera.image_size_px;
        let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 7).unwrap();
        group.bench_with_input(
            BenchmarkId::new("stereo_pair", format!("{w}x{h}")),
            &scale,
            |b, _| b.iter(|| renderer.render(&body, &Isometry3::identity(), 0)),
        );
    }
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let world_from_camera = body * camera.body_from_camera();
    let origin = Point3::from(world_from_camera.translation.vector);
    let [w, h] = camera.image_size_px.map(|n| n as usize);
    let rows: Vec<Vec<Vector3<f64>>> = (0..h)
        .map(|v| {
            (0..w)
                .map(|u| {
                    world_from_camera.rotation * camera.pixel_ray(u as f64, v as f64).normalize()
                })
                .collect()
        })
        .collect();
    group.bench_function("first_hits_512x384/four_at_a_time", |b| {
        let mut hits = Vec::new();
        b.iter(|| {
            rows.iter()
                .map(|dirs| {
                    ground.first_hits(&origin, dirs, 0.01, 30.0, &mut hits);
                    hits.iter().flatten().count()
                })
                .sum::<usize>()
        })
    });
    group.bench_function("first_hits_512x384/one_at_a_time", |b| {
        b.iter(|| {
            rows.iter()
                .flatten()
                .filter(|dir| ground.first_hit(&origin, dir, 0.01, 30.0).is_some())
                .count()
        })
    });
    group.bench_function("ground_maps_3x3_m", |b| {
        let terrain = Terrain::flat(3.0).unwrap();
        let soils = SoilMap::uniform(Soil::gravel(), 3.0).unwrap();
        b.iter(|| GroundMaps::build(&terrain, &soils, &spec, 7).unwrap())
    });
    group.finish();
}

criterion_group!(benches, stereo_pair);
criterion_main!(benches);
