"""drape.run, drape.check and RunResult against the command line."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from conftest import PEDESTAL, REPO, default_sigint, drape, pedestal, short_pedestal, write_scenario

# The tolerance the issue asks for. Both paths call the same library on the
# same text, so they agree to the last bit; 1e-9 m leaves room for nothing
# but a different computation.
TOLERANCE = 1e-9


def cli_run(cli: Path, scenario: Path, out: Path) -> drape.RunResult:
    subprocess.run([str(cli), "run", str(scenario), "--out", str(out), "--quiet"], check=True)
    return drape.RunResult(out)


def assert_same_run(python: drape.RunResult, command_line: drape.RunResult) -> None:
    a, b = python.history, command_line.history
    assert list(a) == list(b)
    assert len(a["step"]) == len(b["step"]) == python.summary["steps"] + 1
    np.testing.assert_array_equal(a["time"], b["time"])
    monitors = [c for c in a if c.endswith(("_x", "_y", "_z")) and c[:-2] in python.summary["monitors"]]
    assert len(monitors) == 3 * len(python.summary["monitors"]) > 0
    for column in monitors:
        assert np.max(np.abs(a[column] - b[column])) <= TOLERANCE, column
    for name, p in python.summary["monitors"].items():
        assert np.max(np.abs(np.subtract(p, command_line.summary["monitors"][name]))) <= TOLERANCE
    assert python.frames == command_line.frames
    assert np.max(np.abs(python.positions() - command_line.positions())) <= TOLERANCE
    for key in ("status", "steps", "time", "newton_iterations", "first_contact_time", "nodes", "dofs"):
        assert python.summary[key] == command_line.summary[key], key


def test_the_pedestal_from_python_equals_the_command_line(cli, tmp_path):
    command_line = cli_run(cli, PEDESTAL, tmp_path / "cli")
    python = drape.run(PEDESTAL, out=tmp_path / "py")
    assert python.summary["status"] == "completed"
    assert python.summary["first_contact_time"] is not None
    assert_same_run(python, command_line)
    # The command line and Python keep the same scenario for --resume.
    assert (tmp_path / "py" / "scenario.toml").read_text() == PEDESTAL.read_text()
    assert (tmp_path / "py" / "scenario.path").read_text() == str(PEDESTAL.resolve())


def test_a_dict_runs_as_its_file_does(cli, tmp_path):
    doc = short_pedestal()
    scenario = write_scenario(doc, tmp_path / "short.toml")
    command_line = cli_run(cli, scenario, tmp_path / "cli")
    python = drape.run(doc, out=tmp_path / "py")
    assert_same_run(python, command_line)
    # The dict's text is kept where --resume and the readers look for it.
    kept = tmp_path / "py" / "scenario.toml"
    assert (tmp_path / "py" / "scenario.path").read_text() == str(kept.resolve())
    assert drape.check(kept)["nodes"] == 121


@pytest.mark.skipif(sys.platform == "win32", reason="file names are not bytes on Windows")
def test_a_scenario_path_that_is_not_utf8_is_kept_in_its_own_bytes(tmp_path):
    """scenario.path holds the path's bytes, as the command line writes them
    (Python wrote it lossily: a resume would look for another file)."""
    import os

    folder = os.fsencode(tmp_path) + b"/caf\xe9"
    os.mkdir(folder)
    scenario = Path(os.fsdecode(folder + b"/short.toml"))
    write_scenario(short_pedestal(), tmp_path / "short.toml").rename(scenario)
    out = tmp_path / "out"
    drape.run(scenario, out=out)
    assert (out / "scenario.path").read_bytes() == os.fsencode(scenario.resolve())


def test_check_counts_the_pieces_of_a_mesh():
    # The pedestal's sheet is one piece; the two plies of issue 33's Gmsh
    # mesh are two.
    assert drape.check(short_pedestal())["pieces"] == 1
    plies = short_pedestal()
    plies["mesh"] = {"shape": "file", "path": str(REPO / "crates/drape/tests/meshes/two-plies-t3.msh")}
    plies.pop("obstacle", None)
    plies.pop("contact", None)
    plies.pop("monitor", None)
    info = drape.check(plies)
    assert (info["elements"], info["pieces"]) == (324, 2)


def test_self_contact_from_a_dict_keeps_two_plies_apart(tmp_path):
    # Issue 33's two plies dropped onto the pedestal with `self = True`
    # from a dict: the upper ply lands on the lower one and stays at
    # least self_distance / 2 above it where they overlap.
    plies = pedestal(
        **{
            "mesh": {"shape": "file", "path": str(REPO / "crates/drape/tests/meshes/two-plies-t3.msh")},
            "contact.self": True,
            "contact.self_distance": 2.0e-3,
            "time.segments": [{"steps": 140, "dt": 1.0e-3}],
            "output.every": 50,
        }
    )
    plies.pop("monitor", None)
    result = drape.run(plies, out=tmp_path / "plies")
    assert result.summary["status"] == "completed"
    start = drape.RunResult(tmp_path / "plies").positions(step=0)
    end = result.positions()
    centre = lambda z: int(np.argmin(np.hypot(start[:, 0], start[:, 1]) + 10.0 * np.abs(start[:, 2] - z)))
    lower, upper = centre(0.0), centre(0.01)
    assert end[upper, 2] - end[lower, 2] >= 1.0e-3, (end[upper], end[lower])


def test_the_result_reads_the_outputs(tmp_path):
    info = drape.check(short_pedestal())
    res = drape.run(short_pedestal(), out=tmp_path / "run")
    steps = res.summary["steps"]
    assert steps == 40
    history = res.history
    assert history is res.history or history.keys() == res.history.keys()
    for name, column in history.items():
        assert isinstance(column, np.ndarray) and column.dtype == np.float64 and column.shape == (steps + 1,), name
    np.testing.assert_array_equal(history["step"], np.arange(steps + 1))
    # Frames every 10 steps and the last.
    assert res.frames == [0, 10, 20, 30, 40]
    last = res.positions()
    assert last.shape == (info["nodes"], 3) and last.dtype == np.float64
    np.testing.assert_array_equal(last, res.positions(40))
    # A monitor's final position is its node's row in the last frame, and
    # its history's last row.
    for name, node in info["monitors"].items():
        np.testing.assert_array_equal(last[node], res.summary["monitors"][name])
        assert [history[f"{name}_{a}"][-1] for a in "xyz"] == res.summary["monitors"][name]
    # The first frame is the flat initial mesh.
    first = res.positions(0)
    assert np.all(first[:, 2] == 0.0)
    assert np.all(last[:, 2] < 0.0)
    with pytest.raises(ValueError, match=r"0, 10, 20, 30, 40"):
        res.positions(15)
    with pytest.raises(ValueError, match="-1 for the last frame"):
        res.positions(-2)
    again = drape.RunResult(tmp_path / "run")
    assert again.summary == res.summary and again.out == tmp_path / "run"
    assert "status='completed'" in repr(res)


def test_scenario_errors_carry_the_file_the_key_and_the_line(cli, tmp_path):
    text = PEDESTAL.read_text().replace("poisson_ratio = 0.3", "poisson_ratio = 0.7")
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text)
    line = next(i for i, l in enumerate(text.splitlines(), 1) if l.startswith("poisson_ratio"))
    with pytest.raises(drape.ScenarioError) as caught:
        drape.check(scenario)
    e = caught.value
    assert (e.file, e.key, e.line) == (str(scenario), "material.poisson_ratio", line)
    assert isinstance(e, ValueError) and isinstance(e, drape.DrapeError)
    # The message is the command line's.
    shown = subprocess.run([str(cli), "check", str(scenario)], capture_output=True, text=True)
    assert shown.returncode == 2
    assert shown.stderr.strip() == f"error: {e}"
    # drape.run refuses it the same way, before the output directory exists.
    with pytest.raises(drape.ScenarioError) as again:
        drape.run(scenario, out=tmp_path / "out")
    assert str(again.value) == str(e)
    assert not (tmp_path / "out").exists()


def test_a_parse_error_names_the_key_and_the_line(tmp_path):
    scenario = tmp_path / "typo.toml"
    scenario.write_text(PEDESTAL.read_text().replace("density = 320.0", 'density = "heavy"'))
    with pytest.raises(drape.ScenarioError) as caught:
        drape.check(scenario)
    e = caught.value
    assert e.key == "material.density" and e.line is not None and e.file == str(scenario)
    assert f"{scenario}, line {e.line}: `material.density`" in str(e)


def test_a_dict_error_has_its_key_and_no_line():
    doc = pedestal(**{"load": [{"kind": "surface", "force": [0, 0, -1.8816], "ramp": -1.0}]})
    with pytest.raises(drape.ScenarioError) as caught:
        drape.check(doc)
    e = caught.value
    assert (e.file, e.key, e.line) == ("<dict>", "load[0].ramp", None)
    assert str(e).startswith("<dict>: `load[0].ramp`")


def test_what_is_not_a_scenario_is_refused(tmp_path):
    with pytest.raises(TypeError, match="path of a TOML file"):
        drape.check(42)
    with pytest.raises(TypeError, match=r"scenario key `material.density`: a value of type object has no TOML value"):
        drape.check(pedestal(**{"material.density": object()}))
    with pytest.raises(ValueError, match="needs out="):
        drape.run(short_pedestal())
    with pytest.raises(drape.ScenarioError, match="cannot read"):
        drape.check(tmp_path / "missing.toml")


def test_a_dict_that_contains_itself_is_a_value_error():
    """Issue 34: a dict that contains itself, or nests 10,000 deep, is a
    ValueError naming the key path, where the conversion to TOML recursed
    without a limit and killed the interpreter (SIGSEGV)."""
    doc = pedestal()
    doc["material"]["self"] = doc["material"]
    with pytest.raises(ValueError, match=r"scenario key `material\.self\.self.*`: nested more than 32"):
        drape.check(doc)
    deep = pedestal()
    inner = deep["mesh"]
    for _ in range(10_000):
        inner["x"] = {}
        inner = inner["x"]
    with pytest.raises(ValueError, match=r"scenario key `mesh\.x\.x.*`: nested more than 32 tables or lists deep"):
        drape.check(deep)
    listed = pedestal()
    loop = []
    loop.append(loop)
    listed["material"]["density"] = loop
    with pytest.raises(ValueError, match=r"scenario key `material\.density\[0\]\[0\]"):
        drape.check(listed)


def test_a_failed_run_raises_run_error_with_what_it_wrote(tmp_path):
    # One Newton iteration and no cut-back: the first contact step fails.
    doc = short_pedestal()
    doc["solver"] = {"max_iterations": 1, "max_cutbacks": 0}
    with pytest.raises(drape.RunError) as caught:
        drape.run(doc, out=tmp_path / "run")
    e = caught.value
    assert e.out == tmp_path / "run"
    assert e.result is not None and e.result.summary["status"] == "failed"
    assert e.result.summary["message"] in str(e)
    assert len(e.result.history["step"]) == e.result.summary["steps"] + 1


def test_an_output_directory_of_someone_else_is_refused(tmp_path):
    out = tmp_path / "theirs"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(drape.OutputError, match="notes.txt") as refused:
        drape.run(short_pedestal(), out=out)
    # It names Python's argument too, not only the command line's option.
    assert "out= from Python" in str(refused.value)
    assert (out / "notes.txt").read_text() == "mine"


def test_the_gil_is_released_while_the_solver_runs(tmp_path):
    # The pedestal at 20 x 20 takes about half a second. While it runs in a
    # thread, this thread must keep running Python: with the GIL held, it
    # would stall for the whole run.
    done = threading.Event()
    errors = []

    def work():
        try:
            drape.run(PEDESTAL, out=tmp_path / "run")
        except BaseException as e:  # reported below
            errors.append(e)
        finally:
            done.set()

    thread = threading.Thread(target=work)
    start = time.perf_counter()
    thread.start()
    ticks, longest, last = 0, 0.0, time.perf_counter()
    while not done.is_set():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
        ticks += 1
        time.sleep(0.001)
    thread.join()
    elapsed = time.perf_counter() - start
    assert not errors, errors
    assert elapsed > 0.2
    # The run re-enters Python for signals every 50 ms at most, for a few
    # microseconds; a stall of half the run means the GIL was held.
    assert longest < elapsed / 2, (longest, elapsed)
    assert ticks > 50


INTERRUPTED = """
import sys, drape
try:
    drape.run(sys.argv[1], out=sys.argv[2])
except KeyboardInterrupt as e:
    print("KeyboardInterrupt:", e)
    sys.exit(130)
print("not interrupted")
"""


def start_interruptible(scenario: Path, out: Path) -> subprocess.Popen:
    """`drape.run(scenario, out=out)` in a child that a test interrupts
    with SIGINT (INTERRUPTED prints what the KeyboardInterrupt said)."""
    return subprocess.Popen(
        [sys.executable, "-c", INTERRUPTED, str(scenario), str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_sigint,
    )


def test_ctrl_c_stops_the_run_as_the_command_line_does(tmp_path):
    # A long pedestal (3,000 steps after the fall at 10 x 10: a second or two).
    doc = short_pedestal()
    doc["time"]["segments"] = [{"steps": 10, "dt": 0.01}, {"steps": 3000, "dt": 1.0e-4}]
    scenario = write_scenario(doc, tmp_path / "long.toml")
    out = tmp_path / "run"
    child = start_interruptible(scenario, out)
    history = out / "history.csv"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not history.is_file() or history.read_text().count("\n") < 30):
        assert child.poll() is None, child.communicate()
        time.sleep(0.02)
    child.send_signal(2)  # SIGINT, as Ctrl-C in a terminal
    stdout, stderr = child.communicate(timeout=60)
    assert child.returncode == 130, (stdout, stderr)
    assert "KeyboardInterrupt: interrupted after step" in stdout
    assert "resume=True" in stdout
    summary = drape.RunResult(out).summary
    assert summary["status"] == "interrupted"
    assert (out / "checkpoint.bin").is_file()
    rows = history.read_text().count("\n") - 1
    assert rows == summary["steps"] + 1 and summary["time"] < 0.39
    # Resumed, it ends where an uninterrupted run ends, to the last bit.
    resumed = drape.run(scenario, out=out, resume=True)
    straight = drape.run(scenario, out=tmp_path / "straight")
    assert resumed.summary["status"] == straight.summary["status"] == "completed"
    assert resumed.summary["steps"] == straight.summary["steps"]
    assert resumed.summary["monitors"] == straight.summary["monitors"]
    np.testing.assert_array_equal(resumed.positions(), straight.positions())


def test_ctrl_c_reaches_a_step_under_way(tmp_path):
    """Issue 46: Ctrl-C inside a long step ends it at its next Newton
    iteration, not after it. The whole weight of a 40-ring disc with
    bending in one static increment takes 52 Newton iterations, about 14 s
    on a 2-core machine; the signal comes a second into it."""
    doc = tomllib.loads((REPO / "crates" / "drape-bench" / "scenarios" / "quasi-static-60.toml").read_text())
    doc["mesh"]["rings"] = 40
    doc["analysis"]["steps"] = 1
    scenario = write_scenario(doc, tmp_path / "one-increment.toml")
    out = tmp_path / "run"
    child = start_interruptible(scenario, out)
    history = out / "history.csv"
    deadline = time.monotonic() + 60
    # The history's first row (t = 0) is written before the first step.
    while time.monotonic() < deadline and not history.is_file():
        assert child.poll() is None, child.communicate()
        time.sleep(0.02)
    time.sleep(1.0)
    assert child.poll() is None, child.communicate()
    signalled = time.monotonic()
    child.send_signal(2)  # SIGINT, as Ctrl-C in a terminal
    stdout, stderr = child.communicate(timeout=120)
    waited = time.monotonic() - signalled
    assert child.returncode == 130, (stdout, stderr)
    assert "KeyboardInterrupt:" in stdout and "resume=True" in stdout
    summary = drape.RunResult(out).summary
    # Stopped inside the increment: no step taken, a checkpoint to resume.
    assert summary["status"] == "interrupted", summary["message"]
    assert summary["steps"] == 0, summary
    assert (out / "checkpoint.bin").is_file()
    # An iteration at 15,000 unknowns takes a fraction of a second.
    assert waited < 5.0, waited


def test_a_multilevel_settle_from_python_equals_the_command_line(cli, tmp_path):
    """Issue 43: `[refine]` through `drape.run` — the same levels, history
    and last frame (on the finest mesh) as `drape run`."""
    scenario = REPO / "crates" / "drape" / "tests" / "scenarios" / "multilevel-tester.toml"
    command_line = cli_run(cli, scenario, tmp_path / "cli")
    python = drape.run(scenario, out=tmp_path / "py")
    levels = python.summary["levels"]
    assert len(levels) == 3
    assert [l["elements"] for l in levels] == [l["elements"] for l in command_line.summary["levels"]]
    assert levels[0]["elements"] < levels[1]["elements"] < levels[2]["elements"]
    assert python.summary["elements"] == levels[2]["elements"]
    np.testing.assert_array_equal(python.history["elements"], command_line.history["elements"])
    assert python.history["elements"][0] == levels[0]["elements"]
    assert python.history["elements"][-1] == levels[2]["elements"]
    assert python.positions().shape == (levels[2]["nodes"], 3)
    # (It has no monitors: the history's time, the frames and the last
    # positions stand for the run.)
    np.testing.assert_array_equal(python.history["time"], command_line.history["time"])
    assert python.frames == command_line.frames
    assert np.max(np.abs(python.positions() - command_line.positions())) <= TOLERANCE
    for key in ("status", "steps", "newton_iterations", "nodes", "elements"):
        assert python.summary[key] == command_line.summary[key], key


def test_bending_friction_held_by_a_stick_from_a_dict(cli, tmp_path):
    """The keys of bending hysteresis held by a stick (README, `[material]`)
    from a dict: the run is the command line's, comes to rest (a stick does
    not creep) and dissipates by the slip."""
    doc = {
        "mesh": {"shape": "rectangle", "size": [0.1, 0.1], "divisions": [6, 6]},
        "material": {
            "youngs_modulus": 2.0e6,
            "poisson_ratio": 0.3,
            "density": 320.0,
            "thickness": 0.6e-3,
            "bending_rigidity": 2.0e-5,
            "bending_hysteresis": 2.0e-4,
            "bending_hysteresis_stiffness": 2.0e-4,
        },
        "load": [{"kind": "gravity", "acceleration": [0.0, 0.0, -9.8]}],
        "fix": [{"at": [-0.05, 0.05, 0.0]}, {"at": [0.05, 0.05, 0.0]}],
        "time": {
            "beta": 1.0,
            "gamma": 1.5,
            "segments": [{"steps": 2000, "dt": 1.0e-2}],
            "adaptive": True,
            "rest": {"speed": 1.0e-4, "after": 0.2},
        },
        "monitor": [{"name": "corner", "at": [-0.05, -0.05, 0.0]}],
    }
    scenario = write_scenario(doc, tmp_path / "stick.toml")
    command_line = cli_run(cli, scenario, tmp_path / "cli")
    python = drape.run(doc, out=tmp_path / "py")
    assert_same_run(python, command_line)
    assert python.summary["status"] == "completed"
    assert python.summary["at_rest"] is True
    assert python.history["friction_dissipation"][-1] > 0.0
    # A stiffness with a creep rate is refused, naming both keys.
    doc["material"]["bending_hysteresis_rate"] = 1.0
    with pytest.raises(drape.ScenarioError) as e:
        drape.run(doc, out=tmp_path / "both")
    assert "bending_hysteresis_stiffness" in str(e.value)
    assert "bending_hysteresis_rate" in str(e.value)
