//! A single run's `report.md`: the runs, Table I, Table II per test run,
//! learned hyperparameters, optimiser starts, dead reckoning and residual
//! statistics.

use std::fmt::Write as _;

use gpodo_datasets::speed_check::unit_warning;
use gpodo_frontends::scheme::SchemeResult;

use crate::config::DatasetSpec;
use crate::execute::calibration::ResidualStatistics;
use crate::execute::results::{Attitude, ExperimentResults, RegressorResult};
use crate::report::controls::controls_section;
use crate::report::hindsight::hindsight_section;
use crate::report::table::{Align, Table};

fn mm(v: f64) -> String {
    format!("{:.2}", v * 1e3)
}

fn opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{:.*}", digits, v * scale))
}

/// The Markdown report.
pub fn markdown(r: &ExperimentResults) -> String {
    let mut s = String::new();
    let c = &r.config;
    let _ = writeln!(s, "# Experiment `{}`\n", c.name);
    if let Some(d) = &c.description {
        let _ = writeln!(s, "{}\n", d.trim());
    }
    let _ = writeln!(
        s,
        "Data: {}. Training rows: {}, test rows: {}. Motion model: {}. Code: `{}`. Wall time: {:.1} s{}.\n",
        r.dataset.source,
        r.dataset.n_train,
        r.dataset.n_test,
        r.motion_model.as_deref().unwrap_or("none (residual table)"),
        r.code_version,
        r.duration_secs,
        r.cpu_secs
            .map_or(String::new(), |c| format!(", CPU time: {c:.1} s"))
    );
    runs_section(&mut s, r);
    table_one(&mut s, r);
    table_two(&mut s, r);
    controls_section(&mut s, r);
    hindsight_section(&mut s, r);
    hyperparameter_section(&mut s, r);
    start_section(&mut s, r);
    dead_reckoning_section(&mut s, r);
    statistics_section(&mut s, r);
    s
}

fn runs_section(s: &mut String, r: &ExperimentResults) {
    if r.dataset.train_runs.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Runs\n\n| run | role | samples | duration [s] | path [m] |\n|---|---|---:|---:|---:|"
    );
    for (role, runs) in [
        ("train", &r.dataset.train_runs),
        ("test", &r.dataset.test_runs),
    ] {
        for run in runs {
            let _ = writeln!(
                s,
                "| {} | {role} | {} | {:.1} | {:.2} |",
                run.name, run.samples, run.duration_secs, run.path_length_m
            );
        }
    }
    if let Some(slope) = r.dataset.terrain_max_slope_deg {
        let _ = writeln!(s, "\nSteepest terrain slope: {slope:.1}°.");
    }
    match r.dataset.speed_ratio {
        None => {
            let _ = writeln!(
                s,
                "\nUnit check: none; fewer than {} seconds of the training runs drive faster than {} m/s.",
                gpodo_datasets::speed_check::MIN_MOVING_WINDOWS,
                gpodo_datasets::speed_check::MOVING_SPEED_MPS
            );
        }
        Some(ratio) => {
            let verdict = unit_warning(ratio).map_or_else(
                || "within [0.5, 2]: the wheels' units are plausible".to_string(),
                |w| format!("**outside [0.5, 2]**: {w}"),
            );
            let _ = writeln!(
                s,
                "\nUnit check: the motion model's speed is {ratio:.3}× the ground truth's (median over the training runs' moving seconds), {verdict}."
            );
        }
    }
    let yaw = r
        .dataset
        .yaw_rate_without_imu
        .as_deref()
        .unwrap_or("the wheels");
    let no_imu = format!(
        "No IMU: the motion model took its yaw rate from {yaw}, and the regressors got no IMU inputs"
    );
    match r.dataset.attitude {
        Attitude::Imu => {}
        Attitude::Level => {
            let _ = writeln!(
                s,
                "\n{no_imu}. The ground was taken as level: roll, pitch and their rates 0."
            );
        }
        Attitude::GroundTruth => {
            let _ = writeln!(
                s,
                "\n{no_imu}. Roll and pitch for the load weighting came from the ground truth (off board, `attitude_without_imu: ground_truth`); they are not regressor inputs."
            );
        }
    }
    s.push('\n');
}

/// A count the regressor used below the one it asked (a sparse GP's
/// inducing points, k-NN's neighbours, with fewer training rows): the
/// label's setting (`m`, `k`), what it names, the count asked and used.
fn clamped(reg: &RegressorResult) -> Option<(&'static str, &'static str, usize, usize)> {
    let (key, noun, parameter, asked) = match &reg.spec {
        gpodo_regressors::RegressorSpec::SparseGp(p) => {
            ("m", "inducing points", "inducing_points", p.inducing.count)
        }
        gpodo_regressors::RegressorSpec::Knn(p) => ("k", "neighbours", "k", p.k),
        gpodo_regressors::RegressorSpec::Zero { .. }
        | gpodo_regressors::RegressorSpec::ExactGp(_)
        | gpodo_regressors::RegressorSpec::Ilgr(_)
        | gpodo_regressors::RegressorSpec::SparseSpectrum(_)
        | gpodo_regressors::RegressorSpec::StreamingSparseGp(_)
        | gpodo_regressors::RegressorSpec::External(_) => return None,
    };
    let used = reg
        .fit
        .parameters
        .iter()
        .find(|(name, _)| name == parameter)
        .map(|(_, v)| *v as usize)?;
    (used < asked).then_some((key, noun, asked, used))
}

/// The regressor's label as a table shows it: with the count it used
/// where that is below the one its label asks (`m=1869 of 1000000000
/// asked`), and the kernel `kernel: auto` chose (`auto → rbf + linear`).
fn shown_label(reg: &RegressorResult) -> String {
    let label = match clamped(reg) {
        Some((key, _, asked, used)) => reg.label.replacen(
            &format!("{key}={asked}"),
            &format!("{key}={used} of {asked} asked"),
            1,
        ),
        None => reg.label.clone(),
    };
    match chosen_kernel(reg) {
        Some((kernel, _)) => label.replacen(": auto", &format!(": auto → {kernel}"), 1),
        None => label,
    }
}

/// The kernel `kernel: auto` kept (the highest log marginal likelihood)
/// and every candidate with its LML.
fn chosen_kernel(reg: &RegressorResult) -> Option<(&str, &[(String, f64)])> {
    let tried = &reg.fit.kernel_candidates;
    let best = tried.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((best.0.as_str(), tried.as_slice()))
}

/// A line for each `kernel: auto` fit: the kernel kept and every
/// candidate's log marginal likelihood.
fn kernel_choices(s: &mut String, regressors: &[RegressorResult]) {
    for reg in regressors {
        if let Some((kernel, tried)) = chosen_kernel(reg) {
            let all: Vec<String> = tried
                .iter()
                .map(|(k, lml)| format!("{k} {lml:.2}"))
                .collect();
            let _ = writeln!(
                s,
                "`{}` kept {kernel}, the highest log marginal likelihood of {}.\n",
                reg.label,
                all.join(", ")
            );
        }
    }
}

/// A line for each regressor that used a smaller count than its label
/// asks (there were fewer training rows).
fn clamped_counts(s: &mut String, regressors: &[RegressorResult]) {
    for reg in regressors {
        if let Some((_, noun, asked, used)) = clamped(reg) {
            let _ = writeln!(
                s,
                "`{}` used {used} {noun}, one per training row, not the {asked} asked.\n",
                reg.label
            );
        }
    }
}

fn table_one(s: &mut String, r: &ExperimentResults) {
    let targets = r.dataset.target_names.join(", ");
    let residuals = &r.config.residuals;
    let units = match (
        &r.config.dataset,
        residuals.window_secs,
        residuals.score_window_secs,
    ) {
        (DatasetSpec::ResidualTable { .. }, _, _) => "in the table's target units".to_string(),
        (_, Some(w), _) => format!("m/s ({w}-s mean body-velocity residuals)"),
        (_, None, Some(w)) => format!(
            "m/s (trained on per-step body-velocity residuals, scored on the test runs' {w}-s means: each window's per-step predictions averaged with the window's weights, their variances as if the steps' errors were independent)"
        ),
        (_, None, None) => "m/s (per-step body-velocity residuals)".to_string(),
    };
    let mut pooled = Table::new(&["Regressor", "RMSE", "MAE"]);
    let mut detail = Table::new(&[
        "Regressor",
        "RMSE per output",
        "MAE per output",
        "NLPD",
        "95% coverage",
        "fit wall [s]",
        "LML",
        "evaluations",
        "jitter",
    ])
    .align(&[1, 2], Align::Left);
    for reg in &r.regressors {
        let e = &reg.evaluation.pooled;
        pooled.push(vec![
            shown_label(reg),
            format!("{:.6}", e.rmse),
            format!("{:.6}", e.mae),
        ]);
        let per = &reg.evaluation.per_output;
        let rmse: Vec<String> = per.iter().map(|p| mm(p.rmse)).collect();
        let mae: Vec<String> = per.iter().map(|p| mm(p.mae)).collect();
        detail.push(vec![
            shown_label(reg),
            rmse.join(" / "),
            mae.join(" / "),
            format!("{:.3}", e.nlpd),
            format!("{:.3}", e.coverage95),
            format!("{:.3}", reg.fit.duration_secs),
            opt(reg.fit.objective, 1.0, 2),
            reg.fit.evaluations.map_or("–".into(), |e| e.to_string()),
            reg.fit.jitter.map_or("–".into(), |j| format!("{j:.1e}")),
        ]);
    }
    let _ = write!(
        s,
        "## Table I — residual prediction on the test rows\n\nRMSE and MAE pooled over the outputs ({targets}), in the paper's layout; {units}.\n\n{}\nPer output (× 1000), predictive quality and fit (log marginal likelihood on the standardised training rows; evaluations of the objective and its gradient). The fits run concurrently, sharing the cores: a fit's wall time is measured while the others run, so the times can add up to more than the run's wall time; the run's CPU time is in its header.\n\n{}\n",
        pooled.markdown(),
        detail.markdown()
    );
    clamped_counts(s, &r.regressors);
    kernel_choices(s, &r.regressors);
    if !r.absolute_regressors.is_empty() {
        let mut absolute = Table::new(&["Regressor", "RMSE", "MAE", "fit wall [s]"]);
        for reg in &r.absolute_regressors {
            let e = &reg.evaluation.pooled;
            absolute.push(vec![
                reg.label.clone(),
                format!("{:.6}", e.rmse),
                format!("{:.6}", e.mae),
                format!("{:.3}", reg.fit.duration_secs),
            ]);
        }
        let _ = write!(
            s,
            "Regressors of |residual| (the authors' targets), which set the covariance of a scheme's odometry; scored against |residual| on the test rows:\n\n{}\n",
            absolute.markdown()
        );
    }
}

fn table_two(s: &mut String, r: &ExperimentResults) {
    if r.schemes.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Table II — localisation and mapping per scheme\n\nEach scheme runs the visual front end (simulated VO, keyframes, loop closing, factrs pose graph fusing VO with the wheel odometry, corrected and weighted as each scheme's odometry says) over the test run; errors are positions at every sensor sample against ground truth. Frames and RMSE are also given relative to the first scheme. Compute = frames × frame cost + keyframes × keyframe cost. Trajectories (TUM) are in `trajectories/`, figures in `plots/`.\n"
    );
    for traverse in r.traverses.iter() {
        let rows: Vec<_> = r
            .schemes
            .iter()
            .filter(|x| x.traverse == traverse.name())
            .collect();
        let Some(first) = rows.first() else {
            continue;
        };
        let mut table = Table::new(&[
            "Scheme",
            "#Frames",
            "#Keyframes",
            "RMSE [m]",
            "Max E. [m]",
            "Final E. [m]",
            "Travel Distance E. [%]",
            "frames / first",
            "RMSE / first",
            "compute [s]",
            "VO losses",
            "lost [s]",
            "loop closures",
            "residuals",
        ])
        .align(&[13], Align::Left);
        for x in &rows {
            let m = &x.run.metrics;
            table.push(vec![
                x.label.clone(),
                x.run.frames.to_string(),
                x.run.keyframes.to_string(),
                format!("{:.3}", m.rmse_m),
                format!("{:.3}", m.max_error_m),
                format!("{:.3}", m.final_error_m),
                format!("{:.2}", m.travel_distance_error_percent),
                format!(
                    "{:.2}",
                    x.run.frames as f64 / first.run.frames.max(1) as f64
                ),
                format!(
                    "{:.2}",
                    m.rmse_m / first.run.metrics.rmse_m.max(f64::MIN_POSITIVE)
                ),
                format!("{:.1}", x.run.compute_ms / 1e3),
                x.run.tracking_losses.to_string(),
                format!("{:.0}", x.run.lost_secs),
                match x.run.rejected_closures {
                    0 => x.run.loop_closures.to_string(),
                    n => format!("{} ({n} dropped)", x.run.loop_closures),
                },
                x.residuals.clone(),
            ]);
        }
        let _ = writeln!(
            s,
            "Run `{}` ({:.2} m):\n\n{}",
            traverse.name(),
            traverse.path_length_m(),
            table.markdown()
        );
        rover_table(s, &rows);
        learning_curves(s, &rows);
    }
}

/// What a rover team reads per scheme: the drift since the last look, the
/// relative pose error, the compute per metre and where the RMSE comes
/// from.
fn rover_table(s: &mut String, rows: &[&SchemeResult]) {
    let mut table = Table::new(&[
        "Scheme",
        "drift since look, max [mm]",
        "drift since look, p95 [mm]",
        "RPE 1 m [mm]",
        "RPE 10 s [mm]",
        "compute [ms/m]",
        "RMSE at keyframes [m]",
        "at other frames [m]",
        "between frames [m]",
    ])
    .align(&[0], Align::Left);
    for x in rows {
        let m = &x.run.rover;
        table.push(vec![
            x.label.clone(),
            format!("{:.1}", 1e3 * m.drift_since_look_max_m),
            format!("{:.1}", 1e3 * m.drift_since_look_p95_m),
            format!("{:.1}", 1e3 * m.rpe_1m_m),
            format!("{:.1}", 1e3 * m.rpe_10s_m),
            format!("{:.0}", m.cpu_ms_per_m),
            format!("{:.3}", m.rmse_keyframes_m),
            format!("{:.3}", m.rmse_processed_m),
            format!("{:.3}", m.rmse_between_m),
        ]);
    }
    let _ = writeln!(
        s,
        "What a rover team reads: the drift since the last look (at each sample, ‖error − error at the last tracked frame‖), the relative pose error over 1 m and over 10 s of travel (RMS of the translation of (T_i⁻¹T_j)⁻¹(T̂_i⁻¹T̂_j)), the compute model per metre, and the RMSE over the samples of keyframes, of the other processed frames, and between processed frames.\n\n{}",
        table.markdown()
    );
}

/// Frames per metre over time for schemes that learn online.
fn learning_curves(s: &mut String, rows: &[&SchemeResult]) {
    let online: Vec<_> = rows.iter().filter(|x| x.run.online_targets > 0).collect();
    if online.is_empty() {
        return;
    }
    const BIN_SECS: f64 = 120.0;
    let end = online
        .iter()
        .filter_map(|x| x.run.processed.last().map(|p| p.time_secs))
        .fold(0.0, f64::max);
    let t0 = online
        .iter()
        .filter_map(|x| x.run.processed.first().map(|p| p.time_secs))
        .fold(f64::INFINITY, f64::min);
    let names: Vec<String> = online.iter().map(|x| x.label.clone()).collect();
    let _ = writeln!(
        s,
        "Online learning from VO: frames processed per metre driven, in {BIN_SECS:.0}-s bins (the model starts knowing nothing).\n\n| time [s] | {} |\n|---:|{}",
        names.join(" | "),
        "---:|".repeat(names.len())
    );
    let mut start = t0;
    while start < end {
        let cells: Vec<String> = online
            .iter()
            .map(|x| {
                let inside: Vec<_> = x
                    .run
                    .processed
                    .iter()
                    .filter(|p| p.time_secs >= start && p.time_secs < start + BIN_SECS)
                    .collect();
                match (inside.first(), inside.last()) {
                    (Some(a), Some(b)) if b.distance_m > a.distance_m + 0.05 => {
                        format!("{:.1}", inside.len() as f64 / (b.distance_m - a.distance_m))
                    }
                    _ => "–".into(),
                }
            })
            .collect();
        let _ = writeln!(s, "| {:.0} | {} |", start - t0, cells.join(" | "));
        start += BIN_SECS;
    }
    s.push('\n');
}

/// The input columns that do not vary over `rows` (population standard
/// deviation at most [`gpodo_traits::MIN_STD`]): a kernel cannot learn
/// from them, so their lengthscales say nothing.
fn constant_inputs(rows: &gpodo_traits::ResidualDataset) -> Vec<String> {
    let n = rows.inputs.nrows() as f64;
    (0..rows.inputs.ncols())
        .filter(|&c| {
            let column = || (0..rows.inputs.nrows()).map(move |i| rows.inputs.get(i, c));
            let mean = column().sum::<f64>() / n;
            let var = column().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
            var.sqrt() <= gpodo_traits::MIN_STD
        })
        .filter_map(|c| rows.input_names.get(c).cloned())
        .collect()
}

/// How many of the shortest lengthscales to list per model.
const RELEVANT_INPUTS: usize = 6;

fn hyperparameter_section(s: &mut String, r: &ExperimentResults) {
    let fitted: Vec<&RegressorResult> = r
        .regressors
        .iter()
        .filter(|reg| !reg.fit.parameters.is_empty())
        .collect();
    if fitted.is_empty() {
        return;
    }
    let constant = r
        .train_rows
        .as_ref()
        .map(constant_inputs)
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "## Learned hyperparameters\n\nStandardised units. The shortest lengthscales mark the inputs the model relies on most (all values in `metrics.json`).\n\n| Regressor | noise variance | signal variance | shortest lengthscales |\n|---|---:|---:|---|"
    );
    for reg in fitted {
        let find = |suffix: &str| {
            reg.fit
                .parameters
                .iter()
                .filter(|(n, _)| {
                    n.ends_with(suffix) && !n.contains("linear") && !n.contains("white")
                })
                .map(|(_, v)| format!("{v:.3e}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut lengthscales: Vec<(&str, f64)> = reg
            .fit
            .parameters
            .iter()
            .filter_map(|(n, v)| {
                let start = n.find(".lengthscale[")?;
                Some((&n[start + ".lengthscale[".len()..n.len() - 1], *v))
            })
            .collect();
        lengthscales.retain(|(name, _)| !constant.iter().any(|c| c == name));
        lengthscales.sort_by(|a, b| a.1.total_cmp(&b.1));
        let shortest: Vec<String> = lengthscales
            .iter()
            .take(RELEVANT_INPUTS)
            .map(|(name, v)| format!("{name} {v:.2}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            reg.label,
            find("noise_variance"),
            find(".variance"),
            if shortest.is_empty() {
                "–".into()
            } else {
                shortest.join(", ")
            }
        );
    }
    if !constant.is_empty() {
        let _ = writeln!(
            s,
            "\nConstant on the training rows, so left out of the shortest lengthscales: {}.",
            constant.join(", ")
        );
    }
    s.push('\n');
}

/// The optimiser's candidate starts of every fitted model: how multimodal
/// each problem was, and which starts the optimiser ran from.
fn start_section(s: &mut String, r: &ExperimentResults) {
    let with_starts: Vec<&RegressorResult> = r
        .regressors
        .iter()
        .filter(|reg| !reg.fit.starts.is_empty())
        .collect();
    if with_starts.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Optimiser starts\n\nEvery candidate start scored by the objective (LML or bound, standardised units); the optimiser ran from the best ones for a few iterations each (the race), went on from the leader alone, and kept the highest optimum (marked **bold**); evaluations and iterations are those of each start's runs.\n\n| Regressor | start | objective at start | objective reached | evaluations | iterations |\n|---|---|---:|---:|---:|---:|"
    );
    let value = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.2}"));
    for reg in with_starts {
        let best = reg
            .fit
            .starts
            .iter()
            .filter_map(|st| st.final_objective)
            .fold(f64::NEG_INFINITY, f64::max);
        for st in &reg.fit.starts {
            let reached = match st.final_objective {
                Some(v) if v == best => format!("**{v:.2}**"),
                other => value(other),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                reg.label,
                st.label,
                value(st.start_objective),
                reached,
                st.evaluations.map_or("".into(), |e| e.to_string()),
                st.iterations.map_or("".into(), |i| i.to_string()),
            );
        }
    }
    s.push('\n');
}

fn dead_reckoning_section(s: &mut String, r: &ExperimentResults) {
    if r.dead_reckoning.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Parametric odometry alone on the test runs\n\nDead reckoning with the motion model from the first ground-truth pose.\n\n| run | distance [m] | final error [m] | max error [m] | travel distance error [%] |\n|---|---:|---:|---:|---:|"
    );
    for (name, d) in &r.dead_reckoning {
        let _ = writeln!(
            s,
            "| {name} | {:.2} | {:.3} | {:.3} | {:.2} |",
            d.distance_m, d.final_error_m, d.max_error_m, d.final_error_percent
        );
    }
    s.push('\n');
}

/// One row of the residual-statistics table: its cells, "–" where a
/// statistic does not apply.
fn statistics_cells(label: &str, st: &ResidualStatistics) -> Vec<String> {
    let join = |v: &[f64]| v.iter().map(|x| mm(*x)).collect::<Vec<_>>().join(" / ");
    vec![
        label.to_string(),
        st.n_rows.to_string(),
        join(&st.mean_abs),
        join(&st.p95_abs),
        opt(st.moving_fraction, 100.0, 0),
        opt(st.mean_wheel_speed_moving_mps, 100.0, 2),
        opt(st.median_slip_ratio_x, 100.0, 1),
        opt(st.corr_abs_x_abs_pitch, 1.0, 2),
        opt(st.corr_abs_x_abs_roll, 1.0, 2),
    ]
}

/// How much of the residual is row-to-row noise: RMS against the
/// successive-difference noise estimate, per output.
fn noise_rows(s: &mut String, r: &ExperimentResults) {
    let sets = [("train", &r.train_statistics), ("test", &r.test_statistics)];
    if sets.iter().any(|(_, st)| st.rms.is_empty()) {
        return;
    }
    let _ = writeln!(
        s,
        "\nHow much of the residual is noise (per output, × 1000): RMS, and the noise standard deviation estimated from successive rows (√(mean((y[k+1] − y[k])²)/2), right for noise independent from row to row on a slowly changing residual). Where the two are close, the residual is mostly noise at the rows' rate and no regressor can predict it.\n\n| rows | RMS | noise (successive differences) | noise / RMS |\n|---|---|---|---|"
    );
    for (name, st) in sets {
        let join = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{:.2}", 1000.0 * x))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        let ratio: Vec<String> = st
            .noise_sd
            .iter()
            .zip(&st.rms)
            .map(|(n, r)| {
                if *r > 0.0 {
                    format!("{:.2}", n / r)
                } else {
                    "–".into()
                }
            })
            .collect();
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} |",
            join(&st.rms),
            join(&st.noise_sd),
            ratio.join(" / ")
        );
    }
}

fn statistics_section(s: &mut String, r: &ExperimentResults) {
    let units = if matches!(r.config.dataset, DatasetSpec::ResidualTable { .. }) {
        "the table's target units"
    } else {
        "mm/s, as the targets are body-velocity residuals"
    };
    let mut rows = vec![
        statistics_cells("train", &r.train_statistics),
        statistics_cells("test", &r.test_statistics),
    ];
    if let Some((name, st)) = &r.reference_statistics {
        rows.push(statistics_cells(&format!("reference `{name}`"), st));
    }
    let header = [
        "rows",
        "n",
        "mean abs",
        "p95 abs",
        "moving [%]",
        "wheel speed [cm/s]",
        "median slip ratio x [%]",
        "corr pitch",
        "corr roll",
    ];
    // A statistic no row has (no wheels in a residual table) is left out.
    let shown: Vec<usize> = (0..header.len())
        .filter(|&c| c < 2 || rows.iter().any(|row| row[c] != "–"))
        .collect();
    let mut table = Table::new(&shown.iter().map(|&c| header[c]).collect::<Vec<_>>())
        .align(&[2, 3], Align::Left);
    for row in &rows {
        table.push(shown.iter().map(|&c| row[c].clone()).collect());
    }
    let wheels = if shown.len() > 4 {
        "; moving rows have a mean wheel speed above 5 mm/s; slip ratio = |residual x| / wheel speed on moving rows; correlations of |residual x| with |pitch| and |roll|"
    } else {
        ""
    };
    let _ = write!(
        s,
        "## Residual statistics\n\nAbsolute residuals of the rows as used (mean and 95th percentile per output, × 1000: {units}){wheels}.\n\n{}",
        table.markdown()
    );
    if let Some((_, st)) = &r.reference_statistics {
        let ratios: Vec<String> = r
            .train_statistics
            .mean_abs
            .iter()
            .zip(&st.mean_abs)
            .map(|(a, b)| format!("{:.2}", a / b))
            .collect();
        let _ = writeln!(
            s,
            "\nMean |residual| ratio training rows / reference per output: {} (within a factor 1.5 means the simulated testbed's lessons should transfer).",
            ratios.join(" / ")
        );
    }
    noise_rows(s, r);
}
