"""Shared fixtures: the `zakai` command-line binary the bit-for-bit tests compare with."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli() -> str:
    """The `zakai` binary: `ZAKAI_CLI`, else the one `cargo test --workspace` builds."""
    path = os.environ.get("ZAKAI_CLI") or str(ROOT / "target" / "debug" / "zakai")
    if not os.path.exists(path):
        found = shutil.which("zakai")
        if found is None:
            pytest.fail(f"the zakai CLI is needed at {path} (cargo build -p zakai-cli)")
        path = found
    return path
