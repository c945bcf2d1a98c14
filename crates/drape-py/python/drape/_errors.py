"""drape's exceptions.

The native module raises them too (``drape._drape`` builds them from the
library's errors), so their constructors take keywords only beside the
message, and they pickle with their attributes (a sweep's workers may send
them across processes).
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's: see __init__.py

if TYPE_CHECKING:  # `import drape` stays light: these are for the annotations
    from pathlib import Path
    from typing import Any, Optional


class DrapeError(Exception):
    """Base class of the errors drape raises."""

    def __reduce__(self) -> Any:
        return (_rebuild, (type(self), self.args, self.__dict__))


def _rebuild(cls: type, args: tuple, state: dict) -> DrapeError:
    error = cls.__new__(cls)
    Exception.__init__(error, *args)
    error.__dict__.update(state)
    return error


class ScenarioError(DrapeError, ValueError):
    """A scenario that cannot be used: a TOML syntax error, an unknown key,
    a wrong type, a value out of range, a mesh that cannot be read.

    ``str(error)`` is the message the command line prints, e.g.
    ``scenario.toml, line 14: `material.poisson_ratio` must be in [0, 0.5),
    got 0.7``.

    Attributes:
        message: the whole message.
        file: the scenario file (``"<dict>"`` for a dict), or None.
        key: the dotted key, e.g. ``material.poisson_ratio`` or
            ``load[1].value``, when the error is about one.
        line: the 1-based line in ``file``, when known (never for a dict).
    """

    def __init__(
        self,
        message: str,
        *,
        file: Optional[str] = None,
        key: Optional[str] = None,
        line: Optional[int] = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.key = key
        self.line = line


class RunError(DrapeError, RuntimeError):
    """A run that stopped on a failure (a step that did not converge even
    cut back, a material instability, an output that could not be written).

    Everything computed up to the failure is on disk.

    Attributes:
        message: what happened.
        out: the output directory.
        result: a ``RunResult`` of what the run wrote (its summary says
            ``"failed"``; None where the summary itself could not be
            written), or None when it wrote nothing.
    """

    def __init__(self, message: str, *, out: Optional[Path] = None, result: Any = None) -> None:
        super().__init__(message)
        self.message = message
        self.out = out
        self.result = result


class OutputError(DrapeError):
    """An output directory that cannot be used (another process writes
    into it; it holds files drape did not write) or read.

    Attributes:
        message: what is wrong.
        path: the directory.
    """

    def __init__(self, message: str, *, path: Optional[Path] = None) -> None:
        super().__init__(message)
        self.message = message
        self.path = path


class SweepError(DrapeError, ValueError):
    """A sweep file that cannot be run, found before any case runs: a
    missing or unreadable base scenario, a dotted key the scenario does not
    have, lists of unequal length in ``zip`` mode, values of a type the key
    does not take; or a sweep directory that cannot be used (a file where
    it or its ``cases`` should be, a ``results.csv`` that is not a sweep's).

    Attributes:
        message: what is wrong, naming the sweep file and the parameter.
    """

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message
