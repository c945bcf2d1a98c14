"""``python -m drape sweep SWEEP.toml [--out DIR] [--workers N]
[--engine local|ray|dask] [--address ADDR]``.

Exit codes as ``drape run``'s: 0 every case completed, 1 some case failed
(its row in ``results.csv`` says why; the others ran), 2 bad input (the
sweep file, its base scenario, the options; nothing ran), 130 interrupted
(run the same command again to finish).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import List, Optional

from ._errors import DrapeError
from ._sweep import ENGINES, sweep


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
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    args = _parser().parse_args(argv)
    if args.workers is not None and args.workers < 1:
        print("error: --workers must be at least 1", file=sys.stderr)
        return 2
    if args.address and args.engine == "local":
        print("error: --address names a Ray or Dask cluster: use it with --engine ray or --engine dask", file=sys.stderr)
        return 2
    out = args.out if args.out is not None else Path("out") / args.sweep.stem
    try:
        rows = sweep(args.sweep, out=out, workers=args.workers, engine=args.engine, address=args.address)
    except (DrapeError, ImportError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            f"interrupted: the cases done so far are in {out / 'results.csv'}; run the same command again to finish",
            file=sys.stderr,
        )
        return 130
    failed = [r for r in rows if r["status"] != "completed"]
    print(
        f"{len(rows)} cases: {len(rows) - len(failed)} completed, {len(failed)} failed; results in {out / 'results.csv'}"
    )
    for row in failed:
        print(f"case {row['case']:04d} {row['status']}: {row['message']}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
