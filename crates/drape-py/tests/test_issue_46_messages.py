"""Issue 46's small messages, from Python: a completed run without a
checkpoint has nothing to resume; a second run on one directory in this
process is told so."""

from __future__ import annotations

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
