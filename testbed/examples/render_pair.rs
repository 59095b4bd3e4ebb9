//! Renders stereo pairs of the simulated ExoTeR testbed and writes them as
//! PNG: one at the test traverse's start, then one per soil, on flat
//! patches of that soil, from ExoTeR's mast camera.
//!
//! ```text
//! cargo run --release -p gpodo-testbed --example render_pair -- OUT_DIR [SCALE] [SEED]
//! ```
//!
//! SCALE (default 1) renders at that fraction of the Bumblebee2's
//! 1024 × 768; SEED (default 7) is the testbed's.

use std::path::PathBuf;
use std::time::Instant;

use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use gpodo_vision::png_io::write_png_gray;
use nalgebra::{Isometry3, Vector3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(
        args.next()
            .ok_or("usage: render_pair OUT_DIR [SCALE] [SEED]")?,
    );
    let scale: f64 = args.next().map_or(Ok(1.0), |s| s.parse())?;
    let seed: u64 = args.next().map_or(Ok(7), |s| s.parse())?;
    std::fs::create_dir_all(&out)?;
    let camera = CameraParams::exoter_bumblebee2().scaled(scale);
    let spec = SceneSpec::default();

    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, seed);
    config.training_runs = 1;
    config.training_run_secs = 10.0;
    let testbed = config.simulate()?;
    let clock = Instant::now();
    let ground = GroundMaps::build(&testbed.terrain, &testbed.soils, &spec, seed)?;
    println!("ground maps: {:.2} s", clock.elapsed().as_secs_f64());
    let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), seed)?;
    let test = testbed.test.first().ok_or("no test run")?;
    let start = test.ground_truth.first().ok_or("an empty test run")?;
    let clock = Instant::now();
    let frame = renderer.render(start, &Isometry3::identity(), 0);
    println!("one pair: {:.3} s", clock.elapsed().as_secs_f64());
    write_png_gray(&out.join("testbed-left.png"), &frame.left)?;
    write_png_gray(&out.join("testbed-right.png"), &frame.right)?;

    for soil in [Soil::loose_sand(), Soil::gravel(), Soil::compact()] {
        let name = soil.name.clone();
        let flat = GroundMaps::build(
            &Terrain::flat(9.0)?,
            &SoilMap::uniform(soil, 9.0)?,
            &spec,
            seed,
        )?;
        let renderer = StereoRenderer::new(camera, &flat, SensorSpec::default(), seed)?;
        let body = Isometry3::new(Vector3::new(4.5, 4.5, 0.25), Vector3::zeros());
        let frame = renderer.render(&body, &Isometry3::identity(), 0);
        write_png_gray(&out.join(format!("{name}-left.png")), &frame.left)?;
        write_png_gray(&out.join(format!("{name}-right.png")), &frame.right)?;
    }
    println!("wrote {}", out.display());
    Ok(())
}
