//! What a feature tracker sees on real ground images: the boxes of
//! `../shared/data/images/` that the rendered soils are calibrated
//! against, each named and chosen by looking at its image, and their
//! measurements (FAST-9 corner density at ORB-SLAM2's two thresholds,
//! ORB keypoint density, grey-level spread).
//!
//! The thresholds are ExoTeR's ORB-SLAM2 settings (`iniThFAST: 20`, the
//! first try in every cell, and `minThFAST: 7`, the retry in a cell where
//! the first found nothing). Corners are detected on the whole image, with
//! OpenCV's non-maximum suppression, and counted inside the box. ORB
//! keypoints are extracted from the whole image with ExoTeR's ORB-SLAM2
//! settings for its size ([`OrbParams::exoter_for_size`]: 3000 at
//! 1024 × 768), so a box holds the share of the budget its texture wins.

use std::path::Path;

use gpodo_vision::orb::{Features, OrbParams, extract};
use gpodo_vision::png_io::read_png_gray;
use gpodo_vision::stats::{corner_density, grey_levels};
use gpodo_vision::{GrayImage, PixelBox};

use crate::TestbedError;

/// ORB-SLAM2's FAST thresholds on ExoTeR: `iniThFAST`, then `minThFAST`.
pub const FAST_THRESHOLDS: [u8; 2] = [20, 7];

/// What a box of a real image shows, for the soil it is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ground {
    /// Loose sand (the PRL's, with boot prints; or Martian ripples).
    Sand,
    /// Rocks and flagstones: what the rendered gravel is compared with.
    Rock,
    /// Bedrock and rubble on Mars.
    Bedrock,
}

/// A named box of a real image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RealBox {
    /// Short name, used in tables.
    pub name: &'static str,
    /// The image, relative to `shared/data/images/`.
    pub file: &'static str,
    /// The pixels.
    pub pixels: PixelBox,
    /// What it shows.
    pub ground: Ground,
    /// Why this box: what it holds and what it leaves out.
    pub why: &'static str,
}

const fn pixel_box(x: usize, y: usize, width: usize, height: usize) -> PixelBox {
    PixelBox {
        x,
        y,
        width,
        height,
    }
}

/// `prl-sand-navcam`'s pixels: the PRL's sand as the mast camera sees it,
/// the box rendered soils are measured in too.
pub const PRL_SAND_NAVCAM: PixelBox = pixel_box(620, 340, 360, 300);

/// The boxes, chosen by looking at the images.
pub const REAL_BOXES: [RealBox; 8] = [
    RealBox {
        name: "prl-sand-loccam",
        file: "exoter-prl/Loccam_example1_image.png",
        pixels: pixel_box(100, 250, 500, 400),
        ground: Ground::Sand,
        why: "loose sand with boot prints in the middle of the LocCam view; leaves out the sample tube (lower right), the arm (right) and the dark rover shadow (top)",
    },
    RealBox {
        name: "prl-sand-navcam",
        file: "exoter-prl/Navcam_example3_image.png",
        pixels: PRL_SAND_NAVCAM,
        ground: Ground::Sand,
        why: "loose sand with boot prints as the mast camera sees it, right of the tube and below the flagstones and rocks",
    },
    RealBox {
        name: "prl-flagstones",
        file: "exoter-prl/Navcam_example3_image.png",
        pixels: pixel_box(20, 150, 240, 150),
        ground: Ground::Rock,
        why: "the pale flagstones on the left, with their dark joints; leaves out the tripod's legs",
    },
    RealBox {
        name: "prl-rock-large",
        file: "exoter-prl/Navcam_example3_image.png",
        pixels: pixel_box(445, 235, 120, 90),
        ground: Ground::Rock,
        why: "the face of the large basalt-like rock right of the tripod, inside its outline",
    },
    RealBox {
        name: "prl-rock-left",
        file: "exoter-prl/Navcam_example3_image.png",
        pixels: pixel_box(160, 310, 120, 85),
        ground: Ground::Rock,
        why: "the face of the rock at the lower left of the flagstones, inside its outline",
    },
    RealBox {
        name: "mars-ripples",
        file: "curiosity-navcam/sol01371.png",
        pixels: pixel_box(440, 300, 220, 250),
        ground: Ground::Sand,
        why: "the sand ripples between the bedrock slabs, clear of the slabs and of the rover's wheel",
    },
    RealBox {
        name: "mars-bedrock",
        file: "curiosity-navcam/sol01343.png",
        pixels: pixel_box(600, 520, 180, 170),
        ground: Ground::Bedrock,
        why: "a fractured bedrock slab right of centre, with its cracks",
    },
    RealBox {
        name: "mars-rubble",
        file: "curiosity-navcam/sol01343.png",
        pixels: pixel_box(150, 120, 250, 250),
        ground: Ground::Bedrock,
        why: "loose rocks and pebbles on sand at the upper left",
    },
];

/// A box's measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxMeasurement {
    /// The box.
    pub region: RealBox,
    /// FAST-9 corners per 10⁴ pixels at each of [`FAST_THRESHOLDS`].
    pub corners_per_10k_px: [f64; 2],
    /// ORB keypoints per 10⁴ pixels, of the whole image's.
    pub orb_per_10k_px: f64,
    /// Mean grey level.
    pub grey_mean: f64,
    /// Standard deviation of the grey levels.
    pub grey_std: f64,
}

/// The ORB features of `image` with ExoTeR's ORB-SLAM2 settings for its
/// size.
///
/// # Errors
/// [`TestbedError::Image`] for an image too small to hold a pyramid.
pub fn orb_features(image: &GrayImage) -> Result<Features, TestbedError> {
    Ok(extract(
        image,
        &OrbParams::exoter_for_size(image.width(), image.height()),
    )?)
}

/// Keypoints of `features` inside `region`, per 10⁴ of its pixels.
pub fn orb_density(features: &Features, region: &PixelBox) -> f64 {
    let inside = features
        .keypoints
        .iter()
        .filter(|k| region.contains(k.x.round() as usize, k.y.round() as usize))
        .count();
    inside as f64 * 1e4 / region.area() as f64
}

/// Measures `region` of `image` (the box's file, already read), whose ORB
/// features are `features`.
///
/// # Errors
/// [`TestbedError::Image`] when the box leaves the image.
pub fn measure_box(
    image: &GrayImage,
    features: &Features,
    region: RealBox,
) -> Result<BoxMeasurement, TestbedError> {
    let levels = grey_levels(image, &region.pixels)?;
    let mut corners_per_10k_px = [0.0; 2];
    for (out, threshold) in corners_per_10k_px.iter_mut().zip(FAST_THRESHOLDS) {
        *out = corner_density(image, &region.pixels, threshold)?;
    }
    Ok(BoxMeasurement {
        region,
        corners_per_10k_px,
        orb_per_10k_px: orb_density(features, &region.pixels),
        grey_mean: levels.mean,
        grey_std: levels.std,
    })
}

/// Measures every box of [`REAL_BOXES`], reading the images under
/// `images_dir` (`shared/data/images/`).
///
/// # Errors
/// [`TestbedError::Image`] naming an image that cannot be read.
pub fn measure_real_boxes(images_dir: &Path) -> Result<Vec<BoxMeasurement>, TestbedError> {
    let mut out = Vec::with_capacity(REAL_BOXES.len());
    let mut last: Option<(&str, GrayImage, Features)> = None;
    for region in REAL_BOXES {
        let (image, features) = match last.take() {
            Some((file, image, features)) if file == region.file => (image, features),
            _ => {
                let image = read_png_gray(&images_dir.join(region.file))?;
                let features = orb_features(&image)?;
                (image, features)
            }
        };
        out.push(measure_box(&image, &features, region)?);
        last = Some((region.file, image, features));
    }
    Ok(out)
}

/// ORB keypoints of each image of [`REAL_BOXES`] under `images_dir`, as a
/// Markdown table: image, size, keypoints (against the settings' cap) and
/// levels.
///
/// # Errors
/// [`TestbedError::Image`] naming an image that cannot be read.
pub fn orb_image_table(images_dir: &Path) -> Result<String, TestbedError> {
    let mut s =
        String::from("| image | size | ORB keypoints | cap | levels |\n|---|---|---:|---:|---:|\n");
    let mut files: Vec<&str> = REAL_BOXES.iter().map(|b| b.file).collect();
    files.dedup();
    for file in files {
        let image = read_png_gray(&images_dir.join(file))?;
        let (w, h) = (image.width(), image.height());
        let params = OrbParams::exoter_for_size(w, h);
        let features = extract(&image, &params)?;
        s.push_str(&format!(
            "| `{file}` | {w} × {h} | {} | {} | {} |\n",
            features.keypoints.len(),
            params.features,
            params.levels
        ));
    }
    Ok(s)
}

/// The measurements as a Markdown table (what `testbed/README.md` shows).
pub fn markdown_table(measurements: &[BoxMeasurement]) -> String {
    let mut s = String::from(
        "| box | image | pixels (x, y, w × h) | ground | FAST corners / 10⁴ px at 20 | at 7 | ORB keypoints / 10⁴ px | grey mean | grey std |\n|---|---|---|---|---:|---:|---:|---:|---:|\n",
    );
    for m in measurements {
        let r = &m.region;
        let p = r.pixels;
        s.push_str(&format!(
            "| {} | `{}` | ({}, {}, {} × {}) | {:?} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |\n",
            r.name,
            r.file,
            p.x,
            p.y,
            p.width,
            p.height,
            r.ground,
            m.corners_per_10k_px[0],
            m.corners_per_10k_px[1],
            m.orb_per_10k_px,
            m.grey_mean,
            m.grey_std
        ));
    }
    s
}
