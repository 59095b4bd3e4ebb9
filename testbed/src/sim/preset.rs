//! Simulator settings and presets: the whole testbed (terrain, soils, slip,
//! sensors, rover, runs) from one seed.
//!
//! The `exoter-prl` preset mimics the paper's experiments in ESA's Planetary
//! Robotics Laboratory: a 9 × 9 m Mars-like area with slopes up to ~20°,
//! several training runs covering all manoeuvres, and a held-out test
//! traverse along a 42.3 m route (the paper's: 42.35 m). The same seed gives bit-identical
//! data: the terrain and soils draw from stream 0 of a ChaCha8 generator
//! seeded with it, run `i` from stream `i + 1`.

use gpodo_kinematics::RoverDescription;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::sim::driver::Driver;
use crate::sim::manoeuvre::{DriverParams, PlanarPose};
use crate::sim::route::{Route, SANDY_SLOPE_MIN_DEG, route_start_pose, route_waypoints};
use crate::sim::rover::World;
use crate::sim::sensors::SensorNoise;
use crate::sim::slip::SlipParams;
use crate::sim::soil::{Soil, SoilMap, SoilMapSpec};
use crate::sim::terrain::{Terrain, TerrainSpec};
use gpodo_datasets::log::RoverLog;

/// The random stream of the test route (the runs use streams 0 to
/// `training_runs + 1`).
const ROUTE_STREAM: u64 = 1 << 40;

/// Longest run the simulator accepts (s): one day.
pub const MAX_RUN_SECS: f64 = 86_400.0;

/// Named simulator presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's testbed: 4 training runs of 10 min and the 42.3 m test
    /// traverse.
    ExoterPrl,
}

impl Preset {
    /// The preset's name as written in configs (`exoter-prl`).
    pub fn name(self) -> &'static str {
        match self {
            Self::ExoterPrl => "exoter-prl",
        }
    }
}

impl std::str::FromStr for Preset {
    type Err = TestbedError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "exoter-prl" => Ok(Self::ExoterPrl),
            other => Err(TestbedError::InvalidConfig {
                field: "preset".into(),
                expected: format!("one of exoter-prl, found `{other}`"),
            }),
        }
    }
}

/// Everything the simulator needs; `SimulatorConfig::preset` fills it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulatorConfig {
    /// Seed of every random draw.
    pub seed: u64,
    /// Number of training runs. Default 4.
    pub training_runs: usize,
    /// Duration of each training run (s). Default 600.
    pub training_run_secs: f64,
    /// Longest the test traverse may take (s). Default 2400.
    pub test_max_secs: f64,
    /// Sensor period (s). Default 0.08 (12.5 Hz, as ExoTeR).
    pub dt_secs: f64,
    /// Native camera rate (Hz). Default 10.
    pub camera_rate_hz: f64,
    /// Steering joint speed limit (rad/s). Default 0.4.
    pub steering_rate_radps: f64,
    /// Std of the wheel sinkage fluctuation in soft ground (m). Default 0.002.
    pub sinkage_m: f64,
    /// Distance over which the sinkage decorrelates (m). Default 0.1.
    pub sinkage_length_m: f64,
    /// Terrain.
    pub terrain: TerrainSpec,
    /// Soils.
    pub soils: SoilMapSpec,
    /// Slip model.
    pub slip: SlipParams,
    /// Driver.
    pub driver: DriverParams,
    /// Sensor noise.
    pub sensors: SensorNoise,
    /// The test traverse's route. Default the paper's.
    pub route: Route,
}

impl Default for SimulatorConfig {
    fn default() -> Self {
        Self::preset(Preset::ExoterPrl, 0)
    }
}

/// The simulated testbed and its runs.
#[derive(Debug, Clone)]
pub struct SimulatedTestbed {
    /// The rover that drove.
    pub description: RoverDescription,
    /// The ground.
    pub terrain: Terrain,
    /// The soils.
    pub soils: SoilMap,
    /// Training runs.
    pub train: Vec<RoverLog>,
    /// Held-out test runs (the test traverse).
    pub test: Vec<RoverLog>,
}

impl SimulatorConfig {
    /// The settings of a preset with a seed.
    pub fn preset(preset: Preset, seed: u64) -> Self {
        match preset {
            Preset::ExoterPrl => Self {
                seed,
                training_runs: 4,
                training_run_secs: 600.0,
                test_max_secs: 2400.0,
                dt_secs: 0.08,
                camera_rate_hz: 10.0,
                steering_rate_radps: 0.4,
                sinkage_m: 0.002,
                sinkage_length_m: 0.1,
                terrain: TerrainSpec {
                    max_slope_deg: 20.0,
                    roughness_m: 0.008,
                    ..TerrainSpec::default()
                },
                soils: SoilMapSpec::default(),
                slip: SlipParams::default(),
                driver: DriverParams {
                    stop_time_fraction: 0.25,
                    speed_mps: 0.037,
                    ..DriverParams::default()
                },
                sensors: SensorNoise {
                    mocap_jitter_m: 5e-4,
                    ..SensorNoise::default()
                },
                route: Route::Paper,
            },
        }
    }

    /// Checks every field, naming the first bad one.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        let bad = |field: &str, expected: &str| {
            Err(TestbedError::InvalidConfig {
                field: field.into(),
                expected: expected.into(),
            })
        };
        // Durations are bounded so a typo cannot ask for years of samples.
        let duration = |v: f64| v.is_finite() && v > 0.0 && v <= MAX_RUN_SECS;
        if !(1..=1000).contains(&self.training_runs) {
            return bad("training_runs", "between 1 and 1000 runs");
        }
        if !duration(self.training_run_secs) {
            return bad("training_run_secs", "a duration in (0, 86400] s");
        }
        if !duration(self.test_max_secs) {
            return bad("test_max_secs", "a duration in (0, 86400] s");
        }
        if !(self.sinkage_m.is_finite() && (0.0..=0.05).contains(&self.sinkage_m)) {
            return bad("sinkage_m", "a height in [0, 0.05] m");
        }
        if !(self.sinkage_length_m.is_finite() && self.sinkage_length_m > 0.0) {
            return bad("sinkage_length_m", "a positive distance in m");
        }
        self.sensors.validate()?;
        if !(self.dt_secs.is_finite() && self.dt_secs > 0.0 && self.dt_secs <= 1.0) {
            return bad("dt_secs", "a sensor period in (0, 1] s");
        }
        if !(self.camera_rate_hz.is_finite() && self.camera_rate_hz > 0.0) {
            return bad("camera_rate_hz", "a positive rate in Hz");
        }
        if !(self.steering_rate_radps.is_finite() && self.steering_rate_radps > 0.0) {
            return bad("steering_rate_radps", "a positive rate in rad/s");
        }
        self.terrain.validate()?;
        self.soils.validate()?;
        self.slip.validate()?;
        self.driver.validate()?;
        Ok(())
    }

    fn rng(&self, stream: u64) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(stream);
        rng
    }

    /// Generates the testbed and drives every run.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] for bad settings,
    /// [`TestbedError::Simulation`] if a run fails.
    pub fn simulate(&self) -> Result<SimulatedTestbed, TestbedError> {
        self.validate()?;
        let description = RoverDescription::exoter();
        let mut rng = self.rng(0);
        let terrain = Terrain::generate(&self.terrain, &mut rng)?;
        let soils = SoilMap::generate(&self.soils, self.terrain.size_m, &mut rng)?;
        let slip = self.slip.clone().check()?;
        let world = World {
            description: &description,
            terrain: &terrain,
            soils: &soils,
            slip: &slip,
            noise: self.sensors,
            dt_secs: self.dt_secs,
            camera_rate_hz: self.camera_rate_hz,
            steering_rate_radps: self.steering_rate_radps,
            sinkage_m: self.sinkage_m,
            sinkage_length_m: self.sinkage_length_m,
        };
        let size = self.terrain.size_m;
        // The route draws from a stream of its own, apart from the runs'.
        let sandy_slope = |x: f64, y: f64| {
            let g = terrain.gradient(x, y);
            soils.soil_at(x, y).name == Soil::loose_sand().name
                && g.norm().atan() >= SANDY_SLOPE_MIN_DEG.to_radians()
        };
        let route = route_waypoints(self.route, size, &sandy_slope, &mut self.rng(ROUTE_STREAM))?;
        // Run `i` draws from stream `i + 1` whatever thread runs it, so the
        // runs are simulated in parallel with the same result as in series.
        let run = |i: usize| -> Result<RoverLog, TestbedError> {
            let mut rng = self.rng(i as u64 + 1);
            if i == self.training_runs {
                let mut driver = Driver::follow(self.driver.clone(), &route)?;
                let start = route_start_pose(&route);
                return world.run("test", &mut driver, start, self.test_max_secs, &mut rng);
            }
            let mut driver = Driver::training(self.driver.clone(), size)?;
            let margin = (self.driver.edge_margin_m + 0.5).min(size / 2.0);
            let start = PlanarPose {
                x_m: rng.random_range(margin..size - margin),
                y_m: rng.random_range(margin..size - margin),
                yaw_rad: rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            };
            let name = format!("train_{:02}", i + 1);
            world.run(&name, &mut driver, start, self.training_run_secs, &mut rng)
        };
        let mut train = (0..=self.training_runs)
            .into_par_iter()
            .map(run)
            .collect::<Result<Vec<_>, _>>()?;
        let test = train.split_off(self.training_runs);
        Ok(SimulatedTestbed {
            description,
            terrain,
            soils,
            train,
            test,
        })
    }
}
