//! The simulator against the odometry model: without slip and sensor noise
//! the residual is only what the model cannot represent (terrain curvature,
//! unknown contact angles), and the same seed gives the same data.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_datasets::log::RoverLog;
use gpodo_datasets::residuals::{ResidualConfig, residual_dataset};
use gpodo_kinematics::{
    ContactAngleSource, RoverDescription, WeightedJacobianConfig, WeightedJacobianModel,
};
use gpodo_testbed::sim::driver::Driver;
use gpodo_testbed::sim::manoeuvre::{DriverParams, PlanarPose};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_testbed::sim::rover::World;
use gpodo_testbed::sim::sensors::SensorNoise;
use gpodo_testbed::sim::slip::SlipParams;
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::{Terrain, TerrainSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn frictionless_slip() -> SlipParams {
    SlipParams {
        downhill_skid_factor: 0.0,
        cross_slope_factor: 0.0,
        load_slip_gain: 0.0,
        lateral_scale: 0.0,
        turn_on_spot_factor: 0.0,
        point_turn_factor: 0.0,
        ackermann_factor: 0.0,
        slip_noise_std: 0.0,
        lateral_noise_ratio: 0.0,
        turn_slip_noise_std: 0.0,
        yaw_noise_rad_per_m: 0.0,
        ..SlipParams::default()
    }
}

fn perfect_soil() -> Soil {
    Soil {
        name: "perfect".into(),
        slip_base: 0.0,
        slope_slip_gain: 0.0,
        lateral_slip_gain: 0.0,
        turn_slip: 0.0,
        vibration_mps2: 0.0,
        texture: 1.0,
    }
}

fn no_slip_run(terrain: &Terrain, secs: f64) -> RoverLog {
    no_slip_run_with_sinkage(terrain, secs, 0.0)
}

fn no_slip_run_with_sinkage(terrain: &Terrain, secs: f64, sinkage_m: f64) -> RoverLog {
    let description = RoverDescription::exoter();
    let soils = SoilMap::uniform(perfect_soil(), terrain.size_m()).unwrap();
    let slip = frictionless_slip().check().unwrap();
    let world = World {
        description: &description,
        terrain,
        soils: &soils,
        slip: &slip,
        noise: SensorNoise::none(),
        dt_secs: 0.08,
        camera_rate_hz: 10.0,
        steering_rate_radps: 0.4,
        sinkage_m,
        sinkage_length_m: 0.1,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut driver = Driver::training(DriverParams::default(), terrain.size_m()).unwrap();
    let start = PlanarPose {
        x_m: 4.0,
        y_m: 4.5,
        yaw_rad: 0.3,
    };
    world
        .run("no_slip", &mut driver, start, secs, &mut rng)
        .unwrap()
}

/// Median and maximum |residual| per axis, one row per step, over the steps
/// that `keep` accepts; also how many steps were kept.
fn residual_stats(
    log: &RoverLog,
    contact_angles: ContactAngleSource,
    keep: impl Fn(usize) -> bool,
) -> ([f64; 3], [f64; 3], usize) {
    let config = WeightedJacobianConfig {
        contact_angles,
        ..Default::default()
    };
    let model = WeightedJacobianModel::new(RoverDescription::exoter(), config).unwrap();
    let rows = residual_dataset(
        &[log],
        &model,
        0.07,
        &ResidualConfig {
            window_secs: None,
            absolute_targets: true,
            ..Default::default()
        },
    )
    .unwrap();
    let kept: Vec<usize> = (0..rows.len()).filter(|&k| keep(k)).collect();
    let mut median = [0.0; 3];
    let mut max = [0.0; 3];
    for j in 0..3 {
        let mut col: Vec<f64> = kept.iter().map(|&k| rows.targets.get(k, j)).collect();
        col.sort_by(f64::total_cmp);
        median[j] = col[col.len() / 2];
        max[j] = col[col.len() - 1];
    }
    (median, max, kept.len())
}

/// Whether the rover drives at step `k` without moving its steering.
fn driving_straight_wheels(log: &RoverLog, k: usize) -> bool {
    let s = &log.samples[k];
    s.wheels.iter().any(|w| w.rate_radps.abs() > 0.1)
        && s.steering.iter().all(|j| j.rate_radps == 0.0)
}

#[test]
fn without_slip_on_a_plane_the_model_recovers_the_motion() {
    let terrain = Terrain::plane(9.0, 12.0, 0.7).unwrap();
    let log = no_slip_run(&terrain, 240.0);
    let (_, max, _) = residual_stats(&log, ContactAngleSource::AssumeZero, |_| true);
    println!("plane, no slip: max |residual| = {max:?}");
    // What remains is the chord of a turning step (v·ω·dt/2 ≈ 1e-4 m/s).
    assert!(max.iter().all(|v| *v < 2e-4), "{max:?}");
    // Driving straight up, down and across the 12° slope, the model is
    // exact to round-off.
    let straight = |k: usize| {
        driving_straight_wheels(&log, k) && log.samples[k].gyro_radps().unwrap().norm() < 1e-12
    };
    let (_, max, n) = residual_stats(&log, ContactAngleSource::AssumeZero, straight);
    println!("plane, no slip, {n} straight steps: max |residual| = {max:?}");
    assert!(n > 300, "only {n} straight steps");
    assert!(max.iter().all(|v| *v < 1e-12), "{max:?}");
}

#[test]
fn without_slip_on_hills_the_residual_is_small() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let terrain = Terrain::generate(&TerrainSpec::default(), &mut rng).unwrap();
    let log = no_slip_run(&terrain, 360.0);
    for source in [
        ContactAngleSource::AssumeZero,
        ContactAngleSource::FromSample,
    ] {
        let (median, max, n) = residual_stats(&log, source, |k| driving_straight_wheels(&log, k));
        println!("hills, no slip, {source:?}: {n} driving steps, median {median:?}, max {max:?}");
        assert!(n > 1000, "only {n} driving steps");
        // Terrain curvature is what the model cannot represent while
        // driving. (Steering in place is left out: a contact point off the
        // steering axis scrubs, which is slip the model rightly sees.)
        // Forward and lateral speed to 0.2 mm/s; the vertical one depends on
        // the contact angles the model assumes to be zero (1 mm/s).
        assert!(
            median[0] < 2e-4 && median[1] < 2e-4 && median[2] < 1e-3,
            "{source:?}: {median:?}"
        );
        assert!(max.iter().all(|v| *v < 3e-3), "{source:?}: {max:?}");
    }
}

#[test]
fn same_seed_gives_bit_identical_runs() {
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 5);
    config.training_runs = 1;
    config.training_run_secs = 30.0;
    config.test_max_secs = 30.0;
    config.training_runs = 3;
    let a = config.simulate().unwrap();
    // Same numbers whatever the thread count.
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = one_thread.install(|| config.simulate()).unwrap();
    assert_eq!(a.train, b.train);
    assert_eq!(a.test, b.test);
    config.seed = 6;
    let c = config.simulate().unwrap();
    assert_ne!(a.train, c.train);
}

#[test]
fn noiseless_imu_reads_the_ground_truth_motion() {
    let terrain = Terrain::plane(9.0, 10.0, 2.0).unwrap();
    let log = no_slip_run_with_sinkage(&terrain, 120.0, 0.002);
    let dt = 0.08;
    let gt = &log.ground_truth;
    let mut sinking = 0;
    for k in 1..log.samples.len() - 1 {
        let s = &log.samples[k];
        let r = gt[k].rotation;
        // Specific force: acceleration minus gravity, in the body frame.
        let a = (gt[k + 1].translation.vector - 2.0 * gt[k].translation.vector
            + gt[k - 1].translation.vector)
            / (dt * dt);
        let f = r.inverse() * (a + nalgebra::Vector3::new(0.0, 0.0, 9.81));
        let imu = s.imu.unwrap();
        assert!(
            (imu.accel_mps2 - f).amax() < 1e-6,
            "k={k}: {} vs {f}",
            imu.accel_mps2
        );
        if (gt[k + 1].translation.z - gt[k].translation.z).abs() > 1e-6 {
            sinking += 1;
        }
        // Gyro: the body rate over the step; attitude: roll and pitch of the pose.
        let w = (gt[k].rotation.inverse() * gt[k + 1].rotation).scaled_axis() / dt;
        assert!((imu.gyro_radps - w).amax() < 1e-9, "k={k}");
        let (roll, pitch, _) = r.euler_angles();
        assert!((imu.roll_rad - roll).abs() < 1e-12 && (imu.pitch_rad - pitch).abs() < 1e-12);
    }
    assert!(sinking > 100, "the run never sank: {sinking}");
}

#[test]
fn bad_simulator_settings_are_rejected_by_name() {
    let base = SimulatorConfig::preset(Preset::ExoterPrl, 1);
    type Change = Box<dyn Fn(&mut SimulatorConfig)>;
    let cases: Vec<(&str, Change)> = vec![
        (
            "training_run_secs",
            Box::new(|c| c.training_run_secs = 1e12),
        ),
        ("training_runs", Box::new(|c| c.training_runs = 0)),
        ("sinkage_m", Box::new(|c| c.sinkage_m = -1.0)),
        (
            "sensors.gyro_noise_radps",
            Box::new(|c| c.sensors.gyro_noise_radps = -1e-3),
        ),
    ];
    for (field, change) in cases {
        let mut c = base.clone();
        change(&mut c);
        let err = c.simulate().unwrap_err().to_string();
        assert!(err.contains(field), "{field}: {err}");
    }
}

/// The median ratio of the model's speed to the true one over the moving
/// seconds of `config`'s training runs, with every wheel rate multiplied
/// by `wheel_scale` (a unit error).
fn speed_ratio(config: &SimulatorConfig, wheel_scale: f64) -> f64 {
    let bed = config.simulate().unwrap();
    let model =
        WeightedJacobianModel::new(bed.description.clone(), WeightedJacobianConfig::default())
            .unwrap();
    let mut steps = Vec::new();
    for log in &bed.train {
        let mut log = log.clone();
        for s in &mut log.samples {
            for w in &mut s.wheels {
                w.rate_radps *= wheel_scale;
            }
        }
        steps.push(
            gpodo_datasets::residuals::log_steps(&log, &model, bed.description.wheel_radius_m)
                .unwrap(),
        );
    }
    gpodo_datasets::speed_check::median_speed_ratio(&steps).unwrap()
}

#[test]
fn the_speed_check_passes_slipping_runs_and_catches_a_two_pi_unit_error() {
    use gpodo_datasets::speed_check::plausible;
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 7);
    config.training_runs = 2;
    config.training_run_secs = 120.0;
    config.test_max_secs = 10.0;
    let ratio = speed_ratio(&config, 1.0);
    assert!(plausible(ratio) && (ratio - 1.0).abs() < 0.3, "{ratio}");
    // All loose sand: the rover slips, the check stays silent.
    config.soils.sand_fraction = 1.0;
    config.soils.gravel_fraction = 0.0;
    let sand = speed_ratio(&config, 1.0);
    assert!(plausible(sand), "{sand}");
    // Wheel speeds in rpm read as rad/s would be 60/2π too large; rad/s
    // read as rpm, 2π/60 too small; here a 2π error either way.
    let fast = speed_ratio(&config, std::f64::consts::TAU);
    let slow = speed_ratio(&config, 1.0 / std::f64::consts::TAU);
    assert!(!plausible(fast) && fast > 4.0, "{fast}");
    assert!(!plausible(slow) && slow < 0.25, "{slow}");
}
