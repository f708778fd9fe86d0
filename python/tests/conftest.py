"""Shared fixtures: the `zakai` command-line binary the bit-for-bit tests compare with, and
statsmodels for the tests that need it (each such test skips alone where it is missing).

With ``ZAKAI_NO_SKIPS=1`` (the README's test command sets it) a skipped test fails the run:
there every optional package is installed, so a skip would be a check that silently vanished."""

import os
import shutil

import pytest


@pytest.fixture(scope="session")
def cli() -> str:
    """The `zakai` binary: `ZAKAI_CLI`, else the one the test command's `cargo test --workspace`
    builds into the shared cache (scripts/cache.sh)."""
    cache = os.environ.get("ZAKAI_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "zakai"
    )
    target = os.environ.get("CARGO_TARGET_DIR") or os.path.join(cache, "target")
    path = os.environ.get("ZAKAI_CLI") or os.path.join(target, "debug", "zakai")
    if not os.path.exists(path):
        found = shutil.which("zakai")
        if found is None:
            pytest.fail(f"the zakai CLI is needed at {path} (cargo build -p zakai-cli)")
        path = found
    return path


@pytest.fixture(scope="session")
def sm():
    """``statsmodels.api``; the test that asks for it is skipped without it."""
    return pytest.importorskip("statsmodels.api")


def pytest_sessionfinish(session, exitstatus):
    """Under ``ZAKAI_NO_SKIPS=1``, any skipped test turns the run red."""
    if os.environ.get("ZAKAI_NO_SKIPS") != "1":
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = reporter.stats.get("skipped", []) if reporter else []
    if skipped:
        for report in skipped:
            reporter.write_line(f"skipped under ZAKAI_NO_SKIPS=1: {report.nodeid} {report.longrepr}")
        session.exitstatus = 1
