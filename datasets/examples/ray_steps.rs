#![allow(missing_docs, clippy::unwrap_used)]
use gpodo_datasets::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_datasets::sim::soil::{SoilMap, SoilMapSpec};
use gpodo_datasets::sim::terrain::{Terrain, TerrainSpec};
use gpodo_traits::CameraParams;
use nalgebra::{Isometry3, Vector3};
use rand::SeedableRng;

fn main() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let terrain = Terrain::generate(&TerrainSpec::default(), &mut rng).unwrap();
    let soils = SoilMap::generate(&SoilMapSpec::default(), 9.0, &mut rng).unwrap();
    let ground = GroundMaps::build(&terrain, &soils, &SceneSpec::default(), 3).unwrap();
    println!("max height {}", ground.max_height_m);
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let r = StereoRenderer::new(camera, &ground, SensorSpec::default(), 3).unwrap();
    let t = std::time::Instant::now();
    let mut n = 0;
    let k: usize = std::env::var("RENDERS")
        .map(|v| v.parse().unwrap())
        .unwrap_or(1);
    for (x, y, yaw) in [
        (2.0, 4.5, 0.0),
        (4.5, 4.5, 1.0),
        (7.0, 2.0, 2.5),
        (1.0, 1.0, 0.7),
    ]
    .into_iter()
    .take(k)
    {
        let z = terrain.height(x, y) + 0.25;
        let body = Isometry3::new(Vector3::new(x, y, z), Vector3::new(0.0, 0.0, yaw));
        let motion = Isometry3::new(Vector3::new(0.0003, 0.0, 0.0), Vector3::zeros());
        let f = r.render(&body, &motion, 0);
        n += f.left.pixels().len();
        let mut h: u64 = 1469598103934665603;
        for b in f.left.pixels().iter().chain(f.right.pixels()) {
            h = (h ^ u64::from(*b)).wrapping_mul(1099511628211);
        }
        for d in &f.depth_m {
            h = (h ^ u64::from(d.to_bits())).wrapping_mul(1099511628211);
        }
        println!("hash {h:x}");
    }
    println!("{} px, {:?}", n, t.elapsed());
}
