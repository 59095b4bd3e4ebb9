//! The rendered stereo camera against closed forms: on a flat plane the
//! depth buffer is the ray–plane distance and every pixel's ground point
//! projects back onto it; block matching the rendered pair finds the
//! disparity `f b / Z`; blur grows with the angular rate; sand gives fewer
//! FAST corners than gravel; and the bytes do not depend on the threads.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoFrame, StereoRenderer};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;
use gpodo_vision::fast::detect;
use nalgebra::{Isometry3, Point3, Vector3};

/// A 9 × 9 m flat testbed of one soil.
fn flat(soil: Soil, spec: &SceneSpec) -> GroundMaps {
    let terrain = Terrain::flat(9.0).unwrap();
    let soils = SoilMap::uniform(soil, 9.0).unwrap();
    GroundMaps::build(&terrain, &soils, spec, 11).unwrap()
}

/// A scene whose ground is the exact plane z = 0: no relief, no stones.
fn plane_spec() -> SceneSpec {
    let mut spec = SceneSpec::default();
    for look in [&mut spec.compact, &mut spec.loose_sand, &mut spec.gravel] {
        look.relief_octaves_m.clear();
        look.stones.clear();
    }
    spec.map_cell_m = 0.004;
    spec
}

/// The body at the area's centre, 0.25 m up (ExoTeR resting on flat
/// ground), heading along +x turned by `yaw_rad`.
fn body(yaw_rad: f64) -> Isometry3<f64> {
    Isometry3::new(Vector3::new(4.5, 4.5, 0.25), Vector3::z() * yaw_rad)
}

fn still() -> Isometry3<f64> {
    Isometry3::identity()
}

#[test]
fn on_a_plane_depth_is_the_ray_plane_distance_and_points_project_back_to_their_pixels() {
    let ground = flat(Soil::loose_sand(), &plane_spec());
    let camera = CameraParams::exoter_bumblebee2().scaled(0.25);
    let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 1).unwrap();
    let pose = body(0.3);
    let frame = renderer.render(&pose, &still(), 0);
    let world_from_camera = pose * camera.body_from_camera();
    let [w, h] = camera.image_size_px.map(|n| n as usize);
    let (mut seen, mut worst_depth, mut worst_px) = (0, 0.0f64, 0.0f64);
    for v in 0..h {
        for u in 0..w {
            let depth = f64::from(frame.depth_m[v * w + u]);
            let ray = camera.pixel_ray(u as f64, v as f64);
            let dir = world_from_camera.rotation * ray;
            let origin = world_from_camera.translation.vector;
            if dir.z >= 0.0 {
                assert!(depth.is_infinite(), "pixel ({u}, {v}) above the horizon");
                continue;
            }
            // The plane z = 0 meets the ray at s = −o_z / d_z in units of
            // the z = 1 ray, which is the depth along the optical axis.
            let expected = -origin.z / dir.z;
            if expected > 29.0 {
                continue;
            }
            seen += 1;
            worst_depth = worst_depth.max((depth - expected).abs() / expected);
            let p_world = world_from_camera * Point3::from(ray * depth);
            assert!(p_world.z.abs() < 1e-3 * expected, "{p_world}");
            let [pu, pv] = camera
                .project(&(world_from_camera.inverse() * p_world))
                .unwrap();
            worst_px = worst_px
                .max((pu - u as f64).abs())
                .max((pv - v as f64).abs());
        }
    }
    assert!(seen > w * h / 2, "{seen} ground pixels");
    assert!(worst_depth < 1e-4, "relative depth error {worst_depth}");
    assert!(worst_px < 0.5, "reprojection off by {worst_px} px");
}

/// The disparity of the `radius`-patch of `left` at `(u, v)` on `right`'s
/// row: the best sum of absolute differences over `0..max`, refined by a
/// parabola through its neighbours.
fn block_match(left: &GrayImage, right: &GrayImage, u: usize, v: usize, max: usize) -> f64 {
    let radius = 5;
    let sad = |d: usize| -> f64 {
        let mut s = 0.0;
        for dv in 0..=2 * radius {
            for du in 0..=2 * radius {
                let (x, y) = (u + du - radius, v + dv - radius);
                s += (f64::from(left.get(x, y)) - f64::from(right.get(x - d, y))).abs();
            }
        }
        s
    };
    let costs: Vec<f64> = (0..max).map(sad).collect();
    let best = (1..max - 1)
        .min_by(|&a, &b| costs[a].total_cmp(&costs[b]))
        .unwrap();
    let (a, b, c) = (costs[best - 1], costs[best], costs[best + 1]);
    let denominator = a - 2.0 * b + c;
    let offset = if denominator > 0.0 {
        0.5 * (a - c) / denominator
    } else {
        0.0
    };
    best as f64 + offset
}

#[test]
fn block_matching_the_pair_finds_the_disparity_of_the_planes_depth() {
    let mut spec = plane_spec();
    spec.map_cell_m = 0.0025;
    let ground = flat(Soil::gravel(), &spec);
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 2).unwrap();
    let frame = renderer.render(&body(0.0), &still(), 0);
    let [w, h] = camera.image_size_px.map(|n| n as usize);
    let max = 72;
    let mut errors = Vec::new();
    for v in (h / 2..h - 8).step_by(16) {
        for u in (max + 8..w - 8).step_by(16) {
            let z = f64::from(frame.depth_m[v * w + u]);
            let expected = camera.disparity_px(z);
            let found = block_match(&frame.left, &frame.right, u, v, max);
            errors.push((found - expected).abs());
        }
    }
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    assert!(errors.len() > 200, "{} patches", errors.len());
    assert!(
        mean < 0.5,
        "mean disparity error {mean} px over {} patches",
        errors.len()
    );
}

/// Mean absolute horizontal difference of neighbouring grey levels.
fn sharpness(image: &GrayImage) -> f64 {
    let (w, h) = (image.width(), image.height());
    let mut sum = 0.0;
    for v in h / 2..h {
        for u in 1..w {
            sum += (f64::from(image.get(u, v)) - f64::from(image.get(u - 1, v))).abs();
        }
    }
    sum / ((h - h / 2) * (w - 1)) as f64
}

#[test]
fn blur_grows_with_the_angular_rate() {
    let ground = flat(Soil::gravel(), &SceneSpec::default());
    let camera = CameraParams {
        exposure_secs: 0.02,
        ..CameraParams::exoter_bumblebee2().scaled(0.25)
    };
    let noiseless = SensorSpec {
        electrons_per_dn: 1e12,
        read_noise_dn: 0.0,
        ..SensorSpec::default()
    };
    let renderer = StereoRenderer::new(camera, &ground, noiseless, 3).unwrap();
    let values: Vec<f64> = [0.0, 0.5, 1.0, 2.0]
        .iter()
        .map(|&rate_radps: &f64| {
            let turn = Isometry3::rotation(Vector3::z() * rate_radps * camera.exposure_secs);
            sharpness(&renderer.render(&body(0.0), &turn, 0).left)
        })
        .collect();
    for pair in values.windows(2) {
        assert!(pair[1] < pair[0], "sharpness {values:?}");
    }
}

#[test]
fn sand_gives_fewer_fast_corners_than_gravel() {
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let counts: Vec<[usize; 2]> = [Soil::loose_sand(), Soil::gravel()]
        .into_iter()
        .map(|soil| {
            let ground = flat(soil, &SceneSpec::default());
            let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 4).unwrap();
            let image = renderer.render(&body(0.0), &still(), 0).left;
            [20, 7].map(|t| detect(&image, t, true).len())
        })
        .collect();
    for k in 0..2 {
        assert!(
            counts[0][k] < counts[1][k],
            "sand {:?}, gravel {:?}",
            counts[0],
            counts[1]
        );
    }
}

#[test]
fn the_bytes_do_not_depend_on_the_thread_count_and_the_noise_on_the_frame() {
    let camera = CameraParams::exoter_bumblebee2().scaled(0.25);
    let render = |threads: usize, frame: u64| -> StereoFrame {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let spec = SceneSpec {
                map_cell_m: 0.005,
                ..SceneSpec::default()
            };
            let ground = flat(Soil::gravel(), &spec);
            let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 5).unwrap();
            let turn = Isometry3::rotation(Vector3::z() * 0.01);
            renderer.render(&body(1.0), &turn, frame)
        })
    };
    let one = render(1, 17);
    assert!(one == render(2, 17));
    let other = render(2, 18);
    assert_eq!(one.depth_m, other.depth_m);
    assert_ne!(one.left, other.left, "another frame draws other noise");
}

#[test]
fn the_rays_cast_together_meet_the_ground_where_each_cast_alone_does() {
    // A 3 × 3 m patch of gravel (its stones the most work for a ray), seen
    // from inside near an edge and from outside: rays meet the patch, the
    // lab's floor beyond it, or nothing.
    let terrain = Terrain::flat(3.0).unwrap();
    let soils = SoilMap::uniform(Soil::gravel(), 3.0).unwrap();
    let ground = GroundMaps::build(&terrain, &soils, &SceneSpec::default(), 5).unwrap();
    let dirs: Vec<Vector3<f64>> = (0..120)
        .flat_map(|a| (0..40).map(move |e| (f64::from(a) * 3.0, f64::from(e) * 2.7 - 88.0)))
        .map(|(azimuth_deg, elevation_deg): (f64, f64)| {
            let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
            Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin())
        })
        .collect();
    let (mut on_patch, mut on_floor, mut none) = (0, 0, 0);
    for origin in [Point3::new(2.9, 1.5, 0.8), Point3::new(-0.5, 1.2, 0.6)] {
        let mut hits = Vec::new();
        ground.first_hits(&origin, &dirs, 0.01, 30.0, &mut hits);
        assert_eq!(hits.len(), dirs.len());
        for (dir, hit) in dirs.iter().zip(&hits) {
            let alone = ground.first_hit(&origin, dir, 0.01, 30.0);
            assert_eq!(hit.map(f64::to_bits), alone.map(f64::to_bits), "{dir:?}");
            match hit {
                Some(t) => {
                    let p = origin + dir * *t;
                    if (0.0..=3.0).contains(&p.x) && (0.0..=3.0).contains(&p.y) {
                        on_patch += 1;
                    } else {
                        on_floor += 1;
                    }
                }
                None => none += 1,
            }
        }
    }
    assert!(
        on_patch > 1000 && on_floor > 1000 && none > 1000,
        "{on_patch} on the patch, {on_floor} on the floor, {none} none"
    );
}
