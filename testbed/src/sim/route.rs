//! The test traverse's route: the paper's fixed 42.3 m route, or a route
//! drawn per seed with the same length and terrain statistics, so that
//! seeds differ in where the rover turns and what it crosses, not only in
//! the noise along one path.
//!
//! A random route has [`RANDOM_ROUTE_WAYPOINTS`] waypoints drawn uniformly
//! in the paper route's square (1.4 m inside the edges, scaled with the
//! area) and is kept when its length is within 10 % of the paper route's
//! and the share of its length in the middle of the area (where the hills
//! are: the central half of each side) is within 10 percentage points of
//! the paper route's.
//!
//! A sandy-slope route is, of the first [`SANDY_SLOPE_DRAWS`] random
//! routes of the paper route's length (the middle-share limit dropped: the
//! hills are where the slopes are), the one with the largest share of its
//! length on loose sand at a slope of [`SANDY_SLOPE_MIN_DEG`] or more. It
//! is for experiments about where slip is, such as Table II's positive
//! control; `testbed/tests/sandy_slopes.rs` prints the shares against
//! random routes'.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::sim::manoeuvre::{PlanarPose, test_traverse_waypoints};

/// Which route the test traverse follows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// The paper's fixed route (42.34 m at 9 m), the same for every seed.
    #[default]
    Paper,
    /// A route drawn per seed with the paper route's length (±10 %) and
    /// share of length in the middle of the area (±10 points).
    Random,
    /// Of [`SANDY_SLOPE_DRAWS`] routes drawn per seed with the paper
    /// route's length (±10 %), the one with the most of its length on
    /// loose sand at a slope of [`SANDY_SLOPE_MIN_DEG`] or more.
    SandySlopes,
}

/// The slope from which loose sand counts as a sandy slope (degrees).
pub const SANDY_SLOPE_MIN_DEG: f64 = 8.0;

/// The routes of the paper route's length a sandy-slope route is chosen
/// from.
pub const SANDY_SLOPE_DRAWS: usize = 200;

/// Waypoints of a random route (the paper's has 9).
pub const RANDOM_ROUTE_WAYPOINTS: usize = 9;

/// Draws before a random route gives up (each draw is cheap).
const MAX_DRAWS: usize = 100_000;

/// Length of the polyline through `points` (m).
pub fn polyline_length(points: &[(f64, f64)]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum()
}

/// The share of the polyline's length inside the central square of side
/// `area_size_m / 2` (sampled every centimetre).
pub fn central_share(points: &[(f64, f64)], area_size_m: f64) -> f64 {
    let (lo, hi) = (area_size_m / 4.0, 3.0 * area_size_m / 4.0);
    length_share(points, 0.01, &|x, y| {
        (lo..=hi).contains(&x) && (lo..=hi).contains(&y)
    })
}

/// The share of the polyline's length (sampled every 5 cm) on ground that
/// `sandy_slope` says is a sandy slope.
pub fn sandy_slope_share(points: &[(f64, f64)], sandy_slope: &dyn Fn(f64, f64) -> bool) -> f64 {
    length_share(points, 0.05, sandy_slope)
}

/// The share of the polyline's length where `inside(x, y)` holds, sampled
/// at the midpoints of steps of at most `step_m`.
fn length_share(points: &[(f64, f64)], step_m: f64, inside: &dyn Fn(f64, f64) -> bool) -> f64 {
    let (mut total, mut within) = (0.0, 0.0);
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let length = (x1 - x0).hypot(y1 - y0);
        let steps = (length / step_m).ceil().max(1.0) as usize;
        let step = length / steps as f64;
        for k in 0..steps {
            let t = (k as f64 + 0.5) / steps as f64;
            if inside(x0 + t * (x1 - x0), y0 + t * (y1 - y0)) {
                within += step;
            }
            total += step;
        }
    }
    if total > 0.0 { within / total } else { 0.0 }
}

/// The waypoints of `route` in an area of side `area_size_m`; a random
/// route draws from `rng`. `sandy_slope(x, y)` says whether the ground at
/// `(x, y)` is loose sand at [`SANDY_SLOPE_MIN_DEG`] or more; only
/// [`Route::SandySlopes`] reads it.
///
/// # Errors
/// [`TestbedError::Simulation`] when no random route meets the limits in
/// 100 000 draws.
pub fn route_waypoints<R: Rng + ?Sized>(
    route: Route,
    area_size_m: f64,
    sandy_slope: &dyn Fn(f64, f64) -> bool,
    rng: &mut R,
) -> Result<Vec<(f64, f64)>, TestbedError> {
    let paper = test_traverse_waypoints(area_size_m);
    if route == Route::Paper {
        return Ok(paper);
    }
    let (length, share) = (polyline_length(&paper), central_share(&paper, area_size_m));
    let (lo, hi) = (1.4 * area_size_m / 9.0, 7.6 * area_size_m / 9.0);
    let mut best: Option<(f64, Vec<(f64, f64)>)> = None;
    let mut of_length = 0;
    for _ in 0..MAX_DRAWS {
        let points: Vec<(f64, f64)> = (0..RANDOM_ROUTE_WAYPOINTS)
            .map(|_| (rng.random_range(lo..hi), rng.random_range(lo..hi)))
            .collect();
        if (polyline_length(&points) / length - 1.0).abs() > 0.1 {
            continue;
        }
        match route {
            Route::Paper | Route::Random => {
                if (central_share(&points, area_size_m) - share).abs() <= 0.1 {
                    return Ok(points);
                }
            }
            Route::SandySlopes => {
                let sandy = sandy_slope_share(&points, sandy_slope);
                if best.as_ref().is_none_or(|(b, _)| sandy > *b) {
                    best = Some((sandy, points));
                }
                of_length += 1;
                if of_length == SANDY_SLOPE_DRAWS {
                    break;
                }
            }
        }
    }
    best.map(|(_, points)| points)
        .ok_or_else(|| TestbedError::Simulation {
            detail: format!("no random route of {length:.1} m ± 10 % in {MAX_DRAWS} draws"),
        })
}

/// Where a route starts: on its first waypoint, facing the second.
pub fn route_start_pose(points: &[(f64, f64)]) -> PlanarPose {
    let (x0, y0) = points.first().copied().unwrap_or_default();
    let (x1, y1) = points.get(1).copied().unwrap_or((x0 + 1.0, y0));
    PlanarPose {
        x_m: x0,
        y_m: y0,
        yaw_rad: (y1 - y0).atan2(x1 - x0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_paper_route_is_the_fixed_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let points = route_waypoints(Route::Paper, 9.0, &|_, _| false, &mut rng).unwrap();
        assert_eq!(points, test_traverse_waypoints(9.0));
        assert!((polyline_length(&points) - 42.34).abs() < 0.01);
    }

    #[test]
    fn random_routes_keep_the_length_and_the_middle_but_turn_elsewhere() {
        let paper = test_traverse_waypoints(9.0);
        let (length, share) = (polyline_length(&paper), central_share(&paper, 9.0));
        let routes: Vec<Vec<(f64, f64)>> = (0..20)
            .map(|seed| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                route_waypoints(Route::Random, 9.0, &|_, _| false, &mut rng).unwrap()
            })
            .collect();
        for r in &routes {
            assert!((polyline_length(r) / length - 1.0).abs() <= 0.1);
            assert!((central_share(r, 9.0) - share).abs() <= 0.1);
            assert!(
                r.iter()
                    .all(|&(x, y)| (1.4..7.6).contains(&x) && (1.4..7.6).contains(&y))
            );
        }
        // Every seed turns somewhere else.
        for (i, a) in routes.iter().enumerate() {
            for b in &routes[i + 1..] {
                assert_ne!(a, b);
            }
            assert_ne!(a, &paper);
        }
        // The same seed, the same route.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        assert_eq!(
            route_waypoints(Route::Random, 9.0, &|_, _| false, &mut rng).unwrap(),
            routes[3]
        );
    }

    #[test]
    fn the_central_share_of_a_straight_line_through_the_middle() {
        // Corner to corner of a 9 m area: the central square covers half
        // of the diagonal.
        let share = central_share(&[(0.0, 0.0), (9.0, 9.0)], 9.0);
        assert!((share - 0.5).abs() < 1e-3, "{share}");
    }
}
