"""gpodo.run: experiment files and dicts through the command line's runner,
with the same numbers as `gpodo run`, the tables as DataFrames, the
errors naming the file, line and key, and Ctrl-C stopping the run."""

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

import gpodo

REPO = pathlib.Path(__file__).resolve().parents[2]
PAPER = REPO / "experiments" / "paper.yaml"

# Keys that differ between two runs of the same experiment: wall and CPU
# times, and the code version (the CLI's `git describe`).
VOLATILE = {"duration_secs", "cpu_secs", "code_version"}


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if k not in VOLATILE}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def small(**changes):
    """A small experiment: the paper's testbed cut short (one 60-s training
    run, the first 120 s of the test traverse), the parametric model alone,
    and two fixed-rate schemes."""
    experiment = {
        "name": "small",
        "base": str(PAPER),
        "dataset": {"training_runs": 1, "training_run_secs": 60.0, "test_max_secs": 120.0},
        "regressors": [{"kind": "zero"}],
        "schemes": [
            {"label": "fixed 2.5 fps", "selector": {"kind": "fixed_rate", "fps": 2.5}},
            {"label": "fixed 0.5 fps", "selector": {"kind": "fixed_rate", "fps": 0.5}},
        ],
    }
    experiment.update(changes)
    return experiment


def test_paper_yaml_gives_the_command_lines_metrics(paper_cli):
    cli = json.loads((paper_cli / "metrics.json").read_text())
    results = gpodo.run(PAPER, progress=False)
    assert results.report_path is None
    assert strip(results.metrics) == strip(cli)
    table1 = results.table1()
    assert list(table1["regressor"]) == [r["label"] for r in cli["regressors"]]
    assert table1["rmse"].tolist() == [r["evaluation"]["pooled"]["rmse"] for r in cli["regressors"]]
    table2 = results.table2()
    assert len(table2) == len(cli["schemes"])
    assert table2["frames"].tolist() == [s["run"]["frames"] for s in cli["schemes"]]
    assert table2["rmse_m"].tolist() == [s["run"]["metrics"]["rmse_m"] for s in cli["schemes"]]
    assert table2["rpe_1m_m"].tolist() == [s["run"]["rover"]["rpe_1m_m"] for s in cli["schemes"]]
    assert (table2["drift_since_look_max_m"] >= table2["drift_since_look_p95_m"]).all()


def test_a_dict_runs_and_its_tables_and_trajectories_are_dataframes():
    seen = []
    results = gpodo.run(small(), progress=lambda *event: seen.append(event))
    assert seen == [(1, 1, "base")]
    table2 = results.table2()
    assert table2["scheme"].tolist() == ["fixed 2.5 fps", "fixed 0.5 fps"]
    assert table2["frames"].iloc[0] > 4 * table2["frames"].iloc[1]
    assert results.curves().empty
    path = results.trajectories("fixed 2.5 fps")
    assert list(path.columns[:4]) == ["time", "x", "y", "z"]
    assert path["time"].is_monotonic_increasing and len(path) > 100
    # The trajectory is the one whose error the table gives (the RMSE of
    # the positions, the estimate aligned to the truth at the start).
    error = ((path[["x", "y", "z"]].values - path[["x_true", "y_true", "z_true"]].values) ** 2).sum(1)
    assert error.mean() ** 0.5 == pytest.approx(table2["rmse_m"].iloc[0], rel=0.5)
    with pytest.raises(ValueError, match="no scheme `nothing`"):
        results.trajectories("nothing")


def test_curves_are_the_points_of_the_schemes_with_a_curve():
    experiment = small()
    for scheme in experiment["schemes"]:
        scheme["curve"] = "fixed rate"
    experiment["schemes"].append(
        {"label": "fixed 1.0 fps", "selector": {"kind": "fixed_rate", "fps": 1.0}}
    )
    curves = gpodo.run(experiment, progress=False).curves()
    assert curves["scheme"].tolist() == ["fixed 2.5 fps", "fixed 0.5 fps"]
    assert set(curves["curve"]) == {"fixed rate"}
    assert curves["frames"].is_monotonic_decreasing


def test_seeds_replace_the_files_and_threads_change_no_number():
    one = gpodo.run(small(), seeds=[3, 4], threads=1, progress=False)
    two = gpodo.run(small(), seeds=[3, 4], threads=2, progress=False)
    assert [r.replicate for r in one.runs] == [3, 4]
    assert set(one.table2()["seed"]) == {3, 4}
    assert strip(one.metrics) == strip(two.metrics)
    assert one.table2()["rmse_m"].iloc[0] != one.table2()["rmse_m"].iloc[2]


def test_out_writes_the_command_lines_files(tmp_path):
    results = gpodo.run(small(), out=tmp_path / "small", progress=False)
    assert results.report_path == tmp_path / "small" / "report.md"
    assert results.report_path.exists()
    written = json.loads((tmp_path / "small" / "metrics.json").read_text())
    assert strip(written) == strip(results.metrics)


def test_a_bad_dict_names_the_key_path_and_a_bad_file_its_line(tmp_path):
    bad = small()
    bad["schemes"][1]["selector"]["fps"] = -1.0
    with pytest.raises(ValueError, match=r"schemes\[1\]\.selector\.fps"):
        gpodo.run(bad, progress=False)
    path = tmp_path / "bad.yaml"
    path.write_text(f"name: bad\nbase: {PAPER}\nregressors:\n  - kind: exactgp\n")
    with pytest.raises(ValueError, match=r"bad\.yaml:4:11; expected"):
        gpodo.run(path, progress=False)
    with pytest.raises(FileNotFoundError):
        gpodo.run(tmp_path / "missing.yaml")
    # An error in the dict's base file names that file's line.
    base = tmp_path / "base.yaml"
    base.write_text(path.read_text())
    with pytest.raises(ValueError, match=r"base\.yaml:4:11; expected"):
        gpodo.run({"base": str(base), "name": "derived"}, progress=False)
    with pytest.raises(ValueError, match="NaN"):
        gpodo.run(small(dataset={"training_run_secs": float("nan")}), progress=False)
    with pytest.raises(TypeError, match="no place"):
        gpodo.run(small(name=object()), progress=False)


def test_an_exception_in_the_progress_callback_stops_the_run_and_the_next_run_goes(tmp_path):
    def stop(done, total, key):
        raise KeyboardInterrupt

    out = tmp_path / "stopped"
    with pytest.raises(KeyboardInterrupt):
        gpodo.run(small(), seeds=[1, 2, 3], threads=1, progress=stop, out=out)
    # The first run is recorded; the stop kept the others from running.
    assert len((out / "runs.jsonl").read_text().splitlines()) == 1
    with pytest.raises(ValueError, match="force=True"):
        gpodo.run(small(), seeds=[1, 2, 3], out=out, progress=False)
    again = gpodo.run(small(), seeds=[1, 2, 3], out=out, force=True, progress=False)
    assert len(again.runs) == 3 and again.report_path == out / "report.md"


def test_ctrl_c_stops_a_run_promptly(tmp_path):
    script = tmp_path / "long.py"
    # Python's own Ctrl-C handler, also where this process was started with
    # SIGINT ignored (a background job of a shell), which the child inherits.
    script.write_text(
        "import signal, gpodo\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "print('running', flush=True)\n"
        f"gpodo.run({str(PAPER)!r}, progress=False)\n"
        "print('finished')\n"
    )
    process = subprocess.Popen(
        [sys.executable, str(script)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    # Ctrl-C two seconds into the run, not during the imports.
    assert process.stdout.readline().strip() == "running"
    time.sleep(2.0)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode != 0
    assert "KeyboardInterrupt" in err and "finished" not in out
    # The paper's experiment takes about 20 s: the stop came well before.
    assert time.monotonic() - sent < 10.0, err
