"""gpodo.simulate, gpodo.read_bag and gpodo.residuals: the command line's
logs and residual rows as DataFrames, the same numbers as its files."""

import subprocess
import warnings

import numpy as np
import pandas as pd
import pytest

import gpodo
from conftest import REPO


def test_simulate_gives_the_logs_gpodo_simulate_writes(tmp_path, gpodo_cli):
    settings = dict(training_runs=2, training_run_secs=60.0, test_max_secs=40.0)
    subprocess.run(
        [str(gpodo_cli), "simulate", "--out", str(tmp_path), "--quiet", "--seed", "3",
         "--training-runs", "2", "--training-run-secs", "60", "--test-max-secs", "40"],
        check=True,
        capture_output=True,
    )
    train, test = gpodo.simulate("exoter-prl", seed=3, **settings)
    assert [f.attrs["name"] for f in train + test] == ["train_01", "train_02", "test"]
    for frame in train + test:
        written = pd.read_csv(tmp_path / f"{frame.attrs['name']}.csv")
        assert list(frame.columns) == list(written.columns)
        np.testing.assert_array_equal(frame.values, written.values)
    assert "gyro_z_radps" in train[0].columns
    no_imu, _ = gpodo.simulate("exoter-prl", seed=3, imu=False, **settings)
    assert "gyro_z_radps" not in no_imu[0].columns
    with pytest.raises(ValueError, match="preset `mars`"):
        gpodo.simulate("mars")


def test_residuals_of_the_simulated_runs_are_the_experiments_rows(paper_cli):
    train, _ = gpodo.simulate("exoter-prl", seed=7, training_run_secs=300.0)
    motion_model = {
        "kind": "weighted_jacobian",
        "config": {"weighting": "normal_force", "contact_angles": "assume_zero"},
    }
    X, Y = gpodo.residuals(train, motion_model=motion_model, window_secs=1.0)
    written = pd.read_csv(paper_cli / "residuals_train.csv")
    assert list(written.columns) == list(X.columns) + list(Y.columns)
    np.testing.assert_allclose(
        np.hstack([X.values, Y.values]), written.values, rtol=1e-12, atol=1e-15
    )
    # A rover description's path is the weighted Jacobian model of it.
    X2, Y2 = gpodo.residuals(train[0], motion_model=REPO / "kinematics" / "rovers" / "exoter.yaml")
    assert X2.shape[1] == X.shape[1] and len(X2) < len(X)
    # Two logs of the same name are two logs.
    X1, _ = gpodo.residuals(train[0], motion_model=motion_model)
    X3, _ = gpodo.residuals([train[0], train[0]], motion_model=motion_model)
    assert len(X3) == 2 * len(X1)
    np.testing.assert_array_equal(X3.values[len(X1):], X1.values)
    fitted = gpodo.ExactGP(kernel="rbf").fit(X.iloc[:200], Y.iloc[:200])
    assert fitted.predict(X.iloc[200:210]).shape == (10, 3)


def test_read_bag_is_gpodo_import_and_warns_of_wrong_units(tmp_path, gpodo_cli):
    bags, logs = tmp_path / "bags", tmp_path / "logs"
    subprocess.run(
        [str(gpodo_cli), "simulate", "--format", "mcap", "--wheel-rate", "rpm", "--quiet",
         "--training-runs", "1", "--training-run-secs", "60", "--test-max-secs", "60",
         "--out", str(bags)],
        check=True,
        capture_output=True,
    )
    topics = bags / "topics.yaml"
    subprocess.run(
        [str(gpodo_cli), "import", "--topics", str(topics), "--out", str(logs), "--quiet",
         str(bags / "test.mcap")],
        check=True,
        capture_output=True,
    )
    rover = REPO / "kinematics" / "rovers" / "exoter.yaml"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = gpodo.read_bag(bags / "test.mcap", topics=topics, rover=rover)
    written = pd.read_csv(logs / "test.csv")
    assert log.attrs["name"] == "test"
    assert list(log.columns) == list(written.columns)
    np.testing.assert_allclose(log.values, written.values, rtol=1e-15)
    # The topic map forgets that the rates are motor rpm: the unit check warns.
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text(topics.read_text().replace("rate_scale: 0.10471975511965977", "rate_scale: 1.0"))
    with pytest.warns(UserWarning, match="unit"):
        gpodo.read_bag(bags / "test.mcap", topics=wrong, rover=rover)
    with pytest.raises(ValueError, match="missing.mcap"):
        gpodo.read_bag(tmp_path / "missing.mcap", topics=topics)
