"""gpodo's estimators from Python: the same numbers as the Rust library,
an independent NumPy posterior, scikit-learn's conventions, saved models
shared with the command line, errors, the GIL and interruption."""

import json
import os
import pickle
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, cross_val_score
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

import gpodo
from gpodo import ILGR, ExactGP, SparseGP, StreamingSparseGP


def data(n=120, d=3, outputs=3, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, d))
    Y = np.column_stack(
        [np.sin(X[:, 0] + k) + 0.3 * X[:, 1] * k + 0.05 * rng.normal(size=n) for k in range(outputs)]
    )
    return X, Y


# --- The same numbers as the Rust library, and an independent posterior ---


def test_the_fit_equals_the_rust_librarys_on_the_same_rows(tmp_path, fit_csv):
    X, Y = data()
    # The columns the Rust example reads, already z-scored as it expects.
    X = (X - X.mean(0)) / X.std(0)
    table = tmp_path / "rows.csv"
    header = ",".join([f"x{i}" for i in range(X.shape[1])] + ["y0", "y1", "y2"])
    np.savetxt(table, np.column_stack([X, Y]), delimiter=",", header=header, comments="", fmt="%.17g")
    out = subprocess.run([str(fit_csv), str(table)], capture_output=True, text=True, check=True)
    rust = json.loads(out.stdout.strip().splitlines()[-1])
    gp = ExactGP().fit(X, Y)
    assert abs(gp.log_marginal_likelihood_value_ - rust["lml"]) <= 1e-12 * abs(rust["lml"])


def test_predictions_equal_a_numpy_gp_posterior_at_the_learned_hyperparameters():
    X, Y = data(outputs=1)
    y = Y[:, 0]
    gp = ExactGP(standardize=False).fit(X, y)
    h = gp.hyperparameters_
    variance = h["rbf.variance"]
    lengthscales = np.array([h[f"rbf.lengthscale[x{i}]"] for i in range(X.shape[1])])
    noise = h["noise_variance"]

    def k(a, b):
        d = (a[:, None, :] - b[None, :, :]) / lengthscales
        return variance * np.exp(-0.5 * (d**2).sum(-1))

    Xs = np.random.default_rng(9).normal(size=(15, X.shape[1]))
    K = k(X, X) + noise * np.eye(len(X))
    Ks = k(X, Xs)
    mean = Ks.T @ np.linalg.solve(K, y)
    latent = variance - np.einsum("ij,ij->j", Ks, np.linalg.solve(K, Ks))
    got_mean, got_std = gp.predict(Xs, return_std=True)
    _, got_latent_std = gp.predict(Xs, return_std=True, latent=True)
    np.testing.assert_allclose(got_mean, mean, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(got_latent_std**2, latent, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(got_std**2, latent + noise, rtol=1e-8, atol=1e-10)


# --- scikit-learn's conventions ---


@pytest.mark.parametrize("make", [ExactGP, lambda: SparseGP(n_inducing=20), ILGR])
def test_multi_output_and_single_output_shapes(make):
    X, Y = data()
    model = make().fit(X, Y)
    mean, std = model.predict(X[:7], return_std=True)
    assert mean.shape == std.shape == (7, 3)
    single = make().fit(X, Y[:, 0])
    assert single.predict(X[:7]).shape == (7,)


def test_fitted_attributes_name_the_hyperparameters_and_the_likelihood():
    X, Y = data()
    gp = ExactGP().fit(X, Y)
    assert isinstance(gp.log_marginal_likelihood_value_, float)
    assert gp.n_evaluations_ > 0
    assert {"rbf.variance", "rbf.lengthscale[x0]", "noise_variance"} <= set(gp.hyperparameters_)
    independent = ExactGP(outputs="independent").fit(X, Y)
    lml = independent.log_marginal_likelihood_value_
    assert lml.shape == (3,)
    assert abs(lml.sum() - independent.fit_report_["objective"]) < 1e-9 * abs(lml.sum())


def test_they_work_in_pipelines_grid_searches_and_cross_validation():
    X, Y = data(n=90)
    pipe = make_pipeline(StandardScaler(), ExactGP(hyperopt={"max_iters": 30}))
    scores = cross_val_score(pipe, X, Y[:, 0], cv=3)
    assert np.all(scores > 0.8)
    grid = GridSearchCV(ExactGP(hyperopt={"max_iters": 30}), {"kernel": ["rbf", "rbf + linear"]}, cv=3)
    grid.fit(X, Y[:, 0])
    assert grid.best_params_["kernel"] in {"rbf", "rbf + linear"}
    cloned = clone(ExactGP(kernel="matern52", seed=3))
    assert cloned.get_params()["kernel"] == "matern52" and not hasattr(cloned, "model_")


def test_latent_std_is_below_the_noisy_one():
    X, Y = data(outputs=1)
    gp = ExactGP().fit(X, Y[:, 0])
    _, noisy = gp.predict(X, return_std=True)
    _, latent = gp.predict(X, return_std=True, latent=True)
    assert np.all(latent < noisy)
    with pytest.raises(ValueError, match="no latent variance"):
        ILGR().fit(X, Y[:, 0]).predict(X, return_std=True, latent=True)


@pytest.mark.parametrize("make", [ExactGP, lambda: SparseGP(n_inducing=20), ILGR])
def test_they_pickle_to_identical_predictions(make):
    X, Y = data()
    model = make().fit(X, Y)
    again = pickle.loads(pickle.dumps(model))
    a, sa = model.predict(X, return_std=True)
    b, sb = again.predict(X, return_std=True)
    assert np.array_equal(a, b) and np.array_equal(sa, sb)


def test_ilgr_learns_on_with_partial_fit():
    X, Y = data(n=300, outputs=1)
    y = Y[:, 0]
    online = ILGR().fit(X[:50], y[:50])
    before = np.mean((online.predict(X[200:]) - y[200:]) ** 2)
    for start in range(50, 200, 25):
        online.partial_fit(X[start : start + 25], y[start : start + 25])
    after = np.mean((online.predict(X[200:]) - y[200:]) ** 2)
    assert after < before
    with pytest.raises(ValueError, match="features"):
        online.partial_fit(X[:5, :2], y[:5])


def test_the_streaming_sparse_gp_learns_on_in_batches_and_pickles_mid_batch():
    X, Y = data(n=300, outputs=1)
    y = Y[:, 0]
    online = StreamingSparseGP(n_inducing=20, warmup_rows=50, batch_rows=10).fit(X[:50], y[:50])
    before = np.mean((online.predict(X[200:]) - y[200:]) ** 2)
    for start in range(50, 195, 25):
        online.partial_fit(X[start : start + 25], y[start : start + 25])
    after = np.mean((online.predict(X[200:]) - y[200:]) ** 2)
    assert after < before
    # 145 rows after the first batch: 14 batches learned, 5 rows pending,
    # which a pickled copy keeps and completes as the original does.
    again = pickle.loads(pickle.dumps(online))
    online.partial_fit(X[195:200], y[195:200])
    again.partial_fit(X[195:200], y[195:200])
    assert np.array_equal(online.predict(X[200:]), again.predict(X[200:]))
    assert json.loads(online.model_.to_json())["state"]["batches"] == 16


def test_settings_reach_the_spec_unless_a_parameter_overrides_them():
    spec = StreamingSparseGP(settings={"batch_iters": 0, "batch_rows": 5}, batch_rows=7)._spec()
    assert spec["batch_iters"] == 0 and spec["batch_rows"] == 7
    assert SparseGP(settings={"standardize": False})._spec()["standardize"] is False
    assert ILGR(settings={"forgetting": 0.9})._spec()["forgetting"] == 0.9


def test_a_dataframes_column_names_are_recorded_and_saved(tmp_path):
    pd = pytest.importorskip("pandas")
    X, Y = data(outputs=1)
    frame = pd.DataFrame(X, columns=["roll", "pitch", "spd_fl"])
    gp = ExactGP().fit(frame, Y[:, 0])
    assert list(gp.feature_names_in_) == ["roll", "pitch", "spd_fl"]
    gp.save(tmp_path / "m.gpodo")
    saved = json.loads((tmp_path / "m.gpodo").read_text())
    assert saved["input_names"] == ["roll", "pitch", "spd_fl"]
    assert ExactGP().fit(X, Y[:, 0]).model_.input_names == ["x0", "x1", "x2"]


# --- Saved models shared with the command line ---


def write_csv(path, names, rows):
    np.savetxt(path, rows, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def read_predictions(path):
    table = np.genfromtxt(path, delimiter=",", names=True)
    names = table.dtype.names
    means = np.column_stack([table[n] for n in names if n.startswith("mean_")])
    variances = np.column_stack([table[n] for n in names if n.startswith("var_")])
    return means, variances


def test_a_model_saved_in_python_predicts_the_same_in_the_cli(tmp_path, gpodo_cli):
    X, Y = data()
    gp = ExactGP().fit(X, Y)
    gp.save(tmp_path / "py.gpodo")
    write_csv(tmp_path / "rows.csv", ["x2", "x0", "x1"], X[:, [2, 0, 1]])
    subprocess.run(
        [str(gpodo_cli), "--quiet", "predict", "--model", str(tmp_path / "py.gpodo"),
         "--input", str(tmp_path / "rows.csv"), "--out", str(tmp_path / "pred.csv")],
        check=True,
    )
    cli_mean, cli_var = read_predictions(tmp_path / "pred.csv")
    mean, std = gp.predict(X, return_std=True)
    np.testing.assert_allclose(cli_mean, mean, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(cli_var, std**2, rtol=1e-12, atol=1e-15)


def test_a_model_saved_by_the_cli_predicts_the_same_in_python(tmp_path, gpodo_cli):
    X, Y = data()
    names = ["a", "b", "c", "t1", "t2", "t3"]
    write_csv(tmp_path / "table.csv", names, np.column_stack([X, Y]))
    (tmp_path / "exp.yaml").write_text(
        "name: t\ndataset: {kind: residual_table, path: table.csv, targets: [t1, t2, t3], train_fraction: 0.8}\n"
        "regressors:\n  - kind: exact_gp\n    kernel: rbf\n"
    )
    subprocess.run(
        [str(gpodo_cli), "--quiet", "fit", str(tmp_path / "exp.yaml"), "--regressor", "exact GP: rbf",
         "--save", str(tmp_path / "cli.gpodo")],
        check=True,
    )
    model = gpodo.load_model(tmp_path / "cli.gpodo")
    assert list(model.feature_names_in_) == ["a", "b", "c"]
    subprocess.run(
        [str(gpodo_cli), "--quiet", "predict", "--model", str(tmp_path / "cli.gpodo"),
         "--input", str(tmp_path / "table.csv"), "--out", str(tmp_path / "pred.csv")],
        check=True,
    )
    cli_mean, cli_var = read_predictions(tmp_path / "pred.csv")
    mean, std = model.predict(X, return_std=True)
    np.testing.assert_allclose(mean, cli_mean, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(std**2, cli_var, rtol=1e-12, atol=1e-15)


# --- Errors, never crashes ---


@pytest.mark.parametrize(
    "X, y, message",
    [
        (np.array([[np.nan, 1.0], [2.0, 3.0], [1.0, 1.0]]), np.ones(3), "NaN"),
        (np.array([[np.inf, 1.0], [2.0, 3.0], [1.0, 1.0]]), np.ones(3), "infinity"),
        (np.ones((4, 2)), np.ones(3), "inconsistent numbers of samples"),
        (np.empty((0, 2)), np.empty(0), "0 sample"),
        (np.array([["a", "b"], ["c", "d"]]), np.ones(2), "could not convert"),
        (np.ones((1, 2)), np.ones(1), "at least 2 samples"),
    ],
)
def test_bad_input_is_a_value_error_naming_it(X, y, message):
    with pytest.raises(ValueError, match=message):
        ExactGP().fit(X, y)


def test_an_unknown_kernel_lists_the_known_ones():
    X, Y = data()
    with pytest.raises(ValueError, match="unknown kernel `rbff`.*rbf, matern52"):
        ExactGP(kernel="rbf + rbff").fit(X, Y)
    with pytest.raises(ValueError, match="unknown field"):
        ExactGP(settings={"max_iter": 3}).fit(X, Y)


def test_predicting_with_the_wrong_width_or_before_fitting_is_an_error():
    from sklearn.exceptions import NotFittedError

    X, Y = data()
    with pytest.raises(NotFittedError):
        ExactGP().predict(X)
    gp = ExactGP().fit(X, Y)
    with pytest.raises(ValueError, match="features"):
        gp.predict(X[:, :2])


def test_a_rust_panic_is_a_runtime_error_and_python_goes_on():
    # pyo3's own PanicException derives from BaseException, so this
    # catches only the conversion to RuntimeError.
    from gpodo import _native

    with pytest.raises(RuntimeError, match="a bug; please report it.*deliberate panic"):
        _native._panic_for_tests("deliberate panic")
    X, Y = data()
    assert ExactGP().fit(X, Y).predict(X).shape == Y.shape


# --- Python keeps running during a fit ---


def test_other_threads_run_while_a_fit_runs():
    X, Y = data(n=700, d=6)
    counter = [0]
    done = threading.Event()
    progress = {}

    def spin():
        while not done.is_set():
            counter[0] += 1

    def fit():
        before = counter[0]
        ExactGP(hyperopt={"max_iters": 40}).fit(X, Y)
        progress["during"] = counter[0] - before
        done.set()

    spinner = threading.Thread(target=spin)
    spinner.start()
    fit()
    spinner.join()
    # Holding the GIL through the fit would leave the spinner a few
    # switch intervals at most; released, it runs the whole fit long.
    assert progress["during"] > 100_000, progress


def test_ctrl_c_interrupts_a_fit_at_its_next_iteration():
    X, Y = data(n=1500, d=8)
    # Python's own Ctrl-C handler, as in a terminal or a notebook (a process
    # started in the background by a shell inherits SIGINT ignored).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            ExactGP(hyperopt={"max_iters": 1000}).fit(X, Y)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


def test_progress_goes_to_sys_stderr_only_when_verbose(capsys):
    X, Y = data()
    ExactGP(hyperopt={"max_iters": 5}).fit(X, Y)
    assert capsys.readouterr().err == ""
    ExactGP(hyperopt={"max_iters": 5}, verbose=True).fit(X, Y)
    assert "gpodo: start 0, iteration 1" in capsys.readouterr().err


def test_every_public_name_has_a_docstring():
    for name in gpodo.__all__:
        assert getattr(gpodo, name).__doc__, name
    for cls in (ExactGP, SparseGP, ILGR, StreamingSparseGP):
        for method in ("fit", "predict", "save"):
            assert getattr(cls, method).__doc__, (cls, method)
    assert ILGR.partial_fit.__doc__
    assert StreamingSparseGP.partial_fit.__doc__
