//! The ground of the simulated testbed: a smooth, analytic height field.
//!
//! It stands in for the Mars-like 9×9 m area of ESA's Planetary Robotics Lab
//! (paper §V): a gentle tilted plane, a few Gaussian hills and dips near the
//! middle of the area, and low-amplitude sinusoidal bumps (the small-scale
//! roughness that makes the bogies and the IMU see vibrations). World frame:
//! `x`, `y` horizontal over `[0, size]×[0, size]`, `z` up, heights in metres.
//!
//! The hills and the plane are rescaled after drawing so that the steepest
//! slope on a dense grid over the area matches the requested maximum; the
//! achieved value is stored ([`Terrain::max_slope_deg`]). Everything is a
//! closed-form sum, so heights and gradients are exact, smooth and finite
//! everywhere, also outside the area.

use std::f64::consts::{PI, TAU};

use nalgebra::{Vector2, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::error::require;

/// Number of sinusoidal components of the small-scale roughness.
const ROUGHNESS_WAVES: usize = 6;
/// Wavelength range of the roughness components, in metres.
const ROUGHNESS_WAVELENGTH_M: (f64, f64) = (0.5, 1.5);
/// Hill centres are drawn in this fraction range of the area side (the middle).
const HILL_CENTRE_FRACTION: (f64, f64) = (0.25, 0.75);
/// Hill widths (Gaussian σ) as a fraction of the area side.
const HILL_WIDTH_FRACTION: (f64, f64) = (0.08, 0.2);
/// Unscaled hill height magnitudes (the whole shape is rescaled afterwards).
const HILL_HEIGHT: (f64, f64) = (0.4, 1.0);
/// Probability that a drawn feature is a hill rather than a dip.
const HILL_PROBABILITY: f64 = 0.7;
/// Unscaled slope of the background plane (rise over run).
const PLANE_SLOPE: (f64, f64) = (0.02, 0.06);
/// Target spacing of the grid on which the maximum slope is measured, metres.
const SLOPE_GRID_SPACING_M: f64 = 0.05;
/// Upper bound on grid points per side (keeps huge areas cheap).
const SLOPE_GRID_MAX_POINTS: usize = 401;

/// What terrain to generate; read from configs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TerrainSpec {
    /// Side of the square test area, metres. Default 9.0 (the PRL testbed).
    pub size_m: f64,
    /// Number of Gaussian hills and dips. Default 7.
    pub hills: usize,
    /// Steepest slope over the area, degrees, in (0, 60). Default 20.
    pub max_slope_deg: f64,
    /// RMS height of the small-scale sinusoidal bumps, metres, in [0, 0.05].
    /// Default 0.004.
    pub roughness_m: f64,
}

impl Default for TerrainSpec {
    fn default() -> Self {
        Self {
            size_m: 9.0,
            hills: 7,
            max_slope_deg: 20.0,
            roughness_m: 0.004,
        }
    }
}

impl TerrainSpec {
    /// Checks every field, naming the first bad one.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] with the field name and the expected
    /// range.
    pub fn validate(&self) -> Result<(), TestbedError> {
        require(
            self.size_m.is_finite() && self.size_m > 0.0 && self.size_m <= 1000.0,
            "size_m",
            "a value in (0, 1000]",
        )?;
        require(self.hills <= 200, "hills", "at most 200")?;
        require(
            self.max_slope_deg.is_finite() && self.max_slope_deg > 0.0 && self.max_slope_deg < 60.0,
            "max_slope_deg",
            "a value in (0, 60)",
        )?;
        require(
            self.roughness_m.is_finite() && (0.0..=0.05).contains(&self.roughness_m),
            "roughness_m",
            "a value in [0, 0.05]",
        )
    }
}

/// One Gaussian hill (positive height) or dip (negative height).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hill {
    centre: Vector2<f64>,
    height_m: f64,
    width_m: f64,
}

impl Hill {
    fn bell(&self, p: Vector2<f64>) -> f64 {
        let r2 = (p - self.centre).norm_squared();
        self.height_m * (-r2 / (2.0 * self.width_m * self.width_m)).exp()
    }

    fn gradient(&self, p: Vector2<f64>) -> Vector2<f64> {
        let d = p - self.centre;
        -self.bell(p) / (self.width_m * self.width_m) * d
    }
}

/// One sinusoidal bump component `a·sin(k·p + φ)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Wave {
    wavevector_radpm: Vector2<f64>,
    amplitude_m: f64,
    phase_rad: f64,
}

impl Wave {
    fn height(&self, p: Vector2<f64>) -> f64 {
        self.amplitude_m * (self.wavevector_radpm.dot(&p) + self.phase_rad).sin()
    }

    fn gradient(&self, p: Vector2<f64>) -> Vector2<f64> {
        self.amplitude_m
            * (self.wavevector_radpm.dot(&p) + self.phase_rad).cos()
            * self.wavevector_radpm
    }
}

/// The large-scale shape: hills plus a plane through the area's centre.
#[derive(Clone, Debug, PartialEq)]
struct Shape {
    hills: Vec<Hill>,
    plane_gradient: Vector2<f64>,
    centre: Vector2<f64>,
}

impl Shape {
    fn height(&self, p: Vector2<f64>) -> f64 {
        let plane = self.plane_gradient.dot(&(p - self.centre));
        plane + self.hills.iter().map(|h| h.bell(p)).sum::<f64>()
    }

    fn gradient(&self, p: Vector2<f64>) -> Vector2<f64> {
        self.hills
            .iter()
            .fold(self.plane_gradient, |g, h| g + h.gradient(p))
    }

    fn scaled(mut self, factor: f64) -> Self {
        self.plane_gradient *= factor;
        for hill in &mut self.hills {
            hill.height_m *= factor;
        }
        self
    }
}

/// An analytic height field `z = h(x, y)` over the test area (world frame).
#[derive(Clone, Debug, PartialEq)]
pub struct Terrain {
    size_m: f64,
    shape: Shape,
    waves: Vec<Wave>,
    offset_m: f64,
    max_slope_deg: f64,
}

impl Terrain {
    /// Draws a terrain from `spec`: hills near the middle, a gentle plane and
    /// bumps, with the hills and plane rescaled so that the steepest slope on
    /// a ~5 cm grid over the area equals `spec.max_slope_deg`. Heights are
    /// shifted to a zero mean over the area. Deterministic given `rng`.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when `spec` is invalid, or naming
    /// `roughness_m` when the bumps alone are already steeper than
    /// `max_slope_deg`.
    pub fn generate<R: Rng + ?Sized>(
        spec: &TerrainSpec,
        rng: &mut R,
    ) -> Result<Self, TestbedError> {
        spec.validate()?;
        let shape = random_shape(spec, rng);
        let waves = random_waves(spec.roughness_m, rng);
        let grid = slope_grid(spec.size_m);
        let shape_grads: Vec<_> = grid.iter().map(|&p| shape.gradient(p)).collect();
        let wave_grads: Vec<_> = grid.iter().map(|&p| wave_gradient(&waves, p)).collect();
        let target = spec.max_slope_deg.to_radians().tan();
        let factor = solve_shape_scale(&shape_grads, &wave_grads, target)?;
        let achieved = max_slope(&shape_grads, &wave_grads, factor);
        let mut terrain = Self {
            size_m: spec.size_m,
            shape: shape.scaled(factor),
            waves,
            offset_m: 0.0,
            max_slope_deg: achieved.atan().to_degrees(),
        };
        terrain.offset_m =
            grid.iter().map(|p| terrain.height(p.x, p.y)).sum::<f64>() / grid.len() as f64;
        Ok(terrain)
    }

    /// Exactly level ground at height 0.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming `size_m` when it is not a finite
    /// positive value.
    pub fn flat(size_m: f64) -> Result<Self, TestbedError> {
        Self::plane(size_m, 0.0, 0.0)
    }

    /// An exact inclined plane of `slope_deg` (in [0, 90)) that descends
    /// towards the world azimuth `downhill_azimuth_rad` (0 = +x, π/2 = +y);
    /// height 0 at the area's centre, no bumps.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming `size_m`, `slope_deg` or
    /// `downhill_azimuth_rad`.
    pub fn plane(
        size_m: f64,
        slope_deg: f64,
        downhill_azimuth_rad: f64,
    ) -> Result<Self, TestbedError> {
        require(
            size_m.is_finite() && size_m > 0.0,
            "size_m",
            "a finite value > 0",
        )?;
        require(
            slope_deg.is_finite() && (0.0..90.0).contains(&slope_deg),
            "slope_deg",
            "a value in [0, 90)",
        )?;
        require(
            downhill_azimuth_rad.is_finite(),
            "downhill_azimuth_rad",
            "a finite angle",
        )?;
        let downhill = Vector2::new(downhill_azimuth_rad.cos(), downhill_azimuth_rad.sin());
        let shape = Shape {
            hills: Vec::new(),
            plane_gradient: -slope_deg.to_radians().tan() * downhill,
            centre: Vector2::repeat(size_m / 2.0),
        };
        Ok(Self {
            size_m,
            shape,
            waves: Vec::new(),
            offset_m: 0.0,
            max_slope_deg: slope_deg,
        })
    }

    /// Height of the ground at world `(x, y)`, metres. Finite everywhere.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let p = Vector2::new(x, y);
        self.shape.height(p) + self.waves.iter().map(|w| w.height(p)).sum::<f64>() - self.offset_m
    }

    /// Exact gradient `(∂h/∂x, ∂h/∂y)` at world `(x, y)` (rise over run).
    pub fn gradient(&self, x: f64, y: f64) -> Vector2<f64> {
        let p = Vector2::new(x, y);
        self.shape.gradient(p) + wave_gradient(&self.waves, p)
    }

    /// Unit upward surface normal at world `(x, y)` (its `z` is > 0).
    pub fn normal(&self, x: f64, y: f64) -> Vector3<f64> {
        let g = self.gradient(x, y);
        Vector3::new(-g.x, -g.y, 1.0).normalize()
    }

    /// Side of the square area, metres.
    pub fn size_m(&self) -> f64 {
        self.size_m
    }

    /// Steepest slope over the area in degrees: the value achieved on the
    /// generation grid (or the exact slope of a plane).
    pub fn max_slope_deg(&self) -> f64 {
        self.max_slope_deg
    }
}

fn random_shape<R: Rng + ?Sized>(spec: &TerrainSpec, rng: &mut R) -> Shape {
    let size = spec.size_m;
    let hills = (0..spec.hills)
        .map(|_| {
            let centre = Vector2::new(
                size * uniform(rng, HILL_CENTRE_FRACTION),
                size * uniform(rng, HILL_CENTRE_FRACTION),
            );
            let sign = if rng.random::<f64>() < HILL_PROBABILITY {
                1.0
            } else {
                -1.0
            };
            Hill {
                centre,
                height_m: sign * uniform(rng, HILL_HEIGHT),
                width_m: size * uniform(rng, HILL_WIDTH_FRACTION),
            }
        })
        .collect();
    let azimuth = uniform(rng, (0.0, TAU));
    let plane_gradient = uniform(rng, PLANE_SLOPE) * Vector2::new(azimuth.cos(), azimuth.sin());
    Shape {
        hills,
        plane_gradient,
        centre: Vector2::repeat(size / 2.0),
    }
}

/// Bumps whose summed RMS height is `roughness_m` (each component has RMS
/// `a/√2`; amplitudes are normalised so that `sqrt(Σ a²/2) = roughness_m`).
fn random_waves<R: Rng + ?Sized>(roughness_m: f64, rng: &mut R) -> Vec<Wave> {
    let drawn: Vec<(f64, f64, f64, f64)> = (0..ROUGHNESS_WAVES)
        .map(|_| {
            let weight = uniform(rng, (0.5, 1.0));
            let wavelength = uniform(rng, ROUGHNESS_WAVELENGTH_M);
            (
                weight,
                wavelength,
                uniform(rng, (0.0, TAU)),
                uniform(rng, (0.0, TAU)),
            )
        })
        .collect();
    let weight_norm = drawn.iter().map(|d| d.0 * d.0).sum::<f64>().sqrt();
    drawn
        .into_iter()
        .map(|(weight, wavelength, direction, phase_rad)| Wave {
            wavevector_radpm: 2.0 * PI / wavelength
                * Vector2::new(direction.cos(), direction.sin()),
            amplitude_m: roughness_m * weight * 2f64.sqrt() / weight_norm,
            phase_rad,
        })
        .collect()
}

fn wave_gradient(waves: &[Wave], p: Vector2<f64>) -> Vector2<f64> {
    waves
        .iter()
        .fold(Vector2::zeros(), |g, w| g + w.gradient(p))
}

/// Grid points over `[0, size]²` at about [`SLOPE_GRID_SPACING_M`] spacing.
fn slope_grid(size_m: f64) -> Vec<Vector2<f64>> {
    let per_side =
        ((size_m / SLOPE_GRID_SPACING_M).ceil() as usize + 1).clamp(2, SLOPE_GRID_MAX_POINTS);
    let step = size_m / (per_side - 1) as f64;
    (0..per_side)
        .flat_map(|i| (0..per_side).map(move |j| Vector2::new(i as f64 * step, j as f64 * step)))
        .collect()
}

/// Steepest `|factor·∇shape + ∇bumps|` over the grid (rise over run).
fn max_slope(shape: &[Vector2<f64>], waves: &[Vector2<f64>], factor: f64) -> f64 {
    shape
        .iter()
        .zip(waves)
        .map(|(s, w)| (factor * s + w).norm())
        .fold(0.0, f64::max)
}

/// The factor for the shape that makes the grid's steepest slope equal
/// `target`. The steepest slope is convex in the factor and starts below the
/// target, so bisection finds the single crossing.
fn solve_shape_scale(
    shape: &[Vector2<f64>],
    waves: &[Vector2<f64>],
    target: f64,
) -> Result<f64, TestbedError> {
    let bumps_alone = max_slope(shape, waves, 0.0);
    require(
        bumps_alone < target,
        "roughness_m",
        "bumps whose slope stays below max_slope_deg",
    )?;
    let shape_alone = max_slope(shape, &vec![Vector2::zeros(); shape.len()], 1.0);
    let (mut lo, mut hi) = (
        0.0,
        (target + bumps_alone) / shape_alone.max(f64::MIN_POSITIVE),
    );
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if max_slope(shape, waves, mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

fn uniform<R: Rng + ?Sized>(rng: &mut R, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

#[cfg(test)]
mod tests;
