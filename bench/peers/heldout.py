#!/usr/bin/env python3
"""Held-out RMSE of the peer benchmark's fits, from their final hyperparameters.

Every fit of the peer benchmark (GPy and scikit-learn from
`fit_peers.py`, gpodo from its `fit_csv` example) prints one JSON line with
its final ARD RBF hyperparameters ("variance", "lengthscales",
"noise_variance"). This script applies one predictor to all of them, so
that the figures differ only by the hyperparameters each optimiser found:
the GP posterior mean on the standardised training rows (the same
preprocessing as `fit_peers.py`: first N rows, first D inputs, z-scored with
the training mean and population std), mapped back to the targets' units
and scored on held-out rows standardised with the training statistics.

Held-out rows, disjoint from every training prefix:

* the authors' table (default): rows 2001 to the end (`--test-from 2000`),
  337 rows that no n <= 2000 fit trained on;
* the simulated testbed (`--test-table results/peer-table-sim/residuals_test.csv
  --targets res_vx,res_vy,res_vz`): the test traverse's residuals.

For each JSON line whose n and d match, one JSON line goes to stdout with the
RMSE pooled over the 3 outputs and per output (targets' units), the RMSE of
predicting no residual (0, the parametric model alone), and "lml_check",
the jitter-free LML recomputed at the line's hyperparameters (it should equal
the line's own "lml").

    python bench/peers/heldout.py --n 1000 --d 28 --fits fits.jsonl
    python bench/peers/heldout.py --table results/peer-table-sim/residuals_train.csv \\
        --test-table results/peer-table-sim/residuals_test.csv \\
        --targets res_vx,res_vy,res_vz --n 4000 --d 28 --fits fits.jsonl
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fit_peers import (  # noqa: E402
    add_table_arguments, exact_lml, load_table, rbf, standardiser, targets_of,
)


def posterior_mean(x, y, x_test, variance, lengthscales, noise):
    k = rbf(x, x, variance, lengthscales)
    k[np.diag_indices_from(k)] += noise
    factor = scipy.linalg.cho_factor(k, lower=True)
    return rbf(x_test, x, variance, lengthscales) @ scipy.linalg.cho_solve(factor, y)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_table_arguments(ap)
    ap.add_argument("--n", type=int, required=True, help="training rows (the first N)")
    ap.add_argument("--d", type=int, required=True, help="inputs (the first D)")
    ap.add_argument("--test-from", type=int, default=2000,
                    help="held-out rows: the training table's rows from this index on "
                         "(0-based, after the header; default 2000)")
    ap.add_argument("--test-table", type=Path, default=None,
                    help="held-out rows from this CSV instead (same columns)")
    ap.add_argument("--fits", type=Path, required=True,
                    help="JSON lines of fits (fit_peers.py, fit_csv); others are skipped")
    args = ap.parse_args()

    targets = targets_of(args)
    x_all, y_all, _ = load_table(args.table, None, args.d, targets)
    if args.n > x_all.shape[0]:
        sys.exit(f"--n {args.n} but {args.table} has only {x_all.shape[0]} rows")
    x_raw, y_raw = x_all[: args.n], y_all[: args.n]
    if args.test_table is not None:
        x_test_raw, y_test, _ = load_table(args.test_table, None, args.d, targets)
    else:
        if args.test_from < args.n:
            sys.exit(f"--test-from {args.test_from} overlaps the {args.n} training rows")
        x_test_raw, y_test = x_all[args.test_from:], y_all[args.test_from:]
    if x_test_raw.shape[0] == 0:
        sys.exit("no held-out rows")

    x_mean, x_std = standardiser(x_raw)
    y_mean, y_std = standardiser(y_raw)
    x, y = (x_raw - x_mean) / x_std, (y_raw - y_mean) / y_std
    x_test = (x_test_raw - x_mean) / x_std
    zero_rmse = float(np.sqrt(np.mean(y_test ** 2)))

    with open(args.fits) as fh:
        for number, line in enumerate(fh, 1):
            line = line.strip()
            if not line.startswith("{"):
                continue
            try:
                fit = json.loads(line)
            except json.JSONDecodeError as e:
                sys.exit(f"{args.fits}:{number}: not JSON: {e}")
            if fit.get("n") != args.n or fit.get("d") != args.d:
                continue
            if fit.get("variance") is None or fit.get("lengthscales") is None:
                continue
            variance, noise = fit["variance"], fit["noise_variance"]
            lengthscales = np.asarray(fit["lengthscales"], dtype=float)
            if lengthscales.shape != (args.d,):
                sys.exit(f"{args.fits}:{number}: {lengthscales.size} lengthscales, "
                         f"expected {args.d}")
            mean = posterior_mean(x, y, x_test, variance, lengthscales, noise)
            err = mean * y_std + y_mean - y_test
            print(json.dumps({
                "impl": fit.get("impl"),
                "start": fit.get("start"),
                "n": args.n,
                "d": args.d,
                "test_rows": int(x_test.shape[0]),
                "rmse": float(np.sqrt(np.mean(err ** 2))),
                "rmse_per_output": [float(v) for v in np.sqrt(np.mean(err ** 2, axis=0))],
                "rmse_zero": zero_rmse,
                "lml": fit.get("lml"),
                "lml_check": exact_lml(x, y, variance, lengthscales, noise),
            }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
