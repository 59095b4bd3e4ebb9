"""Learning a planetary rover's odometry error from Python, with gpodo.

The authors' ExoTeR table (shared/data/exoter_gp_train_1s.csv) holds 2337
one-second rows of a rover's proprioceptive inputs (attitude, bogie and
steering angles and rates, wheel speeds, IMU) and the absolute error of its
parametric odometry along x, y and z (m/s). This script does what a
researcher does with it, in the paper's split (the first 80 % of the rows,
in time order, train; the last 20 % test):

1. fit an exact GP with an RBF-ARD kernel, one kernel for the three
   outputs (the paper's model);
2. predict the held-out rows with their uncertainty, and score them;
3. save the model, and load it back as the rover's on-board code would,
   predicting one row at a time.

Run it from the repository root:

    python python/examples/exoter.py [TABLE.csv]
"""

import pathlib
import sys
import time

import numpy as np
import pandas as pd

import gpodo

REPO = pathlib.Path(__file__).resolve().parents[2]
TABLE = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else REPO / ".." / "shared" / "data" / "exoter_gp_train_1s.csv"
TARGETS = ["abs_err_vx", "abs_err_vy", "abs_err_vz"]

# --- The data: 28 inputs, 3 outputs, split in time order. ---
table = pd.read_csv(TABLE)
inputs = [c for c in table.columns if c not in TARGETS]
split = int(0.8 * len(table))
train, test = table.iloc[:split], table.iloc[split:]
print(f"{len(train)} training rows, {len(test)} test rows, {len(inputs)} inputs")

# --- 1. Fit. A DataFrame's column names become the model's input names. ---
gp = gpodo.ExactGP(kernel="rbf")
start = time.perf_counter()
gp.fit(train[inputs], train[TARGETS])
seconds = time.perf_counter() - start
print(
    f"fitted in {seconds:.1f} s: log marginal likelihood {gp.log_marginal_likelihood_value_:.2f} "
    f"after {gp.n_evaluations_} evaluations"
)
lengthscales = {
    name[len("rbf.lengthscale[") : -1]: value
    for name, value in gp.hyperparameters_.items()
    if name.startswith("rbf.lengthscale[")
}
shortest = sorted(lengthscales.items(), key=lambda kv: kv[1])[:5]
print("shortest lengthscales (the inputs the GP relies on most):")
for name, value in shortest:
    print(f"  {name:18s} {value:.2f}")

# --- 2. Predict with uncertainty, and score. ---
mean, std = gp.predict(test[inputs], return_std=True)
truth = test[TARGETS].to_numpy()
rmse = np.sqrt(np.mean((mean - truth) ** 2))
rmse_zero = np.sqrt(np.mean(truth**2))
covered = np.mean(np.abs(mean - truth) <= 1.96 * std)
print(f"held-out RMSE {rmse:.6f} m/s (predicting no error: {rmse_zero:.6f}); {covered:.1%} within ±1.96σ")

# --- 3. Save, and load as on-board code: one row at a time, by name. ---
path = pathlib.Path("exoter.gpodo")
gp.save(path)
onboard = gpodo.load_model(path)
row = test[inputs].iloc[[0]]
m, s = onboard.predict(row, return_std=True)
print(f"saved {path}; on board, the first test row: {m[0]} ± {s[0]} m/s")
assert np.allclose(m, mean[:1], rtol=1e-12, atol=0)
