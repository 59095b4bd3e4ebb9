//! How each soil looks: its albedo texture, its micro-relief and the
//! stones lying on it, and the lab's lighting. Every setting is in
//! [`SceneSpec`], serialisable, with its default documented; the defaults
//! of the soils' looks are calibrated against real images
//! (`testbed/README.md`, "Real ground images").

use serde::{Deserialize, Serialize};

use crate::TestbedError;

/// One soil's appearance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SoilLook {
    /// Mean albedo of the ground (0–1).
    pub albedo: f64,
    /// Albedo noise: the amplitude of each octave, from the coarsest.
    pub albedo_octaves: Vec<f64>,
    /// Cell of the coarsest albedo octave (m); each next octave halves it.
    pub albedo_cell_m: f64,
    /// Micro-relief (ripples, prints, clods): the height amplitude of each
    /// octave (m), from the coarsest; its shading is most of a loose
    /// soil's texture.
    pub relief_octaves_m: Vec<f64>,
    /// Cell of the coarsest relief octave (m).
    pub relief_cell_m: f64,
    /// Stones lying on the soil, from pebbles to rocks.
    pub stones: Vec<StoneSize>,
}

/// One size class of stones: half-ellipsoids of radius `r` and height
/// `height_ratio · r`, scattered uniformly on the soil.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoneSize {
    /// Stones per square metre of this soil.
    pub per_m2: f64,
    /// Radius range `[min, max]` (m), drawn uniformly.
    pub radius_m: [f64; 2],
    /// Height over radius.
    pub height_ratio: f64,
    /// Albedo range `[min, max]`, drawn uniformly per stone.
    pub albedo: [f64; 2],
}

/// The lab's lighting: one key light (a directional lamp) plus ambient
/// light, radiance `albedo · (ambient + key · max(0, n·l) · lit)` with
/// `lit` 0 in a cast shadow (of the slopes and the stones).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lighting {
    /// Key light's elevation above the horizon (rad; default 0.87, 50°).
    pub key_elevation_rad: f64,
    /// Key light's azimuth, the direction it comes from (rad from world
    /// +x towards +y; default 2.36, 135°).
    pub key_azimuth_rad: f64,
    /// Key light's intensity (default 0.75).
    pub key: f64,
    /// Ambient light (default 0.25).
    pub ambient: f64,
}

impl Default for Lighting {
    fn default() -> Self {
        Self {
            key_elevation_rad: 50f64.to_radians(),
            key_azimuth_rad: 135f64.to_radians(),
            key: 0.75,
            ambient: 0.25,
        }
    }
}

impl Lighting {
    /// The unit vector towards the key light (world frame, z up).
    pub fn towards_key(&self) -> nalgebra::Vector3<f64> {
        let (e, a) = (self.key_elevation_rad, self.key_azimuth_rad);
        nalgebra::Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin())
    }
}

/// The camera's scene beyond the simulator's geometry: the soils' looks,
/// the lighting, and what lies outside the test area.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SceneSpec {
    /// Compact soil.
    pub compact: SoilLook,
    /// Loose sand.
    pub loose_sand: SoilLook,
    /// Gravel.
    pub gravel: SoilLook,
    /// The lighting.
    pub lighting: Lighting,
    /// Beyond the test area the camera sees the lab's floor: flat at
    /// height 0, untextured, of this albedo (default 0.2).
    pub floor_albedo: f64,
    /// Radiance of a ray that meets no ground within 30 m (the dark hall;
    /// default 0.05).
    pub background: f64,
    /// Ground resolution of the precomputed height and radiance maps (m;
    /// default 0.0025).
    pub map_cell_m: f64,
}

impl Default for SceneSpec {
    /// The looks calibrated against the real images
    /// (`testbed/README.md`, "Real ground images"): each soil's FAST
    /// corner densities at thresholds 20 and 7 within a factor 1.5 of its
    /// real counterpart's. Rocks (stones of 3 cm and more) are a setting
    /// of their own, not calibrated.
    fn default() -> Self {
        let pebbles = |per_m2: f64| StoneSize {
            per_m2,
            radius_m: [0.004, 0.012],
            height_ratio: 0.6,
            albedo: [0.2, 0.35],
        };
        let rocks = |per_m2: f64, albedo: [f64; 2]| StoneSize {
            per_m2,
            radius_m: [0.04, 0.12],
            height_ratio: 0.7,
            albedo,
        };
        Self {
            compact: SoilLook {
                albedo: 0.4,
                albedo_octaves: vec![0.05, 0.04, 0.03, 0.02, 0.02, 0.025, 0.025, 0.025],
                albedo_cell_m: 0.4,
                relief_octaves_m: vec![0.004, 0.002, 0.0018, 0.0015, 0.0012, 0.0012],
                relief_cell_m: 0.2,
                stones: vec![pebbles(16.0)],
            },
            loose_sand: SoilLook {
                albedo: 0.42,
                albedo_octaves: vec![0.04, 0.03, 0.02, 0.012, 0.012, 0.014, 0.018, 0.018],
                albedo_cell_m: 0.5,
                relief_octaves_m: vec![0.005, 0.0025, 0.002, 0.002, 0.0015, 0.0012],
                relief_cell_m: 0.2,
                stones: vec![
                    StoneSize {
                        radius_m: [0.004, 0.01],
                        ..pebbles(15.0)
                    },
                    StoneSize {
                        radius_m: [0.03, 0.12],
                        ..rocks(0.5, [0.15, 0.3])
                    },
                ],
            },
            gravel: SoilLook {
                albedo: 0.38,
                albedo_octaves: vec![0.06, 0.05, 0.05, 0.05, 0.06, 0.07, 0.07],
                albedo_cell_m: 0.2,
                relief_octaves_m: vec![0.004, 0.002, 0.0015, 0.0015, 0.0012],
                relief_cell_m: 0.1,
                stones: vec![
                    StoneSize {
                        per_m2: 300.0,
                        radius_m: [0.006, 0.02],
                        height_ratio: 0.6,
                        albedo: [0.25, 0.5],
                    },
                    rocks(6.0, [0.15, 0.45]),
                ],
            },
            lighting: Lighting::default(),
            floor_albedo: 0.2,
            background: 0.05,
            map_cell_m: 0.0025,
        }
    }
}

fn invalid(field: String, expected: &str) -> TestbedError {
    TestbedError::InvalidConfig {
        field,
        expected: expected.into(),
    }
}

impl SoilLook {
    fn validate(&self, prefix: &str) -> Result<(), TestbedError> {
        let unit = |v: f64| v.is_finite() && (0.0..=1.0).contains(&v);
        if !unit(self.albedo) {
            return Err(invalid(format!("{prefix}.albedo"), "an albedo in [0, 1]"));
        }
        for (name, cell, amplitudes) in [
            ("albedo", self.albedo_cell_m, &self.albedo_octaves),
            ("relief", self.relief_cell_m, &self.relief_octaves_m),
        ] {
            if !(cell.is_finite() && cell > 0.0) {
                return Err(invalid(
                    format!("{prefix}.{name}_cell_m"),
                    "a positive cell size (m)",
                ));
            }
            if amplitudes.len() > 16 || !amplitudes.iter().all(|a| a.is_finite() && *a >= 0.0) {
                return Err(invalid(
                    format!("{prefix}.{name}_octaves"),
                    "at most 16 non-negative amplitudes",
                ));
            }
        }
        for (i, s) in self.stones.iter().enumerate() {
            let field = |f: &str| format!("{prefix}.stones[{i}].{f}");
            if !(s.per_m2.is_finite() && (0.0..=5000.0).contains(&s.per_m2)) {
                return Err(invalid(field("per_m2"), "a density in [0, 5000] per m²"));
            }
            let [r0, r1] = s.radius_m;
            if !(r0.is_finite() && r1.is_finite() && 0.0 < r0 && r0 <= r1 && r1 <= 0.5) {
                return Err(invalid(
                    field("radius_m"),
                    "[min, max] with 0 < min ≤ max ≤ 0.5 m",
                ));
            }
            if !(s.height_ratio.is_finite() && (0.0..=2.0).contains(&s.height_ratio)) {
                return Err(invalid(field("height_ratio"), "a ratio in [0, 2]"));
            }
            let [a0, a1] = s.albedo;
            if !(unit(a0) && unit(a1) && a0 <= a1) {
                return Err(invalid(field("albedo"), "[min, max] albedos in [0, 1]"));
            }
        }
        Ok(())
    }
}

impl SceneSpec {
    /// Checks every field.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming the field (under `prefix`).
    pub fn validate(&self, prefix: &str) -> Result<(), TestbedError> {
        self.compact.validate(&format!("{prefix}.compact"))?;
        self.loose_sand.validate(&format!("{prefix}.loose_sand"))?;
        self.gravel.validate(&format!("{prefix}.gravel"))?;
        let l = &self.lighting;
        if !(l.key_elevation_rad.is_finite()
            && l.key_elevation_rad > 0.0
            && l.key_elevation_rad <= std::f64::consts::FRAC_PI_2)
        {
            return Err(invalid(
                format!("{prefix}.lighting.key_elevation_rad"),
                "an elevation in (0, π/2] rad",
            ));
        }
        for (name, v) in [
            ("lighting.key", l.key),
            ("lighting.ambient", l.ambient),
            ("floor_albedo", self.floor_albedo),
            ("background", self.background),
        ] {
            if !(v.is_finite() && (0.0..=2.0).contains(&v)) {
                return Err(invalid(format!("{prefix}.{name}"), "a value in [0, 2]"));
            }
        }
        if !l.key_azimuth_rad.is_finite() {
            return Err(invalid(
                format!("{prefix}.lighting.key_azimuth_rad"),
                "a finite angle (rad)",
            ));
        }
        if !(self.map_cell_m.is_finite() && (0.0005..=0.05).contains(&self.map_cell_m)) {
            return Err(invalid(
                format!("{prefix}.map_cell_m"),
                "a cell in [0.0005, 0.05] m",
            ));
        }
        Ok(())
    }

    /// The look of `soil`, by its name (`compact`, `loose_sand`, `gravel`).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] for a soil of another name, which
    /// has no look.
    pub fn look_of(&self, soil: &crate::sim::soil::Soil) -> Result<&SoilLook, TestbedError> {
        match soil.name.as_str() {
            "compact" => Ok(&self.compact),
            "loose_sand" => Ok(&self.loose_sand),
            "gravel" => Ok(&self.gravel),
            other => Err(invalid(
                format!("soil `{other}`"),
                "a soil the camera has a look for: compact, loose_sand or gravel",
            )),
        }
    }
}
