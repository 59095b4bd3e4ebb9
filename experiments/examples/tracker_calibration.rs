//! The statistical tracker beside the stereo VO on the same rendered
//! requests (`gpodo_experiments::commands::tracker_calibration`): writes one row per
//! request to `OUT/requests.csv` and prints both trackers' curves over
//! geometric overlap, gap and drive.
//!
//! ```text
//! cargo run --release -p gpodo-experiments --example tracker_calibration -- OUT [FRAMES]
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fmt::Write as _;
use std::path::PathBuf;

use gpodo_experiments::commands::tracker_calibration::{
    BinSummary, Drive, Observation, by_overlap, observe_all, summarise,
};
use gpodo_frontends::vo::SimulatedVoParams;
use gpodo_frontends::vo::stereo::StereoVoParams;

/// Gaps of 0.4 to 20 s.
const GAPS: [usize; 8] = [1, 3, 6, 12, 18, 25, 35, 50];

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(
        args.next()
            .ok_or_else(|| anyhow::anyhow!("usage: OUT [FRAMES]"))?,
    );
    let frames: usize = args.next().map_or(Ok(101), |a| a.parse())?;
    std::fs::create_dir_all(&out)?;
    let stereo = StereoVoParams::default();
    let simulated = SimulatedVoParams::default();
    let drives = Drive::calibration_set(frames);
    let observations =
        observe_all(&drives, &stereo, &simulated, &GAPS, 2).map_err(anyhow::Error::msg)?;
    let mut csv = String::from(
        "drive,gap_secs,overlap,rotation_rad,distance_m,supply,tracked,inliers,err_rx,err_ry,err_rz,err_tx,err_ty,err_tz,success_probability,sigma_r,sigma_t\n",
    );
    for o in &observations {
        let (tracked, inliers, e) = match &o.stereo {
            Some((r, t, n)) => (1, *n, [r.x, r.y, r.z, t.x, t.y, t.z]),
            None => (0, 0, [f64::NAN; 6]),
        };
        writeln!(
            csv,
            "{},{},{:.6},{:.6},{:.6},{:.6},{tracked},{inliers},{},{:.6},{:.6e},{:.6e}",
            o.drive,
            o.gap_secs,
            o.overlap,
            o.rotation_rad,
            o.distance_m,
            o.supply,
            e.map(|v| format!("{v:.6e}")).join(","),
            o.success_probability,
            o.sigmas.0,
            o.sigmas.1,
        )?;
    }
    std::fs::write(out.join("requests.csv"), csv)?;
    println!("By geometric overlap:\n{}", BinSummary::TABLE_HEADER);
    for (lo, b) in by_overlap(&observations) {
        println!("{}", b.table_row(&format!("{lo:.1}–{:.1}", lo + 0.1)));
    }
    println!("\nBy gap:\n{}", BinSummary::TABLE_HEADER);
    for gap in GAPS {
        let secs = gap as f64 / 2.5;
        let b = summarise(
            observations
                .iter()
                .filter(|o| (o.gap_secs - secs).abs() < 1e-9),
        );
        println!("{}", b.table_row(&format!("{secs:.1} s")));
    }
    println!("\nBy drive:\n{}", BinSummary::TABLE_HEADER);
    for d in &drives {
        let b = summarise(observations.iter().filter(|o| o.drive == d.name));
        println!("{}", b.table_row(d.name));
    }
    fit(&observations, &drives, &stereo);
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The statistical tracker's parameters fitted to the stereo VO's
/// measurements, printed.
fn fit(observations: &[Observation], drives: &[Drive], stereo: &StereoVoParams) {
    let of = |name: &'static str| observations.iter().filter(move |o| o.drive == name);
    // Features per frame: inliers over geometric overlap on compact soil,
    // still camera, at the shortest gap (the most the tracker keeps).
    let per_overlap = |name: &'static str| {
        median(
            of(name)
                .filter(|o| o.gap_secs < 0.5)
                .filter_map(|o| o.stereo.map(|(_, _, n)| n as f64 / o.overlap))
                .collect(),
        )
    };
    let compact = per_overlap("compact");
    println!(
        "\nFits:\n- features_per_frame F = {compact:.0} (median inliers / overlap, compact, 0.4 s)"
    );
    for d in drives {
        let ratio = per_overlap(d.name) / compact;
        println!("- {}: inliers / compact's = {ratio:.3}", d.name);
    }
    // The overlap model's depth range: driving straight, the inliers per
    // feature at full overlap against the model's overlap at each range.
    let straight: Vec<&Observation> = of("straight at 0.1 m/s")
        .filter(|o| o.stereo.is_some() && o.gap_secs > 0.5)
        .collect();
    let misfit = |depth_range_m: f64| {
        let camera = gpodo_traits::CameraParams {
            depth_range_m,
            ..stereo.camera
        };
        straight
            .iter()
            .map(|o| {
                let (_, _, n) = o.stereo.unwrap();
                (n as f64 / compact - camera.body_overlap(&o.truth)).powi(2)
            })
            .sum::<f64>()
    };
    let (best, _) = (10..=60)
        .map(|k| f64::from(k) * 0.05)
        .map(|d| (d, misfit(d)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    println!(
        "- depth_range_m = {best:.2} (least squares of inliers / F against the overlap, straight at 0.1 m/s; 3.0 gives {:.2}, {best:.2} gives {:.2})",
        misfit(3.0),
        misfit(best)
    );
    // Blur half-width: the share left, 1 / (1 + b / b½).
    if let Some(blurred) = drives.iter().find(|d| d.shake_radps > 0.0) {
        let camera = stereo.camera;
        let rate = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(blurred.speed_mps, 0.0, 0.0),
            nalgebra::UnitQuaternion::from_euler_angles(
                0.0,
                0.0,
                blurred.turn_radps + blurred.shake_radps,
            ),
        );
        let b = camera.motion_blur_px(&rate);
        let r = per_overlap(blurred.name) / compact;
        println!(
            "- blur {b:.2} px leaves {r:.3}: blur_half_px b½ = b r / (1 − r) = {:.2}",
            b * r / (1.0 - r)
        );
    }
    // Error model on compact soil and turning in place: per-axis RMS error
    // against distance (translation) and angle (rotation), per gap, as
    // σ · o^p = σ0 + k x, for p in 0, 0.5, 1.
    for (what, pick) in [("translation", 1usize), ("rotation", 0usize)] {
        let mut best: Option<(f64, f64, f64, f64)> = None;
        for p in [0.0, 0.5, 1.0, 1.5] {
            let mut rows = Vec::new();
            for name in ["compact", "straight at 0.1 m/s", "turning in place"] {
                for gap in GAPS {
                    let secs = gap as f64 / 2.5;
                    let at: Vec<&Observation> = of(name)
                        .filter(|o| (o.gap_secs - secs).abs() < 1e-9 && o.stereo.is_some())
                        .collect();
                    if at.len() < 10 {
                        continue;
                    }
                    let n = at.len() as f64;
                    let sd = (at
                        .iter()
                        .map(|o| {
                            let (r, t, _) = o.stereo.unwrap();
                            (if pick == 1 {
                                t.norm_squared()
                            } else {
                                r.norm_squared()
                            }) / 3.0
                        })
                        .sum::<f64>()
                        / n)
                        .sqrt();
                    let x = at
                        .iter()
                        .map(|o| {
                            if pick == 1 {
                                o.distance_m
                            } else {
                                o.rotation_rad
                            }
                        })
                        .sum::<f64>()
                        / n;
                    let o = at.iter().map(|o| o.overlap).sum::<f64>() / n;
                    rows.push((x, sd * o.powf(p), sd));
                }
            }
            // Least squares of y = a + k x.
            let n = rows.len() as f64;
            let (sx, sy) = rows.iter().fold((0.0, 0.0), |a, r| (a.0 + r.0, a.1 + r.1));
            let (mx, my) = (sx / n, sy / n);
            let sxx: f64 = rows.iter().map(|r| (r.0 - mx).powi(2)).sum();
            let sxy: f64 = rows.iter().map(|r| (r.0 - mx) * (r.1 - my)).sum();
            let k = (sxy / sxx).max(0.0);
            let a = (my - k * mx).max(1e-9);
            // Relative misfit of the standard deviations.
            let misfit = rows
                .iter()
                .map(|r| ((a + k * r.0) / r.1.max(1e-12) - 1.0).powi(2))
                .sum::<f64>()
                / n;
            println!(
                "- {what}, p = {p}: σ0 = {a:.3e}, k = {k:.3e}, mean squared relative misfit {misfit:.3}"
            );
            if best.is_none_or(|b| misfit < b.3) {
                best = Some((p, a, k, misfit));
            }
        }
        if let Some((p, a, k, _)) = best {
            println!("  best {what}: p = {p}, σ0 = {a:.3e}, k = {k:.3e}");
        }
    }
}
