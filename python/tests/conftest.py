"""Where the tests find gpodo's binaries: the CLI (`gpodo`), built by
`cargo test --workspace --all-targets --release`, and the Rust library's
own fit (`fit_csv`, an example of gpodo-regressors), built by
`cargo build --release -p gpodo-regressors --example fit_csv` (`cargo
test` builds examples as test harnesses only)."""

import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
RELEASE = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release"


def _binary(path, command):
    if path.exists():
        return path
    if os.environ.get("GPODO_REQUIRE_PYTHON"):
        raise FileNotFoundError(f"{path} is not built ({command})")
    pytest.skip(f"{path} is not built")


@pytest.fixture
def gpodo_cli():
    """The `gpodo` command-line binary."""
    return _binary(RELEASE / "gpodo", "cargo test --workspace --all-targets --release")


@pytest.fixture
def fit_csv():
    """The Rust library's exact-GP fit of a CSV (regressors/examples/fit_csv.rs)."""
    return _binary(
        RELEASE / "examples" / "fit_csv",
        "cargo build --release -p gpodo-regressors --example fit_csv",
    )


@pytest.fixture(scope="session")
def paper_cli(tmp_path_factory):
    """The folder `gpodo run experiments/paper.yaml --out …` wrote (its
    `metrics.json` and `residuals_train.csv`), run once per session."""
    import subprocess

    cli = _binary(RELEASE / "gpodo", "cargo test --workspace --all-targets --release")
    out = tmp_path_factory.mktemp("paper") / "cli"
    subprocess.run(
        [str(cli), "run", str(REPO / "experiments" / "paper.yaml"), "--out", str(out), "--quiet"],
        check=True,
        capture_output=True,
        cwd=REPO,
    )
    return out
