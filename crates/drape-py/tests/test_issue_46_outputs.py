"""Issue 46: a result reads its own run, a run in progress or killed opens,
a sweep keeps a user's files, a refused run leaves nothing behind."""

from __future__ import annotations

import csv
import signal
import subprocess
import time

import numpy as np
import pytest

import drape

from conftest import run_module, short_pedestal, write_scenario


def test_a_result_reads_its_own_run_after_a_change_of_directory(tmp_path, monkeypatch):
    # Two runs into "o" relative to two working directories; the first
    # result must go on reading the first run's history and frames.
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    monkeypatch.chdir(tmp_path / "a")
    first = drape.run(short_pedestal(), out="o")
    assert first.out == tmp_path / "a" / "o" and first.out.is_absolute()
    opened = drape.RunResult("o")
    assert opened.out == tmp_path / "a" / "o"
    monkeypatch.chdir(tmp_path / "b")
    other = short_pedestal()
    other["time"]["segments"] = [{"steps": 3, "dt": 0.01}]
    drape.run(other, out="o")
    for result in (first, opened):
        steps = result.summary["steps"]
        assert steps == 40
        np.testing.assert_array_equal(result.history["step"], np.arange(steps + 1))
        assert result.frames == [0, 10, 20, 30, 40]


def test_a_run_in_progress_or_killed_opens_with_no_summary(cli, tmp_path):
    # A long pedestal run killed by SIGKILL mid-way: history, frames and
    # scenario on disk, no summary.json. It opens (as measure, plot and
    # render read it), its summary None.
    doc = short_pedestal()
    doc["time"]["segments"] = [{"steps": 10, "dt": 0.01}, {"steps": 30000, "dt": 1.0e-4}]
    scenario = write_scenario(doc, tmp_path / "long.toml")
    out = tmp_path / "run"
    child = subprocess.Popen([str(cli), "run", "--quiet", str(scenario), "--out", str(out)])
    history = out / "history.csv"
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline and (not history.is_file() or history.read_text().count("\n") < 45):
            assert child.poll() is None, "the run ended before it was killed"
            time.sleep(0.02)
        # In progress: no summary yet.
        running = drape.RunResult(out)
        assert running.summary is None
        # The frames written so far (a writer thread follows the steps).
        assert running.frames[0] == 0 and all(step % 10 == 0 for step in running.frames)
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=60)
    assert not (out / "summary.json").exists()
    killed = drape.RunResult(out)
    assert killed.summary is None and killed.out == out
    rows = len(killed.history["step"])
    assert rows >= 45
    np.testing.assert_array_equal(killed.history["step"], np.arange(rows))
    assert killed.frames[0] == 0 and killed.positions().shape == killed.positions(0).shape
    assert "summary=None" in repr(killed)
    # A directory that holds no run is still refused, saying what it lacks.
    (tmp_path / "empty").mkdir()
    with pytest.raises(drape.OutputError, match="no summary.json, history.csv"):
        drape.RunResult(tmp_path / "empty")
    with pytest.raises(drape.OutputError, match="output directory of a drape run"):
        drape.RunResult(tmp_path / "absent")


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


ONE_CASE = 'base = "base.toml"\n[parameters]\n"material.density" = [300.0]\n'


def one_case_sweep(folder):
    write_scenario(short_pedestal(), folder / "base.toml")
    sweep = folder / "sweep.toml"
    sweep.write_text(ONE_CASE)
    return sweep


def test_a_sweep_keeps_a_users_own_results_csv(tmp_path):
    sweep = one_case_sweep(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    mine = out / "results.csv"
    mine.write_text("fabric,drape coefficient\nM1,0.42\n")
    done = run_module("sweep", str(sweep), "--out", str(out), cwd=tmp_path)
    assert done.returncode == 2, done
    assert done.stderr.count("\n") == 1 and str(mine) in done.stderr, done.stderr
    assert "not a sweep's" in done.stderr
    assert mine.read_text() == "fabric,drape coefficient\nM1,0.42\n"
    assert sorted(p.name for p in out.iterdir()) == ["results.csv"]
    # A results.csv with a sweep's header but no cases beside it is not
    # one either (a sweep's own sits beside its cases/).
    mine.write_text("case,status,x\n0,completed,1\n")
    with pytest.raises(drape.SweepError, match="results.csv"):
        drape.sweep(sweep, out=out, workers=1, progress=False)
    assert mine.read_text() == "case,status,x\n0,completed,1\n"
    # A sweep's own is rewritten, and the same sweep again skips its
    # completed case.
    mine.unlink()
    (first,) = drape.sweep(sweep, out=out, workers=1, progress=False)
    assert first["status"] == "completed"
    summary = out / "cases" / "0000" / "summary.json"
    before = summary.stat().st_mtime_ns
    again = run_module("sweep", str(sweep), "--out", str(out), cwd=tmp_path)
    assert again.returncode == 0, again
    assert summary.stat().st_mtime_ns == before
    assert read_csv(out / "results.csv")[0]["status"] == "completed"


def test_a_sweep_into_a_file_is_one_line_and_exit_2(tmp_path):
    sweep = one_case_sweep(tmp_path)
    a_file = tmp_path / "a-file"
    a_file.write_text("mine")
    done = run_module("sweep", str(sweep), "--out", str(a_file), cwd=tmp_path)
    assert done.returncode == 2, done
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert str(a_file) in done.stderr and "not a directory" in done.stderr
    assert a_file.read_text() == "mine"
    out = tmp_path / "out"
    out.mkdir()
    (out / "cases").write_text("mine")
    done = run_module("sweep", str(sweep), "--out", str(out), cwd=tmp_path)
    assert done.returncode == 2, done
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert str(out / "cases") in done.stderr and "not a directory" in done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["cases"]


def test_a_refused_run_writes_nothing(tmp_path, monkeypatch):
    # out="" names no directory: refused naming the empty value, and no
    # drape.lock in the working directory.
    monkeypatch.chdir(tmp_path)
    with pytest.raises(drape.OutputError, match=r'"" is an empty path'):
        drape.run(short_pedestal(), out="")
    with pytest.raises(drape.OutputError, match=r'"" is an empty path'):
        drape.run(short_pedestal(), out="", resume=True)
    assert list(tmp_path.iterdir()) == []
    # A directory with a file of the user's: refused by name, left as it was.
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(drape.OutputError, match="notes.txt"):
        drape.run(short_pedestal(), out=out)
    assert [p.name for p in out.iterdir()] == ["notes.txt"]
