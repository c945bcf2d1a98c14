"""Sweep files that cannot run are refused with a clear message before any
case runs (nothing is written), by drape.sweep and by python -m drape."""

from __future__ import annotations

import pytest

from conftest import drape, run_module, short_pedestal, write_scenario

BAD = {
    "a key the scenario does not have": (
        '[parameters]\n"material.youngs_modulu" = [1.0e6, 2.0e6]\n',
        "case 0000: `material`: unknown field `youngs_modulu`",
    ),
    "a table the scenario does not have": (
        '[parameters]\n"materials.density" = [300.0]\n',
        "unknown field `materials`",
    ),
    "an entry the base does not have": (
        '[parameters]\n"obstacle[1].max" = [[0.05, 0.05, -0.05]]\n',
        "parameter `obstacle[1].max`: the base scenario's `obstacle` has 1 entry (obstacle[0] to obstacle[0]), not [1]",
    ),
    "an index into a table": (
        '[parameters]\n"material[0].density" = [300.0]\n',
        "parameter `material[0].density`: `material` is not a list in the base scenario",
    ),
    "a key under a value": (
        '[parameters]\n"material.density.x" = [300.0]\n',
        "parameter `material.density.x`: `material.density` is a value in the base scenario, not a table",
    ),
    "another shape's key": (
        '[parameters]\n"obstacle[0].radius" = [0.05]\n',
        '`obstacle[0]` (shape = "box"): unknown field `radius`',
    ),
    "a value of the wrong type": (
        '[parameters]\n"material.density" = [300.0, "heavy"]\n',
        "case 0001: `material.density`: invalid type: string \"heavy\", expected f64",
    ),
    "a key given twice": (
        '[parameters]\n"material.density" = [300.0, 320.0]\n[parameters.material]\ndensity = [340.0]\n',
        "parameter `material.density` is given twice",
    ),
    "zip lists of unequal length": (
        'mode = "zip"\n[parameters]\n"material.density" = [300.0, 320.0, 340.0]\n"contact.penalty" = [1.0e4, 2.0e4]\n',
        'mode = "zip" takes lists of one length: `material.density` has 3, `contact.penalty` has 2',
    ),
    "a value that is not a list": (
        '[parameters]\n"material.density" = 300.0\n',
        "parameter `material.density`: expected a non-empty list of values, got 300.0",
    ),
    "an empty list": ('[parameters]\n"material.density" = []\n', "expected a non-empty list of values, got []"),
    "no parameters": ("", "the [parameters] table is missing or empty"),
    "an unknown mode": ('mode = "product"\n[parameters]\n"material.density" = [1.0]\n', "mode = 'product': expected \"grid\""),
    "an unknown key": ('modes = "zip"\n[parameters]\n"material.density" = [1.0]\n', "unknown key `modes`"),
    "a malformed key": ('[parameters]\n"obstacle[x].max" = [1.0]\n', "`obstacle[x]` is not a key part"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_a_bad_sweep_is_refused_before_any_case_runs(name, tmp_path):
    text, message = BAD[name]
    write_scenario(short_pedestal(), tmp_path / "base.toml")
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('base = "base.toml"\n' + text)
    with pytest.raises(drape.SweepError) as caught:
        drape.sweep(sweep, out=tmp_path / "out")
    assert message in str(caught.value)
    assert str(caught.value).startswith(f"{sweep}: ")
    assert not (tmp_path / "out").exists()


def test_a_missing_base_is_refused(tmp_path):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('base = "nowhere.toml"\n[parameters]\n"material.density" = [300.0]\n')
    done = run_module("sweep", str(sweep), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip() == (
        f"error: {sweep}: base = 'nowhere.toml': there is no such file ({tmp_path / 'nowhere.toml'})"
    )
    assert not (tmp_path / "out").exists()

    sweep.write_text('[parameters]\n"material.density" = [300.0]\n')
    with pytest.raises(drape.SweepError, match="`base` is missing"):
        drape.sweep(sweep, out=tmp_path / "out")
    sweep.write_text('base = "nowhere.toml"\n[parameters\n')
    with pytest.raises(drape.SweepError, match="the sweep file is not a valid TOML file"):
        drape.sweep(sweep, out=tmp_path / "out")
    with pytest.raises(drape.SweepError, match="the sweep file cannot be read: No such file"):
        drape.sweep(tmp_path / "absent.toml", out=tmp_path / "out")
    sweep.write_text('base = "base.toml"\n[parameters]\n"material.density" = [300.0]\n')
    (tmp_path / "base.toml").write_text("[mesh\n")
    with pytest.raises(drape.SweepError, match=r"base = 'base.toml': .*base.toml is not a valid TOML file"):
        drape.sweep(sweep, out=tmp_path / "out")


def test_bad_options_are_refused(tmp_path):
    write_scenario(short_pedestal(), tmp_path / "base.toml")
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('base = "base.toml"\n[parameters]\n"material.density" = [300.0]\n')
    with pytest.raises(ValueError, match="engine='spark'"):
        drape.sweep(sweep, engine="spark")
    with pytest.raises(ValueError, match="workers=0"):
        drape.sweep(sweep, workers=0)
    done = run_module("sweep", str(sweep), "--address", "127.0.0.1:1", cwd=tmp_path)
    assert done.returncode == 2 and "--address names a Ray or Dask cluster" in done.stderr
    assert not (tmp_path / "out").exists()
