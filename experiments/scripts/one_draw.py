"""How likely one route is to show the paper's Table II gap by chance.

The paper ran each scheme once, on one route: 0.145 m for its GP schedule
against 0.204 m for ORB-SLAM at 0.5 fps, a gap of 59 mm (a ratio of
0.71). Given a sweep's runs (one route each), this reads the two rows'
per-route RMSEs, removes their mean difference (the policy's effect,
made zero), and asks how often one route still shows a gap at least as
large, two ways that make no normal assumption:

* sign flip: under a zero effect the centred difference of a route is as
  likely negative as positive, so P(Δ ≤ −gap) is estimated by the share
  of routes with |Δ − mean| ≥ gap, halved (likewise for the log ratio);
* bootstrap: the share of routes, drawn with replacement, whose centred
  difference is ≤ −gap (the same as the plain share of routes).

Usage: python experiments/scripts/one_draw.py RUNS.jsonl POLICY FIXED
(labels of the two schemes; the paper's gap and ratio are the defaults).
"""

import json
import math
import sys


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    path, policy, fixed = sys.argv[1:4]
    gap = float(sys.argv[4]) if len(sys.argv) > 4 else 0.204 - 0.145
    ratio = float(sys.argv[5]) if len(sys.argv) > 5 else 0.145 / 0.204
    pairs = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip():
                continue
            run = json.loads(line)
            rmse = {m["label"]: m["rmse_m"] for m in run["metrics"]["schemes"]}
            if policy not in rmse or fixed not in rmse:
                sys.exit(f"{path}:{n}: no scheme `{policy}` or `{fixed}`")
            pairs.append((rmse[policy], rmse[fixed]))
    routes = len(pairs)
    delta = [a - b for a, b in pairs]
    log_ratio = [math.log(a / b) for a, b in pairs]
    mean_delta = sum(delta) / routes
    mean_log = sum(log_ratio) / routes
    centred = [d - mean_delta for d in delta]
    centred_log = [r - mean_log for r in log_ratio]
    sd = math.sqrt(sum(c * c for c in centred) / (routes - 1))
    flip = sum(abs(c) >= gap for c in centred) / (2 * routes)
    flip_ratio = sum(abs(c) >= -math.log(ratio) for c in centred_log) / (2 * routes)
    below = sum(c <= -gap for c in centred) / routes
    print(f"{routes} routes; {policy} against {fixed}")
    print(f"mean Δ {1000 * mean_delta:+.1f} mm, σ of Δ a route {1000 * sd:.1f} mm,"
          f" geometric-mean ratio {math.exp(mean_log):.3f}")
    print(f"P(Δ ≤ −{1000 * gap:.0f} mm | zero effect): sign flip {flip:.3f},"
          f" bootstrap {below:.3f}; routes with |Δ − mean| ≥ gap:"
          f" {sum(abs(c) >= gap for c in centred)}")
    print(f"P(ratio ≤ {ratio:.2f} | zero effect): sign flip {flip_ratio:.3f};"
          f" routes with a centred ratio ≤ {ratio:.2f} or ≥ {1 / ratio:.2f}:"
          f" {sum(abs(c) >= -math.log(ratio) for c in centred_log)}")


if __name__ == "__main__":
    main()
