//! The files of a single run: `report.md`, `metrics.json`, the residual
//! rows as CSV, the trajectories of Table II (TUM) and its figures (with
//! images, the frames around each loss of track). Files
//! are written to a temporary name and renamed, so a crash never leaves a
//! half-written report.

use std::path::{Path, PathBuf};

use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::tum::{StampedPose, format_tum};

use crate::execute::results::ExperimentResults;
use crate::report::run::markdown;
use crate::report::{loss_strips, plots};
use crate::util::output::{slug, write_file};

/// Writes `report.md` and `metrics.json` into `dir` (created if needed),
/// the residual rows, and with schemes the trajectories and (when `plots`)
/// the figures; returns the report's and the metrics' paths.
///
/// # Errors
/// Any I/O or serialisation error.
pub fn write_report(
    results: &ExperimentResults,
    dir: &Path,
    plots: bool,
) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(dir)?;
    let md = dir.join("report.md");
    let json = dir.join("metrics.json");
    write_file(&json, serde_json::to_string_pretty(results)?.as_bytes())?;
    write_file(&md, markdown(results).as_bytes())?;
    for (name, rows) in [
        ("residuals_train.csv", &results.train_rows),
        ("residuals_test.csv", &results.test_rows),
    ] {
        if let Some(rows) = rows {
            write_file(&dir.join(name), residual_csv(rows).as_bytes())?;
        }
    }
    write_table_two_files(results, dir, plots)?;
    Ok((md, json))
}

/// Trajectories (TUM) and figures of Table II.
fn write_table_two_files(
    results: &ExperimentResults,
    dir: &Path,
    plots: bool,
) -> anyhow::Result<()> {
    if results.schemes.is_empty() {
        return Ok(());
    }
    let (traj_dir, plot_dir) = (dir.join("trajectories"), dir.join("plots"));
    std::fs::create_dir_all(&traj_dir)?;
    std::fs::create_dir_all(&plot_dir)?;
    let mut losses = String::new();
    for (t, traverse) in results.traverses.iter().enumerate() {
        let stamped = |poses: &[nalgebra::Isometry3<f64>]| -> Vec<StampedPose> {
            traverse
                .times_secs()
                .iter()
                .zip(poses)
                .map(|(&time_secs, &pose)| StampedPose { time_secs, pose })
                .collect()
        };
        let name = slug(traverse.name());
        write_file(
            &traj_dir.join(format!("{name}.ground_truth.tum")),
            format_tum(
                &format!("ground truth of `{}` (world_from_body)", traverse.name()),
                &stamped(traverse.ground_truth()),
            )
            .as_bytes(),
        )?;
        write_file(
            &traj_dir.join(format!("{name}.windows.csv")),
            windows_csv(traverse).as_bytes(),
        )?;
        for scheme in results
            .schemes
            .iter()
            .filter(|r| r.traverse == traverse.name())
        {
            let file = format!("{name}.{}", slug(&scheme.label));
            let comment = format!(
                "`{}` on `{}`: {} frames, {} keyframes (world_from_body)",
                scheme.label,
                traverse.name(),
                scheme.run.frames,
                scheme.run.keyframes
            );
            write_file(
                &traj_dir.join(format!("{file}.tum")),
                format_tum(&comment, &stamped(&scheme.run.trajectory)).as_bytes(),
            )?;
            write_file(
                &traj_dir.join(format!("{file}.frames.csv")),
                frames_csv(traverse, &scheme.run.processed).as_bytes(),
            )?;
            if !plots {
                continue;
            }
            let title = format!(
                "{}: {} frames, {} keyframes, RMSE {:.3} m",
                scheme.label, scheme.run.frames, scheme.run.keyframes, scheme.run.metrics.rmse_m
            );
            write_file(
                &plot_dir.join(format!("fig5_{file}.svg")),
                plots::trajectory_svg(traverse, &scheme.run, &title)?.as_bytes(),
            )?;
            if let Some(frames) = results.camera_frames.of(t) {
                losses += &loss_strips::write_strips(traverse, frames, scheme, &plot_dir, &file)?;
            }
        }
        if !plots {
            continue;
        }
        if let Some((label, predictions)) = residual_map_source(results, t) {
            write_file(
                &plot_dir.join(format!("fig3_{name}.svg")),
                plots::residual_map_svg(traverse, predictions, &label)?.as_bytes(),
            )?;
        }
    }
    if !losses.is_empty() {
        write_file(
            &plot_dir.join("losses.md"),
            format!("{}{losses}", loss_strips::INDEX_HEADER).as_bytes(),
        )?;
    }
    Ok(())
}

/// The windows of a traverse: where each starts on the ground truth and
/// its true residual (what the odometry misses over the window, m/s in
/// the body frame).
fn windows_csv(traverse: &gpodo_frontends::traverse::Traverse) -> String {
    let mut out = String::from(
        "start_s,end_s,x_m,y_m,true_residual_x_mps,true_residual_y_mps,true_residual_z_mps\n",
    );
    for w in traverse.windows() {
        let at = traverse.ground_truth_at(w.start_secs).translation.vector;
        let r = w.true_residual;
        out += &format!(
            "{},{},{},{},{},{},{}\n",
            w.start_secs, w.end_secs, at.x, at.y, r.x, r.y, r.z
        );
    }
    out
}

/// The frames a scheme processed, each at its ground-truth position, and
/// whether it became a keyframe or was lost.
fn frames_csv(
    traverse: &gpodo_frontends::traverse::Traverse,
    processed: &[gpodo_frontends::run::ProcessedFrame],
) -> String {
    let mut out = String::from("frame,time_s,distance_m,x_m,y_m,keyframe,tracked\n");
    for f in processed {
        let at = traverse.ground_truth_at(f.time_secs).translation.vector;
        out += &format!(
            "{},{},{},{},{},{},{}\n",
            f.frame, f.time_secs, f.distance_m, at.x, at.y, f.keyframe, f.tracked
        );
    }
    out
}

/// The predictions Fig. 3 shows: those of the first scheme's regressor
/// that gates on residuals, or else of the first regressor with any.
fn residual_map_source(
    results: &ExperimentResults,
    t: usize,
) -> Option<(String, &[ResidualPrediction])> {
    let labels = results.config.regressor_labels();
    let gating = results
        .config
        .schemes
        .iter()
        .filter(|s| s.online.is_none() && s.selector.reads_residuals())
        .filter_map(|s| s.regressor_index(&labels).ok());
    let any = 0..results.window_predictions.len();
    gating.chain(any).find_map(|r| {
        let p = results.window_predictions.get(r)?.as_ref()?.get(t)?;
        Some((labels[r].clone(), p.as_slice()))
    })
}

/// A residual dataset as CSV: input columns, then target columns, full
/// precision (the format `kind: residual_table` reads back).
pub fn residual_csv(data: &gpodo_traits::ResidualDataset) -> String {
    let mut s = data.input_names.join(",");
    for t in &data.target_names {
        s.push(',');
        s.push_str(t);
    }
    s.push('\n');
    for (x, y) in data.inputs.rows().zip(data.targets.rows()) {
        let cells: Vec<String> = x.iter().chain(y).map(|v| v.to_string()).collect();
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}
