"""Experiment files from Python: ``gpodo.run`` runs one (or a dict of the
same schema) through the command line's runner, and ``Results`` gives
Table I, Table II, the frames-versus-error curves and the trajectories as
pandas DataFrames."""

import json
import os
import pathlib
import sys
import warnings

import numpy as np

from . import _native

__all__ = ["run", "Results"]

_POSE = ["x", "y", "z", "qx", "qy", "qz", "qw"]


def _pandas():
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - pandas is a dependency
        raise ImportError("gpodo's tables are pandas DataFrames: pip install pandas") from e
    return pandas


def _print_progress(done, total, key):
    """The default progress: one line on ``sys.stderr``, rewritten after
    each run (Jupyter shows it under the cell)."""
    end = "\n" if done == total else ""
    sys.stderr.write(f"\rgpodo: {done}/{total} runs done ({key}){end}")
    sys.stderr.flush()


def _plain(value):
    """A dict's value JSON cannot hold as it is: a path as its text, a NumPy
    number as a Python one."""
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{value!r} ({type(value).__name__}) has no place in an experiment")


def run(path_or_dict, out=None, seeds=None, threads=None, progress=True, force=False):
    """Runs an experiment file, or a dict with the same schema, through the
    same runner as ``gpodo run``, and returns its :class:`Results`.

    Parameters
    ----------
    path_or_dict : str, os.PathLike or dict
        An experiment or sweep file (``experiments/paper.yaml``), or its
        content as a dict. A dict's ``base:`` and relative paths are
        resolved from the current directory.
    out : str or os.PathLike, optional
        The results folder, written as ``gpodo run --out`` writes it
        (records, reports, figures). None (the default) writes nothing.
    seeds : list of int, optional
        Replaces the file's ``seeds:`` list (one run per seed).
    threads : int, optional
        The size of the rayon pool the work runs on, local to this call
        (default: one thread per core). The numbers do not depend on it.
    progress : bool or callable, default True
        True prints ``done/total runs`` to ``sys.stderr`` after each run;
        a callable is called as ``progress(done, total, run_key)`` on the
        calling thread; False shows nothing.
    force : bool, default False
        With ``out``, start over a sweep whose folder holds runs already
        (``gpodo run --force``); a single run is always run again.

    The GIL is released while the runner works. Ctrl-C stops it as the
    command line's first Ctrl-C does and raises ``KeyboardInterrupt``.

    Raises
    ------
    ValueError
        A bad file names its file, line and field; a bad dict names the
        key's path (``schemes[3].selector.fps``). Bad data (a missing
        table) names the file. A single run that fails raises its reason;
        the failed runs of a sweep are named in a ``UserWarning``, and the
        others are returned.
    """
    if isinstance(path_or_dict, dict):
        try:
            text = json.dumps(path_or_dict, default=_plain, allow_nan=False)
        except ValueError as e:
            raise ValueError(f"the experiment dict holds a NaN or an infinity: {e}") from None
        file = pathlib.Path.cwd() / "<experiment dict>"
    else:
        text = None
        file = pathlib.Path(path_or_dict)
        if not file.is_file():
            raise FileNotFoundError(f"{file}: no such experiment file")
    if progress is True:
        callback = _print_progress
    elif callable(progress):
        callback = progress
    else:
        callback = None
    name, report, runs = _native.run_experiment(
        str(file),
        text,
        None if out is None else str(out),
        None if seeds is None else [int(s) for s in seeds],
        None if threads is None else int(threads),
        callback,
        bool(force),
    )
    results = Results(name, report, runs)
    failed = [r for r in results.runs if r.failure is not None]
    if failed and len(results.runs) == 1:
        raise ValueError(failed[0].failure)
    if failed:
        reasons = "; ".join(f"`{r.key}`: {r.failure}" for r in failed)
        warnings.warn(f"{len(failed)} of {len(results.runs)} runs failed: {reasons}", stacklevel=2)
    return results


class Run:
    """One run of an experiment: its key (``base`` for a single run), the
    swept values (``assignment``), its seed, the metrics (the dict
    ``metrics.json`` holds; None when it failed) and why it failed."""

    def __init__(self, key, assignment, seed, replicate, metrics, failure, trajectories):
        self.key = key
        self.assignment = dict(assignment)
        self.seed = seed
        self.replicate = replicate
        self.metrics = None if metrics is None else json.loads(metrics)
        self.failure = failure
        self._trajectories = trajectories

    def __repr__(self):
        state = "failed" if self.failure else "ok"
        return f"Run({self.key!r}, seed={self.replicate}, {state})"


class Results:
    """What :func:`run` returns: the runs of an experiment, with its tables
    as pandas DataFrames.

    Attributes
    ----------
    name : str
        The experiment's ``name:``.
    runs : list of Run
        Every run, in the plan's order.
    report_path : pathlib.Path or None
        The report written into ``out`` (None when ``out`` was None).
    """

    def __init__(self, name, report_path, runs):
        self.name = name
        self.report_path = None if report_path is None else pathlib.Path(report_path)
        self.runs = [Run(*r) for r in runs]

    def __repr__(self):
        return f"Results({self.name!r}, {len(self.runs)} runs)"

    @property
    def metrics(self):
        """The dict ``metrics.json`` holds, for a single run; for a sweep, a
        dict of them by run key (a failed run's is None)."""
        if len(self.runs) == 1:
            return self.runs[0].metrics
        return {r.key: r.metrics for r in self.runs}

    def _ok_runs(self):
        return [r for r in self.runs if r.metrics is not None]

    def _run_columns(self, r):
        row = {"run": r.key, "seed": r.replicate}
        row.update(r.assignment)
        return row

    def table1(self):
        """Table I: one row per (run, regressor), with the run's swept
        values as columns and the held-out scores (pooled over the outputs:
        ``rmse``, ``mae``, ``nlpd``, ``coverage95``; per output:
        ``rmse[<output>]``), the training rows and the fit's duration."""
        pd = _pandas()
        rows = []
        for r in self._ok_runs():
            targets = r.metrics["dataset"].get("target_names") or []
            for reg in r.metrics["regressors"]:
                row = self._run_columns(r)
                ev = reg["evaluation"]
                row["regressor"] = reg["label"]
                row.update({k: ev["pooled"][k] for k in ("rmse", "mae", "nlpd", "coverage95")})
                for i, scores in enumerate(ev["per_output"]):
                    name = targets[i] if i < len(targets) else str(i)
                    row[f"rmse[{name}]"] = scores["rmse"]
                row["n_train"] = reg["fit"]["n_samples"]
                row["fit_secs"] = reg["fit"]["duration_secs"]
                rows.append(row)
        return pd.DataFrame(rows)

    def table2(self):
        """Table II: one row per (run, scheme, test run), with the run's
        swept values as columns, the scheme's ``curve`` (None outside a
        curve), the frames and keyframes processed, the trajectory errors
        (``rmse_m``, ``max_error_m``, ``final_error_m``,
        ``travel_distance_error_percent``, ``distance_m``) and the tracking
        losses, seconds lost, loop closures and online targets, and what a
        rover team reads: the drift since the last look
        (``drift_since_look_max_m``, ``drift_since_look_p95_m``), the
        relative pose error over 1 m and 10 s (``rpe_1m_m``,
        ``rpe_10s_m``), the compute model per metre (``cpu_ms_per_m``) and
        the RMSE at keyframes, other processed frames and between them
        (``rmse_keyframes_m``, ``rmse_processed_m``, ``rmse_between_m``)."""
        pd = _pandas()
        rows = []
        for r in self._ok_runs():
            curves = {s["label"]: s.get("curve") for s in r.metrics["config"].get("schemes", [])}
            for s in r.metrics["schemes"]:
                run = s["run"]
                row = self._run_columns(r)
                row.update(
                    {
                        "scheme": s["label"],
                        "traverse": s["traverse"],
                        "curve": curves.get(s["label"]),
                        "frames": run["frames"],
                        "keyframes": run["keyframes"],
                    }
                )
                row.update(run["metrics"])
                for k in ("tracking_losses", "lost_secs", "loop_closures", "online_targets"):
                    row[k] = run[k]
                row["rejected_closures"] = run.get("rejected_closures", 0)
                row.update(run.get("rover", {}))
                rows.append(row)
        return pd.DataFrame(rows)

    def curves(self):
        """The frames-versus-error curves (schemes with a ``curve:``): the
        rows of :meth:`table2` that are a curve's points, or an empty
        DataFrame when the file has none."""
        table = self.table2()
        if table.empty or "curve" not in table:
            return table
        return table[table["curve"].notna()].reset_index(drop=True)

    def trajectories(self, scheme, traverse=None, run=None):
        """The trajectory of ``scheme`` on a test run: a DataFrame of
        ``time`` and the estimated pose (``x y z qx qy qz qw``, world from
        body) beside the true one (the same names with ``_true``).

        ``traverse`` names the test run and ``run`` the run's key; each may
        be left out when there is only one.
        """
        pd = _pandas()
        ok = self._ok_runs()
        if run is None:
            if len(ok) != 1:
                raise ValueError(f"{len(ok)} runs: name one with run= ({[r.key for r in ok]})")
            chosen = ok[0]
        else:
            found = [r for r in ok if r.key == run]
            if not found:
                raise ValueError(f"no run `{run}`: one of {[r.key for r in ok]}")
            chosen = found[0]
        found = [t for t in chosen._trajectories if t[0] == scheme]
        if not found:
            names = sorted({t[0] for t in chosen._trajectories})
            raise ValueError(f"no scheme `{scheme}` in run `{chosen.key}`: one of {names}")
        if traverse is not None:
            found = [t for t in found if t[1] == traverse]
            if not found:
                raise ValueError(f"scheme `{scheme}` did not run on `{traverse}`")
        elif len(found) > 1:
            raise ValueError(f"several test runs: name one with traverse= ({[t[1] for t in found]})")
        _, _, times, estimate, truth = found[0]
        data = np.hstack([np.asarray(times), np.asarray(estimate), np.asarray(truth)])
        return pd.DataFrame(data, columns=["time"] + _POSE + [f"{c}_true" for c in _POSE])
