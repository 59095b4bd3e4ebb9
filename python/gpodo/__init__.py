"""gpodo: Gaussian-process models of robot odometry errors, in Python.

scikit-learn estimators over gpodo's Rust regressors, which share saved
models with the ``gpodo`` command line::

    from gpodo import ExactGP
    gp = ExactGP(kernel="rbf").fit(X, y)
    mean, std = gp.predict(X_new, return_std=True)
    gp.save("model.gpodo")                 # what `gpodo predict --model` reads
    again = gpodo.load_model("model.gpodo")

See ``help(gpodo.ExactGP)``, ``help(gpodo.SparseGP)``, ``help(gpodo.ILGR)``,
``help(gpodo.StreamingSparseGP)``.

Experiment files run as ``gpodo run`` runs them, with the tables as pandas
DataFrames::

    results = gpodo.run("experiments/paper.yaml")
    results.table2()                        # one row per scheme and test run
    results.trajectories("fixed 2.5 fps")   # time, estimate and truth

Simulated testbeds, ROS bags and residual rows as DataFrames::

    train, test = gpodo.simulate("exoter-prl", seed=7)
    X, Y = gpodo.residuals(train)           # ready for ExactGP().fit(X, Y)
    log = gpodo.read_bag("run.mcap", topics="topics.yaml")

See ``help(gpodo.run)``, ``help(gpodo.Results)``, ``help(gpodo.simulate)``,
``help(gpodo.read_bag)`` and ``help(gpodo.residuals)``.
"""

import json

import numpy as np

from . import _native
from ._estimators import ILGR, ExactGP, SparseGP, StreamingSparseGP
from ._data import read_bag, residuals, simulate
from ._experiments import Results, run

__all__ = [
    "ExactGP",
    "SparseGP",
    "ILGR",
    "StreamingSparseGP",
    "load_model",
    "kernel_names",
    "run",
    "Results",
    "simulate",
    "read_bag",
    "residuals",
]

_KINDS = {
    "exact_gp": ExactGP,
    "sparse_gp": SparseGP,
    "ilgr": ILGR,
    "streaming_sparse_gp": StreamingSparseGP,
}


def kernel_names():
    """The kernel names a kernel expression may combine with ``+`` and ``*``."""
    return _native.kernel_names()


def load_model(path):
    """Reads a model file (what ``gpodo fit --save`` or ``Estimator.save``
    writes) as a fitted estimator of its kind, ready to predict."""
    model = _native.load_model(str(path))
    state = json.loads(model.to_json())["state"]
    kind = state["kind"]
    if kind not in _KINDS:
        raise ValueError(
            f"{path}: a `{kind}` model, which has no Python estimator yet; "
            f"these load: {', '.join(sorted(_KINDS))}"
        )
    params = dict(state["params"])
    estimator = _KINDS[kind]()
    if kind == "exact_gp":
        estimator.set_params(kernel=params["kernel"])
    elif kind == "sparse_gp":
        estimator.set_params(
            kernel=params["kernel"],
            approximation=params["approximation"],
            n_inducing=params["inducing"]["count"],
        )
    elif kind == "streaming_sparse_gp":
        estimator.set_params(
            kernel=params["kernel"],
            n_inducing=params["inducing"]["count"],
            batch_rows=params["batch_rows"],
        )
    estimator.model_ = model
    estimator.n_features_in_ = len(model.input_names)
    names = model.input_names
    if names != [f"x{i}" for i in range(len(names))]:
        estimator.feature_names_in_ = np.asarray(names, dtype=object)
    estimator._y_was_1d = len(model.target_names) == 1
    estimator._set_fitted_attributes({"parameters": [], "objective": None, "evaluations": None})
    return estimator
