"""The drape test: several specimens of one scenario, differing by a
seeded perturbation, run side by side (README, "The drape test").

The specimens and the report are the native module's
(``_drape._specimens``, ``_drape._test_report``: the same code as the
command line's ``drape test``, so either front end can run or complete a
test); the specimens run as a sweep's cases do, on one of the sweep
engines (:mod:`drape._engines`), each on one thread.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

from . import _drape, _progress
from ._sweep import ENGINES


def test(scenario: Union[str, os.PathLike], specimens: int, options: Dict[str, Any]) -> Dict[str, Any]:
    """:func:`drape.test` (its docstring says what it does); ``options``
    its keyword arguments."""
    out, jobs, engine, address, seed, progress = (
        options[k] for k in ("out", "jobs", "engine", "address", "seed", "progress")
    )
    if engine not in ENGINES:
        raise ValueError(f"engine={engine!r}: expected one of {', '.join(ENGINES)}")
    if not isinstance(specimens, int) or isinstance(specimens, bool) or specimens < 1:
        raise ValueError(f"specimens={specimens!r}: expected a whole number >= 1")
    if jobs is not None and (not isinstance(jobs, int) or isinstance(jobs, bool) or jobs < 1):
        raise ValueError(f"jobs={jobs!r}: expected a whole number >= 1")
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**64:
        raise ValueError(f"seed={seed!r}: expected a whole number in [0, 2^64)")
    if address is not None and engine == "local":
        raise ValueError("address= names a Ray or Dask cluster: use it with engine='ray' or engine='dask'")
    from . import _engines

    start_engine = _engines.get(engine)  # ImportError with the install hint, before anything runs
    path = Path(scenario)
    out = Path(out) if out is not None else Path("out") / f"{path.stem}-test"
    out = out.absolute()
    plans: List[Dict[str, Any]] = _drape._specimens(str(path), specimens, seed, str(out))
    outcomes: Dict[int, Dict[str, Any]] = {
        p["index"]: {"index": p["index"], "status": "completed", "message": ""} for p in plans if p["done"]
    }
    tasks = [
        {"index": p["index"], "dir": str(out / "specimens" / p["name"]), "text": p["text"], "threads": 1}
        for p in plans
        if not p["done"]
    ]
    workers = jobs or os.cpu_count() or 1
    bar = _progress.Bar(len(plans), done=len(outcomes), enabled=progress)
    try:
        if tasks:
            for outcome in start_engine(tasks, workers, address):
                outcomes[outcome["index"]] = {
                    "index": outcome["index"],
                    "status": outcome["status"],
                    "message": outcome.get("message") or "",
                }
                bar.update(failed=outcome["status"] != "completed")
    finally:
        bar.close()
        # Written on Ctrl-C too, with what was done; a specimen not
        # started is "interrupted".
        text = _drape._test_report(str(path), specimens, seed, str(out), list(outcomes.values()))
    return json.loads(text)


__all__ = ["test"]
