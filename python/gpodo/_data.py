"""Rover logs as pandas DataFrames: a simulated testbed, a bag imported
through a topic map, and the residual rows of logs under a motion model,
each as the command line computes them."""

import json
import os
import pathlib
import tempfile
import warnings

from . import _native
from ._experiments import _pandas

__all__ = ["simulate", "read_bag", "residuals"]


def _frame(log):
    name, columns, rows, camera_times = log
    frame = _pandas().DataFrame(rows, columns=columns)
    frame.attrs["name"] = name
    frame.attrs["camera_times"] = list(camera_times)
    return frame


def simulate(
    preset="exoter-prl",
    seed=7,
    training_runs=None,
    training_run_secs=None,
    test_max_secs=None,
    imu=True,
):
    """Simulates a testbed, as ``gpodo simulate`` does, and returns its
    training runs and its test runs: two lists of DataFrames with the
    rover-log columns (``time_s``, the ground-truth pose, the IMU, each
    joint's position and rate; see ``datasets/README.md``). Each
    DataFrame's ``attrs`` hold the run's ``name`` and its camera frame
    times (``camera_times``).

    ``training_runs``, ``training_run_secs`` and ``test_max_secs`` change
    the preset's (``experiments/paper.yaml`` takes 300-s training runs);
    ``imu=False`` leaves the IMU columns out.
    """
    train, test = _native.simulate(
        str(preset), int(seed), training_runs, training_run_secs, test_max_secs, bool(imu)
    )
    return [_frame(log) for log in train], [_frame(log) for log in test]


def read_bag(path, topics, rover=None):
    """Imports the ROS bag at ``path`` (MCAP, or a ROS 2 ``.db3``/ROS 1
    ``.bag`` where gpodo reads them) through the topic map at ``topics``
    (the YAML ``gpodo import --topics`` reads), and returns the rover log as
    a DataFrame (its ``attrs``: ``name``, ``camera_times``).

    With ``rover`` (a robot description YAML), the wheels' speed is
    checked against the ground truth's as ``gpodo import --rover`` does; a
    failed check, and any damage the import found, are issued as Python
    warnings (``UserWarning``).
    """
    path = pathlib.Path(path)
    log, found = _native.read_bag(
        str(path), str(topics), path.stem, None if rover is None else str(rover)
    )
    for message in found:
        warnings.warn(message, UserWarning, stacklevel=2)
    return _frame(log)


def residuals(log, motion_model=None, window_secs=1.0):
    """The residual rows of a rover log (a DataFrame as :func:`simulate` or
    :func:`read_bag` return, or a list of them, whose rows are
    concatenated in order): ``(X, Y)``, DataFrames of the inputs and the
    targets ``y_k = s(k+1) − s(k) − g(s(k), u(k))``, named as the command
    line names them, ready for the estimators.

    ``motion_model`` is given as in an experiment file's ``motion_model:``:
    a dict (``{"kind": "weighted_jacobian", "config": {...}}``), or the
    path of a rover description (the weighted Jacobian model of that
    rover); None is the weighted Jacobian model of the built-in
    ExoTeR-like rover. ``window_secs`` sums the steps over windows of
    that many seconds (None: one row per step).
    """
    pd = _pandas()
    logs = log if isinstance(log, (list, tuple)) else [log]
    if motion_model is None:
        spec = {"kind": "weighted_jacobian"}
    elif isinstance(motion_model, (str, os.PathLike)):
        spec = {"kind": "weighted_jacobian", "rover": str(pathlib.Path(motion_model).resolve())}
    else:
        spec = dict(motion_model)
    settings = {"window_secs": window_secs}
    with tempfile.TemporaryDirectory(prefix="gpodo-") as folder:
        paths = []
        for i, frame in enumerate(logs):
            # A folder per log: two logs of the same name stay apart.
            name = frame.attrs.get("name") or f"run{i}"
            path = pathlib.Path(folder) / str(i) / f"{name}.csv"
            path.parent.mkdir()
            frame.to_csv(path, index=False, float_format="%.17g")
            paths.append(str(path))
        inputs, targets, input_names, target_names = _native.residuals(
            paths, json.dumps(spec), json.dumps(settings)
        )
    return pd.DataFrame(inputs, columns=input_names), pd.DataFrame(targets, columns=target_names)
