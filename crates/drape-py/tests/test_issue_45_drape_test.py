"""Issue 45: ``drape.test`` and ``python -m drape test`` (README, "The
drape test"), on a small drape tester (the example's on 5 rings, 30
steps of 2 ms: a fraction of a second a specimen).

The same test on the local pool, a local Ray cluster and a local Dask
cluster gives the same specimens, drape coefficients and folds as the
command line's ``drape test`` (the same seed); an engine whose package
cannot be imported is skipped, saying so, as in test_engines.py.
"""

from __future__ import annotations

import json
import subprocess

import pytest

from conftest import EXAMPLES, drape, run_module
from test_engines import engine_available

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib


def small_tester(folder, test_table=None):
    """The drape tester on 5 rings, 30 fixed steps of 2 ms, with a [test]
    table."""
    doc = tomllib.loads((EXAMPLES / "drape-tester.toml").read_text())
    doc["mesh"]["rings"] = 5
    doc["time"] = {"beta": 1.0, "gamma": 1.5, "segments": [{"steps": 30, "dt": 2.0e-3}]}
    doc["test"] = test_table or {"waviness": 1.0e-3, "cut_angle": 5.0}
    path = folder / "tester.toml"
    path.write_text(drape._drape._scenario_text(doc, str(folder), str(path)))
    return path


def results(report):
    return [(s["specimen"], s["status"], s["drape_coefficient"], s["folds"]) for s in report["specimens"]]


@pytest.fixture(scope="module")
def command_line_test(tmp_path_factory, cli):
    folder = tmp_path_factory.mktemp("cli")
    scenario = small_tester(folder)
    out = folder / "out"
    subprocess.run(
        [str(cli), "test", str(scenario), "--specimens", "3", "--jobs", "2", "--seed", "5", "--out", str(out), "-q"],
        check=True,
        capture_output=True,
    )
    return json.loads((out / "test.json").read_text())


def test_local_gives_the_command_lines_results(command_line_test, tmp_path):
    scenario = small_tester(tmp_path)
    report = drape.test(scenario, 3, out=tmp_path / "out", jobs=2, seed=5, progress=False)
    assert results(report) == results(command_line_test)
    for key in ("mean", "sd", "ci95", "fold_histogram", "modal_folds", "dc_at_modal_folds"):
        assert report[key] == command_line_test[key], key
    without_wall_time = lambda r: [{k: v for k, v in s.items() if k != "wall_seconds"} for s in r["specimens"]]
    assert without_wall_time(report) == without_wall_time(command_line_test)
    assert (tmp_path / "out" / "test.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Run again: nothing left to do, the same report.
    again = drape.test(scenario, 3, out=tmp_path / "out", jobs=2, seed=5, progress=False)
    assert results(again) == results(report)


@pytest.mark.parametrize("engine, module", [("dask", "dask.distributed"), ("ray", "ray")])
def test_an_engine_gives_the_local_results(engine, module, command_line_test, tmp_path):
    engine_available(engine, module)
    scenario = small_tester(tmp_path)
    out = tmp_path / "out"
    done = run_module(
        "test", str(scenario), "--specimens", "3", "--jobs", "2", "--seed", "5", "--engine", engine, "--out", str(out),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "3 of 3 specimens measured" in done.stdout
    assert results(json.loads((out / "test.json").read_text())) == results(command_line_test)


def test_bad_input_names_key_and_line(tmp_path):
    scenario = small_tester(tmp_path, {"waviness": -1.0})
    with pytest.raises(drape.ScenarioError) as e:
        drape.test(scenario, 2, out=tmp_path / "out", progress=False)
    assert e.value.key == "test.waviness" and e.value.line is not None
    assert "-1" in str(e.value)
    assert not (tmp_path / "out" / "specimens" / "0000").exists()
    with pytest.raises(ValueError):
        drape.test(scenario, 0, out=tmp_path / "out")
    done = run_module("test", str(scenario), "--specimens", "2", cwd=tmp_path)
    assert done.returncode == 2 and "test.waviness" in done.stderr
