//! Tests of [`super`].
use super::*;
use crate::sim::driver::Driver;
use crate::sim::manoeuvre::{DriverParams, PlanarPose};
use crate::sim::soil::{SoilMap, SoilMapSpec};
use crate::sim::terrain::{Terrain, TerrainSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const SPEED: f64 = 0.04;

/// Gravity in the body frame for a nose-up angle and a left-side-up angle.
fn gravity(nose_up_rad: f64, left_up_rad: f64) -> Vector3<f64> {
    let (x, y) = (-nose_up_rad.sin(), -left_up_rad.sin());
    Vector3::new(x, y, -(1.0 - x * x - y * y).sqrt())
}

fn input(
    commanded: PlanarTwist,
    gravity_body: Vector3<f64>,
    soil: &Soil,
    kind: ManoeuvreKind,
) -> SlipInput<'_> {
    SlipInput {
        commanded,
        gravity_body,
        soil,
        load_imbalance: 0.0,
        kind,
        noise: SlipNoise::default(),
        in_burst: false,
    }
}

fn forward_slip(soil: &Soil, nose_up_rad: f64) -> f64 {
    let model = SlipModel::default();
    let twist = PlanarTwist::new(SPEED, 0.0, 0.0);
    let out = model.apply(&input(
        twist,
        gravity(nose_up_rad, 0.0),
        soil,
        ManoeuvreKind::Straight,
    ));
    1.0 - out.twist.vx_mps / SPEED
}

#[test]
fn zero_command_gives_exactly_zero_motion() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let mut inp = input(
        PlanarTwist::ZERO,
        gravity(0.3, 0.2),
        &sand,
        ManoeuvreKind::Stop,
    );
    inp.load_imbalance = 1.0;
    inp.noise = SlipNoise {
        longitudinal: 2.0,
        lateral: -2.0,
        yaw: 1.5,
    };
    assert_eq!(model.apply(&inp), SlipOutcome::default());
}

#[test]
fn level_ground_without_noise_slips_by_the_soil_base() {
    for soil in [Soil::compact(), Soil::gravel(), Soil::loose_sand()] {
        assert!((forward_slip(&soil, 0.0) - soil.slip_base).abs() < 1e-12);
    }
}

#[test]
fn slip_grows_exponentially_uphill_and_steeper_on_sand() {
    let (sand, compact) = (Soil::loose_sand(), Soil::compact());
    let slip_at = |soil: &Soil, deg: f64| forward_slip(soil, deg.to_radians());
    let sand_curve = [0.0, 5.0, 10.0, 15.0].map(|d| slip_at(&sand, d));
    let increments: Vec<f64> = sand_curve.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(increments.iter().all(|&d| d > 0.0));
    assert!(
        increments.windows(2).all(|w| w[1] > w[0]),
        "not convex: {increments:?}"
    );
    assert_eq!(slip_at(&sand, 20.0), SlipParams::default().max_slip);
    assert!(slip_at(&compact, 20.0) < 0.5 * slip_at(&sand, 20.0));
    assert!(slip_at(&compact, 10.0) < 0.5 * slip_at(&sand, 10.0));
}

#[test]
fn downhill_makes_the_rover_skid_ahead_of_its_wheels() {
    let slip = forward_slip(&Soil::loose_sand(), -(15f64.to_radians()));
    assert!((-0.2..0.0).contains(&slip), "slip {slip}");
}

#[test]
fn cross_slope_adds_longitudinal_slip_on_either_side() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let twist = PlanarTwist::new(SPEED, 0.0, 0.0);
    let slip = |left_up: f64| {
        model.apply(&input(
            twist,
            gravity(0.0, left_up),
            &sand,
            ManoeuvreKind::Straight,
        ))
    };
    let (left, right) = (slip(0.2), slip(-0.2));
    assert!((left.slope.cross_rad - 0.2).abs() < 1e-12);
    assert!((left.longitudinal_slip - right.longitudinal_slip).abs() < 1e-12);
    assert!(left.longitudinal_slip > sand.slip_base);
}

#[test]
fn uphill_is_measured_along_the_motion_direction() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let backward = PlanarTwist::new(-SPEED, 0.0, 0.0);
    let nose_down = gravity(-0.2, 0.0);
    let out = model.apply(&input(backward, nose_down, &sand, ManoeuvreKind::Straight));
    assert!((out.slope.uphill_rad - 0.2).abs() < 1e-12);
    assert!(out.twist.vx_mps > -SPEED * (1.0 - sand.slip_base));
}

#[test]
fn cross_slope_drifts_downhill_in_proportion_to_speed() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let left_up = gravity(0.0, 0.2);
    let drift = |speed: f64| {
        let twist = PlanarTwist::new(speed, 0.0, 0.0);
        model
            .apply(&input(twist, left_up, &sand, ManoeuvreKind::Straight))
            .twist
            .vy_mps
    };
    let expected = -sand.lateral_slip_gain * SPEED * 0.2f64.sin();
    assert!((drift(SPEED) - expected).abs() < 1e-12);
    assert!((drift(2.0 * SPEED) - 2.0 * expected).abs() < 1e-12);
}

#[test]
fn turn_on_spot_loses_more_yaw_than_ackermann_and_more_on_sand() {
    let model = SlipModel::default();
    let level = gravity(0.0, 0.0);
    let yaw =
        |soil: &Soil, kind, twist| model.apply(&input(twist, level, soil, kind)).twist.wz_radps;
    let on_spot = PlanarTwist::new(0.0, 0.0, 0.1);
    let arc = PlanarTwist::new(SPEED, 0.0, 0.1);
    let (sand, compact) = (Soil::loose_sand(), Soil::compact());
    assert!(
        yaw(&sand, ManoeuvreKind::TurnOnSpot, on_spot) < yaw(&sand, ManoeuvreKind::Ackermann, arc)
    );
    assert!(
        yaw(&sand, ManoeuvreKind::TurnOnSpot, on_spot)
            < yaw(&compact, ManoeuvreKind::TurnOnSpot, on_spot)
    );
    assert!(yaw(&compact, ManoeuvreKind::TurnOnSpot, on_spot) < 0.1);
}

#[test]
fn turning_on_the_spot_on_a_slope_slides_downhill() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let on_spot = PlanarTwist::new(0.0, 0.0, 0.1);
    let out = model.apply(&input(
        on_spot,
        gravity(0.2, 0.0),
        &sand,
        ManoeuvreKind::TurnOnSpot,
    ));
    assert!(out.twist.vx_mps < 0.0 && out.twist.vy_mps.abs() < 1e-15);
    assert_eq!(out.longitudinal_slip, 0.0);
}

#[test]
fn load_imbalance_adds_slip() {
    let model = SlipModel::default();
    let compact = Soil::compact();
    let twist = PlanarTwist::new(SPEED, 0.0, 0.0);
    let mut inp = input(twist, gravity(0.0, 0.0), &compact, ManoeuvreKind::Straight);
    let even = model.apply(&inp).longitudinal_slip;
    inp.load_imbalance = 1.0;
    let uneven = model.apply(&inp).longitudinal_slip;
    assert!((uneven - even - model.params().load_slip_gain).abs() < 1e-12);
}

#[test]
fn noise_perturbs_slip_by_its_documented_scale() {
    let model = SlipModel::default();
    let compact = Soil::compact();
    let twist = PlanarTwist::new(SPEED, 0.0, 0.0);
    let mut inp = input(twist, gravity(0.0, 0.0), &compact, ManoeuvreKind::Straight);
    inp.noise = SlipNoise {
        longitudinal: 1.0,
        lateral: 1.0,
        yaw: 1.0,
    };
    let out = model.apply(&inp);
    let p = model.params();
    assert!((out.longitudinal_slip - compact.slip_base - p.slip_noise_std).abs() < 1e-12);
    assert!((out.twist.vy_mps - p.lateral_noise_ratio * SPEED).abs() < 1e-12);
    assert!((out.twist.wz_radps - p.yaw_noise_rad_per_m * SPEED).abs() < 1e-12);
}

#[test]
fn slip_is_clamped_and_invalid_inputs_stay_finite() {
    let model = SlipModel::default();
    let sand = Soil::loose_sand();
    let steep = |uphill_rad: f64| SlopeAngles {
        uphill_rad,
        cross_rad: 0.0,
    };
    assert_eq!(
        model.longitudinal_slip(&sand, steep(1.5), 1.0, 5.0),
        model.params().max_slip
    );
    assert_eq!(
        model.longitudinal_slip(&sand, steep(-1.5), 0.0, -50.0),
        model.params().min_slip
    );
    let mut inp = input(
        PlanarTwist::new(SPEED, 0.0, 0.1),
        Vector3::zeros(),
        &sand,
        ManoeuvreKind::Ackermann,
    );
    inp.load_imbalance = f64::NAN;
    inp.noise.lateral = f64::INFINITY;
    let out = model.apply(&inp);
    assert!(
        out.twist.vx_mps.is_finite()
            && out.twist.vy_mps.is_finite()
            && out.twist.wz_radps.is_finite()
    );
}

#[test]
fn invalid_params_are_rejected_by_name() {
    let err = SlipParams {
        max_slip: 1.2,
        ..SlipParams::default()
    }
    .check()
    .unwrap_err();
    assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "max_slip"));
}

/// One second of a slip-only simulation reduced like the real table:
/// `|mean res_x|`, `|mean res_y|`, mean wheel speed, mean pitch, mean roll.
type Row = [f64; 5];

fn body_gravity(terrain: &Terrain, pose: &PlanarPose) -> (Vector3<f64>, f64, f64) {
    let up = terrain.normal(pose.x_m, pose.y_m);
    let heading = Vector3::new(pose.yaw_rad.cos(), pose.yaw_rad.sin(), 0.0);
    let x = (heading - heading.dot(&up) * up).normalize();
    let y = up.cross(&x);
    let g = -Vector3::z();
    let body = Vector3::new(x.dot(&g), y.dot(&g), up.dot(&g));
    (body, (-body.x).asin(), body.y.asin())
}

/// Drives the training driver over a random testbed with slip-free
/// commands and slipping motion; the residual is commanded − actual.
fn simulate_rows(seed: u64, duration_secs: f64) -> Vec<Row> {
    let dt: f64 = 0.08;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let terrain = Terrain::generate(&TerrainSpec::default(), &mut rng).unwrap();
    let soils = SoilMap::generate(&SoilMapSpec::default(), 9.0, &mut rng).unwrap();
    let model = SlipModel::default();
    let mut noise =
        SlipNoiseProcess::new(model.params().noise_correlation_time_secs, &mut rng).unwrap();
    let mut driver = Driver::training(DriverParams::default(), 9.0).unwrap();
    let mut pose = PlanarPose {
        x_m: 4.5,
        y_m: 4.5,
        yaw_rad: 0.0,
    };
    let per_second = (1.0 / dt).round() as usize;
    let (mut rows, mut window) = (Vec::new(), Vec::<Row>::new());
    for step in 0..(duration_secs / dt) as usize {
        let command = driver.command(pose, step as f64 * dt, &mut rng);
        let (g, pitch, roll) = body_gravity(&terrain, &pose);
        let inp = SlipInput {
            commanded: command.twist,
            gravity_body: g,
            soil: soils.soil_at(pose.x_m, pose.y_m),
            load_imbalance: (0.8 * g.xy().norm() / g.z.abs()).min(1.0),
            kind: command.kind,
            noise: noise.step(dt, &mut rng),
            in_burst: false,
        };
        let actual = model.apply(&inp).twist;
        let wheel = command.twist.speed_mps() + 0.3 * command.twist.wz_radps.abs();
        let res = [
            command.twist.vx_mps - actual.vx_mps,
            command.twist.vy_mps - actual.vy_mps,
        ];
        window.push([res[0], res[1], wheel, pitch, roll]);
        if window.len() == per_second {
            let mean = |i: usize| window.iter().map(|r| r[i]).sum::<f64>() / window.len() as f64;
            rows.push([mean(0).abs(), mean(1).abs(), mean(2), mean(3), mean(4)]);
            window.clear();
        }
        let (sin, cos) = pose.yaw_rad.sin_cos();
        pose.x_m += (cos * actual.vx_mps - sin * actual.vy_mps) * dt;
        pose.y_m += (sin * actual.vx_mps + cos * actual.vy_mps) * dt;
        pose.yaw_rad += actual.wz_radps * dt;
    }
    rows
}

fn mean_of(rows: &[Row], column: usize) -> f64 {
    rows.iter().map(|r| r[column]).sum::<f64>() / rows.len() as f64
}

fn correlation_with_abs(rows: &[Row], column: usize, angle: usize) -> f64 {
    let (ma, mb) = (
        mean_of(rows, column),
        rows.iter().map(|r| r[angle].abs()).sum::<f64>() / rows.len() as f64,
    );
    let (mut cov, mut va, mut vb) = (0.0, 0.0, 0.0);
    for r in rows {
        let (a, b) = (r[column] - ma, r[angle].abs() - mb);
        cov += a * b;
        va += a * a;
        vb += b * b;
    }
    cov / (va * vb).sqrt()
}

#[test]
fn default_parameters_land_near_the_real_rover_residuals() {
    let rows: Vec<Row> = (0..4)
        .flat_map(|seed| simulate_rows(seed, 2400.0))
        .collect();
    let moving: Vec<Row> = rows.iter().copied().filter(|r| r[2] > 1e-3).collect();
    let mut ratios: Vec<f64> = moving.iter().map(|r| r[0] / r[2]).collect();
    ratios.sort_by(f64::total_cmp);
    let median_ratio = ratios[ratios.len() / 2];
    let moving_share = moving.len() as f64 / rows.len() as f64;
    let (res_x, res_y, wheel) = (mean_of(&rows, 0), mean_of(&rows, 1), mean_of(&rows, 2));
    let (corr_pitch, corr_roll) = (
        correlation_with_abs(&rows, 0, 3),
        correlation_with_abs(&rows, 0, 4),
    );
    eprintln!(
        "simulated vs real: moving {moving_share:.2} vs 0.71 | mean |res| x {:.2} vs 4.1, y {:.2} vs 2.3 mm/s | \
         median |res_x|/wheel {median_ratio:.3} vs 0.083 | wheel {:.1} vs 2.7 cm/s | \
         corr(|res_x|, |pitch|) {corr_pitch:.2} vs 0.35, |roll| {corr_roll:.2} vs 0.31",
        1e3 * res_x,
        1e3 * res_y,
        1e2 * wheel
    );
    let within = |value: f64, real: f64| (real / 1.5..=real * 1.5).contains(&value);
    assert!(within(median_ratio, 0.083) && within(res_x, 0.0041) && within(res_y, 0.0023));
    assert!(within(wheel, 0.027) && within(moving_share, 0.71));
    assert!(corr_pitch > 0.15 && corr_roll > 0.0);
}

#[test]
fn a_burst_adds_its_extra_slip_on_an_uphill_before_the_clamp() {
    let sand = Soil::loose_sand();
    let with_bursts = SlipParams {
        bursts: Some(SlipBursts::default()),
        ..SlipParams::default()
    }
    .check()
    .unwrap();
    let twist = PlanarTwist::new(SPEED, 0.0, 0.0);
    let slip = |model: &SlipModel, nose_up: f64, in_burst: bool| {
        let mut inp = input(twist, gravity(nose_up, 0.0), &sand, ManoeuvreKind::Straight);
        inp.in_burst = in_burst;
        model.apply(&inp).longitudinal_slip
    };
    let five = 5f64.to_radians();
    let calm = slip(&with_bursts, five, false);
    assert_eq!(calm, slip(&SlipModel::default(), five, false));
    let burst = slip(&with_bursts, five, true);
    assert!(
        (burst - calm - 0.3 * (3.0 * five).exp()).abs() < 1e-12,
        "{calm} {burst}"
    );
    // Without `bursts`, the flag does nothing.
    assert_eq!(slip(&SlipModel::default(), five, true), calm);
    // On a steep slope the clamp holds.
    assert_eq!(slip(&with_bursts, 20f64.to_radians(), true), 0.9);
}
