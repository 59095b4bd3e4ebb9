//! Soils of the simulated testbed and the map of where each one lies.
//!
//! The PRL testbed mixes soil types (paper §V). Each [`Soil`] carries the
//! traction parameters that [`super::slip`] turns into wheel slip; a
//! [`SoilMap`] paints the area with random Voronoi patches of compact soil,
//! loose sand and gravel.
//!
//! Soil is deliberately *not* one of the regressor's inputs: the rover cannot
//! sense it, so the soil-dependent part of the odometry residual is what a
//! learner cannot explain from proprioception alone.

use nalgebra::Vector2;
use rand::Rng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::error::require;

/// Grid points per side used to estimate patch area fractions.
const AREA_GRID_POINTS: usize = 200;

/// Traction properties of one soil type.
///
/// Slip ratios are dimensionless, `s = 1 − v_actual / v_commanded` along the
/// motion direction (0 = perfect traction, 1 = spinning in place, < 0 =
/// skidding ahead of the wheels). See [`super::slip`] for how they combine.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Soil {
    /// Human-readable name, e.g. `"loose_sand"`.
    pub name: String,
    /// Longitudinal slip ratio on level ground (dimensionless, in [0, 0.9)).
    pub slip_base: f64,
    /// Gain of the slope term of the longitudinal slip (dimensionless): slip
    /// grows by `slope_slip_gain·(exp(k·θ_up) − 1)` on an uphill angle `θ_up`,
    /// `k` being [`super::slip::SlipParams::slope_rate_per_rad`].
    pub slope_slip_gain: f64,
    /// Downhill drift on a cross slope per unit of ground speed and of
    /// `sin(cross-slope angle)` (dimensionless; m/s of drift per m/s of speed).
    pub lateral_slip_gain: f64,
    /// Fraction of the commanded yaw rate lost in a turn on the spot
    /// (dimensionless, in [0, 1)); other turns lose a smaller share.
    pub turn_slip: f64,
    /// Standard deviation of the extra body vibration this soil causes at
    /// typical driving speed, m/s² (for the accelerometer model).
    pub vibration_mps2: f64,
    /// Matchable image features this soil offers per frame, relative to
    /// compact soil's (dimensionless, > 0): what the simulated tracker's
    /// feature supply reads under the camera's footprint. Measured as the
    /// stereo VO's inliers on the rendered camera (see
    /// `frontends/README.md`); no published per-soil counts were found.
    pub texture: f64,
}

impl Default for Soil {
    /// The compact preset.
    fn default() -> Self {
        Self::compact()
    }
}

impl Soil {
    /// Compact, cohesive soil: good traction (≈ 6% slip at 5°, 10% at 10°,
    /// 32% at 20°). `slip_base` 0.03, `slope_slip_gain` 0.04,
    /// `lateral_slip_gain` 0.15, `turn_slip` 0.05, `vibration_mps2` 0.02,
    /// `texture` 1 (the reference).
    pub fn compact() -> Self {
        Self {
            name: "compact".to_owned(),
            slip_base: 0.03,
            slope_slip_gain: 0.04,
            lateral_slip_gain: 0.15,
            turn_slip: 0.05,
            vibration_mps2: 0.02,
            texture: 1.0,
        }
    }

    /// Loose sand: poor traction whose slip rises steeply with slope, like the
    /// slip-versus-slope curves of Mars rovers (≈ 16% at 5°, 30% at 10°, 54%
    /// at 15°, the 0.9 clamp at 20° with the default slope rate). `slip_base`
    /// 0.08, `slope_slip_gain` 0.12, `lateral_slip_gain` 0.45, `turn_slip`
    /// 0.15, `vibration_mps2` 0.03, `texture` 1.3 (the stereo VO's inliers on
    /// the rendered sand, whose look is calibrated against ExoTeR's lab,
    /// over compact soil's: `experiments/examples/tracker_calibration.rs`).
    pub fn loose_sand() -> Self {
        Self {
            name: "loose_sand".to_owned(),
            slip_base: 0.08,
            slope_slip_gain: 0.12,
            lateral_slip_gain: 0.45,
            turn_slip: 0.15,
            vibration_mps2: 0.03,
            texture: 1.3,
        }
    }

    /// Gravel: intermediate traction, rough ride (≈ 10% slip at 5°, 18% at
    /// 10°, 55% at 20°). `slip_base` 0.05, `slope_slip_gain` 0.07,
    /// `lateral_slip_gain` 0.25, `turn_slip` 0.10, `vibration_mps2` 0.06,
    /// `texture` 1.9 (the stereo VO's inliers on
    /// the rendered gravel over compact soil's, as for sand).
    pub fn gravel() -> Self {
        Self {
            name: "gravel".to_owned(),
            slip_base: 0.05,
            slope_slip_gain: 0.07,
            lateral_slip_gain: 0.25,
            turn_slip: 0.10,
            vibration_mps2: 0.06,
            texture: 1.9,
        }
    }

    /// Checks every parameter, naming the first bad one (prefixed with the
    /// soil's name, e.g. `loose_sand.turn_slip`).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        let in_range = |v: f64, lo: f64, hi: f64| v.is_finite() && v >= lo && v < hi;
        let checks = [
            (
                "slip_base",
                in_range(self.slip_base, 0.0, 0.9),
                "a value in [0, 0.9)",
            ),
            (
                "slope_slip_gain",
                in_range(self.slope_slip_gain, 0.0, 10.0),
                "a value in [0, 10)",
            ),
            (
                "lateral_slip_gain",
                in_range(self.lateral_slip_gain, 0.0, 10.0),
                "a value in [0, 10)",
            ),
            (
                "turn_slip",
                in_range(self.turn_slip, 0.0, 1.0),
                "a value in [0, 1)",
            ),
            (
                "vibration_mps2",
                in_range(self.vibration_mps2, 0.0, 100.0),
                "a value in [0, 100)",
            ),
            (
                "texture",
                self.texture.is_finite() && self.texture > 0.0 && self.texture <= 10.0,
                "a value in (0, 10]",
            ),
        ];
        for (field, ok, expected) in checks {
            require(ok, &format!("{}.{field}", self.name), expected)?;
        }
        Ok(())
    }
}

/// How to paint the area with soils; read from configs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SoilMapSpec {
    /// Number of Voronoi patches. Default 24.
    pub cells: usize,
    /// Share of patches that are loose sand, in [0, 1]. Default 0.35.
    pub sand_fraction: f64,
    /// Share of patches that are gravel, in [0, 1]; the rest is compact.
    /// Default 0.25.
    pub gravel_fraction: f64,
    /// Parameters of the compact soil. Default [`Soil::compact`].
    pub compact: Soil,
    /// Parameters of the loose sand. Default [`Soil::loose_sand`].
    pub loose_sand: Soil,
    /// Parameters of the gravel. Default [`Soil::gravel`].
    pub gravel: Soil,
}

impl Default for SoilMapSpec {
    fn default() -> Self {
        Self {
            cells: 24,
            sand_fraction: 0.35,
            gravel_fraction: 0.25,
            compact: Soil::compact(),
            loose_sand: Soil::loose_sand(),
            gravel: Soil::gravel(),
        }
    }
}

impl SoilMapSpec {
    /// Checks every field, naming the first bad one.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        require(
            (1..=10_000).contains(&self.cells),
            "cells",
            "a value in [1, 10000]",
        )?;
        let fraction = |v: f64| v.is_finite() && (0.0..=1.0).contains(&v);
        require(
            fraction(self.sand_fraction),
            "sand_fraction",
            "a value in [0, 1]",
        )?;
        require(
            fraction(self.gravel_fraction),
            "gravel_fraction",
            "a value in [0, 1]",
        )?;
        require(
            self.sand_fraction + self.gravel_fraction <= 1.0,
            "gravel_fraction",
            "a value with sand_fraction + gravel_fraction <= 1",
        )?;
        self.compact.validate()?;
        self.loose_sand.validate()?;
        self.gravel.validate()
    }
}

/// One Voronoi patch: its seed point and soil index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    seed: Vector2<f64>,
    soil: usize,
}

/// Where each soil lies: the nearest-seed (Voronoi) patches over the area,
/// defined everywhere (points outside the area take the nearest patch).
#[derive(Clone, Debug, PartialEq)]
pub struct SoilMap {
    size_m: f64,
    soils: Vec<Soil>,
    cells: Vec<Cell>,
}

impl SoilMap {
    /// Index of the compact soil in [`SoilMap::soils`] of a generated map.
    pub const COMPACT: usize = 0;
    /// Index of the loose sand in [`SoilMap::soils`] of a generated map.
    pub const LOOSE_SAND: usize = 1;
    /// Index of the gravel in [`SoilMap::soils`] of a generated map.
    pub const GRAVEL: usize = 2;

    /// Draws `spec.cells` seeds uniformly over `[0, size_m]²` and gives
    /// `round(sand_fraction·cells)` of them loose sand,
    /// `round(gravel_fraction·cells)` gravel and the rest compact soil, in a
    /// random order. Deterministic given `rng`.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when `spec` or `size_m` is invalid.
    pub fn generate<R: Rng + ?Sized>(
        spec: &SoilMapSpec,
        size_m: f64,
        rng: &mut R,
    ) -> Result<Self, TestbedError> {
        spec.validate()?;
        require(
            size_m.is_finite() && size_m > 0.0,
            "size_m",
            "a finite value > 0",
        )?;
        let mut labels = patch_labels(spec);
        labels.shuffle(rng);
        let cells = labels
            .into_iter()
            .map(|soil| Cell {
                seed: Vector2::new(size_m * rng.random::<f64>(), size_m * rng.random::<f64>()),
                soil,
            })
            .collect();
        Ok(Self {
            size_m,
            soils: vec![
                spec.compact.clone(),
                spec.loose_sand.clone(),
                spec.gravel.clone(),
            ],
            cells,
        })
    }

    /// A map with one soil everywhere (its index is 0).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when `soil` or `size_m` is invalid.
    pub fn uniform(soil: Soil, size_m: f64) -> Result<Self, TestbedError> {
        soil.validate()?;
        require(
            size_m.is_finite() && size_m > 0.0,
            "size_m",
            "a finite value > 0",
        )?;
        Ok(Self {
            size_m,
            soils: vec![soil],
            cells: vec![Cell {
                seed: Vector2::repeat(size_m / 2.0),
                soil: 0,
            }],
        })
    }

    /// A map of given patches: `patches` are (seed point, soil) pairs, each
    /// soil's area the points nearer its seed than any other's.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when a soil, a seed or `size_m` is
    /// invalid, or there is no patch.
    pub fn from_patches(
        patches: Vec<((f64, f64), Soil)>,
        size_m: f64,
    ) -> Result<Self, TestbedError> {
        require(!patches.is_empty(), "patches", "at least one patch")?;
        require(
            size_m.is_finite() && size_m > 0.0,
            "size_m",
            "a finite value > 0",
        )?;
        let mut soils = Vec::with_capacity(patches.len());
        let mut cells = Vec::with_capacity(patches.len());
        for (i, ((x, y), soil)) in patches.into_iter().enumerate() {
            soil.validate()?;
            require(
                x.is_finite() && y.is_finite(),
                "patches",
                "finite seed points",
            )?;
            soils.push(soil);
            cells.push(Cell {
                seed: Vector2::new(x, y),
                soil: i,
            });
        }
        Ok(Self {
            size_m,
            soils,
            cells,
        })
    }

    /// The soil under world `(x, y)`.
    pub fn soil_at(&self, x: f64, y: f64) -> &Soil {
        &self.soils[self.soil_index_at(x, y)]
    }

    /// Index into [`SoilMap::soils`] of the soil under world `(x, y)`
    /// (non-finite coordinates give the first patch's soil).
    pub fn soil_index_at(&self, x: f64, y: f64) -> usize {
        let p = Vector2::new(x, y);
        self.cells
            .iter()
            .min_by(|a, b| {
                (a.seed - p)
                    .norm_squared()
                    .total_cmp(&(b.seed - p).norm_squared())
            })
            .map_or(0, |cell| cell.soil)
    }

    /// All soils of the map, indexed as [`SoilMap::soil_index_at`] returns.
    pub fn soils(&self) -> &[Soil] {
        &self.soils
    }

    /// Side of the mapped area, metres.
    pub fn size_m(&self) -> f64 {
        self.size_m
    }

    /// Fraction of the area covered by soil `index`, estimated on a 200×200
    /// grid of cell centres.
    pub fn area_fraction(&self, index: usize) -> f64 {
        let step = self.size_m / AREA_GRID_POINTS as f64;
        let coordinate = |i: usize| (i as f64 + 0.5) * step;
        let hits = (0..AREA_GRID_POINTS)
            .flat_map(|i| (0..AREA_GRID_POINTS).map(move |j| (i, j)))
            .filter(|&(i, j)| self.soil_index_at(coordinate(i), coordinate(j)) == index)
            .count();
        hits as f64 / (AREA_GRID_POINTS * AREA_GRID_POINTS) as f64
    }
}

/// Soil labels of the patches before shuffling.
fn patch_labels(spec: &SoilMapSpec) -> Vec<usize> {
    let n = spec.cells;
    let sand = ((spec.sand_fraction * n as f64).round() as usize).min(n);
    let gravel = ((spec.gravel_fraction * n as f64).round() as usize).min(n - sand);
    (0..n)
        .map(|i| match i {
            i if i < sand => SoilMap::LOOSE_SAND,
            i if i < sand + gravel => SoilMap::GRAVEL,
            _ => SoilMap::COMPACT,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn default_map(seed: u64) -> SoilMap {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        SoilMap::generate(&SoilMapSpec::default(), 9.0, &mut rng).unwrap()
    }

    #[test]
    fn presets_order_traction_from_compact_to_sand() {
        let (c, g, s) = (Soil::compact(), Soil::gravel(), Soil::loose_sand());
        assert!(c.slip_base < g.slip_base && g.slip_base < s.slip_base);
        assert!(c.slope_slip_gain < g.slope_slip_gain && g.slope_slip_gain < s.slope_slip_gain);
        assert!(c.lateral_slip_gain < s.lateral_slip_gain && c.turn_slip < s.turn_slip);
        for soil in [c, g, s] {
            soil.validate().unwrap();
        }
    }

    #[test]
    fn sand_covers_roughly_a_third_of_the_area() {
        let fractions: Vec<f64> = (0..10)
            .map(|seed| default_map(seed).area_fraction(SoilMap::LOOSE_SAND))
            .collect();
        let mean = fractions.iter().sum::<f64>() / fractions.len() as f64;
        assert!((0.28..=0.42).contains(&mean), "mean sand fraction {mean}");
        assert!(
            fractions.iter().all(|f| (0.15..=0.6).contains(f)),
            "{fractions:?}"
        );
    }

    #[test]
    fn area_fractions_of_all_soils_sum_to_one() {
        let map = default_map(3);
        let total: f64 = (0..map.soils().len()).map(|i| map.area_fraction(i)).sum();
        assert!((total - 1.0).abs() < 1e-12);
    }

    #[test]
    fn soil_at_agrees_with_soil_index_at_and_is_defined_outside_the_area() {
        let map = default_map(4);
        for &(x, y) in &[(0.5, 0.5), (4.5, 4.5), (-20.0, 3.0), (f64::NAN, 1.0)] {
            assert_eq!(map.soil_at(x, y), &map.soils()[map.soil_index_at(x, y)]);
        }
    }

    #[test]
    fn a_map_from_patches_puts_each_soil_nearest_its_seed() {
        let map = SoilMap::from_patches(
            vec![
                ((2.0, 4.5), Soil::loose_sand()),
                ((7.0, 4.5), Soil::gravel()),
            ],
            9.0,
        )
        .unwrap();
        assert_eq!(map.soil_at(4.4, 1.0).name, "loose_sand");
        assert_eq!(map.soil_at(4.6, 8.0).name, "gravel");
        let err = SoilMap::from_patches(Vec::new(), 9.0).unwrap_err();
        assert!(err.to_string().contains("patches"), "{err}");
        let bad = SoilMap::from_patches(vec![((f64::NAN, 0.0), Soil::compact())], 9.0);
        assert!(bad.is_err());
    }

    #[test]
    fn same_seed_gives_the_same_map() {
        assert_eq!(default_map(5), default_map(5));
    }

    #[test]
    fn uniform_map_has_one_soil_everywhere() {
        let map = SoilMap::uniform(Soil::loose_sand(), 9.0).unwrap();
        assert_eq!(map.soil_at(1.0, 8.0).name, "loose_sand");
        assert_eq!(map.area_fraction(0), 1.0);
    }

    #[test]
    fn spec_validation_names_the_bad_field() {
        let spec = SoilMapSpec {
            sand_fraction: 0.8,
            gravel_fraction: 0.5,
            ..SoilMapSpec::default()
        };
        let err = spec.validate().unwrap_err();
        assert!(
            matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "gravel_fraction")
        );
        let mut spec = SoilMapSpec::default();
        spec.loose_sand.turn_slip = 1.5;
        let err = spec.validate().unwrap_err();
        assert!(
            matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "loose_sand.turn_slip")
        );
    }
}
