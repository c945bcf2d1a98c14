"""``python -m drape sweep SWEEP.toml [--out DIR] [--workers N]
[--engine local|ray|dask] [--address ADDR]`` and ``python -m drape test
SCENARIO.toml --specimens N [--out DIR] [--jobs J] [--engine
local|ray|dask] [--address ADDR] [--seed S]``.

Exit codes as ``drape run``'s: 0 every case (specimen) completed, 1 some
failed (its row in ``results.csv``, its entry in ``test.json``, says why;
the others ran), 2 bad input (the sweep file, the scenario, the options;
nothing ran), 130 interrupted (run the same command again to finish).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any, Callable, List, Optional, Tuple

from ._errors import DrapeError
from ._sweep import ENGINES, sweep
from . import test


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m drape",
        description="drape from Python: parameter sweeps (run and check scenarios with drape.run and drape.check).",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    s = commands.add_parser(
        "sweep",
        help="run one scenario over a grid of parameter values",
        description=(
            "Run the base scenario of SWEEP.toml for every combination (mode = \"grid\") or every i-th "
            "tuple (mode = \"zip\") of the [parameters]' values. Writes DIR/cases/NNNN/ (each case's "
            "scenario and outputs) and DIR/results.csv (a row per case). Cases completed by an earlier "
            "run of the same sweep are not run again."
        ),
    )
    s.add_argument("sweep", type=Path, metavar="SWEEP.toml", help="the sweep file")
    s.add_argument("--out", type=Path, metavar="DIR", help="output directory [default: ./out/<sweep stem>]")
    s.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help=f"cases at once (local) or CPUs of a local cluster (ray, dask) [default: {os.cpu_count() or 1}, the CPUs here]",
    )
    s.add_argument("--engine", choices=ENGINES, default="local", help="where the cases run [default: local]")
    s.add_argument(
        "--address",
        metavar="ADDR",
        help="the Ray or Dask cluster to use (its files must see DIR at the same path); without it a local one is started",
    )
    t = commands.add_parser(
        "test",
        help="a drape test: several specimens of one scenario, side by side",
        description=(
            "Run N specimens of SCENARIO.toml that differ by a seeded perturbation ([test]: waviness, "
            "the cut's angle to the warp, face up or down), one thread each. Writes DIR/specimens/NNNN/ "
            "(ordinary run directories), DIR/test.json (each specimen's drape coefficient and folds, "
            "mean, sd, 95 %% interval, fold histogram) and DIR/test.png. Specimens completed by an "
            "earlier run of the same test are not run again."
        ),
    )
    t.add_argument("scenario", type=Path, metavar="SCENARIO.toml", help="the scenario file")
    t.add_argument("--specimens", type=int, required=True, metavar="N", help="how many specimens")
    t.add_argument("--out", type=Path, metavar="DIR", help="output directory [default: ./out/<stem>-test]")
    t.add_argument(
        "--jobs",
        "--workers",
        dest="jobs",
        type=int,
        metavar="J",
        help=f"specimens at once (local) or CPUs of a local cluster (ray, dask) [default: {os.cpu_count() or 1}]",
    )
    t.add_argument("--engine", choices=ENGINES, default="local", help="where the specimens run [default: local]")
    t.add_argument("--address", metavar="ADDR", help="the Ray or Dask cluster to use")
    t.add_argument("--seed", type=int, default=0, metavar="S", help="the test's seed [default: 0]")
    return parser


def _guarded(call: Callable[[], Any], results: Path, what: str) -> Tuple[Any, Optional[int]]:
    """``call()``, or the exit code of its failure: 2 for bad input
    (nothing ran), 130 for Ctrl-C (``results`` has what was done)."""
    try:
        return call(), None
    except (DrapeError, ImportError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return None, 2
    except KeyboardInterrupt:
        print(
            f"interrupted: the {what} done so far are in {results}; run the same command again to finish",
            file=sys.stderr,
        )
        return None, 130


def _test_main(args: argparse.Namespace) -> int:
    out = args.out if args.out is not None else Path("out") / f"{args.scenario.stem}-test"
    report, code = _guarded(
        lambda: test(
            args.scenario,
            args.specimens,
            out=out,
            jobs=args.jobs,
            engine=args.engine,
            address=args.address,
            seed=args.seed,
        ),
        out / "test.json",
        "specimens",
    )
    if code is not None:
        return code
    print(report["message"])
    print(f"results in {out / 'test.json'}")
    unfinished = [s for s in report["specimens"] if s["status"] != "completed"]
    for s in unfinished:
        print(f"specimen {s['specimen']:04d} {s['status']}: {s['message']}", file=sys.stderr)
    return 1 if unfinished else 0


def main(argv: Optional[List[str]] = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "test":
        return _test_main(args)
    if args.workers is not None and args.workers < 1:
        print("error: --workers must be at least 1", file=sys.stderr)
        return 2
    if args.address and args.engine == "local":
        print("error: --address names a Ray or Dask cluster: use it with --engine ray or --engine dask", file=sys.stderr)
        return 2
    out = args.out if args.out is not None else Path("out") / args.sweep.stem
    rows, code = _guarded(
        lambda: sweep(args.sweep, out=out, workers=args.workers, engine=args.engine, address=args.address),
        out / "results.csv",
        "cases",
    )
    if code is not None:
        return code
    failed = [r for r in rows if r["status"] != "completed"]
    print(
        f"{len(rows)} cases: {len(rows) - len(failed)} completed, {len(failed)} failed; results in {out / 'results.csv'}"
    )
    for row in failed:
        print(f"case {row['case']:04d} {row['status']}: {row['message']}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
