"""Where the tests find gpodo's binaries: the CLI (`gpodo`) and the Rust
library's own fit (`fit_csv`, an example of gpodo-regressors), built by
`cargo test --workspace --all-targets --release` before pytest runs."""

import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
RELEASE = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release"


def _binary(path):
    if path.exists():
        return path
    if os.environ.get("GPODO_REQUIRE_PYTHON"):
        raise FileNotFoundError(f"{path} is not built (cargo test --workspace --all-targets --release)")
    pytest.skip(f"{path} is not built")


@pytest.fixture
def gpodo_cli():
    """The `gpodo` command-line binary."""
    return _binary(RELEASE / "gpodo")


@pytest.fixture
def fit_csv():
    """The Rust library's exact-GP fit of a CSV (regressors/examples/fit_csv.rs)."""
    return _binary(RELEASE / "examples" / "fit_csv")
