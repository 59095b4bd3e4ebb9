"""scikit-learn estimators over gpodo's regressors.

Each estimator's parameters are the settings of a `regressors:` entry of a
gpodo experiment file (``kind: exact_gp``, ``sparse_gp``, ``ilgr``,
``streaming_sparse_gp``), under
the same names, with these exceptions:

===========================  ==========================================
Python                       YAML
===========================  ==========================================
``SparseGP(n_inducing=m)``   ``inducing: {count: m}`` (and for
                             ``StreamingSparseGP``)
``hyperopt={...}``           the ``hyperopt:`` block, e.g. ``{"max_iters": 50}``
``init={...}``               the ``init:`` block (initial hyperparameters)
``settings={...}``           any other field, as written in YAML
``verbose=True``             (Python only) print the optimiser's progress
===========================  ==========================================

A parameter left at ``None`` takes gpodo's default, so a fit from Python
and ``gpodo fit`` on the same settings and rows give the same numbers.
"""

import json

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from . import _native

__all__ = ["ExactGP", "SparseGP", "ILGR", "StreamingSparseGP"]


def _input_names(estimator, n_features):
    names = getattr(estimator, "feature_names_in_", None)
    if names is not None:
        return [str(n) for n in names]
    return [f"x{i}" for i in range(n_features)]


class _GpodoRegressor(RegressorMixin, BaseEstimator):
    """What every gpodo estimator shares: validation, the fit through the
    native module, prediction with uncertainty, pickling and saving."""

    _kind = None

    def _spec(self):
        raise NotImplementedError

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = True
        return tags

    def fit(self, X, y):
        """Learns the hyperparameters (or the local models) from ``X``
        (n_samples × n_features) and ``y`` (n_samples, or n_samples ×
        n_outputs). Returns the estimator."""
        X, y = validate_data(
            self, X, y, multi_output=True, y_numeric=True, dtype=np.float64
        )
        if X.shape[0] < 2:
            raise ValueError(
                f"gpodo needs at least 2 samples to fit, got {X.shape[0]} sample"
            )
        self._y_was_1d = y.ndim == 1
        Y = y.reshape(-1, 1) if y.ndim == 1 else y
        Y = np.ascontiguousarray(Y, dtype=np.float64)
        X = np.ascontiguousarray(X, dtype=np.float64)
        targets = [f"y{j}" for j in range(Y.shape[1])]
        spec = json.dumps({"kind": self._kind, **self._spec()})
        self.model_ = _native.fit(
            spec,
            X,
            Y,
            _input_names(self, X.shape[1]),
            targets,
            bool(getattr(self, "verbose", False)),
        )
        self._set_fitted_attributes(json.loads(self.model_.fit_report))
        return self

    def _set_fitted_attributes(self, report):
        self.fit_report_ = report
        self.n_evaluations_ = report.get("evaluations")
        self.hyperparameters_ = dict(report.get("parameters") or [])
        self.log_marginal_likelihood_value_ = report.get("objective")

    def _predict_moments(self, X):
        check_is_fitted(self, "model_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        X = np.ascontiguousarray(X, dtype=np.float64)
        return self.model_.predict(X)

    def predict(self, X, return_std=False, latent=False):
        """The predictive mean of each row of ``X``; with
        ``return_std=True`` also the standard deviation of a new
        observation, noise included (as scikit-learn's
        ``GaussianProcessRegressor`` with a ``WhiteKernel``), or with
        ``latent=True`` that of the latent function alone (GPs only)."""
        mean, noisy, latent_var = self._predict_moments(X)
        if latent and latent_var is None:
            raise ValueError(f"{type(self).__name__} has no latent variance")
        var = latent_var if latent else noisy
        if self._y_was_1d:
            mean, var = mean[:, 0], var[:, 0]
        if return_std:
            return mean, np.sqrt(np.maximum(var, 0.0))
        return mean

    def save(self, path):
        """Writes the model file that ``gpodo predict --model`` reads."""
        check_is_fitted(self, "model_")
        self.model_.save(str(path))

    def __getstate__(self):
        state = self.__dict__.copy()
        if "model_" in state:
            state["model_"] = state["model_"].to_json()
        return state

    def __setstate__(self, state):
        if isinstance(state.get("model_"), str):
            state["model_"] = _native.model_from_json(state["model_"])
        self.__dict__.update(state)


def _with_settings(settings, explicit):
    """``settings`` (any field, as in YAML) overridden by the explicit
    parameters that are not None: a parameter left at None neither sets
    nor hides its field."""
    return {**(settings or {}), **{k: v for k, v in explicit.items() if v is not None}}


class ExactGP(_GpodoRegressor):
    """The exact Gaussian process of gpodo (``kind: exact_gp``).

    Parameters
    ----------
    kernel : str, default "rbf"
        A kernel expression (``"rbf + linear"``, ``"matern52 * linear"``)
        of the names ``gpodo.kernel_names()``, or ``"auto"``: each of
        ``kernel_candidates`` fitted, the highest log marginal likelihood
        kept.
    outputs : {"shared", "independent"}, default None ("shared")
        One kernel for every output, or one GP per output.
    standardize, noise_variance, optimize, seed, kernel_candidates
        As in YAML; None takes gpodo's default.
    init, hyperopt : dict, default None
        The ``init:`` and ``hyperopt:`` blocks.
    settings : dict, default None
        Any other field of ``kind: exact_gp``.
    verbose : bool, default False
        Print each optimiser iteration to ``sys.stderr``.

    Attributes
    ----------
    log_marginal_likelihood_value_ : float or ndarray
        The log marginal likelihood on the standardised training rows (one
        per output when ``outputs="independent"``).
    hyperparameters_ : dict
        The learned hyperparameters by name (``rbf.lengthscale[x0]``).
    n_evaluations_ : int
        Objective evaluations the optimiser used.
    """

    _kind = "exact_gp"

    def __init__(
        self,
        kernel="rbf",
        outputs=None,
        standardize=None,
        noise_variance=None,
        optimize=None,
        seed=None,
        kernel_candidates=None,
        init=None,
        hyperopt=None,
        settings=None,
        verbose=False,
    ):
        self.kernel = kernel
        self.outputs = outputs
        self.standardize = standardize
        self.noise_variance = noise_variance
        self.optimize = optimize
        self.seed = seed
        self.kernel_candidates = kernel_candidates
        self.init = init
        self.hyperopt = hyperopt
        self.settings = settings
        self.verbose = verbose

    def _spec(self):
        _check_kernel(self.kernel, allow_auto=True)
        return _with_settings(
            self.settings,
            {
                "kernel": self.kernel,
                "outputs": self.outputs,
                "standardize": self.standardize,
                "noise_variance": self.noise_variance,
                "optimize": self.optimize,
                "seed": self.seed,
                "kernel_candidates": self.kernel_candidates,
                "init": self.init,
                "hyperopt": self.hyperopt,
            }
        )

    def _set_fitted_attributes(self, report):
        super()._set_fitted_attributes(report)
        if self.outputs == "independent":
            self.log_marginal_likelihood_value_ = np.array(
                self.model_.log_marginal_likelihoods()
            )


class SparseGP(_GpodoRegressor):
    """gpodo's sparse GP (``kind: sparse_gp``): VFE or FITC with learned
    inducing inputs.

    Parameters
    ----------
    kernel : str, default "rbf"
        A kernel expression of the names ``gpodo.kernel_names()``.
    approximation : {"vfe", "fitc"}, default "vfe"
    n_inducing : int, default 100
        Inducing points (``inducing: {count: ...}``); at most the rows.
    standardize, noise_variance, optimize, seed
        As in YAML; None takes gpodo's default.
    init, hyperopt, settings, verbose
        As for ``ExactGP``.
    """

    _kind = "sparse_gp"

    def __init__(
        self,
        kernel="rbf",
        approximation="vfe",
        n_inducing=100,
        standardize=None,
        noise_variance=None,
        optimize=None,
        seed=None,
        init=None,
        hyperopt=None,
        settings=None,
        verbose=False,
    ):
        self.kernel = kernel
        self.approximation = approximation
        self.n_inducing = n_inducing
        self.standardize = standardize
        self.noise_variance = noise_variance
        self.optimize = optimize
        self.seed = seed
        self.init = init
        self.hyperopt = hyperopt
        self.settings = settings
        self.verbose = verbose

    def _spec(self):
        _check_kernel(self.kernel, allow_auto=False)
        settings = dict(self.settings or {})
        inducing = dict(settings.pop("inducing", {}) or {})
        inducing["count"] = int(self.n_inducing)
        return _with_settings(
            settings,
            {
                "kernel": self.kernel,
                "approximation": self.approximation,
                "inducing": inducing,
                "standardize": self.standardize,
                "noise_variance": self.noise_variance,
                "optimize": self.optimize,
                "seed": self.seed,
                "init": self.init,
                "hyperopt": self.hyperopt,
            }
        )


class _OnlineRegressor(_GpodoRegressor):
    """An estimator that goes on learning from new rows."""

    def partial_fit(self, X, y):
        """Learns from more rows, one at a time, in order (fits first when
        not fitted yet); a streaming sparse GP learns them in its batches,
        keeping the rows of an unfinished batch until it is complete.
        Returns the estimator."""
        if not hasattr(self, "model_"):
            return self.fit(X, y)
        X, y = validate_data(
            self, X, y, reset=False, multi_output=True, y_numeric=True, dtype=np.float64
        )
        Y = y.reshape(-1, 1) if y.ndim == 1 else y
        if Y.shape[1] != len(self.model_.target_names):
            raise ValueError(
                f"y has {Y.shape[1]} outputs, the model was fitted on {len(self.model_.target_names)}"
            )
        self.model_.update(
            np.ascontiguousarray(X, dtype=np.float64),
            np.ascontiguousarray(Y, dtype=np.float64),
        )
        return self


class ILGR(_OnlineRegressor):
    """Incremental local Gaussian regression (``kind: ilgr``), which goes on
    learning from new rows with ``partial_fit``.

    Parameters
    ----------
    w_gen, init_lengthscale, forgetting, max_models, passes, seed
        As in YAML; None takes gpodo's default.
    settings : dict, default None
        Any other field of ``kind: ilgr``.
    verbose : bool, default False
    """

    _kind = "ilgr"

    def __init__(
        self,
        w_gen=None,
        init_lengthscale=None,
        forgetting=None,
        max_models=None,
        passes=None,
        seed=None,
        settings=None,
        verbose=False,
    ):
        self.w_gen = w_gen
        self.init_lengthscale = init_lengthscale
        self.forgetting = forgetting
        self.max_models = max_models
        self.passes = passes
        self.seed = seed
        self.settings = settings
        self.verbose = verbose

    def _spec(self):
        return _with_settings(
            self.settings,
            {
                "w_gen": self.w_gen,
                "init_lengthscale": self.init_lengthscale,
                "forgetting": self.forgetting,
                "max_models": self.max_models,
                "passes": self.passes,
                "seed": self.seed,
            }
        )


def _check_kernel(kernel, allow_auto):
    if not isinstance(kernel, str):
        raise ValueError(f"kernel must be a string expression, got {kernel!r}")
    if allow_auto and kernel.strip().lower() == "auto":
        return
    known = _native.kernel_names()
    words = kernel.replace("(", " ").replace(")", " ").replace("+", " ").replace("*", " ").split()
    for word in words:
        if word.lower() not in known:
            raise ValueError(
                f"unknown kernel `{word}` in {kernel!r}; known kernels: {', '.join(known)}"
                + (", or `auto`" if allow_auto else "")
            )


class StreamingSparseGP(_OnlineRegressor):
    """The streaming sparse GP (``kind: streaming_sparse_gp``; Bui, Nguyen
    & Turner, NeurIPS 2017): a variational posterior over inducing points,
    learned in batches that are never revisited, with the hyperparameters
    and inducing inputs climbing the streaming bound on each batch. It goes
    on learning with ``partial_fit``.

    Parameters
    ----------
    kernel : str, default "rbf"
        A kernel expression of the names ``gpodo.kernel_names()``.
    n_inducing : int, default 100
        The most inducing points a batch keeps (``inducing: {count: ...}``).
    kept_inducing, warmup_rows, batch_rows, batch_iters, standardize,
    noise_variance, seed
        As in YAML; None takes gpodo's default.
    init, hyperopt, settings, verbose
        As for ``ExactGP``.
    """

    _kind = "streaming_sparse_gp"

    def __init__(
        self,
        kernel="rbf",
        n_inducing=100,
        kept_inducing=None,
        warmup_rows=None,
        batch_rows=None,
        batch_iters=None,
        standardize=None,
        noise_variance=None,
        seed=None,
        init=None,
        hyperopt=None,
        settings=None,
        verbose=False,
    ):
        self.kernel = kernel
        self.n_inducing = n_inducing
        self.kept_inducing = kept_inducing
        self.warmup_rows = warmup_rows
        self.batch_rows = batch_rows
        self.batch_iters = batch_iters
        self.standardize = standardize
        self.noise_variance = noise_variance
        self.seed = seed
        self.init = init
        self.hyperopt = hyperopt
        self.settings = settings
        self.verbose = verbose

    def _spec(self):
        _check_kernel(self.kernel, allow_auto=False)
        settings = dict(self.settings or {})
        inducing = dict(settings.pop("inducing", {}) or {})
        inducing["count"] = int(self.n_inducing)
        return _with_settings(
            settings,
            {
                "kernel": self.kernel,
                "inducing": inducing,
                "kept_inducing": self.kept_inducing,
                "warmup_rows": self.warmup_rows,
                "batch_rows": self.batch_rows,
                "batch_iters": self.batch_iters,
                "standardize": self.standardize,
                "noise_variance": self.noise_variance,
                "seed": self.seed,
                "init": self.init,
                "hyperopt": self.hyperopt,
            }
        )
