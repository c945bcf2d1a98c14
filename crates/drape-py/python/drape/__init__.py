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

or ``python -m drape sweep sweep.toml --out out/sweep``. The README's
"Python" section describes both in full.
"""

from ._drape import RunResult, __version__, check, run
from ._errors import DrapeError, OutputError, RunError, ScenarioError, SweepError
from ._sweep import sweep

__all__ = [
    "run",
    "check",
    "sweep",
    "RunResult",
    "DrapeError",
    "ScenarioError",
    "RunError",
    "OutputError",
    "SweepError",
    "__version__",
]
