//! The statistical tracker's defaults against the stereo VO it is
//! calibrated on (`examples/tracker_calibration.rs` fits them on 101-frame
//! drives; this test draws 66-frame ones): on rendered drives over each
//! soil, straight at 0.1 m/s, turning in place and under motion blur,
//! both trackers get the same requests (gaps of 0.4 to 20 s, a
//! wheel-odometry-like prior), and their curves over the views' geometric
//! overlap agree: the success probability within 0.1 per bin,
//! the error standard deviation within 25 %, over the bins with at least
//! 30 requests (tracked requests, for the error).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_experiments::commands::tracker_calibration::{
    BinSummary, Drive, by_overlap, differences, observe_all, summarise,
};
use gpodo_frontends::vo::SimulatedVoParams;
use gpodo_frontends::vo::stereo::StereoVoParams;

#[test]
fn the_statistical_trackers_curves_follow_the_stereo_vos() {
    let gaps = [1, 3, 6, 12, 18, 25, 35, 50];
    let observations = observe_all(
        &Drive::calibration_set(66),
        &StereoVoParams::default(),
        &SimulatedVoParams::default(),
        &gaps,
        2,
    )
    .unwrap();
    let bins = by_overlap(&observations);
    eprintln!("{}", BinSummary::TABLE_HEADER);
    for (lo, b) in &bins {
        eprintln!("{}", b.table_row(&format!("{lo:.1}")));
    }
    let compared = bins.iter().filter(|(_, b)| b.count >= 30).count();
    assert!(compared >= 6, "only {compared} bins with 30 requests");
    let all = summarise(&observations);
    assert!(
        all.stereo_success < 1.0,
        "the drives never lose track: {all:?}"
    );
    let off = differences(&bins, 30, 0.1, 0.25);
    assert!(off.is_empty(), "{}", off.join("\n"));
}
