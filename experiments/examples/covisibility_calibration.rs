//! The statistical tracker's covisible keyframes calibrated against the
//! stereo VO's local bundle adjustment, on the same rendered drives driven
//! the same way (`gpodo_experiments::commands::keyframe_chain`): at 2.5 fps
//! (every frame) and 0.5 fps (every fifth), the stereo VO tracking its
//! local map without and with the adjustment (ten keyframes behind), the
//! statistical tracker at its calibrated defaults without and with
//! covisible keyframes (ten behind) at several overlap thresholds, over
//! seeds.
//!
//! ```text
//! cargo run --release -p gpodo-experiments --example covisibility_calibration -- [FRAMES] [SEEDS]
//! ```
//!
//! Per drive, rate and tracker it prints the keyframes, their mean spacing,
//! the keyframe links' RMS translation error and mean NEES, and the
//! keyframes' RMS position error in the map (the links' errors
//! accumulated): the statistical tracker's as the mean over seeds.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;

use gpodo_experiments::commands::keyframe_chain::{ChainOutcome, run_chain_with};
use gpodo_experiments::commands::tracker_calibration::Drive;
use gpodo_frontends::vo::stereo::{StereoVo, StereoVoParams};
use gpodo_frontends::vo::{SimulatedVo, SimulatedVoParams};

/// `(keyframes, spacing m, link RMS mm, link NEES, keyframe RMS mm)`.
fn summary(o: &ChainOutcome, path_m: f64) -> [f64; 5] {
    [
        o.keyframes as f64,
        path_m / o.keyframes.max(1) as f64,
        o.link_rms_mm,
        o.nees,
        o.keyframe_rms_mm,
    ]
}

fn row(drive: &str, rate: &str, tracker: &str, s: [f64; 5]) {
    println!(
        "| {drive} | {rate} | {tracker} | {:.1} | {:.3} | {:.2} | {:.1} | {:.2} |",
        s[0], s[1], s[2], s[3], s[4]
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let frames: usize = args
        .next()
        .map_or(150, |s| s.parse().expect("FRAMES: a count"));
    let seeds: u64 = args
        .next()
        .map_or(20, |s| s.parse().expect("SEEDS: a count"));
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .unwrap();
    let stereo = StereoVoParams {
        local_map_keyframes: 10,
        ..StereoVoParams::default()
    };
    println!(
        "| drive | rate | tracker | keyframes | spacing (m) | link RMS (mm) | link NEES | keyframe RMS (mm) |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|");
    for drive in Drive::calibration_set(frames).iter().take(3) {
        let rendered = drive.stereo_frames(&stereo).unwrap();
        let traverse = drive.traverse(&stereo.camera).unwrap();
        let path_m = drive.speed_mps * (frames - 1) as f64 / 2.5;
        for (rate, step) in [("2.5 fps", 1), ("0.5 fps", 5)] {
            for (tracker, ba) in [("stereo, local map", 0), ("stereo, local map and BA", 10)] {
                let params = StereoVoParams {
                    local_ba_keyframes: ba,
                    ..stereo.clone()
                };
                let mut vo = StereoVo::new(params, Arc::clone(&rendered)).unwrap();
                let o = run_chain_with(drive, &stereo.camera, &mut vo, step);
                row(drive.name, rate, tracker, summary(&o, path_m));
            }
            for (tracker, window, min_overlap) in [
                ("statistical", 0, 0.5),
                ("statistical, covisible ≥ 0.3", 10, 0.3),
                ("statistical, covisible ≥ 0.5", 10, 0.5),
                ("statistical, covisible ≥ 0.7", 10, 0.7),
            ] {
                let mut mean = [0.0; 5];
                for seed in 0..seeds {
                    let params = SimulatedVoParams {
                        seed,
                        covisibility_keyframes: window,
                        covisible_min_overlap: min_overlap,
                        ..SimulatedVoParams::default()
                    };
                    let mut vo = SimulatedVo::new(params, &traverse).unwrap();
                    let o = run_chain_with(drive, &stereo.camera, &mut vo, step);
                    for (m, v) in mean.iter_mut().zip(summary(&o, path_m)) {
                        *m += v / seeds as f64;
                    }
                }
                row(drive.name, rate, tracker, mean);
            }
        }
    }
}
