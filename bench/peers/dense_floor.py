#!/usr/bin/env python3
"""The dense floor of one exact-GP evaluation with LAPACK: numpy's Cholesky
plus scipy's dpotri (the inverse from the factor), on an RBF Gram matrix of
n seeded points in 28 dimensions, best of 5, with the BLAS threads the
environment allows (both cores by default).

    /path/to/venv/bin/python bench/peers/dense_floor.py 1869 4000
"""
import sys
import time

import numpy as np
import scipy.linalg.lapack as lapack

try:
    from threadpoolctl import threadpool_info
except ImportError:  # pragma: no cover
    threadpool_info = None


def main():
    for n in [int(a) for a in sys.argv[1:]] or [1869]:
        rng = np.random.default_rng(1)
        x = rng.uniform(-1.7, 1.7, (n, 28)) / np.sqrt(28)
        sq = (x * x).sum(1)
        k = np.exp(-0.5 * np.maximum(sq[:, None] + sq[None, :] - 2 * x @ x.T, 0))
        k[np.diag_indices(n)] += 0.1
        best = [np.inf, np.inf]
        for _ in range(5):
            t0 = time.perf_counter()
            chol = np.linalg.cholesky(k)
            t1 = time.perf_counter()
            _, info = lapack.dpotri(chol, lower=1)
            t2 = time.perf_counter()
            if info != 0:
                sys.exit(f"dpotri failed: info {info}")
            best = [min(best[0], t1 - t0), min(best[1], t2 - t1)]
        threads = None
        if threadpool_info is not None:
            threads = [(i["internal_api"], i["num_threads"]) for i in threadpool_info()
                       if i["user_api"] == "blas"]
        print(f"n={n} cholesky {best[0] * 1e3:.1f} ms, dpotri {best[1] * 1e3:.1f} ms, "
              f"total {sum(best) * 1e3:.1f} ms, blas {threads}")


if __name__ == "__main__":
    main()
