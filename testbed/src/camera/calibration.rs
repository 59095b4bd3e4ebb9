//! The rendered side of the soils' calibration against real images: each
//! soil rendered alone on flat ground by ExoTeR's mast camera at full
//! resolution, measured in the same pixel box as the real NavCam's sand
//! (`prl-sand-navcam`, ground about 1.5–3 m ahead), with the same detector
//! settings as the real boxes ([`crate::real_images`]). The real boxes
//! hold a soil's surface, clear of rocks, so the soil is rendered without
//! its rocks (stones of [`ROCK_RADIUS_M`] and more); pebbles stay part of
//! the surface.

use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;
use gpodo_vision::stats::{corner_density, grey_levels};
use nalgebra::{Isometry3, Vector3};

use super::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use crate::TestbedError;
use crate::real_images::{FAST_THRESHOLDS, PRL_SAND_NAVCAM, orb_density, orb_features};
use crate::sim::soil::{Soil, SoilMap};
use crate::sim::terrain::Terrain;

/// Stones at least this large (radius, m) are rocks, left out of the
/// calibration renders.
pub const ROCK_RADIUS_M: f64 = 0.03;

/// The seeds of the calibration renders: each soil's figures are means
/// over one render per seed (corners at threshold 20 are a few dozen per
/// box, so one render alone is noisy).
pub const CALIBRATION_SEEDS: [u64; 3] = [2026, 2027, 2028];

/// A rendered soil's measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedSoil {
    /// The soil's name.
    pub soil: String,
    /// FAST-9 corners per 10⁴ pixels at each of [`FAST_THRESHOLDS`].
    pub corners_per_10k_px: [f64; 2],
    /// ORB keypoints per 10⁴ pixels, of the whole image's
    /// ([`crate::real_images::orb_features`]).
    pub orb_per_10k_px: f64,
    /// Mean grey level.
    pub grey_mean: f64,
    /// Standard deviation of the grey levels.
    pub grey_std: f64,
    /// The rendered left image.
    pub image: GrayImage,
}

/// Renders `soil` alone, without its rocks, on a flat 6 × 6 m patch as
/// `spec` and `sensor` say, from ExoTeR's Bumblebee2 on a body 0.25 m up
/// near one edge, looking across the patch, once per seed of
/// [`CALIBRATION_SEEDS`], and measures [`PRL_SAND_NAVCAM`]'s box: the means over
/// the seeds, and the first seed's image.
///
/// # Errors
/// [`TestbedError::InvalidConfig`] naming a bad setting.
pub fn render_soil(
    soil: Soil,
    spec: &SceneSpec,
    sensor: SensorSpec,
) -> Result<RenderedSoil, TestbedError> {
    let name = soil.name.clone();
    let mut spec = spec.clone();
    for look in [&mut spec.compact, &mut spec.loose_sand, &mut spec.gravel] {
        look.stones.retain(|s| s.radius_m[0] < ROCK_RADIUS_M);
    }
    let terrain = Terrain::flat(6.0)?;
    let soils = SoilMap::uniform(soil, 6.0)?;
    let camera = CameraParams::exoter_bumblebee2();
    let body = Isometry3::new(Vector3::new(1.0, 3.0, 0.25), Vector3::zeros());
    let region = PRL_SAND_NAVCAM;
    let mut sums = [0.0; 5];
    let mut first = None;
    for seed in CALIBRATION_SEEDS {
        let ground = GroundMaps::build(&terrain, &soils, &spec, seed)?;
        let renderer = StereoRenderer::new(camera, &ground, sensor, seed)?;
        let image = renderer.render(&body, &Isometry3::identity(), 0).left;
        let levels = grey_levels(&image, &region)?;
        sums[0] += corner_density(&image, &region, FAST_THRESHOLDS[0])?;
        sums[1] += corner_density(&image, &region, FAST_THRESHOLDS[1])?;
        sums[2] += levels.mean;
        sums[3] += levels.std;
        sums[4] += orb_density(&orb_features(&image)?, &region);
        first.get_or_insert(image);
    }
    let n = CALIBRATION_SEEDS.len() as f64;
    let image = first.unwrap_or_else(|| GrayImage::filled(1, 1, 0));
    Ok(RenderedSoil {
        soil: name,
        corners_per_10k_px: [sums[0] / n, sums[1] / n],
        grey_mean: sums[2] / n,
        grey_std: sums[3] / n,
        orb_per_10k_px: sums[4] / n,
        image,
    })
}

/// One soil's comparison: the rendered figures against its real
/// counterpart's (a box, or the mean of several).
#[derive(Debug, Clone, PartialEq)]
pub struct SoilComparison {
    /// The rendered soil.
    pub rendered: RenderedSoil,
    /// The real boxes it is compared with.
    pub real_boxes: Vec<&'static str>,
    /// Their mean FAST densities at [`FAST_THRESHOLDS`].
    pub real_corners_per_10k_px: [f64; 2],
    /// Their mean ORB keypoint density.
    pub real_orb_per_10k_px: f64,
    /// Their mean grey-level spread.
    pub real_grey_std: f64,
}

impl SoilComparison {
    /// Rendered over real corner density, per threshold.
    pub fn ratios(&self) -> [f64; 2] {
        [0, 1].map(|k| self.rendered.corners_per_10k_px[k] / self.real_corners_per_10k_px[k])
    }
}

/// Compares each soil, rendered as `spec` and `sensor` say, with its real
/// counterpart among `real` (the measured [`crate::real_images::REAL_BOXES`]): loose sand with
/// the PRL's sand seen by the mast camera (`prl-sand-navcam`, the same
/// view as the render's); gravel with the PRL's rocks and flagstones;
/// compact soil with the real box nearest to it in grey-level spread.
///
/// # Errors
/// As [`render_soil`]; [`TestbedError::InvalidConfig`] when `real` lacks a
/// box named here.
pub fn compare_soils(
    real: &[crate::real_images::BoxMeasurement],
    spec: &SceneSpec,
    sensor: SensorSpec,
) -> Result<Vec<SoilComparison>, TestbedError> {
    let find = |name: &str| {
        real.iter()
            .find(|m| m.region.name == name)
            .ok_or_else(|| TestbedError::InvalidConfig {
                field: format!("real box `{name}`"),
                expected: "a measured box of REAL_BOXES".into(),
            })
    };
    let compare = |rendered: RenderedSoil, names: Vec<&'static str>| {
        let boxes: Vec<_> = names.iter().map(|n| find(n)).collect::<Result<_, _>>()?;
        let n = boxes.len() as f64;
        let mean = |f: &dyn Fn(&crate::real_images::BoxMeasurement) -> f64| {
            boxes.iter().map(|b| f(b)).sum::<f64>() / n
        };
        Ok::<_, TestbedError>(SoilComparison {
            real_corners_per_10k_px: [
                mean(&|b| b.corners_per_10k_px[0]),
                mean(&|b| b.corners_per_10k_px[1]),
            ],
            real_orb_per_10k_px: mean(&|b| b.orb_per_10k_px),
            real_grey_std: mean(&|b| b.grey_std),
            rendered,
            real_boxes: names,
        })
    };
    let sand = render_soil(Soil::loose_sand(), spec, sensor)?;
    let gravel = render_soil(Soil::gravel(), spec, sensor)?;
    let compact = render_soil(Soil::compact(), spec, sensor)?;
    let nearest = real
        .iter()
        .min_by(|a, b| {
            let d = |m: &crate::real_images::BoxMeasurement| (m.grey_std - compact.grey_std).abs();
            d(a).total_cmp(&d(b))
        })
        .map(|m| m.region.name)
        .ok_or_else(|| TestbedError::InvalidConfig {
            field: "real boxes".into(),
            expected: "at least one measured box".into(),
        })?;
    Ok(vec![
        compare(sand, vec!["prl-sand-navcam"])?,
        compare(
            gravel,
            vec!["prl-flagstones", "prl-rock-large", "prl-rock-left"],
        )?,
        compare(compact, vec![nearest])?,
    ])
}

/// The comparison as a Markdown table (what `testbed/README.md` shows).
pub fn comparison_table(comparisons: &[SoilComparison]) -> String {
    let mut s = String::from(
        "| soil | real counterpart | FAST / 10⁴ px at 20: real | rendered | ratio | at 7: real | rendered | ratio | ORB / 10⁴ px: real | rendered | grey std: real | rendered |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for c in comparisons {
        let [r20, r7] = c.ratios();
        s.push_str(&format!(
            "| {} | {} | {:.1} | {:.1} | {:.2} | {:.1} | {:.1} | {:.2} | {:.1} | {:.1} | {:.1} | {:.1} |\n",
            c.rendered.soil,
            c.real_boxes
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", "),
            c.real_corners_per_10k_px[0],
            c.rendered.corners_per_10k_px[0],
            r20,
            c.real_corners_per_10k_px[1],
            c.rendered.corners_per_10k_px[1],
            r7,
            c.real_orb_per_10k_px,
            c.rendered.orb_per_10k_px,
            c.real_grey_std,
            c.rendered.grey_std,
        ));
    }
    s
}
