"""A refused resume from Python is recorded as the command line records it
(issue 19): the directory is held first, and the refusal goes into its
summary (status "failed", the message, the interrupted session's counts
kept), then the exception is raised."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import drape, write_scenario

SQUARE = "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0\nf 1 2 3\nf 1 3 4\n"


def interrupted_run(folder: Path) -> tuple[Path, Path]:
    """A plate meshed by ``square.obj`` in ``folder``, run 10 steps with a
    checkpoint every 5 into ``folder/out``, whose summary is then made to
    say "interrupted" (as if stopped at its last checkpoint: a completed
    run's summary is never touched by a refused resume)."""
    (folder / "square.obj").write_text(SQUARE)
    doc = {
        "mesh": {"shape": "file", "path": "square.obj"},
        "material": {
            "youngs_modulus": 2.0e6,
            "poisson_ratio": 0.3,
            "density": 320.0,
            "thickness": 0.6e-3,
        },
        "load": [{"kind": "gravity", "acceleration": [0.0, 0.0, -9.8]}],
        "time": {"segments": [{"steps": 10, "dt": 1.0e-3}]},
        "output": {"checkpoint_every": 5},
    }
    scenario = write_scenario(doc, folder / "plate.toml")
    out = folder / "out"
    drape.run(scenario, out=out)
    summary = json.loads((out / "summary.json").read_text())
    summary["status"] = "interrupted"
    (out / "summary.json").write_text(json.dumps(summary))
    return scenario, out


def summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def resume_both(cli: Path, scenario: Path, out: Path, expected: type) -> tuple[dict, dict, str]:
    """Resumes a copy of ``out`` with the command line (which must exit 2)
    and ``out`` from Python (which must raise ``expected``); returns both
    summaries, the command line's with its directory's name replaced by
    ``out``'s, and the Python exception's message."""
    twin = out.parent / "twin"
    shutil.copytree(out, twin)
    done = subprocess.run([str(cli), "run", "--resume", str(twin), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    with pytest.raises(expected) as raised:
        drape.run(scenario, out=out, resume=True)
    from_cli = json.loads((twin / "summary.json").read_text().replace(str(twin), str(out)))
    return summary(out), from_cli, str(raised.value)


def test_a_changed_mesh_file_is_recorded_as_the_command_line_records_it(tmp_path, cli):
    scenario, out = interrupted_run(tmp_path)
    rows = (out / "history.csv").read_text()
    (tmp_path / "square.obj").write_text(SQUARE.replace("v 0.1 0.1 0", "v 0.1 0.11 0"))
    from_python, from_cli, message = resume_both(cli, scenario, out, drape.RunError)
    # The same summary, but each names its own way to a fresh run (Python
    # said "without --resume").
    recorded = from_python["message"]
    assert recorded.endswith("start a fresh run (resume=False)"), recorded
    assert "--resume" not in recorded, recorded
    from_cli["message"] = from_cli["message"].replace("(without --resume)", "(resume=False)")
    assert from_python == from_cli
    assert from_python["status"] == "failed"
    assert recorded.startswith("cannot resume: ") and recorded.count("cannot resume") == 1, recorded
    assert "square.obj" in recorded and "has changed" in recorded, recorded
    assert message == recorded
    # The interrupted session's counts and outputs are kept.
    assert from_python["steps"] == 10
    assert (out / "history.csv").read_text() == rows


def test_a_scenario_that_no_longer_reads_is_recorded_and_raised_as_a_scenario_error(tmp_path, cli):
    scenario, out = interrupted_run(tmp_path)
    scenario.write_text(scenario.read_text().replace("poisson_ratio = 0.3", "poisson_ratio = 0.7"))
    from_python, from_cli, message = resume_both(cli, scenario, out, drape.ScenarioError)
    assert from_python == from_cli
    assert from_python["status"] == "failed"
    assert from_python["message"].startswith("cannot resume: "), from_python["message"]
    assert "poisson_ratio" in from_python["message"] and "poisson_ratio" in message
    assert from_python["steps"] == 10


def test_a_resume_of_no_run_creates_nothing(tmp_path):
    scenario, _ = interrupted_run(tmp_path)
    missing = tmp_path / "missing"
    with pytest.raises(drape.OutputError, match="no such directory"):
        drape.run(scenario, out=missing, resume=True)
    assert not missing.exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(drape.OutputError, match="holds no drape run"):
        drape.run(scenario, out=empty, resume=True)
    assert list(empty.iterdir()) == []
