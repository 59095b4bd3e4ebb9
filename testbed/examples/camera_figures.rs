//! Writes `docs/figures/camera-SOIL.png`: the real PRL NavCam image beside
//! a rendered stereo pair of that soil alone, on flat ground, from ExoTeR's
//! mast camera, all three at half the Bumblebee2's resolution (the real
//! image averaged over 2 × 2 pixels, the pair rendered at scale 0.5).
//!
//! ```text
//! cargo run --release -p gpodo-testbed --example camera_figures -- SHARED_IMAGES_DIR OUT_DIR
//! ```

use std::path::PathBuf;

use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;
use gpodo_vision::png_io::{read_png_gray, write_png_gray};
use nalgebra::{Isometry3, Vector3};

/// `image` averaged over 2 × 2 pixels.
fn half(image: &GrayImage) -> GrayImage {
    let (w, h) = (image.width() / 2, image.height() / 2);
    let mut out = GrayImage::filled(w, h, 0);
    for y in 0..h {
        for x in 0..w {
            let sum: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .map(|(dx, dy)| u32::from(image.get(2 * x + dx, 2 * y + dy)))
                .sum();
            out.set(x, y, ((sum + 2) / 4) as u8);
        }
    }
    out
}

/// The images side by side, separated by 8 white columns.
fn side_by_side(images: &[&GrayImage]) -> GrayImage {
    let gap = 8;
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let w = images.iter().map(|i| i.width()).sum::<usize>() + gap * (images.len() - 1);
    let mut out = GrayImage::filled(w, h, 255);
    let mut x0 = 0;
    for image in images {
        for y in 0..image.height() {
            for x in 0..image.width() {
                out.set(x0 + x, y, image.get(x, y));
            }
        }
        x0 += image.width() + gap;
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let images = PathBuf::from(
        args.next()
            .ok_or("usage: camera_figures SHARED_IMAGES_DIR OUT_DIR")?,
    );
    let out = PathBuf::from(
        args.next()
            .ok_or("usage: camera_figures SHARED_IMAGES_DIR OUT_DIR")?,
    );
    std::fs::create_dir_all(&out)?;
    let real = half(&read_png_gray(
        &images.join("exoter-prl/Navcam_example3_image.png"),
    )?);
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let spec = SceneSpec::default();
    for soil in [Soil::loose_sand(), Soil::gravel(), Soil::compact()] {
        let name = soil.name.clone();
        let ground = GroundMaps::build(
            &Terrain::flat(6.0)?,
            &SoilMap::uniform(soil, 6.0)?,
            &spec,
            7,
        )?;
        let renderer = StereoRenderer::new(camera, &ground, SensorSpec::default(), 7)?;
        let body = Isometry3::new(Vector3::new(1.0, 3.0, 0.25), Vector3::zeros());
        let frame = renderer.render(&body, &Isometry3::identity(), 0);
        let figure = side_by_side(&[&real, &frame.left, &frame.right]);
        let path = out.join(format!("camera-{name}.png"));
        write_png_gray(&path, &figure)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
