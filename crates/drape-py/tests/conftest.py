"""Shared pieces of the Python package's tests.

The tests run against the installed package (``scripts/test.sh`` builds it
into a virtual environment) and compare it with the command line: the
``drape`` binary named by ``DRAPE_CLI``, else the workspace's release build
(built here if missing).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import drape
from drape import _drape

REPO = Path(__file__).resolve().parents[3]


def default_sigint() -> None:
    """``preexec_fn`` of a child that a test interrupts with SIGINT: the
    signal's default disposition, whatever the test run's own. A shell
    starts a background job with SIGINT ignored, the child inherits that,
    and Python then installs no KeyboardInterrupt handler — the child
    would never see the test's Ctrl-C (a fresh clone's tests run that way
    failed so)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
EXAMPLES = REPO / "examples"
PEDESTAL = EXAMPLES / "fabric-on-pedestal.toml"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `drape` command line binary."""
    given = os.environ.get("DRAPE_CLI")
    if given:
        path = Path(given)
        assert path.is_file(), f"DRAPE_CLI={given} is not a file"
        return path
    subprocess.run(["cargo", "build", "--release", "-p", "drape-cli", "--quiet"], cwd=REPO, check=True)
    meta = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        cwd=REPO,
        check=True,
        capture_output=True,
        text=True,
    )
    return Path(json.loads(meta.stdout)["target_directory"]) / "release" / "drape"


def pedestal(**changes) -> dict:
    """The pedestal example as a dict, with `changes` (dotted key -> value)."""
    doc = tomllib.loads(PEDESTAL.read_text())
    for key, value in changes.items():
        table = doc
        *path, last = key.split(".")
        for part in path:
            table = table.setdefault(part, {})
        table[last] = value
    return doc


def short_pedestal() -> dict:
    """The pedestal at 10 x 10 squares: the free fall, then 30 steps of
    0.1 ms through the first contact (t = 0.1011 s). Some 50 ms a run."""
    return pedestal(
        **{
            "mesh.divisions": [10, 10],
            "time.segments": [{"steps": 10, "dt": 0.01}, {"steps": 30, "dt": 1.0e-4}],
        }
    )


def write_scenario(doc: dict, path: Path) -> Path:
    """Writes a scenario dict as TOML (drape's own writer)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_drape._scenario_text(doc, str(path.parent), str(path)))
    return path


def run_module(*args: str, cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    """`python -m drape ARGS` in `cwd`, output captured."""
    return subprocess.run(
        [sys.executable, "-m", "drape", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


__all__ = ["REPO", "EXAMPLES", "PEDESTAL", "pedestal", "short_pedestal", "write_scenario", "run_module", "drape"]
