#!/usr/bin/env python3
"""Fit the ExoTeR GP training table with peer GP libraries (GPy, scikit-learn).

Both peers fit the same model as gpodo's exact GP: an ARD RBF kernel shared by
the 3 target columns with one shared Gaussian noise, hyperparameters found by
L-BFGS-B on the log marginal likelihood (LML, summed over the 3 outputs).

Preprocessing (identical for gpodo, see --write-data): the first N rows (time
order) and the first D input columns are taken; every X and Y column is
z-scored with its mean and population standard deviation (ddof=0), a column
whose std is < 1e-12 getting std 1.

Start point (both peers): signal variance 1.0, all lengthscales sqrt(D), noise
variance 0.01.

* GPy: GPRegression(X, Y[n x 3]), m.optimize('lbfgsb', max_iters=M) (paramz
  passes maxiter = maxfun = M to scipy's fmin_l_bfgs_b; softplus transforms).
* scikit-learn: ConstantKernel(1, (1e-6, 1e4)) * RBF([sqrt(D)]*D, (1e-3, 1e5))
  + WhiteKernel(0.01, (1e-8, 1e2)), alpha=0, normalize_y=False, no restarts;
  sklearn's own L-BFGS-B call (log-space theta, bounds) with maxiter = maxfun
  = M, so that evaluations can be counted and the cap matches GPy's.

One JSON line per peer goes to stdout.  "lml" is recomputed by this script
with a plain jitter-free numpy Cholesky at the peer's final hyperparameters
(comparable across peers and with gpodo); "lml_peer" is the peer's own value
(GPy always adds 1e-8 to the diagonal, so its value differs slightly);
"lml_start" is the same jitter-free LML at the start point.  "seconds" is the
wall-clock time of the fit call only.

Usage (from the repository root, with the venv from bench/peers/requirements.txt):

    /path/to/venv/bin/python bench/peers/fit_peers.py --n 500 --d 28
    /path/to/venv/bin/python bench/peers/fit_peers.py --n 1000 --peers gpy \\
        --write-data /tmp/peers/data_n1000_d28.csv
"""

import argparse
import csv
import json
import math
import os
import re
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.optimize

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_TABLE = REPO_ROOT / ".." / "shared" / "data" / "exoter_gp_train_1s.csv"
TARGETS = ["abs_err_vx", "abs_err_vy", "abs_err_vz"]
N_INPUTS = 28
START_VARIANCE = 1.0
START_NOISE = 0.01


class TimeLimit(Exception):
    pass


def load_table(path, n, d, targets=TARGETS):
    with open(path, newline="") as fh:
        header = next(csv.reader(fh))
    if len(header) != N_INPUTS + len(targets) or header[N_INPUTS:] != targets:
        sys.exit(f"unexpected header in {path}: expected {N_INPUTS} inputs then "
                 f"{','.join(targets)}, found {header}")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if n is not None:
        if n > data.shape[0]:
            sys.exit(f"--n {n} but the table has only {data.shape[0]} rows")
        data = data[:n]
    if not 1 <= d <= N_INPUTS:
        sys.exit(f"--d must be in 1..{N_INPUTS}")
    return data[:, :d].copy(), data[:, N_INPUTS:].copy(), header[:d]


def standardiser(a):
    """Column means and population stds (a std < 1e-12 becomes 1)."""
    mean = a.mean(axis=0)
    std = a.std(axis=0, ddof=0)
    return mean, np.where(std < 1e-12, 1.0, std)


def zscore(a):
    mean, std = standardiser(a)
    return (a - mean) / std


def rbf(A, B, variance, lengthscales):
    """The ARD RBF kernel matrix K(A, B)."""
    lengthscales = np.asarray(lengthscales)
    ZA, ZB = A / lengthscales, B / lengthscales
    r2 = np.sum(ZA * ZA, axis=1)[:, None] + np.sum(ZB * ZB, axis=1)[None, :] - 2.0 * ZA @ ZB.T
    return variance * np.exp(-0.5 * np.maximum(r2, 0.0))


def add_table_arguments(ap):
    """--table and --targets, shared by the peer scripts."""
    ap.add_argument("--table", type=Path, default=DEFAULT_TABLE,
                    help="training CSV (default: ../shared/data/exoter_gp_train_1s.csv "
                         "relative to the repository root)")
    ap.add_argument("--targets", default=",".join(TARGETS),
                    help="the table's last three columns, comma-separated (the simulated "
                         "testbed's residuals_train.csv: res_vx,res_vy,res_vz)")


def targets_of(args):
    """The target column names parsed from --targets."""
    return [t.strip() for t in args.targets.split(",") if t.strip()]


def exact_lml(X, Y, variance, lengthscales, noise):
    """Jitter-free LML of an ARD RBF GP, summed over the columns of Y."""
    K = rbf(X, X, variance, lengthscales)
    K[np.diag_indices_from(K)] += noise
    L = np.linalg.cholesky(K)
    alpha = scipy.linalg.cho_solve((L, True), Y)
    n, p = Y.shape
    return float(-0.5 * np.sum(Y * alpha) - p * np.sum(np.log(np.diag(L)))
                 - 0.5 * n * p * math.log(2.0 * math.pi))


def fit_gpy(X, Y, max_iters, time_limit):
    import GPy

    d = X.shape[1]
    kern = GPy.kern.RBF(d, variance=START_VARIANCE, lengthscale=[math.sqrt(d)] * d, ARD=True)
    m = GPy.models.GPRegression(X, Y, kern, noise_var=START_NOISE)
    calls = [0]
    inner = m._objective_grads
    t0 = time.perf_counter()

    def counted(x):
        calls[0] += 1
        if time_limit is not None and time.perf_counter() - t0 > time_limit:
            raise TimeLimit()
        return inner(x)

    m._objective_grads = counted
    status = "ok"
    opt = None
    try:
        opt = m.optimize("lbfgsb", max_iters=max_iters, messages=False)
    except TimeLimit:
        status = "time limit"
    seconds = time.perf_counter() - t0
    variance = float(m.rbf.variance[0])
    lengthscales = [float(v) for v in m.rbf.lengthscale]
    noise = float(m.Gaussian_noise.variance[0])
    return {
        "impl": f"GPy {GPy.__version__}",
        "status": status if opt is None else f"{status}: {opt.status}",
        "seconds": seconds,
        "lml_peer": float(m.log_likelihood()),
        # scipy's funcalls; the wrapper also sees paramz's extra final call.
        "evaluations": int(opt.funct_eval) if opt is not None else calls[0],
        "objective_calls": calls[0],
        "variance": variance,
        "noise_variance": noise,
        "lengthscales": lengthscales,
    }


def fit_sklearn(X, Y, max_iters, time_limit):
    import sklearn
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    d = X.shape[1]
    kernel = (ConstantKernel(START_VARIANCE, (1e-6, 1e4))
              * RBF(length_scale=[math.sqrt(d)] * d, length_scale_bounds=(1e-3, 1e5))
              + WhiteKernel(START_NOISE, (1e-8, 1e2)))
    info = {"nfev": None, "nit": None, "message": None, "calls": 0}
    t0 = time.perf_counter()

    def optimizer(obj_func, initial_theta, bounds):
        def f(theta):
            info["calls"] += 1
            if time_limit is not None and time.perf_counter() - t0 > time_limit:
                raise TimeLimit()
            return obj_func(theta, eval_gradient=True)

        res = scipy.optimize.minimize(f, initial_theta, method="L-BFGS-B", jac=True,
                                      bounds=bounds,
                                      options={"maxiter": max_iters, "maxfun": max_iters})
        info.update(nfev=int(res.nfev), nit=int(res.nit), message=str(res.message))
        return res.x, res.fun

    gpr = GaussianProcessRegressor(kernel=kernel, alpha=0.0, optimizer=optimizer,
                                   normalize_y=False, n_restarts_optimizer=0)
    status = "ok"
    try:
        gpr.fit(X, Y)
    except TimeLimit:
        status = "time limit"
    seconds = time.perf_counter() - t0
    if status != "ok":
        return {"impl": f"scikit-learn {sklearn.__version__}", "status": status,
                "seconds": seconds, "lml_peer": None, "evaluations": info["calls"],
                "variance": None, "noise_variance": None, "lengthscales": None}
    k = gpr.kernel_
    return {
        "impl": f"scikit-learn {sklearn.__version__}",
        "status": f"{status}: {info['message']}",
        "seconds": seconds,
        "lml_peer": float(gpr.log_marginal_likelihood_value_),
        "evaluations": info["nfev"],
        "iterations": info["nit"],
        "variance": float(k.k1.k1.constant_value),
        "noise_variance": float(k.k2.noise_level),
        "lengthscales": [float(v) for v in np.atleast_1d(k.k1.k2.length_scale)],
    }


def fit_gpodo(X, Y, max_iters, time_limit, own_start=False):
    """gpodo's exact GP from Python (`pip install ./python`), on the same
    z-scored rows (its own z-scoring off) with L-BFGS capped at
    `max_iters` iterations: from the peers' start alone, or (`own_start`)
    from gpodo's default start policy. `time_limit` is not supported."""
    import gpodo

    d = X.shape[1]
    settings = {"standardize": False, "hyperopt": {"max_iters": max_iters}}
    if not own_start:
        settings.update(
            init={"variance": START_VARIANCE, "lengthscale": math.sqrt(d)},
            noise_variance=START_NOISE,
            hyperopt={"max_iters": max_iters, "start": {"perturbations": 0}},
        )
    gp = gpodo.ExactGP(kernel="rbf", verbose=True, **settings)
    # Each optimiser iteration's best LML so far, with the seconds since
    # the fit began: gpodo prints it to sys.stderr (verbose), read here.
    trace = []
    t0 = time.perf_counter()

    class Recorder:
        def write(self, line):
            m = re.search(r"iteration (\d+): objective (\S+)", line)
            if m:
                trace.append([time.perf_counter() - t0, float(m.group(2))])

        def flush(self):
            pass

    stderr, sys.stderr = sys.stderr, Recorder()
    try:
        gp.fit(X, Y)
    finally:
        sys.stderr = stderr
    seconds = time.perf_counter() - t0
    h = gp.hyperparameters_
    return {
        "impl": "gpodo (Python)" + (", its own start" if own_start else ""),
        "status": "ok",
        "seconds": seconds,
        "lml_peer": float(gp.log_marginal_likelihood_value_),
        "evaluations": gp.n_evaluations_,
        "variance": h["rbf.variance"],
        "noise_variance": h["noise_variance"],
        "lengthscales": [h[f"rbf.lengthscale[x{j}]"] for j in range(d)],
        "trace": trace,
    }


def fit_gpodo_own_start(X, Y, max_iters, time_limit):
    """`fit_gpodo` from gpodo's own start policy."""
    return fit_gpodo(X, Y, max_iters, time_limit, own_start=True)


PEERS = {
    "gpy": fit_gpy,
    "sklearn": fit_sklearn,
    "gpodo": fit_gpodo,
    "gpodo-own-start": fit_gpodo_own_start,
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_table_arguments(ap)
    ap.add_argument("--n", type=int, default=None, help="use the first N rows (default: all)")
    ap.add_argument("--d", type=int, default=N_INPUTS, help="use the first D input columns")
    ap.add_argument("--peers", default="gpy,sklearn",
                    help="comma list of: gpy, sklearn, gpodo (from Python, the peers' start), "
                         "gpodo-own-start")
    ap.add_argument("--max-iters", type=int, default=1000,
                    help="L-BFGS-B iteration and evaluation cap (both peers)")
    ap.add_argument("--time-limit", type=float, default=None,
                    help="abort a peer's fit after this many seconds (reported as status)")
    ap.add_argument("--write-data", type=Path, default=None,
                    help="write the standardised x0..x{D-1},y0,y1,y2 matrix used to this CSV")
    args = ap.parse_args()

    peers = [p.strip() for p in args.peers.split(",") if p.strip()]
    for p in peers:
        if p not in PEERS:
            sys.exit(f"unknown peer {p!r}; choose from {sorted(PEERS)}")

    X_raw, Y_raw, _ = load_table(args.table, args.n, args.d, targets_of(args))
    X, Y = zscore(X_raw), zscore(Y_raw)
    n, d = X.shape

    if args.write_data is not None:
        args.write_data.parent.mkdir(parents=True, exist_ok=True)
        header = ",".join([f"x{j}" for j in range(d)] + [f"y{j}" for j in range(Y.shape[1])])
        np.savetxt(args.write_data, np.hstack([X, Y]), delimiter=",", fmt="%.17g",
                   header=header, comments="")
        print(f"wrote {args.write_data}", file=sys.stderr)

    # Same objective for every peer at the start point (useful to check gpodo's).
    lml_start = exact_lml(X, Y, START_VARIANCE, [math.sqrt(d)] * d, START_NOISE)
    try:
        from threadpoolctl import threadpool_info
        blas_threads = max((i["num_threads"] for i in threadpool_info()
                            if i.get("user_api") == "blas"), default=None)
    except ImportError:
        blas_threads = None

    for p in peers:
        r = PEERS[p](X, Y, args.max_iters, args.time_limit)
        lml = None
        if r["variance"] is not None:
            lml = exact_lml(X, Y, r["variance"], r["lengthscales"], r["noise_variance"])
        out = {"impl": r.pop("impl"), "n": n, "d": d, "seconds": r.pop("seconds"),
               "lml": lml, "evaluations": r.pop("evaluations")}
        out.update(r)
        # The peers' paths depend on the SciPy release's L-BFGS-B.
        out.update(lml_start=lml_start, blas_threads=blas_threads,
                   numpy=np.__version__, scipy=scipy.__version__)
        print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
