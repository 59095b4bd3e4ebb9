"""Reference client of gpodo's external-regressor protocol (plugins/PROTOCOL.md).

Subclass `Regressor`, implement `fit` and `predict` (and `update` for online
learning), and call `serve(MyRegressor())`: the module reads one JSON request
per line from stdin and writes one JSON reply per line to stdout. Matrices
travel as {"rows": n, "cols": d, "f64le": base64 of the row-major
little-endian float64 bytes}. Only NumPy and the standard library are needed.

Write logs to stderr, never to stdout: stdout carries the replies. gpodo
quotes the last stderr lines when a request fails.
"""

import base64
import json
import sys
import traceback

import numpy as np

PROTOCOL_VERSION = 1


def decode_matrix(m):
    """A wire matrix as an (rows, cols) float64 array."""
    values = np.frombuffer(base64.b64decode(m["f64le"]), dtype="<f8")
    return values.reshape(int(m["rows"]), int(m["cols"]))


def encode_matrix(a):
    """An array as a wire matrix (2-D, float64, row-major, little-endian)."""
    a = np.ascontiguousarray(np.atleast_2d(np.asarray(a, dtype="<f8")))
    return {"rows": a.shape[0], "cols": a.shape[1], "f64le": base64.b64encode(a.tobytes()).decode("ascii")}


class Regressor:
    """A residual regressor: override `fit` and `predict`, optionally `update`."""

    name = "python regressor"

    def configure(self, options):
        """Receives the regressor's extra YAML fields (a dict) before anything else."""
        self.options = dict(options)

    def fit(self, inputs, targets, info):
        """Learns from `inputs` (n x d) and `targets` (n x o), replacing what was learned.

        `info` holds `input_names`, `target_names` and `inputs_standardized`.
        May return a dict with any of `objective`, `evaluations`, `iterations`
        and `parameters` (a list of [name, value] pairs) for gpodo's report.
        """
        raise NotImplementedError

    def predict(self, inputs):
        """Returns (mean, variance), each (m x o), for `inputs` (m x d)."""
        raise NotImplementedError

    # Online learning: define `update(self, inputs, targets)` taking one
    # sample (two 1-D arrays); gpodo then offers the model to its online schemes.

    def capabilities(self):
        caps = ["fit", "predict"]
        if type(self).update is not Regressor.update:
            caps.append("update")
        return caps

    def update(self, inputs, targets):
        raise NotImplementedError


def _handle(model, request):
    op = request.get("op")
    if op == "hello":
        if request.get("protocol") != PROTOCOL_VERSION:
            raise ValueError(f"gpodo speaks protocol {request.get('protocol')}, this client {PROTOCOL_VERSION}")
        model.configure(request.get("options") or {})
        return {"protocol": PROTOCOL_VERSION, "name": model.name, "capabilities": model.capabilities()}
    if op == "fit":
        info = {k: request[k] for k in ("input_names", "target_names", "inputs_standardized")}
        report = model.fit(decode_matrix(request["inputs"]), decode_matrix(request["targets"]), info)
        return dict(report or {})
    if op == "predict":
        mean, variance = model.predict(decode_matrix(request["inputs"]))
        return {"mean": encode_matrix(mean), "variance": encode_matrix(variance)}
    if op == "update":
        model.update(np.asarray(request["inputs"], dtype=float), np.asarray(request["targets"], dtype=float))
        return {}
    if op == "shutdown":
        return {}
    raise ValueError(f"unknown op {op!r}")


def serve(model, stdin=None, stdout=None):
    """Answers gpodo's requests until `shutdown` or the end of stdin."""
    stdin = stdin or sys.stdin
    stdout = stdout or sys.stdout
    for line in stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        reply = {"id": request.get("id"), "ok": True}
        try:
            reply.update(_handle(model, request))
        except Exception as e:  # the request fails, the plugin stays in step
            traceback.print_exc(file=sys.stderr)
            reply = {"id": request.get("id"), "ok": False, "error": f"{type(e).__name__}: {e}"}
        stdout.write(json.dumps(reply) + "\n")
        stdout.flush()
        if request.get("op") == "shutdown":
            return
