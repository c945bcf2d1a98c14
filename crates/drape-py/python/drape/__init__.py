"""drape: membranes and fabrics in large displacement and contact, from
Python.

Run a scenario (a TOML file, or a dict with the same structure) and read
its outputs as NumPy arrays::

    import drape
    res = drape.run("fabric-on-pedestal.toml", out="out/x")
    res.summary                  # dict, as summary.json
    res.history                  # dict: column name -> numpy array, as history.csv
    res.positions(step=-1)       # numpy array (nodes, 3) of a written frame
    drape.check("scenario.toml") # raises drape.ScenarioError with the file, key and line

Sweep one scenario over a grid of parameter values, on this machine or on
a Ray or Dask cluster::

    rows = drape.sweep("sweep.toml", out="out/sweep", workers=4, engine="local")

or ``python -m drape sweep sweep.toml --out out/sweep``. Test a fabric
as a laboratory does, on several specimens that differ by a seeded
perturbation::

    report = drape.test("drape-tester.toml", specimens=6, jobs=2)
    report["mean"], report["ci95"], report["modal_folds"]

or ``python -m drape test drape-tester.toml --specimens 6``. The README's
"Python" section describes them in full.
"""

from __future__ import annotations

from ._drape import RunResult, __version__, check, run
from ._errors import DrapeError, OutputError, RunError, ScenarioError, SweepError

# Not `typing.TYPE_CHECKING`: importing typing costs more than the rest of
# `import drape` (docs/performance.md, "Python"); type checkers read this
# name the same way.
TYPE_CHECKING = False

if TYPE_CHECKING:
    import os
    from typing import Any, Dict, List, Optional, Union


def sweep(
    path: Union[str, "os.PathLike[str]"],
    out: Union[str, "os.PathLike[str]", None] = None,
    workers: Optional[int] = None,
    engine: str = "local",
    address: Optional[str] = None,
    *,
    progress: Optional[bool] = None,
) -> List[Dict[str, Any]]:
    """Runs one scenario over a grid of parameter values.

    Args:
        path: the sweep file: ``base`` (the scenario, relative to it),
            ``mode`` (``"grid"`` or ``"zip"``) and ``[parameters]`` (dotted
            keys -> lists of values), as the README's "Python" section
            describes.
        out: the sweep's directory [default: ``out/<sweep stem>``]: it gets
            ``cases/NNNN/`` (each case's ``scenario.toml`` and outputs) and
            ``results.csv``.
        workers: cases at once (``local``), or the CPUs of the local Ray or
            Dask cluster started when no ``address`` is given [default:
            the CPUs of this machine].
        engine: ``"local"`` (processes on this machine), ``"ray"`` or
            ``"dask"`` (their optional extras: ``pip install "drape[ray]"``).
        address: the Ray or Dask cluster to use; it must see ``out`` at the
            same path and have drape installed.
        progress: draw a progress bar on stderr; default: when stderr is a
            terminal.

    Returns:
        The rows of ``results.csv``, one dict per case in case order:
        ``case``, ``status`` (``completed``, ``failed``, ``interrupted`` or
        ``pending``), one entry per parameter, ``steps``, ``time``,
        ``newton_iterations``, ``wall_seconds``, ``first_contact_time``,
        ``<monitor>_x``/``_y``/``_z`` (final positions) and ``message``.

    Raises:
        SweepError: the sweep file cannot be run, or ``out`` cannot be
            used: a file where it or ``out/cases`` should be, or a
            ``results.csv`` there that is not a sweep's (nothing ran, nothing
            was written).
        ImportError: the engine's package is not installed (nothing ran).
        KeyboardInterrupt: Ctrl-C, after ``results.csv`` was written with
            what was done; calling it again finishes the sweep.

    Cases completed by an earlier call with the same scenario text are not
    run again; a failed case runs again; an interrupted one resumes from
    its checkpoint.
    """
    # The sweeps' modules load when a sweep runs: `import drape` for a run
    # stays light.
    from ._sweep import sweep as run_sweep

    return run_sweep(path, out=out, workers=workers, engine=engine, address=address, progress=progress)


def test(
    scenario: Union[str, "os.PathLike[str]"],
    specimens: int,
    out: Union[str, "os.PathLike[str]", None] = None,
    jobs: Optional[int] = None,
    engine: str = "local",
    address: Optional[str] = None,
    seed: int = 0,
    *,
    progress: Optional[bool] = None,
) -> Dict[str, Any]:
    """A drape test: ``specimens`` specimens of one scenario, differing by
    a seeded perturbation (the scenario's ``[test]`` table: waviness, the
    cut's angle to the warp, face up or down), run side by side, each on
    one thread; as ``drape test`` on the command line (README, "The drape
    test").

    Args:
        scenario: the scenario file (a drape tester: a disc on a
            cylinder).
        specimens: how many (>= 1).
        out: the test's directory [default: ``out/<stem>-test``]: it gets
            ``specimens/NNNN/`` (each an ordinary run directory),
            ``test.json`` and ``test.png``.
        jobs: specimens at once (``local``), or the CPUs of the local Ray
            or Dask cluster started when no ``address`` is given [default:
            the CPUs of this machine].
        engine: ``"local"``, ``"ray"`` or ``"dask"``, as for :func:`sweep`.
        address: the Ray or Dask cluster to use.
        seed: the test's seed; the same seed gives the same specimens.
        progress: draw a progress bar on stderr; default: when stderr is a
            terminal.

    Returns:
        ``test.json`` as a dict: ``specimens`` (each ``specimen``,
        ``status``, ``drape_coefficient``, ``folds``, ``crossings``,
        ``wall_seconds``, ``message`` and its perturbation), ``mean``,
        ``sd``, ``ci95``, ``fold_histogram``, ``modal_folds``,
        ``dc_at_modal_folds``, ``measured`` of ``count``.

    Raises:
        ScenarioError: the scenario or its ``[test]`` table (nothing ran).
        OutputError: ``out`` cannot be used (nothing ran).
        ImportError: the engine's package is not installed (nothing ran).
        KeyboardInterrupt: Ctrl-C, after ``test.json`` was written with
            what was done; calling it again finishes the test.

    Specimens completed by an earlier call (same scenario, seed) are not
    run again; a failed one runs again; an interrupted one resumes, as does
    one killed with a checkpoint left and no summary written (a multilevel
    specimen killed on a finer level resumes at that level's start).
    """
    from ._specimens import test as run_test

    options = {"out": out, "jobs": jobs, "engine": engine, "address": address, "seed": seed, "progress": progress}
    return run_test(scenario, specimens, options)


__all__ = [
    "run",
    "check",
    "sweep",
    "test",
    "RunResult",
    "DrapeError",
    "ScenarioError",
    "RunError",
    "OutputError",
    "SweepError",
    "__version__",
]
