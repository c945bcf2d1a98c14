"""Type hints of drape's native module (``crates/drape-py/src``)."""

import os
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

Scenario = Union[str, "os.PathLike[str]", Mapping[str, Any]]

class RunResult:
    """The outputs of a run: ``summary``, ``history`` and ``positions(step)``.

    ``drape.run`` returns one; ``RunResult(out)`` opens the output directory
    of an earlier run (of ``drape run`` too), or of a sweep's case.
    """

    def __init__(self, out: Union[str, "os.PathLike[str]"]) -> None: ...
    @property
    def out(self) -> Path:
        """The output directory, absolute (against the working directory
        when the run started or the result was opened)."""
    @property
    def summary(self) -> Optional[Dict[str, Any]]:
        """``summary.json`` as a dict (``status``, ``message``, ``steps``,
        ``time``, ``first_contact_time``, ``newton_iterations``,
        ``wall_seconds``, ``nodes``, ``elements``, ``dofs``, ``monitors``
        and more); None without ``summary.json`` (a run in progress, or
        killed before it wrote it), as the file was when the result was
        made."""
    @property
    def history(self) -> Dict[str, npt.NDArray[np.float64]]:
        """``history.csv``: column name -> 1-D float64 array, one entry per
        converged step, step 0 first. Read on first use."""
    @property
    def frames(self) -> List[int]:
        """The steps whose frames were written, in order."""
    def positions(self, step: int = -1) -> npt.NDArray[np.float64]:
        """The (nodes, 3) node positions (m) of the frame of ``step`` (one
        of ``frames``; -1: the last). ValueError for a step without a
        frame."""

def run(
    scenario: Scenario,
    out: Union[str, "os.PathLike[str]", None] = None,
    *,
    resume: bool = False,
) -> RunResult:
    """Runs a scenario (a TOML file, or a dict with its structure) into
    ``out`` [default: ``out/<scenario stem>``; required for a dict], as
    ``drape run`` does, with the GIL released.

    ``resume=True`` continues the interrupted run in ``out`` from its
    checkpoint; a refused resume is recorded in ``out/summary.json`` as
    ``drape run --resume`` records it. Raises ScenarioError (invalid
    scenario), RunError (the run failed, or a resume was refused: "cannot
    resume: ..."; ``.result`` holds its outputs), OutputError (``out``
    unusable; with ``resume``, not a run's directory), KeyboardInterrupt
    (Ctrl-C, after a checkpoint and the summary).
    """

def check(scenario: Scenario) -> Dict[str, Any]:
    """Validates a scenario and builds its model without running it, as
    ``drape check`` does; returns ``title``, ``nodes``, ``elements``,
    ``pieces`` (the mesh's disconnected pieces), ``order``, ``dofs``,
    ``fixed_dofs``, ``mass`` and ``monitors`` (name -> node index). Raises ScenarioError with its file, key and line."""

def _scenario_text(scenario: Mapping[str, Any], folder: str, name: str) -> str: ...
def _specimens(scenario: str, count: int, seed: int, out: str) -> List[Dict[str, Any]]: ...
def _test_report(scenario: str, count: int, seed: int, out: str, outcomes: List[Dict[str, Any]]) -> str: ...
