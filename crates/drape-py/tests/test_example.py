"""examples/python/sweep_bending.py runs (in its --quick form: two
rigidities on a 6-ring mesh) and draws its plot."""

from __future__ import annotations

import re
import subprocess
import sys

from conftest import REPO

EXAMPLE = REPO / "examples" / "python" / "sweep_bending.py"


def test_the_bending_sweep_example_runs_and_plots(tmp_path):
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, str(EXAMPLE), "--out", str(out), "--quick", "--workers", "2"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    png = out / "drape-coefficient.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    coefficients = [float(c) for c in re.findall(r"drape coefficient ([0-9.]+)", done.stdout)]
    heights = [float(z) for z in re.findall(r"rim at z = (-?[0-9.]+) cm", done.stdout)]
    assert len(coefficients) == len(heights) == 2, done.stdout
    # A stiffer fabric hangs less: a larger shadow, a higher rim; and the
    # rim hangs below the pedestal's top (the gripped disc's plane, z = 0).
    assert 0 < coefficients[0] < coefficients[1] <= 1
    assert heights[0] < heights[1] < -0.5
