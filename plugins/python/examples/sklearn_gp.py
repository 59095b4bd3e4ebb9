#!/usr/bin/env python3
"""scikit-learn's GaussianProcessRegressor as a gpodo plugin.

The same model as gpodo's exact GP: one ARD RBF kernel (times a constant)
plus white noise shared by the outputs, L-BFGS-B on the log marginal
likelihood, targets normalised. Needs scikit-learn.

Options (extra YAML fields): `restarts` (n_restarts_optimizer, default 0),
`seed` (default 0), `noise` (initial white-noise level, default 0.01).
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from gpodo_plugin import Regressor, serve  # noqa: E402


class SklearnGp(Regressor):
    name = "scikit-learn GaussianProcessRegressor"

    def fit(self, inputs, targets, info):
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        d = inputs.shape[1]
        kernel = ConstantKernel(1.0, (1e-5, 1e5)) * RBF(np.ones(d), (1e-3, 1e5)) + WhiteKernel(
            float(self.options.get("noise", 0.01)), (1e-9, 1e2)
        )
        self.model = GaussianProcessRegressor(
            kernel=kernel,
            alpha=0.0,
            normalize_y=True,
            n_restarts_optimizer=int(self.options.get("restarts", 0)),
            random_state=int(self.options.get("seed", 0)),
        )
        self.model.fit(inputs, targets)
        params = [["lml_normalised", float(self.model.log_marginal_likelihood_value_)]]
        params += [[f"rbf.lengthscale[{n}]", float(v)] for n, v in zip(info["input_names"], self.model.kernel_.k1.k2.length_scale)]
        return {"objective": float(self.model.log_marginal_likelihood_value_), "parameters": params}

    def predict(self, inputs):
        mean, std = self.model.predict(inputs, return_std=True)
        mean = mean.reshape(inputs.shape[0], -1)
        std = std.reshape(inputs.shape[0], -1)
        return mean, std**2


if __name__ == "__main__":
    serve(SklearnGp())
