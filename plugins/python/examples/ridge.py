#!/usr/bin/env python3
"""Bayesian ridge regression in plain NumPy, as a gpodo plugin (used by gpodo's tests).

A linear model with a bias per output, prior weights N(0, 1/alpha), noise
variance estimated from the training residuals. `update` folds in one more
sample exactly (rank-one update of the posterior precision), so the same
model learns online in gpodo's online schemes.

Options (extra YAML fields): `alpha` (prior precision, default 1.0).
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from gpodo_plugin import Regressor, serve  # noqa: E402


class Ridge(Regressor):
    name = "numpy bayesian ridge"

    def configure(self, options):
        super().configure(options)
        self.alpha = float(options.get("alpha", 1.0))
        self.precision = None

    def _design(self, x):
        return np.hstack([x, np.ones((x.shape[0], 1))])

    def _start(self, d, o):
        self.precision = self.alpha * np.eye(d + 1)
        self.xty = np.zeros((d + 1, o))
        self.yty = np.zeros(o)
        self.n = 0

    def fit(self, inputs, targets, info):
        self._start(inputs.shape[1], targets.shape[1])
        phi = self._design(inputs)
        self.precision += phi.T @ phi
        self.xty += phi.T @ targets
        self.yty += (targets**2).sum(axis=0)
        self.n = inputs.shape[0]
        return {"parameters": [["alpha", self.alpha], ["rows", float(self.n)]]}

    def update(self, inputs, targets):
        if self.precision is None:
            self._start(inputs.shape[0], targets.shape[0])
        phi = np.append(inputs, 1.0)
        self.precision += np.outer(phi, phi)
        self.xty += np.outer(phi, targets)
        self.yty += targets**2
        self.n += 1

    def predict(self, inputs):
        w = np.linalg.solve(self.precision, self.xty)
        # Noise per output: residual sum of squares of the posterior mean.
        rss = self.yty - 2 * (w * self.xty).sum(axis=0) + (w * ((self.precision - self.alpha * np.eye(w.shape[0])) @ w)).sum(axis=0)
        noise = np.maximum(rss, 0.0) / max(self.n, 1) + 1e-12
        phi = self._design(inputs)
        spread = (phi * np.linalg.solve(self.precision, phi.T).T).sum(axis=1)
        return phi @ w, noise[None, :] * (1.0 + spread[:, None])


if __name__ == "__main__":
    serve(Ridge())
