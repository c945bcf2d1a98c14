"""Parameter sweeps: one scenario run over a grid of parameter values
(README, "Sweeps").

A sweep file names a base scenario, a mode and the values of dotted keys::

    base = "fabric-on-pedestal.toml"      # relative to this file
    mode = "grid"                         # "grid" | "zip"
    [parameters]
    "material.youngs_modulus" = [1.0e6, 2.0e6]
    "obstacle[0].max" = [[0.05, 0.05, -0.05], [0.06, 0.06, -0.05]]

Everything is checked before any case runs (:func:`load_plan`): the base
exists and is TOML, every key reaches into the base scenario (a table may be
added, an indexed entry must exist), the lists have one length in ``zip``
mode, and every case's scenario passes drape's parser (known keys, types,
choices). A value out of range is left to its case, which then fails with
the validation message as the command line prints it, while the others go
on.

Each case runs in ``DIR/cases/NNNN/`` (its ``scenario.toml`` and the run's
outputs); ``DIR/results.csv`` has a row per case. A ``results.csv`` already
in ``DIR`` that a sweep did not write is refused, as a run refuses files it
did not write (:func:`_take_directory`). A case whose directory
holds a completed run of the same scenario text is not run again, and an
interrupted one (Ctrl-C: a checkpoint) resumes, so running a sweep again
finishes what a killed or interrupted one left.
"""

from __future__ import annotations

import copy
import csv
import io
import itertools
import json
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib  # type: ignore[no-redef]

from . import _drape, _progress
from ._case import same_scenario, summary_of
from ._errors import ScenarioError, SweepError

#: The engines ``engine=`` takes.
ENGINES = ("local", "ray", "dask")

#: The summary's columns of ``results.csv``, after the parameters.
SUMMARY_COLUMNS = ("steps", "time", "newton_iterations", "wall_seconds", "first_contact_time")

#: A part of a dotted key: a name and its indices (``obstacle[0]``).
_PART = re.compile(r"^([A-Za-z0-9_-]+)((?:\[\d+\])*)$")


@dataclass(frozen=True)
class Case:
    """One case of a sweep: its number, its parameter values (in the sweep
    file's order) and its scenario's TOML text."""

    index: int
    values: Tuple[Any, ...]
    text: str

    @property
    def name(self) -> str:
        """The directory name under ``DIR/cases``: ``0000``, ``0001``, ..."""
        return f"{self.index:04d}"


@dataclass(frozen=True)
class Plan:
    """A sweep file, read and checked: the cases to run."""

    path: Path
    base: Path
    mode: str
    keys: Tuple[str, ...]
    cases: Tuple[Case, ...]
    monitors: Tuple[str, ...] = field(default=())


def load_plan(path: Union[str, os.PathLike]) -> Plan:
    """Reads and checks a sweep file and makes every case's scenario.

    Raises:
        SweepError: whatever would stop the sweep, before anything runs.
    """
    path = Path(path)
    doc = _read_toml(path, f"{path}: the sweep file")
    unknown = sorted(set(doc) - {"base", "mode", "parameters"})
    if unknown:
        names = ", ".join(f"`{k}`" for k in unknown)
        raise SweepError(
            f"{path}: unknown key {names}: a sweep file has `base`, `mode` and a [parameters] table"
        )

    base_name = doc.get("base")
    if base_name is None:
        raise SweepError(
            f'{path}: `base` is missing: the scenario file to vary, relative to the sweep file (base = "scenario.toml")'
        )
    if not isinstance(base_name, str) or not base_name:
        raise SweepError(f"{path}: `base` must be the path of a scenario file, got {base_name!r}")
    base = (path.parent / base_name).absolute()
    if not base.is_file():
        raise SweepError(f"{path}: base = {base_name!r}: there is no such file ({base})")
    base_doc = _read_toml(base, f"{path}: base = {base_name!r}: {base}")

    mode = doc.get("mode", "grid")
    if mode not in ("grid", "zip"):
        raise SweepError(
            f'{path}: mode = {mode!r}: expected "grid" (every combination of the values) '
            f'or "zip" (the first values together, then the second, ...)'
        )

    table = doc.get("parameters")
    if not isinstance(table, dict) or not table:
        raise SweepError(
            f'{path}: the [parameters] table is missing or empty: it lists the values of dotted keys, e.g. "material.youngs_modulus" = [1.0e6, 2.0e6]'
        )
    parameters = _flatten(table, path=path)
    keys = tuple(parameters)
    for key, values in parameters.items():
        if not isinstance(values, list) or not values:
            raise SweepError(
                f"{path}: parameter `{key}`: expected a non-empty list of values, got {values!r}"
            )
        _assign(copy.deepcopy(base_doc), key, values[0], path)

    lists = [parameters[k] for k in keys]
    if mode == "zip":
        lengths = {len(v) for v in lists}
        if len(lengths) > 1:
            sizes = ", ".join(f"`{k}` has {len(v)}" for k, v in zip(keys, lists))
            raise SweepError(f'{path}: mode = "zip" takes lists of one length: {sizes}')
        combinations = list(zip(*lists))
    else:
        combinations = list(itertools.product(*lists))

    cases = []
    for index, values in enumerate(combinations):
        scenario = copy.deepcopy(base_doc)
        for key, value in zip(keys, values):
            _assign(scenario, key, value, path)
        name = f"case {index:04d}"
        try:
            text = _drape._scenario_text(scenario, str(base.parent), name)
        except ScenarioError as e:
            sets = ", ".join(f"{k} = {_cell(v)}" for k, v in zip(keys, values))
            raise SweepError(f"{path}: {e} ({name} sets {sets}; its base is {base})") from None
        cases.append(Case(index, tuple(values), text))

    monitors = tuple(
        m["name"] for m in base_doc.get("monitor", []) if isinstance(m, dict) and isinstance(m.get("name"), str)
    )
    return Plan(path, base, mode, keys, tuple(cases), monitors)


def _read_toml(path: Path, what: str) -> Dict[str, Any]:
    """The TOML document at ``path``; SweepError naming ``what`` if it
    cannot be read or parsed."""
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise SweepError(f"{what} cannot be read: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise SweepError(f"{what} is not a valid TOML file: {e}") from None


def _flatten(table: Dict[str, Any], prefix: str = "", path: Path = Path("sweep")) -> Dict[str, Any]:
    """``{"material": {"density": [..]}}`` (unquoted dotted keys) and
    ``{"material.density": [..]}`` (quoted) alike become
    ``{"material.density": [..]}``; one key given both ways is refused,
    naming it (one of the two was silently dropped)."""
    out: Dict[str, Any] = {}
    for key, value in table.items():
        full = f"{prefix}.{key}" if prefix else key
        inner = _flatten(value, full, path) if isinstance(value, dict) else {full: value}
        for k, v in inner.items():
            if k in out:
                raise SweepError(
                    f"{path}: parameter `{k}` is given twice (as a quoted dotted key and inside a table): give it once"
                )
            out[k] = v
    return out


def _assign(doc: Dict[str, Any], key: str, value: Any, where: Path) -> None:
    """Sets ``key`` (``material.youngs_modulus``, ``obstacle[0].max``,
    ``time.segments[1].dt``) in the scenario ``doc`` to ``value``.

    A missing table is added (the parser then says whether the scenario has
    it); an indexed entry must exist in the base.
    """
    parts = key.split(".")
    node: Any = doc
    reached = ""
    for n, part in enumerate(parts):
        m = _PART.match(part)
        if not m:
            raise SweepError(
                f"{where}: parameter `{key}`: `{part}` is not a key part (a name of letters, digits, _ and -, with [N] to pick an entry)"
            )
        name, indices = m.group(1), [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
        last = n == len(parts) - 1
        if not isinstance(node, dict):
            raise SweepError(f"{where}: parameter `{key}`: `{reached}` is a value in the base scenario, not a table")
        reached = f"{reached}.{name}" if reached else name
        if not indices:
            if last:
                node[name] = value
                return
            node = node.setdefault(name, {})
            continue
        if name not in node:
            raise SweepError(f"{where}: parameter `{key}`: the base scenario has no `{reached}`")
        container: Any = node
        slot: Any = name
        for i in indices:
            item = container[slot]
            if not isinstance(item, list):
                raise SweepError(f"{where}: parameter `{key}`: `{reached}` is not a list in the base scenario")
            if i >= len(item):
                have = f"{len(item)} entr{'y' if len(item) == 1 else 'ies'}"
                span = f" ({reached}[0] to {reached}[{len(item) - 1}])" if item else ""
                raise SweepError(
                    f"{where}: parameter `{key}`: the base scenario's `{reached}` has {have}{span}, not [{i}]"
                )
            reached = f"{reached}[{i}]"
            container, slot = item, i
        if last:
            container[slot] = value
            return
        node = container[slot]


# -- running -----------------------------------------------------------------


def sweep(
    path: Union[str, os.PathLike],
    out: Union[str, os.PathLike, None] = None,
    workers: Optional[int] = None,
    engine: str = "local",
    address: Optional[str] = None,
    *,
    progress: Optional[bool] = None,
) -> List[Dict[str, Any]]:
    """:func:`drape.sweep` (its docstring says what it does)."""
    if engine not in ENGINES:
        raise ValueError(f"engine={engine!r}: expected one of {', '.join(ENGINES)}")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers={workers!r}: expected a whole number >= 1")
    plan = load_plan(path)
    from . import _engines

    start_engine = _engines.get(engine)  # ImportError with the install hint, before anything runs
    out = Path(out) if out is not None else Path("out") / Path(path).stem
    out = out.absolute()
    cpus = os.cpu_count() or 1
    workers = workers or cpus

    results = _take_directory(out)
    rows: Dict[int, Dict[str, Any]] = {}
    todo: List[Case] = []
    for case in plan.cases:
        summary = _completed(out / "cases" / case.name, case.text)
        if summary is not None:
            rows[case.index] = _row(plan, case, "completed", summary.get("message", ""), summary, out)
        else:
            todo.append(case)
    skipped = len(rows)

    # One thread a case when the cases fill the cores (results do not
    # depend on the threads: the library's sums are in a fixed order).
    threads = max(1, cpus // min(workers, max(1, len(todo)))) if engine == "local" else 1
    tasks = [
        {
            "index": case.index,
            "dir": str(out / "cases" / case.name),
            "text": case.text,
            "threads": threads,
        }
        for case in todo
    ]
    by_index = {case.index: case for case in plan.cases}
    bar = _progress.Bar(len(plan.cases), done=skipped, enabled=progress)
    last_write = time.monotonic()
    try:
        if tasks:
            for outcome in start_engine(tasks, workers, address):
                case = by_index[outcome["index"]]
                status = outcome["status"]
                message = _relative(outcome.get("message") or "", out)
                rows[case.index] = _row(plan, case, status, message, outcome.get("summary"), out)
                bar.update(failed=status != "completed")
                if time.monotonic() - last_write > 2.0:
                    _write_results(results, plan, rows)
                    last_write = time.monotonic()
    except KeyboardInterrupt:
        # The engine stopped the running cases; what they wrote says how
        # each ended (interrupted with a checkpoint, or done meanwhile).
        for case in todo:
            summary = summary_of(out / "cases" / case.name)
            if case.index not in rows and summary is not None and same_scenario(out / "cases" / case.name, case.text):
                rows[case.index] = _row(plan, case, str(summary.get("status")), str(summary.get("message", "")), summary, out)
        raise
    finally:
        bar.close()
        _write_results(results, plan, rows)
    return [rows[case.index] for case in plan.cases]


def _take_directory(out: Path) -> Path:
    """Makes ``out`` and ``out/cases`` (where missing) and returns the path
    of ``results.csv``, which must be absent or a sweep's own
    (:func:`_is_sweeps`): a sweep replaces it. SweepError, with nothing
    written, for a file where a directory goes, a ``results.csv`` of
    someone else's, or a directory that cannot be made."""
    cases = out / "cases"
    for path in (out, cases):
        if path.exists() and not path.is_dir():
            raise SweepError(
                f"cannot use {path} as the sweep's {'directory' if path == out else 'cases directory'}: "
                f"it exists and is not a directory; choose another directory (--out; out= from Python)"
            )
    results = out / "results.csv"
    if (results.exists() or results.is_symlink()) and not _is_sweeps(results):
        raise SweepError(
            f"{results}: not a sweep's results.csv (a sweep's starts with the columns case,status and lies "
            f"beside its cases directory), and a sweep would replace it: choose another directory "
            f"(--out; out= from Python), or move it away"
        )
    try:
        cases.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise SweepError(f"cannot make {cases}: {e.strerror or e}") from None
    return results


def _is_sweeps(results: Path) -> bool:
    """Whether ``results`` is a file a sweep wrote: its header starts with
    the columns ``case,status`` (:func:`_columns`), and it lies beside the
    ``cases`` directory, which a sweep makes before it writes any row."""
    if not results.is_file() or not (results.parent / "cases").is_dir():
        return False
    try:
        with open(results, newline="", encoding="utf-8") as f:
            header = next(csv.reader([f.readline()]), [])
    except (OSError, UnicodeDecodeError):
        return False
    return header[:2] == ["case", "status"]


def _completed(case_dir: Path, text: str) -> Optional[Dict[str, Any]]:
    """The summary of a completed run of ``text`` in ``case_dir``, or None."""
    summary = summary_of(case_dir)
    if summary is None or summary.get("status") != "completed":
        return None
    return summary if same_scenario(case_dir, text) else None


def _relative(message: str, out: Path) -> str:
    """Paths in a message relative to the sweep's directory, so that
    ``results.csv`` reads the same wherever the sweep ran."""
    return message.replace(str(out) + os.sep, "")


def _row(
    plan: Plan, case: Case, status: str, message: str, summary: Optional[Dict[str, Any]], out: Path
) -> Dict[str, Any]:
    row: Dict[str, Any] = {"case": case.index, "status": status}
    row.update(zip(plan.keys, case.values))
    summary = summary or {}
    for column in SUMMARY_COLUMNS:
        row[column] = summary.get(column)
    monitors = summary.get("monitors") or {}
    for name in _monitor_names(plan, monitors):
        position = monitors.get(name)
        for axis, c in zip("xyz", range(3)):
            row[f"{name}_{axis}"] = position[c] if position else None
    row["message"] = _relative(message, out)
    # Last, after the columns SPEC §5 lists: the threads the case ran on
    # (its results do not depend on them).
    row["threads"] = summary.get("threads")
    return row


def _monitor_names(plan: Plan, monitors: Dict[str, Any]) -> List[str]:
    return list(plan.monitors) + [m for m in monitors if m not in plan.monitors]


def _columns(plan: Plan, rows: Sequence[Dict[str, Any]]) -> List[str]:
    columns = ["case", "status", *plan.keys, *SUMMARY_COLUMNS]
    names = list(plan.monitors)
    for row in rows:
        for column in row:
            if column.endswith("_x") and column[:-2] not in names and column not in columns:
                names.append(column[:-2])
    columns += [f"{n}_{a}" for n in names for a in "xyz"]
    return columns + ["message", "threads"]


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    if isinstance(value, float):
        return repr(value)
    return json.dumps(value)


def _write_results(path: Path, plan: Plan, rows: Dict[int, Dict[str, Any]]) -> None:
    """``results.csv``: a row per case in case order; a case not run yet
    (an interrupted sweep) has status ``pending``. Written to a temporary
    file and renamed, as drape writes its outputs."""
    ordered = []
    for case in plan.cases:
        row = rows.get(case.index)
        if row is None:
            row = {"case": case.index, "status": "pending", **dict(zip(plan.keys, case.values))}
        ordered.append(row)
    columns = _columns(plan, ordered)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in ordered:
        writer.writerow([_cell(row.get(c)) for c in columns])
    temporary = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    temporary.write_text(buffer.getvalue(), encoding="utf-8")
    os.replace(temporary, path)


__all__ = ["Case", "Plan", "load_plan", "sweep", "ENGINES", "SUMMARY_COLUMNS"]
