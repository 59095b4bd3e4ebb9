//! Tests of [`super`].
use super::*;
use crate::sim::driver::Driver;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const DT: f64 = 0.08;

/// Slip-free integration of a body twist over one step.
fn integrate(pose: PlanarPose, twist: &PlanarTwist) -> PlanarPose {
    let mid_yaw = pose.yaw_rad + 0.5 * twist.wz_radps * DT;
    let (sin, cos) = mid_yaw.sin_cos();
    PlanarPose {
        x_m: pose.x_m + (cos * twist.vx_mps - sin * twist.vy_mps) * DT,
        y_m: pose.y_m + (sin * twist.vx_mps + cos * twist.vy_mps) * DT,
        yaw_rad: pose.yaw_rad + twist.wz_radps * DT,
    }
}

fn polyline_length(points: &[(f64, f64)]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum()
}

#[test]
fn feasible_twists_rotate_about_the_middle_axle_line() {
    let arc = DriveCommand::ackermann(0.04, 0.8);
    assert!((arc.twist.vx_mps / arc.twist.wz_radps - 0.8).abs() < 1e-12);
    let point = DriveCommand::point_turn(0.1, 0.28);
    assert!((point.twist.vx_mps - 0.028).abs() < 1e-12);
    for command in [
        arc,
        point,
        DriveCommand::turn_on_spot(0.1),
        DriveCommand::straight(-0.04),
    ] {
        assert_eq!(command.twist.vy_mps, 0.0);
    }
}

#[test]
fn test_traverse_is_about_42_m_long_and_crosses_the_middle() {
    let points = test_traverse_waypoints(9.0);
    assert!((polyline_length(&points) - 42.35).abs() < 0.1);
    assert!(
        points
            .iter()
            .all(|&(x, y)| (1.0..8.0).contains(&x) && (1.0..8.0).contains(&y))
    );
    let through_middle = points.windows(2).filter(|w| {
        let (a, b) = (Vector2::new(w[0].0, w[0].1), Vector2::new(w[1].0, w[1].1));
        let d = b - a;
        let t = ((Vector2::repeat(4.5) - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        (a + t * d - Vector2::repeat(4.5)).norm() < 0.5
    });
    assert!(through_middle.count() >= 3);
    assert_eq!(test_traverse_waypoints(9.0), points);
}

#[test]
fn following_the_test_traverse_reaches_every_waypoint_and_travels_about_42_m() {
    let points = test_traverse_waypoints(9.0);
    let mut driver = Driver::follow(DriverParams::default(), &points).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut pose = test_traverse_start_pose(9.0);
    let mut closest = vec![f64::INFINITY; points.len()];
    let mut travelled = 0.0;
    let mut steps = 0;
    while !driver.done() && steps < 50_000 {
        let command = driver.command(pose, steps as f64 * DT, &mut rng);
        pose = integrate(pose, &command.twist);
        travelled += command.twist.speed_mps() * DT;
        for (c, &(x, y)) in closest.iter_mut().zip(&points) {
            *c = c.min((pose.x_m - x).hypot(pose.y_m - y));
        }
        steps += 1;
    }
    assert!(driver.done(), "not done after {steps} steps");
    assert!(closest.iter().all(|&c| c < 0.15), "{closest:?}");
    assert!((travelled - 42.0).abs() < 3.0, "travelled {travelled}");
    assert_eq!(driver.command(pose, 1e6, &mut rng), DriveCommand::STOP);
}

fn run_training(seed: u64, duration_secs: f64) -> (Vec<PlanarPose>, Vec<DriveCommand>) {
    let mut driver = Driver::training(DriverParams::default(), 9.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pose = PlanarPose {
        x_m: 4.5,
        y_m: 4.5,
        yaw_rad: 0.3,
    };
    let steps = (duration_secs / DT) as usize;
    let mut poses = Vec::with_capacity(steps);
    let mut commands = Vec::with_capacity(steps);
    for step in 0..steps {
        let command = driver.command(pose, step as f64 * DT, &mut rng);
        pose = integrate(pose, &command.twist);
        poses.push(pose);
        commands.push(command);
    }
    (poses, commands)
}

#[test]
fn training_driver_keeps_the_rover_inside_the_area() {
    for seed in 0..4 {
        let (poses, _) = run_training(seed, 1200.0);
        let inside = |v: f64| (0.5..=8.5).contains(&v);
        assert!(
            poses.iter().all(|p| inside(p.x_m) && inside(p.y_m)),
            "seed {seed}"
        );
    }
}

#[test]
fn training_driver_moves_about_seventy_percent_of_the_time() {
    for seed in 0..4 {
        let (_, commands) = run_training(seed, 3600.0);
        let moving =
            commands.iter().filter(|c| c.kind.is_moving()).count() as f64 / commands.len() as f64;
        assert!((0.6..=0.8).contains(&moving), "seed {seed}: {moving}");
    }
}

#[test]
fn training_driver_uses_every_manoeuvre_with_feasible_twists() {
    let (_, commands) = run_training(7, 3600.0);
    for kind in [
        ManoeuvreKind::Straight,
        ManoeuvreKind::Ackermann,
        ManoeuvreKind::TurnOnSpot,
        ManoeuvreKind::PointTurn,
        ManoeuvreKind::Stop,
    ] {
        assert!(
            commands.iter().any(|c| c.kind == kind),
            "{kind:?} never used"
        );
    }
    for c in commands
        .iter()
        .filter(|c| c.kind == ManoeuvreKind::Ackermann)
    {
        assert!((c.twist.vx_mps / c.twist.wz_radps).abs() >= 0.6 - 1e-9);
    }
    assert!(
        commands.iter().any(|c| c.twist.vx_mps < 0.0),
        "never drove backward"
    );
}

#[test]
fn training_driver_is_deterministic_given_the_seed() {
    assert_eq!(run_training(3, 300.0), run_training(3, 300.0));
}

#[test]
fn stops_are_exactly_zero_twists() {
    let (_, commands) = run_training(5, 600.0);
    assert!(
        commands
            .iter()
            .filter(|c| c.kind == ManoeuvreKind::Stop)
            .all(|c| c.twist.is_zero())
    );
}

#[test]
fn invalid_params_are_rejected_by_name() {
    let params = DriverParams {
        align_stop_rad: 0.5,
        ..DriverParams::default()
    };
    let err = Driver::training(params, 9.0).unwrap_err();
    assert!(
        matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "align_stop_rad")
    );
    let err = Driver::training(DriverParams::default(), 4.0).unwrap_err();
    assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "area_size_m"));
    let err = Driver::follow(DriverParams::default(), &[]).unwrap_err();
    assert!(matches!(err, TestbedError::InvalidConfig { ref field, .. } if field == "waypoints"));
}
