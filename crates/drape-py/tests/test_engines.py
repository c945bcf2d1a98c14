"""The same sweep on the local pool, a local Dask cluster and a local Ray
cluster gives the same results.csv, wall times aside.

An engine whose package cannot be imported is skipped, saying so; where
CI installed it (DRAPE_REQUIRE_RAY=1, DRAPE_REQUIRE_DASK=1) its absence
fails instead.
"""

from __future__ import annotations

import csv
import importlib
import os

import pytest

from conftest import drape, run_module
from test_sweep import make_sweep


def rows_without_wall_times(path):
    """The rows without the columns that describe the machine rather than
    the case: the wall time, and the threads (a local case has the CPUs
    shared among the workers, a cluster's task one)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    drop = {rows[0].index(column) for column in ("wall_seconds", "threads")}
    return [[v for i, v in enumerate(row) if i not in drop] for row in rows]


@pytest.fixture(scope="module")
def local_results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("local")
    sweep = make_sweep(folder)
    drape.sweep(sweep, out=folder / "out", workers=2, progress=False)
    return folder / "out" / "results.csv"


def engine_available(name: str, module: str) -> None:
    try:
        importlib.import_module(module)
    except ImportError as e:
        if os.environ.get(f"DRAPE_REQUIRE_{name.upper()}") == "1":
            pytest.fail(f"{module} was installed for these tests (DRAPE_REQUIRE_{name.upper()}=1) but cannot be imported: {e}")
        pytest.skip(f"engine {name!r} not tested: {module} cannot be imported here ({e}); pip install \"./crates/drape-py[{name}]\"")


@pytest.mark.parametrize("engine, module", [("dask", "dask.distributed"), ("ray", "ray")])
def test_an_engine_gives_the_local_results(engine, module, local_results, tmp_path):
    engine_available(engine, module)
    sweep = make_sweep(tmp_path)
    out = tmp_path / "out"
    done = run_module("sweep", str(sweep), "--out", str(out), "--engine", engine, "--workers", "2", cwd=tmp_path)
    assert done.returncode == 1, done.stderr[-3000:]
    assert "6 cases: 4 completed, 2 failed" in done.stdout
    expected = rows_without_wall_times(local_results)
    assert rows_without_wall_times(out / "results.csv") == expected
    assert [r[1] for r in expected[1:]] == ["completed"] * 4 + ["failed"] * 2


def test_a_missing_engine_is_named_before_anything_runs(tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def without_ray(name, *args, **kwargs):
        if name == "ray" or name.startswith("ray."):
            raise ImportError("No module named 'ray'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without_ray)
    sweep = make_sweep(tmp_path)
    with pytest.raises(ImportError, match=r"pip install \"drape\[ray\]\""):
        drape.sweep(sweep, out=tmp_path / "out", engine="ray")
    assert not (tmp_path / "out").exists()
