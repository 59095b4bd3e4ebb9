//! The stereo VO with ORB-SLAM2's local bundle adjustment against the same
//! VO without it, on rendered drives of ExoTeR's mast camera (512 × 384,
//! 2.5 fps): every frame tracked against the reference keyframe with a
//! wheel-odometry-like prior (5 % short, 0.2° off in yaw), a keyframe
//! when the overlap falls below 0.8 (the front end's rule), and on each
//! new keyframe the adjustment, whose refined links re-place the keyframes.
//!
//! ```text
//! cargo run --release -p gpodo-experiments --example local_ba -- [FRAMES]
//! ```
//!
//! Per drive and setting it prints, from the final map (keyframes as
//! refined, other frames on their keyframe as tracked): the median
//! relative translation and rotation errors at gaps of 1, 5 and 12 frames,
//! the position error at the last frame over the path length, the NEES of
//! the keyframe links (mean; 6 when the covariances are right), the
//! links' RMS translation error and the keyframes' RMS position error, the
//! keyframes, and the adjustment's median time per keyframe on one thread
//! (its matching included, the features cached).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_experiments::commands::keyframe_chain::{median, run_chain};
use gpodo_experiments::commands::tracker_calibration::Drive;
use gpodo_frontends::vo::stereo::StereoVoParams;

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .map_or(150, |s| s.parse().expect("FRAMES: a count"));
    // One thread, as the timing says.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .unwrap();
    let exoter = StereoVoParams::default();
    let strong = StereoVoParams {
        features: Some(1500),
        fast_min_threshold: 20,
        ..StereoVoParams::default()
    };
    println!(
        "| drive | corners | setting | rel. t 1/5/12 (mm) | rel. r 1/5/12 (°) | end error / path | link NEES | link RMS (mm) | keyframe RMS (mm) | keyframes | BA ms/keyframe |"
    );
    println!("|---|---|---|---|---|---:|---:|---:|---:|---:|---:|");
    for drive in Drive::calibration_set(frames).iter().take(3) {
        for (corners, base) in [("ExoTeR's", &exoter), ("strong", &strong)] {
            let frames = drive.stereo_frames(base).unwrap();
            for (setting, params) in [
                ("without", base.clone()),
                (
                    "local BA, 5 behind",
                    StereoVoParams {
                        local_ba_keyframes: 5,
                        ..base.clone()
                    },
                ),
                (
                    "local map, 5 behind",
                    StereoVoParams {
                        local_map_keyframes: 5,
                        ..base.clone()
                    },
                ),
                (
                    "local map and BA, 5 behind",
                    StereoVoParams {
                        local_map_keyframes: 5,
                        local_ba_keyframes: 5,
                        ..base.clone()
                    },
                ),
            ] {
                let o = run_chain(drive, &frames, &params);
                let f = |i: usize| o.relative[i];
                println!(
                    "| {} | {corners} | {setting} | {:.2} / {:.2} / {:.2} | {:.3} / {:.3} / {:.3} | {:.2} % | {:.1} | {:.2} | {:.2} | {} | {:.1} |{}",
                    drive.name,
                    f(0).0,
                    f(1).0,
                    f(2).0,
                    f(0).1,
                    f(1).1,
                    f(2).1,
                    o.drift_percent,
                    o.nees,
                    o.link_rms_mm,
                    o.keyframe_rms_mm,
                    o.keyframes,
                    1e3 * median(o.keyframe_secs.clone()),
                    o.lost_at
                        .map_or(String::new(), |k| format!(" lost at frame {k}")),
                );
            }
        }
    }
}
