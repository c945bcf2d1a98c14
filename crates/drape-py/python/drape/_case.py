"""One case of a sweep, where an engine runs it (a local worker process, a
Ray task, a Dask task), and what the driver reads of a case's directory.

Ctrl-C in a local worker: the pool's processes ignore SIGINT
(:func:`init_local_worker`) except while a case runs, when Python's own
handler is back and ``drape.run`` stops the run after its step with a
checkpoint; a case that has not started when the sweep was interrupted
does not start (:data:`_stop`, set by the driver).
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import signal
import threading
from pathlib import Path
from typing import Any, Dict, Iterator, Optional

from . import _drape
from ._errors import DrapeError, RunError, ScenarioError

#: The summary's entries a sweep keeps of a case.
KEPT = (
    "status",
    "message",
    "monitors",
    "steps",
    "time",
    "newton_iterations",
    "wall_seconds",
    "first_contact_time",
    "threads",
)

#: Set by a local sweep's driver when it is interrupted (an Event shared
#: with the pool's processes), None elsewhere.
_stop: Any = None


def init_local_worker(stop: Any) -> None:
    """Initialiser of a local pool's processes: the driver's stop event, and
    SIGINT ignored between cases."""
    global _stop
    _stop = stop
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _interruptible() -> Iterator[None]:
    """Python's SIGINT handler while a case runs in a local worker, so that
    Ctrl-C ends the run as it ends ``drape run``."""
    if _stop is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def summary_of(case_dir: Path) -> Optional[Dict[str, Any]]:
    """``summary.json`` of a case's directory, or None."""
    try:
        value = json.loads((case_dir / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return value if isinstance(value, dict) else None


def same_scenario(case_dir: Path, text: str) -> bool:
    """Whether the case's ``scenario.toml`` holds ``text``."""
    try:
        return (case_dir / "scenario.toml").read_text(encoding="utf-8") == text
    except (OSError, UnicodeDecodeError):
        return False


def brief(summary: Optional[Dict[str, Any]]) -> Optional[Dict[str, Any]]:
    """The entries of a summary the sweep keeps."""
    return None if summary is None else {k: summary.get(k) for k in KEPT}


def lock_case(case_dir: Path) -> Optional[int]:
    """Takes the case's lock, ``cases/NNNN.lock`` beside its directory
    (inside it, drape would refuse it as a file of someone else's), before
    anything in the directory is touched: the open file descriptor, held
    until it is closed (or the process dies), or None when another process
    holds it — a second sweep into the same directory, whose cases would
    otherwise overwrite each other's ``scenario.toml`` (issue 34)."""
    case_dir.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(case_dir.parent / f"{case_dir.name}.lock", os.O_CREAT | os.O_RDWR, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    return fd


def run_case(task: Dict[str, Any]) -> Dict[str, Any]:
    """Runs one case; returns its outcome: ``index``, ``status``
    (``completed``, ``failed``, ``interrupted``), ``message``, ``summary``.

    Writes ``scenario.toml`` into the case's directory and runs it there;
    an interrupted run of the same text (with its checkpoint) is resumed.
    Every failure of the case is an outcome, not an exception: the sweep
    goes on.
    """
    threads = task.get("threads")
    if threads:
        # Read by the library's thread pools when they start: at the first
        # run in this process.
        os.environ.setdefault("RAYON_NUM_THREADS", str(threads))
    index = task["index"]

    def outcome(status: str, message: str, summary: Optional[Dict[str, Any]]) -> Dict[str, Any]:
        return {"index": index, "status": status, "message": message, "summary": brief(summary)}

    if _stop is not None and _stop.is_set():
        return outcome("interrupted", "not started: the sweep was interrupted", None)
    case_dir = Path(task["dir"])
    lock = lock_case(case_dir)
    if lock is None:
        return outcome(
            "failed",
            f"{case_dir} is in use by another process (another sweep into the same directory?): "
            "the case was left to it; run this sweep again once it has finished",
            None,
        )
    try:
        return _run_locked(task, case_dir, outcome)
    finally:
        os.close(lock)


def _run_locked(task: Dict[str, Any], case_dir: Path, outcome: Any) -> Dict[str, Any]:
    """:func:`run_case` once the case's lock is held."""
    text = task["text"]
    case_dir.mkdir(parents=True, exist_ok=True)
    # A sweep killed between writing the scenario's temporary copy and
    # renaming it leaves the copy behind, and drape refuses a directory
    # holding files it did not write: the case would fail on every re-run.
    # The lock is ours, so any such copy is a dead process's.
    for stale in case_dir.glob(".scenario.toml.tmp-*"):
        stale.unlink(missing_ok=True)
    scenario = case_dir / "scenario.toml"
    same = same_scenario(case_dir, text)
    previous = summary_of(case_dir)
    resume = (
        same
        and previous is not None
        and previous.get("status") == "interrupted"
        and (case_dir / "checkpoint.bin").is_file()
    )
    if not same:
        temporary = case_dir / f".scenario.toml.tmp-{os.getpid()}"
        temporary.write_text(text, encoding="utf-8")
        os.replace(temporary, scenario)
    with _interruptible():
        try:
            try:
                result = _drape.run(str(scenario), out=str(case_dir), resume=resume)
            except RunError as e:
                if not (resume and str(e).startswith("cannot resume")):
                    raise
                # A checkpoint that cannot be resumed: the case starts afresh.
                result = _drape.run(str(scenario), out=str(case_dir))
        except ScenarioError as e:
            return outcome("failed", str(e), None)
        except RunError as e:
            summary = e.result.summary if e.result is not None else None
            return outcome("failed", str(e), dict(summary) if summary is not None else None)
        except DrapeError as e:
            return outcome("failed", str(e), None)
        except KeyboardInterrupt as e:
            return outcome("interrupted", str(e), summary_of(case_dir))
    summary = dict(result.summary)
    return outcome("completed", str(summary.get("message", "")), summary)
