#!/usr/bin/env python3
"""A gpodo plugin that fails on purpose, for the tests of `kind: external`.

The first argument names the failure: crash_on_fit, hang_on_predict,
garbage_on_fit, wrong_shape, nan_variance, refuse_fit, no_update, old_protocol,
fail_if_marker (fit fails while the file named by the `marker` option exists).
It behaves as a mean-only regressor otherwise.
"""

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "plugins" / "python"))
import gpodo_plugin  # noqa: E402
from gpodo_plugin import Regressor, serve  # noqa: E402

MODE = sys.argv[1]


class Misbehaving(Regressor):
    name = f"misbehaving ({MODE})"

    def capabilities(self):
        if MODE == "no_update":
            return ["fit", "predict"]
        return ["fit", "predict", "update"]

    def fit(self, inputs, targets, info):
        print(f"fitting {inputs.shape} in mode {MODE}", file=sys.stderr, flush=True)
        if MODE == "crash_on_fit":
            print("about to crash on purpose", file=sys.stderr, flush=True)
            os._exit(3)
        if MODE == "garbage_on_fit":
            sys.stdout.write("this is not json\n")
            sys.stdout.flush()
            time.sleep(30)
        if MODE == "fail_if_marker" and Path(self.options["marker"]).exists():
            raise RuntimeError(f"marker {self.options['marker']} exists")
        if MODE == "refuse_fit":
            raise ValueError("cannot fit: refused on purpose")
        self.mean = targets.mean(axis=0)
        self.var = targets.var(axis=0) + 1e-9
        return {}

    def update(self, inputs, targets):
        pass

    def predict(self, inputs):
        m = inputs.shape[0]
        mean = np.tile(self.mean, (m, 1))
        var = np.tile(self.var, (m, 1))
        if MODE == "hang_on_predict":
            print("hanging on purpose", file=sys.stderr, flush=True)
            time.sleep(60)
        if MODE == "wrong_shape":
            return mean[:-1], var[:-1]
        if MODE == "nan_variance":
            var[m // 2, 1] = float("nan")
        return mean, var


if __name__ == "__main__":
    if MODE == "old_protocol":
        gpodo_plugin.PROTOCOL_VERSION = 0
        line = sys.stdin.readline()
        request = json.loads(line)
        print(json.dumps({"id": request["id"], "ok": True, "protocol": 0, "capabilities": ["fit", "predict"]}), flush=True)
        sys.stdin.readline()
        sys.exit(0)
    serve(Misbehaving())
