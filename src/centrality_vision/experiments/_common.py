"""What every experiment module shares: its command-line options, its output files, its claims."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["experiment_parser", "prepare_out", "save_outputs", "claim_lines"]

SCHEDULER_HELP = "serial, processes (default), dask, or tcp://host:port"


def experiment_parser(module: str, doc: str, name: str, *, quick_help=None, seed_help=None, runner=False):
    """The options of ``python -m centrality_vision.experiments.<module>``: --quick, --seed, --out
    (default ``results/<name>``) and, for experiments on the shared runner, --scheduler and --workers."""
    parser = argparse.ArgumentParser(prog=f"python -m centrality_vision.experiments.{module}", description=doc.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--seed", type=int, default=0, help=seed_help)
    parser.add_argument("--out", default=f"results/{name}")
    if runner:
        parser.add_argument("--scheduler", default="processes", help=SCHEDULER_HELP)
        parser.add_argument("--workers", type=int, default=None)
    return parser


def prepare_out(args) -> Path:
    """The output folder of parsed ``args``, created if missing."""
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def save_outputs(out: Path, stem: str, text: str, result) -> None:
    """Print the table and write ``stem.txt`` and ``stem.json`` (``result``: a dict or JSON text)."""
    print(text)
    (out / f"{stem}.txt").write_text(text + "\n")
    record = result if isinstance(result, str) else json.dumps(result, indent=1)
    (out / f"{stem}.json").write_text(record + "\n")


def claim_lines(claims: dict, suffix: str = "") -> list[str]:
    """One ``[holds]`` / ``[does not hold]`` line per claim."""
    return [f"[{'holds' if holds else 'does not hold'}] {claim}{suffix}" for claim, holds in claims.items()]
