"""Sweeps: cases, results.csv, failed cases, re-runs and resumption."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import pytest

from conftest import default_sigint, drape, pedestal, run_module, short_pedestal, write_scenario

SPEC_COLUMNS = ["steps", "time", "newton_iterations", "wall_seconds", "first_contact_time"]

GRID = """
base = "base.toml"
mode = "grid"
[parameters]
"material.youngs_modulus" = [1.0e6, 2.0e6, -3.0e6]
"contact.penalty" = [2.0e4, 5.0e4]
"""


def make_sweep(folder: Path, text: str = GRID, base: dict | None = None) -> Path:
    write_scenario(base if base is not None else short_pedestal(), folder / "base.toml")
    path = folder / "sweep.toml"
    path.write_text(text)
    return path


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def start_sweep(sweep: Path, out: Path) -> subprocess.Popen:
    """`python -m drape sweep` with one worker, in a process group of its
    own (a terminal's Ctrl-C, or a kill, reaches the driver and its workers)."""
    return subprocess.Popen(
        [sys.executable, "-m", "drape", "sweep", str(sweep), "--out", str(out), "--workers", "1"],
        cwd=sweep.parent,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=default_sigint,
    )


def mtimes(out: Path) -> dict:
    return {p: p.stat().st_mtime_ns for p in sorted(out.glob("cases/*/summary.json"))}


def test_a_grid_with_an_invalid_value(tmp_path):
    sweep = make_sweep(tmp_path)
    out = tmp_path / "out"
    done = run_module("sweep", str(sweep), "--out", str(out), "--workers", "2", cwd=tmp_path)
    # A failed case makes the sweep's exit code 1, as a failed run makes drape run's.
    assert done.returncode == 1, done.stderr
    assert "6 cases: 4 completed, 2 failed" in done.stdout

    rows = read_csv(out / "results.csv")
    header = list(rows[0])
    assert header == [
        "case",
        "status",
        "material.youngs_modulus",
        "contact.penalty",
        *SPEC_COLUMNS,
        "corner_x",
        "corner_y",
        "corner_z",
        "center_x",
        "center_y",
        "center_z",
        "message",
        "threads",
    ]
    assert [r["case"] for r in rows] == [str(i) for i in range(6)]
    # Grid order: the first parameter varies slowest.
    assert [(r["material.youngs_modulus"], r["contact.penalty"]) for r in rows] == [
        ("1000000.0", "20000.0"),
        ("1000000.0", "50000.0"),
        ("2000000.0", "20000.0"),
        ("2000000.0", "50000.0"),
        ("-3000000.0", "20000.0"),
        ("-3000000.0", "50000.0"),
    ]
    assert [r["status"] for r in rows] == ["completed"] * 4 + ["failed"] * 2
    for r in rows[4:]:
        # The validation message, as `drape check` prints it, naming the
        # case's own scenario (relative to the sweep's directory) and line.
        assert r["message"].startswith(f"cases/000{r['case']}/scenario.toml, line ")
        assert "`material.youngs_modulus` must be a positive finite number, not -3000000" in r["message"]
        assert all(r[c] == "" for c in SPEC_COLUMNS + ["corner_z"])
        assert not (out / "cases" / f"000{r['case']}" / "summary.json").exists()
    good = rows[:4]
    for r in good:
        assert int(r["steps"]) == 40 and float(r["time"]) == pytest.approx(0.103)
        assert float(r["first_contact_time"]) == pytest.approx(0.1011)
        assert r["message"] == "completed 40 steps to t = 0.103000 s"
        # Each row is its case's summary.
        summary = drape.RunResult(out / "cases" / f"000{r['case']}").summary
        assert float(r["corner_z"]) == summary["monitors"]["corner"][2]
        assert int(r["newton_iterations"]) == summary["newton_iterations"]
        assert float(r["wall_seconds"]) == summary["wall_seconds"]
    # Distinct results for distinct parameters.
    assert len({(r["corner_x"], r["corner_z"], r["center_z"]) for r in good}) == 4
    # Each case's directory holds its scenario, with the values set.
    case = tomllib.loads((out / "cases" / "0003" / "scenario.toml").read_text())
    assert case["material"]["youngs_modulus"] == 2.0e6 and case["contact"]["penalty"] == 5.0e4

    # Again: nothing runs, nothing changes, in a few seconds.
    before = (out / "results.csv").read_bytes()
    stamps = mtimes(out)
    start = time.monotonic()
    again = run_module("sweep", str(sweep), "--out", str(out), "--workers", "2", cwd=tmp_path)
    elapsed = time.monotonic() - start
    assert again.returncode == 1
    assert (out / "results.csv").read_bytes() == before
    assert mtimes(out) == stamps and len(stamps) == 4
    assert elapsed < 10, elapsed


def test_the_function_returns_the_rows(tmp_path):
    sweep = make_sweep(
        tmp_path,
        """
base = "base.toml"
mode = "zip"
[parameters]
"obstacle[0].max" = [[0.05, 0.05, -0.05], [0.04, 0.04, -0.06]]
"load[0].force" = [[0.0, 0.0, -1.8816], [0.0, 0.0, -3.0]]
material.density = [320.0, 400.0]
""",
    )
    rows = drape.sweep(sweep, out=tmp_path / "out", workers=1, progress=False)
    assert [r["status"] for r in rows] == ["completed", "completed"]
    assert rows[1]["obstacle[0].max"] == [0.04, 0.04, -0.06]
    assert rows[1]["material.density"] == 400.0
    # zip: the i-th values together, in the case's scenario.
    case = tomllib.loads((tmp_path / "out" / "cases" / "0001" / "scenario.toml").read_text())
    assert case["obstacle"][0]["max"] == [0.04, 0.04, -0.06]
    assert case["load"][0]["force"] == [0.0, 0.0, -3.0]
    assert case["material"]["density"] == 400.0
    # The lower pedestal top is where the centre comes to rest.
    assert rows[0]["center_z"] == pytest.approx(-0.05, abs=1e-3)
    assert rows[1]["center_z"] == pytest.approx(-0.06, abs=1e-3)
    # Free fall to the pedestal's top, sqrt(2 h / a) with a = force / (rho t),
    # seen at the end of the step it happens in: 0.10102 s -> 0.1011 s
    # (h = 5 cm, a = 9.8 m/s^2); 0.0980 s -> 0.1 s (h = 6 cm, a = 12.5 m/s^2).
    assert rows[0]["first_contact_time"] == pytest.approx(0.1011)
    assert rows[1]["first_contact_time"] == pytest.approx(0.1)
    with open(tmp_path / "out" / "results.csv", newline="") as f:
        written = list(csv.reader(f))
    assert written[2][2] == "[0.04, 0.04, -0.06]"


def test_a_mesh_path_is_the_base_scenarios(tmp_path):
    # A relative path in the base is relative to the base; the case's
    # scenario, elsewhere, holds it absolute.
    (tmp_path / "in").mkdir()
    mesh = tmp_path / "in" / "square.obj"
    mesh.write_text("v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0\nf 1 2 3\nf 1 3 4\n")
    base = short_pedestal()
    base["mesh"] = {"shape": "file", "path": "square.obj"}
    base["monitor"] = [{"name": "corner", "at": [0.1, 0.1, 0.0]}]
    write_scenario(base, tmp_path / "in" / "base.toml")
    (tmp_path / "in" / "base.toml").write_text(
        (tmp_path / "in" / "base.toml").read_text().replace(str(mesh), "square.obj")
    )
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('base = "in/base.toml"\n[parameters]\n"material.thickness" = [6e-4]\n')
    rows = drape.sweep(sweep, out=tmp_path / "out", progress=False)
    assert rows[0]["status"] == "completed", rows[0]["message"]
    case = tomllib.loads((tmp_path / "out" / "cases" / "0000" / "scenario.toml").read_text())
    assert case["mesh"]["path"] == str(mesh)


SLOW = """
base = "base.toml"
[parameters]
"material.youngs_modulus" = [1.0e6, 1.5e6, 2.0e6, 2.5e6, 3.0e6, 3.5e6]
"""


def test_a_killed_sweep_runs_only_the_missing_cases(tmp_path):
    # Six cases of about half a second each, one at a time; killed (as by
    # a reboot: SIGKILL to the driver and its workers) after the second.
    base = pedestal(**{"time.segments": [{"steps": 10, "dt": 0.01}, {"steps": 200, "dt": 1.0e-4}]})
    sweep = make_sweep(tmp_path, SLOW, base)
    out = tmp_path / "out"
    driver = start_sweep(sweep, out)
    deadline = time.monotonic() + 120
    try:
        while len(mtimes(out)) < 2:
            assert driver.poll() is None, "the sweep ended before it was killed"
            assert time.monotonic() < deadline
            time.sleep(0.01)
    finally:
        os.killpg(driver.pid, signal.SIGKILL)
        driver.communicate()
    before = {p: s for p, s in mtimes(out).items() if drape.RunResult(p.parent).summary["status"] == "completed"}
    assert 2 <= len(before) < 6

    rows = drape.sweep(sweep, out=out, workers=1, progress=False)
    assert [r["status"] for r in rows] == ["completed"] * 6
    after = mtimes(out)
    # The completed cases were not run again; the others were.
    assert {p: after[p] for p in before} == before
    assert len(after) == 6
    assert all(after[p] > max(before.values()) for p in after if p not in before)
    assert len({r["corner_z"] for r in rows}) == 6


def test_a_sweep_killed_while_writing_a_scenario_runs_the_case_again(tmp_path):
    # Killed between writing a case's scenario to its temporary copy and
    # renaming it, a sweep leaves the copy in the case's directory, which
    # drape refuses as a file it did not write ("holds files drape did
    # not write"): the case failed on every re-run. The re-run removes it.
    base = short_pedestal()
    sweep = make_sweep(tmp_path, 'base = "base.toml"\n[parameters]\n"material.youngs_modulus" = [2.0e6]\n', base)
    out = tmp_path / "out"
    case = out / "cases" / "0000"
    case.mkdir(parents=True)
    (case / ".scenario.toml.tmp-4242").write_text("half a scenario")
    rows = drape.sweep(sweep, out=out, workers=1, progress=False)
    assert rows[0]["status"] == "completed", rows[0]["message"]
    assert not list(case.glob(".scenario.toml.tmp-*"))


def test_an_interrupted_sweep_resumes_its_cases(tmp_path):
    # Ctrl-C (SIGINT to the driver and its worker, as a terminal sends it)
    # stops the running case after its step with a checkpoint; the next
    # run resumes it and ends as an uninterrupted run.
    base = short_pedestal()
    base["time"]["segments"] = [{"steps": 10, "dt": 0.01}, {"steps": 1500, "dt": 1.0e-4}]
    sweep = make_sweep(tmp_path, 'base = "base.toml"\n[parameters]\n"material.youngs_modulus" = [2.0e6]\n', base)
    out = tmp_path / "out"
    driver = start_sweep(sweep, out)
    history = out / "cases" / "0000" / "history.csv"
    deadline = time.monotonic() + 120
    while not history.is_file() or history.read_text().count("\n") < 50:
        assert driver.poll() is None, driver.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.01)
    os.killpg(driver.pid, signal.SIGINT)
    stdout, stderr = driver.communicate(timeout=120)
    assert driver.returncode == 130, (stdout, stderr)
    assert "run the same command again" in stderr
    case = out / "cases" / "0000"
    assert drape.RunResult(case).summary["status"] == "interrupted"
    assert (case / "checkpoint.bin").is_file()
    assert read_csv(out / "results.csv")[0]["status"] == "interrupted"

    rows = drape.sweep(sweep, out=out, workers=1, progress=False)
    assert rows[0]["status"] == "completed"
    # The same sweep uninterrupted: the same row (but the wall time) and
    # the same history, byte for byte; each row records its threads.
    straight = tmp_path / "straight"
    (uninterrupted,) = drape.sweep(sweep, out=straight, workers=1, progress=False)
    machine = ("wall_seconds", "threads")
    assert {k: v for k, v in rows[0].items() if k not in machine} == {
        k: v for k, v in uninterrupted.items() if k not in machine
    }
    assert (case / "history.csv").read_bytes() == (straight / "cases" / "0000" / "history.csv").read_bytes()
    assert uninterrupted["threads"] == drape.RunResult(straight / "cases" / "0000").summary["threads"] >= 1
    assert read_csv(straight / "results.csv")[0]["threads"] == str(uninterrupted["threads"])


def test_the_progress_bar_is_drawn_on_a_terminal_only(tmp_path):
    import io

    from drape._progress import Bar

    quiet = io.StringIO()
    bar = Bar(3, stream=quiet)
    bar.update()
    bar.close()
    assert quiet.getvalue() == ""

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    shown = Terminal()
    bar = Bar(4, done=1, stream=shown)
    bar.update(failed=True)
    bar.close()
    text = shown.getvalue()
    assert "2/4 cases, 1 failed" in text and "left" in text and text.endswith("\n")


def test_a_case_held_by_another_process_is_left_to_it(tmp_path):
    """Issue 34: a case's directory is locked before anything in it is
    touched. With case 0000 held by another process (here this test, as
    a second sweep into the same directory would hold it), the sweep
    leaves it alone — its row failed, saying why, no scenario written
    into it — and runs the others; once it is released, running the
    sweep again completes it."""
    from drape._case import lock_case

    sweep = make_sweep(tmp_path, 'base = "base.toml"\n[parameters]\n"material.density" = [300.0, 320.0]\n')
    out = tmp_path / "out"
    held = lock_case(out / "cases" / "0000")
    assert held is not None
    try:
        rows = drape.sweep(sweep, out=out, workers=1, progress=False)
        assert [r["status"] for r in rows] == ["failed", "completed"]
        assert "in use by another process" in rows[0]["message"]
        assert not (out / "cases" / "0000" / "scenario.toml").exists()
        # Nor can a second holder take it meanwhile.
        assert lock_case(out / "cases" / "0000") is None
    finally:
        os.close(held)
    rows = drape.sweep(sweep, out=out, workers=1, progress=False)
    assert [r["status"] for r in rows] == ["completed", "completed"]


def _spawned_workers(driver_pid: int) -> list[int]:
    """The pids of a local sweep's pool workers: the driver's children
    started by multiprocessing's spawn (not its resource tracker)."""
    pids = []
    for task in Path(f"/proc/{driver_pid}/task").iterdir():
        for child in (task / "children").read_text().split():
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes().replace(b"\0", b" ")
            if b"spawn_main" in cmdline:
                pids.append(int(child))
    return pids


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux's /proc")
def test_a_killed_worker_fails_no_other_case(tmp_path):
    """Issue 34: a local worker killed (SIGKILL, as by the OOM killer)
    while it runs a case broke the whole pool, and every row said
    BrokenProcessPool. Now the cases the pool broke on run again on a
    fresh pool (and one that kills its worker again, alone, fails alone):
    every case completes and the sweep exits 0."""
    base = pedestal(**{"time.segments": [{"steps": 10, "dt": 0.01}, {"steps": 200, "dt": 1.0e-4}]})
    sweep = make_sweep(tmp_path, SLOW, base)
    out = tmp_path / "out"
    driver = start_sweep(sweep, out)
    deadline = time.monotonic() + 120
    killed = None
    try:
        while killed is None:
            assert driver.poll() is None, "the sweep ended before a worker was killed"
            assert time.monotonic() < deadline
            if (out / "cases" / "0000" / "history.csv").is_file():
                workers = _spawned_workers(driver.pid)
                if workers:
                    os.kill(workers[0], signal.SIGKILL)
                    killed = workers[0]
            time.sleep(0.01)
        stdout, stderr = driver.communicate(timeout=240)
    finally:
        if driver.poll() is None:
            os.killpg(driver.pid, signal.SIGKILL)
            driver.communicate()
    assert driver.returncode == 0, stderr
    rows = read_csv(out / "results.csv")
    assert [r["status"] for r in rows] == ["completed"] * 6, [r["message"] for r in rows]
