"""``centrality-vision reproduce``: re-run a thesis experiment from the one registry of experiments."""

from __future__ import annotations

import argparse

from ..experiments._common import MAX_SEED, MAX_SEEDS, MAX_WORKERS, int_in
from ._common import add_progress, out_folder

NAME = "reproduce"


def add_parser(sub) -> argparse.ArgumentParser:
    from ..experiments import EXPERIMENTS

    parser = sub.add_parser(
        NAME,
        help="Re-run one of the thesis' experiments and print our numbers beside the thesis'.",
        description="Re-run a thesis experiment; tables and figures are written under --out/<experiment>/. "
        "'all' runs every experiment and writes --out/report.md with every table and figure.",
        epilog="example:\n  centrality-vision reproduce fig-5.3 --quick --seeds 5 --out results",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "experiment", choices=[*EXPERIMENTS, "all"], help="which table or figure, or all of them with a report"
    )
    parser.add_argument("--quick", action="store_true", help="a small version, for a first look or a test")
    parser.add_argument(
        "--seed", type=int_in(0, MAX_SEED), default=0, help="seed of every random choice (default: %(default)s)"
    )
    parser.add_argument(
        "--seeds",
        type=int_in(1, MAX_SEEDS),
        default=None,
        help="how many seeds each thesis claim is checked over (default: 20, or 3 with --quick)",
    )
    parser.add_argument("--out", default="results", type=out_folder, help="output folder (default: %(default)s)")
    parser.add_argument(
        "--scheduler",
        default=None,
        help="where the units of the long experiments run: serial, processes (default), dask (a local "
        "cluster started for the run) or tcp://host:port (a running Dask scheduler); finished units are kept and "
        "skipped on a re-run",
    )
    parser.add_argument(
        "--workers",
        type=int_in(1, MAX_WORKERS),
        default=None,
        help="processes or Dask workers to start (default: the usable cores)",
    )
    add_progress(parser)
    parser.set_defaults(run=run, _parser=parser)
    return parser


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ..exceptions import InputError
    from ..experiments import RUNNER_EXPERIMENTS, SEEDS_EXPERIMENTS, run_experiment

    if args.scheduler is not None:  # before any experiment runs, not after its first part
        from ..experiments._runner import _check_scheduler

        _check_scheduler(args.scheduler)
    if args.experiment == "all":
        from ..experiments.report import run_all

        path = run_all(
            args.out, quick=args.quick, seed=args.seed, seeds=args.seeds, scheduler=args.scheduler, workers=args.workers
        )
        print(f"wrote {path}")
        return 0
    for option, value, takers in (
        ("scheduler", args.scheduler, RUNNER_EXPERIMENTS),
        ("workers", args.workers, RUNNER_EXPERIMENTS),
        ("seeds", args.seeds, SEEDS_EXPERIMENTS),
    ):
        if value is not None and args.experiment not in takers:
            # (`option` reads --option in the printed message)
            raise InputError(f"`{option}` applies to {', '.join(takers)} (and all); got it for {args.experiment}.")
    code = run_experiment(
        args.experiment,
        Path(args.out) / args.experiment,
        quick=args.quick,
        seed=args.seed,
        seeds=args.seeds,
        scheduler=args.scheduler,
        workers=args.workers,
    )
    report = Path(args.out) / "report.md"
    if code == 0 and report.is_file():  # a snapshot of its own run: it does not follow this one
        from ._common import say

        say(
            f"note: {report} is from an earlier 'reproduce all' and does not show this run; run "
            f"'reproduce all' again to refresh it (the long experiments' stored results are reused)"
        )
    return code
