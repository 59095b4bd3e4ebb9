//! A unit check of the motion model against the ground truth: over the
//! moving parts of a recording, the model's translational speed should be
//! about the true one. A wheel speed read in the wrong unit (rpm as rad/s,
//! a missing gear ratio) makes it off by a large factor, and a regressor
//! would otherwise "learn" the error, so Table I looks like a huge win.

use crate::residuals::LogStep;

/// Windows over which the speeds are averaged (s): long enough that the
/// ground truth's position noise does not dominate a slow rover's speed.
pub const SPEED_WINDOW_SECS: f64 = 1.0;

/// True speeds below this (m/s) count as standing still or turning on the
/// spot: there a simulated or real body creeps by slip at a few mm/s while
/// its wheels barely turn, which says nothing about their units.
pub const MOVING_SPEED_MPS: f64 = 0.01;

/// Moving windows needed for a ratio: fewer (a short run that mostly
/// stands or turns) give no verdict rather than a false alarm.
pub const MIN_MOVING_WINDOWS: usize = 10;

/// The range of the median speed ratio that passes: slip and sinkage move
/// it (loose sand on a slope slips over half), a unit error by far more.
pub const PLAUSIBLE_RATIO: [f64; 2] = [0.5, 2.0];

/// The median, over the moving windows of every run's steps, of the
/// model's horizontal speed over the true one (each averaged over
/// [`SPEED_WINDOW_SECS`]); `None` when fewer than [`MIN_MOVING_WINDOWS`]
/// windows move.
pub fn median_speed_ratio(runs: &[Vec<LogStep>]) -> Option<f64> {
    let mut ratios = Vec::new();
    for steps in runs {
        window_ratios(steps, &mut ratios);
    }
    if ratios.len() < MIN_MOVING_WINDOWS {
        return None;
    }
    let mid = ratios.len() / 2;
    Some(*ratios.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// Appends to `ratios` the speed ratio of every moving window of one run.
fn window_ratios(steps: &[LogStep], ratios: &mut Vec<f64>) {
    let Some(t0) = steps.first().map(|s| s.time_secs) else {
        return;
    };
    let mut window = 0usize;
    let (mut model, mut truth, mut secs) = ([0.0f64; 2], [0.0f64; 2], 0.0);
    let mut flush = |model: [f64; 2], truth: [f64; 2], secs: f64| {
        if secs < 0.5 * SPEED_WINDOW_SECS {
            return;
        }
        let speed = |v: [f64; 2]| (v[0] / secs).hypot(v[1] / secs);
        let true_speed = speed(truth);
        if true_speed > MOVING_SPEED_MPS {
            ratios.push(speed(model) / true_speed);
        }
    };
    for step in steps {
        let index = ((step.time_secs - t0) / SPEED_WINDOW_SECS).floor() as usize;
        if index != window {
            flush(model, truth, secs);
            (model, truth, secs, window) = ([0.0; 2], [0.0; 2], 0.0, index);
        }
        let v = step.twist.linear_mps;
        let t = v + step.residual;
        for (i, (m, r)) in model.iter_mut().zip(truth.iter_mut()).enumerate() {
            *m += v[i] * step.dt_secs;
            *r += t[i] * step.dt_secs;
        }
        secs += step.dt_secs;
    }
    flush(model, truth, secs);
}

/// Whether a median speed ratio is plausible for a model with the right
/// units.
pub fn plausible(ratio: f64) -> bool {
    (PLAUSIBLE_RATIO[0]..=PLAUSIBLE_RATIO[1]).contains(&ratio)
}

/// The warning a ratio outside [`PLAUSIBLE_RATIO`] earns, naming the likely
/// causes; `None` for a plausible ratio.
pub fn unit_warning(ratio: f64) -> Option<String> {
    (!plausible(ratio)).then(|| {
        format!(
            "the motion model's speed is {ratio:.2}× the ground truth's (median over the moving seconds): \
             check the wheels' units (a topic map's `rate_scale` and `position_scale`: 2π/60 for rpm, 1/gear ratio at the motor; \
             a rover description's `wheel_radius_m`)"
        )
    })
}
