"""Issue 46's small messages, from Python: a completed run without a
checkpoint has nothing to resume; a second run on one directory in this
process is told so."""

from __future__ import annotations

import os
import threading
import time

import pytest

import drape

from conftest import short_pedestal


def test_resuming_a_completed_run_without_a_checkpoint_says_nothing_is_left(tmp_path):
    out = tmp_path / "run"
    doc = short_pedestal()
    done = drape.run(doc, out=out)
    assert done.summary["status"] == "completed" and not (out / "checkpoint.bin").exists()
    summary = (out / "summary.json").read_bytes()
    with pytest.raises(drape.RunError, match=r"nothing to resume: the run completed .*\(resume=False\)"):
        drape.run(doc, out=out, resume=True)
    assert (out / "summary.json").read_bytes() == summary


def test_a_second_run_on_one_directory_in_this_process_is_told_so(tmp_path):
    # Two drape.run on one out from two threads: the second is refused,
    # told the holder is another run in this process (it was told "another
    # drape process (process N)" with its own pid).
    out = tmp_path / "run"
    doc = short_pedestal()
    doc["time"]["segments"] = [{"steps": 10, "dt": 0.01}, {"steps": 3000, "dt": 1.0e-4}]
    first = {}
    thread = threading.Thread(target=lambda: first.setdefault("result", drape.run(doc, out=out)))
    thread.start()
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (out / "history.csv").is_file():
            time.sleep(0.005)
        with pytest.raises(drape.OutputError) as refused:
            drape.run(short_pedestal(), out=out)
    finally:
        thread.join(timeout=120)
    message = str(refused.value)
    assert f"another run in this process (process {os.getpid()})" in message, message
    assert "another drape process" not in message
    assert first["result"].summary["status"] == "completed"
