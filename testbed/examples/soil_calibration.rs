//! Prints the soils' calibration table: each soil rendered alone, against
//! the real boxes it is compared with (`testbed/README.md`).
//!
//! ```text
//! cargo run --release -p gpodo-testbed --example soil_calibration [-- SCENE.yaml [OUT_DIR]]
//! ```
//!
//! SCENE.yaml (optional) is a scene specification to try instead of the
//! defaults (`gpodo_testbed::camera::SceneSpec`, every field optional);
//! OUT_DIR (optional) receives each soil's rendered image as PNG.

use gpodo_testbed::camera::calibration::render_soil;
use gpodo_testbed::camera::{SceneSpec, SensorSpec};
use gpodo_testbed::sim::soil::Soil;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spec: SceneSpec = match std::env::args().nth(1) {
        Some(path) => serde_saphyr::from_str(&std::fs::read_to_string(&path)?)?,
        None => SceneSpec::default(),
    };
    let out = std::env::args().nth(2).map(std::path::PathBuf::from);
    for soil in [Soil::loose_sand(), Soil::gravel(), Soil::compact()] {
        let r = render_soil(soil, &spec, SensorSpec::default())?;
        println!(
            "{}: corners/1e4 px {:.1} (at 20) {:.1} (at 7); grey {:.1} ± {:.1}",
            r.soil, r.corners_per_10k_px[0], r.corners_per_10k_px[1], r.grey_mean, r.grey_std
        );
        if let Some(dir) = &out {
            std::fs::create_dir_all(dir)?;
            let path = dir.join(format!("{}.png", r.soil));
            gpodo_vision::png_io::write_png_gray(&path, &r.image)?;
        }
    }
    Ok(())
}
