//! The stereo VO's local bundle adjustment on a rendered drive (ExoTeR's
//! 3 cm/s with a slow turn on compact soil, 512 × 384, 2.5 fps), driven as
//! the front end drives it: the keyframe links it refines, and the same
//! numbers at 1 and 2 threads.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_experiments::commands::keyframe_chain::run_chain;
use gpodo_experiments::commands::tracker_calibration::Drive;
use gpodo_frontends::vo::stereo::StereoVoParams;

#[test]
fn local_bundle_adjustment_refines_the_keyframe_links_the_same_at_any_thread_count() {
    let drive = Drive::calibration_set(60)[0];
    let with = StereoVoParams {
        local_ba_keyframes: 5,
        ..StereoVoParams::default()
    };
    let run = |threads: usize, params: &StereoVoParams| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let frames = drive.stereo_frames(params).unwrap();
            run_chain(&drive, &frames, params)
        })
    };
    let one = run(1, &with);
    assert_eq!(one.lost_at, None);
    assert!(one.keyframes >= 4, "{} keyframes", one.keyframes);
    // The same numbers (its clock aside) at 2 threads.
    let two = run(2, &with);
    assert_eq!(
        (&one.links, &one.relative, one.drift_percent),
        (&two.links, &two.relative, two.drift_percent)
    );
    let without = run(1, &StereoVoParams::default());
    println!(
        "with: {:?} NEES {:.1}, {} keyframes; without: {:?} NEES {:.1}, {} keyframes",
        one.relative, one.nees, one.keyframes, without.relative, without.nees, without.keyframes
    );
    // The adjustment moves the keyframe links, not which frames are
    // keyframes, and its covariances hold the links' errors better than
    // the motion-only refinement's (NEES nearer 6).
    assert_eq!(one.keyframes, without.keyframes);
    assert_ne!(one.links, without.links);
    assert!(
        (one.nees - 6.0).abs() < (without.nees - 6.0).abs(),
        "NEES {:.1} with, {:.1} without",
        one.nees,
        without.nees
    );
}
