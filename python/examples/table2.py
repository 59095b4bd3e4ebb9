"""Table II from Python, notebook style: run the paper's experiment, plot its
frames against RMSE, and fit the residual model on a simulated testbed.

1. ``gpodo.run`` runs ``experiments/paper.yaml`` through the same runner as
   ``gpodo run`` (nothing is written to disk) and returns Table II as a
   pandas DataFrame: one row per scheme, with the frames it processed and
   the RMSE of its trajectory.
2. With matplotlib installed (it is optional: without it this step is
   skipped, saying so), the frames are plotted against the RMSE, one point
   per scheme, into ``table2.png``.
3. ``gpodo.simulate`` simulates the paper's testbed, ``gpodo.residuals``
   computes the residual rows of its training runs under the paper's
   motion model, and an ``ExactGP`` fitted on them predicts the rows of
   the test traverse, with their uncertainty.

Run it from the repository root (about a minute on two cores):

    python python/examples/table2.py
"""

import pathlib
import time

import numpy as np

import gpodo

REPO = pathlib.Path(__file__).resolve().parents[2]

# 1. The paper's experiment.
started = time.perf_counter()
results = gpodo.run(REPO / "experiments" / "paper.yaml", progress=False)
print(f"ran {results.name} in {time.perf_counter() - started:.1f} s")
table2 = results.table2()
columns = ["scheme", "frames", "keyframes", "rmse_m", "tracking_losses"]
print(table2[columns].to_string(index=False, float_format="{:.3f}".format))
baseline = table2.set_index("scheme").loc["ORB-SLAM 2.5 fps"]
print(f"2.5 fps: {baseline.frames} frames, RMSE {baseline.rmse_m:.3f} m")

# 2. Frames against RMSE.
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no plot (pip install matplotlib)")
else:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.scatter(table2["frames"], table2["rmse_m"])
    for row in table2.itertuples():
        ax.annotate(row.scheme, (row.frames, row.rmse_m), fontsize=6)
    ax.set_xlabel("frames processed")
    ax.set_ylabel("trajectory RMSE [m]")
    ax.set_title("Table II: frames against error, one point per scheme")
    fig.tight_layout()
    fig.savefig("table2.png", dpi=150)
    print("wrote table2.png")

# 3. The residual model on a simulated testbed.
motion_model = {
    "kind": "weighted_jacobian",
    "config": {"weighting": "normal_force", "contact_angles": "assume_zero"},
}
train, test = gpodo.simulate("exoter-prl", seed=7, training_run_secs=300.0)
X, Y = gpodo.residuals(train, motion_model=motion_model)
X_test, Y_test = gpodo.residuals(test, motion_model=motion_model)
print(f"{len(X)} training rows, {len(X_test)} test rows, {X.shape[1]} inputs")
gp = gpodo.ExactGP(kernel="rbf").fit(X, Y)
mean, std = gp.predict(X_test, return_std=True)
rmse = float(np.sqrt(np.mean((mean - Y_test.values) ** 2)))
zero = float(np.sqrt(np.mean(Y_test.values**2)))
inside = float(np.mean(np.abs(mean - Y_test.values) <= 1.96 * std))
print(f"held-out RMSE {rmse:.5f} m/s (predicting no error: {zero:.5f}); {inside:.2f} inside the 95 % band")
