"""Issue 46: a result reads its own run, a run in progress or killed opens,
a sweep keeps a user's files, a refused run leaves nothing behind."""

from __future__ import annotations

import os

import numpy as np

import drape

from conftest import short_pedestal


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
