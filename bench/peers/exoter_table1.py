#!/usr/bin/env python3
"""Table I on the real ExoTeR table with GPy (and scikit-learn), as gpodo runs it.

The same split, preprocessing and model as `experiments/exoter-table1.yaml`:
the authors' 2337 one-second rows in time order, the first floor(0.8 n) rows
train and the rest test; inputs and targets z-scored with the training
rows' mean and population std (std < 1e-12 -> 1); one kernel and one
Gaussian noise shared by the 3 targets; L-BFGS-B on the log marginal
likelihood (LML) summed over the targets; held-out predictions mapped back
to m/s.

Kernels (ARD everywhere, as gpodo's): rbf, rbf+linear, matern52,
matern52+linear. Start (`--start gpy`, default): GPy's defaults, i.e.
variance 1, lengthscales 1, linear variances 1, noise 0.01 (the authors'
`0.01 var(Y)` in standardised units). `--start sqrt-d`: lengthscales sqrt(D),
linear variances 1/D (gpodo's old single start).

One JSON line per (peer, kernel) on stdout: wall seconds of the fit call,
evaluations, the LML recomputed jitter-free at the final hyperparameters
("lml"), the peer's own value ("lml_peer"), held-out RMSE and MAE pooled over
the three targets, and the final hyperparameters.

scikit-learn has no ARD linear kernel, so it runs the rbf and matern52 rows
only (ConstantKernel * RBF / Matern(nu=2.5) + WhiteKernel, alpha=0, its own
L-BFGS-B in log space within gpodo's default bounds).

Usage (from the repository root, with the venv of bench/peers/requirements.txt):

    /path/to/venv/bin/python bench/peers/exoter_table1.py --kernels rbf,matern52 --peers gpy
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fit_peers import DEFAULT_TABLE, N_INPUTS, TARGETS, TimeLimit, load_table  # noqa: E402

KERNELS = ["rbf", "rbf+linear", "matern52", "matern52+linear"]
START_NOISE = 0.01


def split_and_scale(path, train_fraction):
    x, y, names = load_table(path, None, N_INPUTS)
    n_train = int(math.floor(train_fraction * x.shape[0]))

    def stats(a):
        mean = a[:n_train].mean(axis=0)
        std = a[:n_train].std(axis=0, ddof=0)
        return mean, np.where(std < 1e-12, 1.0, std)

    xm, xs = stats(x)
    ym, ys = stats(y)
    xz = (x - xm) / xs
    yz = (y - ym) / ys
    return {
        "x_train": xz[:n_train], "y_train": yz[:n_train],
        "x_test": xz[n_train:], "y_test_raw": y[n_train:],
        "y_mean": ym, "y_std": ys, "names": names,
    }


def jitter_free_lml(k, noise, y):
    k = k.copy()
    k[np.diag_indices_from(k)] += noise
    chol = np.linalg.cholesky(k)
    alpha = scipy.linalg.cho_solve((chol, True), y)
    n, p = y.shape
    return float(-0.5 * np.sum(y * alpha) - p * np.sum(np.log(np.diag(chol)))
                 - 0.5 * n * p * math.log(2.0 * math.pi))


def scores(mean_z, data):
    pred = mean_z * data["y_std"] + data["y_mean"]
    err = pred - data["y_test_raw"]
    return float(np.sqrt(np.mean(err ** 2))), float(np.mean(np.abs(err)))


def gpy_kernel(name, d, lengthscale, linear_variance):
    import GPy

    parts = []
    for leaf in name.split("+"):
        if leaf == "rbf":
            parts.append(GPy.kern.RBF(d, variance=1.0, lengthscale=[lengthscale] * d, ARD=True))
        elif leaf == "matern52":
            parts.append(GPy.kern.Matern52(d, variance=1.0, lengthscale=[lengthscale] * d, ARD=True))
        elif leaf == "linear":
            parts.append(GPy.kern.Linear(d, variances=[linear_variance] * d, ARD=True))
        else:
            sys.exit(f"unknown kernel {leaf!r}")
    kern = parts[0]
    for p in parts[1:]:
        kern = kern + p
    return kern


def fit_gpy(data, kernel, start, max_iters, time_limit):
    import GPy

    d = data["x_train"].shape[1]
    lengthscale, linear_variance = (1.0, 1.0) if start == "gpy" else (math.sqrt(d), 1.0 / d)
    kern = gpy_kernel(kernel, d, lengthscale, linear_variance)
    m = GPy.models.GPRegression(data["x_train"], data["y_train"], kern, noise_var=START_NOISE)
    calls = [0]
    inner = m._objective_grads
    t0 = time.perf_counter()

    def counted(x):
        calls[0] += 1
        if time_limit is not None and time.perf_counter() - t0 > time_limit:
            raise TimeLimit()
        return inner(x)

    m._objective_grads = counted
    status, opt = "ok", None
    try:
        opt = m.optimize("lbfgsb", max_iters=max_iters, messages=False)
    except TimeLimit:
        status = "time limit"
    seconds = time.perf_counter() - t0
    noise = float(m.Gaussian_noise.variance[0])
    lml = jitter_free_lml(m.kern.K(data["x_train"]), noise, data["y_train"])
    mean_z, _ = m.predict_noiseless(data["x_test"])
    rmse, mae = scores(mean_z, data)
    return {
        "impl": f"GPy {GPy.__version__}", "status": status if opt is None else f"{status}: {opt.status}",
        "seconds": seconds, "evaluations": int(opt.funct_eval) if opt is not None else calls[0],
        "lml": lml, "lml_peer": float(m.log_likelihood()), "rmse": rmse, "mae": mae,
        "noise_variance": noise, "parameters": [float(v) for v in m.kern.param_array],
    }


def fit_sklearn(data, kernel, start, max_iters, time_limit):
    import scipy.optimize
    import sklearn
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Matern, WhiteKernel

    if "linear" in kernel:
        return None
    d = data["x_train"].shape[1]
    ls = [1.0 if start == "gpy" else math.sqrt(d)] * d
    stationary = (RBF(ls, (1e-3, 1e5)) if kernel == "rbf"
                  else Matern(ls, (1e-3, 1e5), nu=2.5))
    kern = ConstantKernel(1.0, (1e-6, 1e4)) * stationary + WhiteKernel(START_NOISE, (1e-8, 1e2))
    info = {"nfev": None}
    t0 = time.perf_counter()

    def optimizer(obj_func, theta0, bounds):
        def f(theta):
            if time_limit is not None and time.perf_counter() - t0 > time_limit:
                raise TimeLimit()
            return obj_func(theta, eval_gradient=True)

        res = scipy.optimize.minimize(f, theta0, method="L-BFGS-B", jac=True, bounds=bounds,
                                      options={"maxiter": max_iters, "maxfun": max_iters})
        info["nfev"] = int(res.nfev)
        return res.x, res.fun

    gpr = GaussianProcessRegressor(kernel=kern, alpha=0.0, optimizer=optimizer, normalize_y=False)
    try:
        gpr.fit(data["x_train"], data["y_train"])
    except TimeLimit:
        return {"impl": f"scikit-learn {sklearn.__version__}", "status": "time limit",
                "seconds": time.perf_counter() - t0}
    seconds = time.perf_counter() - t0
    mean_z = gpr.predict(data["x_test"])
    rmse, mae = scores(mean_z, data)
    return {
        "impl": f"scikit-learn {sklearn.__version__}", "status": "ok", "seconds": seconds,
        "evaluations": info["nfev"], "lml": float(gpr.log_marginal_likelihood_value_),
        "lml_peer": float(gpr.log_marginal_likelihood_value_), "rmse": rmse, "mae": mae,
        "noise_variance": float(gpr.kernel_.k2.noise_level),
    }


PEERS = {"gpy": fit_gpy, "sklearn": fit_sklearn}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--table", type=Path, default=DEFAULT_TABLE)
    ap.add_argument("--train-fraction", type=float, default=0.8)
    ap.add_argument("--kernels", default=",".join(KERNELS), help=f"comma list of {KERNELS}")
    ap.add_argument("--peers", default="gpy", help="comma list of: gpy, sklearn")
    ap.add_argument("--start", choices=["gpy", "sqrt-d"], default="gpy")
    ap.add_argument("--max-iters", type=int, default=1000)
    ap.add_argument("--time-limit", type=float, default=None)
    args = ap.parse_args()
    data = split_and_scale(args.table, args.train_fraction)
    for kernel in [k.strip() for k in args.kernels.split(",") if k.strip()]:
        if kernel not in KERNELS:
            sys.exit(f"unknown kernel {kernel!r}; choose from {KERNELS}")
        for peer in [p.strip() for p in args.peers.split(",") if p.strip()]:
            out = PEERS[peer](data, kernel, args.start, args.max_iters, args.time_limit)
            if out is None:
                continue
            out.update(kernel=kernel, start=args.start, n_train=len(data["x_train"]),
                       n_test=len(data["x_test"]))
            print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
