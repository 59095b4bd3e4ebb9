"""Table II's figures as PNG, from what `gpodo run` wrote.

Two figures, each from a results folder:

* ``route RUN_DIR OUT.png --scheme LABEL ...``: one panel per scheme of a
  single run (a file without ``seeds:``). The route's ground truth is
  drawn with each one-second window coloured by the size of its true
  residual (what the wheel odometry misses; slip bursts are its bright
  spots), and over it the frames the scheme processed (dots), its
  keyframes (rings) and the frames where it lost track (red crosses).
  Reads ``trajectories/<traverse>.windows.csv`` and
  ``trajectories/<traverse>.<scheme>.frames.csv``.
* ``curves RESULTS_DIR OUT.png --policy CURVE ...``: frames against RMSE
  over the seeds of a sweep, one panel per policy, with the fixed-rate
  curve of its back end and the A/A band around it: the fixed rate's mean
  RMSE ± the minimum detectable effect of the A/A pair of that back end
  nearest in frames. A policy point inside the band cannot be told from
  frame choice that does nothing. Reads ``tables/curves_points.csv`` and
  ``tables/floor.csv``.

Needs matplotlib and pandas (``pip install matplotlib pandas``). From the
repository root, for example:

    python scripts/table2_figures.py curves results/table2-positive-control \\
        docs/figures/positive-control-curves.png \\
        --policy "drift budget + turn guard (GP)" --policy "authors' schedule (GP)"
"""

import argparse
import math
import pathlib
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import pandas as pd  # noqa: E402


def slug(label):
    """The file-name form of a scheme label, as `gpodo run` writes it."""
    return re.sub(r"-+", "-", re.sub(r"[^a-z0-9]+", "-", label.lower())).strip("-")


def lost_secs(frames):
    """Seconds from each loss of track to the next tracked frame (or the
    last processed frame)."""
    total, since = 0.0, None
    for t, ok in zip(frames.time_s, frames.tracked.astype(str).str.lower() == "true"):
        if not ok and since is None:
            since = t
        elif ok and since is not None:
            total, since = total + t - since, None
    if since is not None:
        total += frames.time_s.iloc[-1] - since
    return total


def route(args):
    run = pathlib.Path(args.run)
    windows = pd.read_csv(run / "trajectories" / f"{args.traverse}.windows.csv")
    residual = (
        windows[["true_residual_x_mps", "true_residual_y_mps", "true_residual_z_mps"]]
        .pow(2)
        .sum(axis=1)
        .pow(0.5)
        * 1000.0
    )
    fig, axes = plt.subplots(
        1,
        len(args.scheme),
        figsize=(5.2 * len(args.scheme), 5.0),
        squeeze=False,
        layout="constrained",
    )
    for ax, label in zip(axes[0], args.scheme):
        path = run / "trajectories" / f"{args.traverse}.{slug(label)}.frames.csv"
        if not path.exists():
            sys.exit(f"{path}: no such file; is `{label}` a scheme of the run?")
        frames = pd.read_csv(path)
        ax.plot(windows.x_m, windows.y_m, color="0.75", lw=0.8, zorder=1)
        spots = ax.scatter(
            windows.x_m,
            windows.y_m,
            c=residual,
            cmap="inferno_r",
            s=6,
            vmin=0.0,
            vmax=residual.quantile(0.995),
            zorder=2,
        )
        tracked = frames.tracked.astype(str).str.lower() == "true"
        keyframe = frames.keyframe.astype(str).str.lower() == "true"
        lost = ~tracked & tracked.shift(fill_value=True)
        ax.scatter(
            frames.x_m[tracked], frames.y_m[tracked], s=2, color="tab:blue", zorder=3,
            label="processed, tracked",
        )
        ax.scatter(
            frames.x_m[~tracked], frames.y_m[~tracked], s=4, color="0.3", marker="+",
            lw=0.5, zorder=3, label="processed while lost",
        )
        ax.scatter(
            frames.x_m[keyframe],
            frames.y_m[keyframe],
            s=16,
            facecolors="none",
            edgecolors="tab:green",
            lw=0.6,
            zorder=4,
            label="keyframe",
        )
        ax.scatter(
            frames.x_m[lost], frames.y_m[lost], s=70, marker="x", color="red", lw=2, zorder=5,
            label="loss of track",
        )
        ax.set_title(
            f"{label}\n{len(frames)} frames, {int(keyframe.sum())} keyframes, "
            f"{int(lost.sum())} losses, lost {lost_secs(frames):.0f} s",
            fontsize=9,
        )
        ax.set_aspect("equal")
        ax.legend(fontsize=6, loc="lower right")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.colorbar(
        spots, ax=axes[0].tolist(), shrink=0.8, label="true residual of the 1 s window [mm/s]"
    )
    fig.suptitle(args.title or f"{run.name}: processed frames over the route", fontsize=10)
    fig.savefig(args.out, dpi=130, bbox_inches="tight")
    print(f"wrote {args.out}")


def curves(args):
    results = pathlib.Path(args.results)
    points = pd.read_csv(results / "tables" / "curves_points.csv")
    floor = pd.read_csv(results / "tables" / "floor.csv")
    columns = min(3, len(args.policy))
    rows_of_panels = math.ceil(len(args.policy) / columns)
    fig, axes = plt.subplots(
        rows_of_panels,
        columns,
        figsize=(5.0 * columns, 4.2 * rows_of_panels),
        squeeze=False,
        sharey=True,
        layout="constrained",
    )
    panels = axes.flatten()
    for ax in panels[len(args.policy) :]:
        ax.set_visible(False)
    for ax, policy in zip(panels, args.policy):
        rows = points[points.curve == policy]
        if rows.empty:
            sys.exit(f"{results}: no curve named `{policy}`")
        back_end = rows.back_end.iloc[0]
        # The first fixed-rate curve of the back end, as the report pairs.
        candidates = points[
            (points.back_end == back_end) & points.curve.str.contains("fixed rate")
        ]
        if candidates.empty:
            sys.exit(f"{results}: no fixed-rate curve of `{back_end}`")
        first = candidates.curve.iloc[0]
        fixed = candidates[candidates.curve == first].sort_values("frames_mean")
        pairs = floor[floor.back_end == back_end]

        def mde(frames):
            if pairs.empty:
                return float("nan")
            nearest = (pairs.frames_mean.apply(math.log) - math.log(frames)).abs().idxmin()
            return pairs.mde_m[nearest]

        band = fixed.frames_mean.apply(mde)
        ax.fill_between(
            fixed.frames_mean,
            fixed.rmse_mean_m - band,
            fixed.rmse_mean_m + band,
            color="0.85",
            label="fixed rate ± A/A MDE",
        )
        ax.plot(fixed.frames_mean, fixed.rmse_mean_m, "o-", color="0.35", ms=3, label="fixed rate")
        rows = rows.sort_values("frames_mean")
        ax.errorbar(
            rows.frames_mean,
            rows.rmse_mean_m,
            yerr=[rows.rmse_mean_m - rows.rmse_low_m, rows.rmse_high_m - rows.rmse_mean_m],
            fmt="s-",
            ms=3,
            capsize=2,
            color="tab:blue",
            label="policy (95 % CI)",
        )
        for budget in (500, 1000):
            ax.axvline(budget, color="0.6", lw=0.6, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xticks([300, 500, 1000, 2000, 4000])
        ax.set_title(policy, fontsize=9)
        ax.set_xlabel("frames processed (mean over routes)")
        ax.legend(fontsize=7)
    for row in axes:
        row[0].set_ylabel("trajectory RMSE [m] (mean over routes)")
    fig.suptitle(args.title or results.name, fontsize=10)
    fig.savefig(args.out, dpi=130, bbox_inches="tight")
    print(f"wrote {args.out}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(required=True)
    r = sub.add_parser("route", help="processed frames over the route, per scheme")
    r.add_argument("run", help="the results folder of a single run")
    r.add_argument("out", help="the PNG to write")
    r.add_argument("--scheme", action="append", required=True, help="a scheme label")
    r.add_argument("--traverse", default="test", help="the traverse (default: test)")
    r.add_argument("--title")
    r.set_defaults(func=route)
    c = sub.add_parser("curves", help="frames against RMSE with the A/A band")
    c.add_argument("results", help="the results folder of a sweep")
    c.add_argument("out", help="the PNG to write")
    c.add_argument("--policy", action="append", required=True, help="a `curve:` name")
    c.add_argument("--title")
    c.set_defaults(func=curves)
    args = parser.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
