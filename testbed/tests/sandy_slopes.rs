//! Sandy-slope routes on the ExoTeR preset's ground keep the paper route's
//! length and spend more of it on loose sand at 8° or more than random
//! routes do; slip bursts change a traverse only where they may happen.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_testbed::sim::route::{
    Route, SANDY_SLOPE_MIN_DEG, polyline_length, route_waypoints, sandy_slope_share,
};
use gpodo_testbed::sim::slip::SlipBursts;
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The preset's ground for `seed`, drawn as the simulator draws it.
fn ground(seed: u64) -> (Terrain, SoilMap) {
    let config = SimulatorConfig::preset(Preset::ExoterPrl, seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let terrain = Terrain::generate(&config.terrain, &mut rng).unwrap();
    let soils = SoilMap::generate(&config.soils, config.terrain.size_m, &mut rng).unwrap();
    (terrain, soils)
}

#[test]
fn sandy_slope_routes_spend_more_of_their_length_on_sandy_slopes() {
    let paper = route_waypoints(
        Route::Paper,
        9.0,
        &|_, _| false,
        &mut ChaCha8Rng::seed_from_u64(0),
    );
    let paper_length = polyline_length(&paper.unwrap());
    let (mut random_shares, mut sandy_shares) = (Vec::new(), Vec::new());
    for seed in 1..=8 {
        let (terrain, soils) = ground(seed);
        let sandy_slope = |x: f64, y: f64| {
            soils.soil_at(x, y).name == Soil::loose_sand().name
                && terrain.gradient(x, y).norm().atan() >= SANDY_SLOPE_MIN_DEG.to_radians()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let random = route_waypoints(Route::Random, 9.0, &sandy_slope, &mut rng).unwrap();
        random_shares.push(sandy_slope_share(&random, &sandy_slope));
        let sandy = route_waypoints(Route::SandySlopes, 9.0, &sandy_slope, &mut rng).unwrap();
        assert!((polyline_length(&sandy) / paper_length - 1.0).abs() <= 0.1);
        sandy_shares.push(sandy_slope_share(&sandy, &sandy_slope));
    }
    eprintln!(
        "sandy-slope share: random routes {random_shares:.3?}, sandy-slope routes {sandy_shares:.3?}"
    );
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(
        mean(&sandy_shares) > 2.0 * mean(&random_shares),
        "{random_shares:?} {sandy_shares:?}"
    );
    for (r, s) in random_shares.iter().zip(&sandy_shares) {
        assert!(s >= r, "{r} {s}");
    }
}

#[test]
fn bursts_change_a_traverse_only_on_the_soils_they_name() {
    let run = |bursts: Option<SlipBursts>| {
        let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 3);
        config.route = Route::SandySlopes;
        config.training_runs = 1;
        config.training_run_secs = 10.0;
        config.test_max_secs = 120.0;
        config.slip.bursts = bursts;
        config.simulate().unwrap().test.remove(0).ground_truth
    };
    let without = run(None);
    let nowhere = run(Some(SlipBursts {
        soils: Vec::new(),
        ..SlipBursts::default()
    }));
    assert_eq!(without, nowhere);
    let on_sand = run(Some(SlipBursts::default()));
    assert_ne!(without, on_sand);
}
