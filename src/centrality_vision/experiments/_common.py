"""What every experiment module shares: its options, its output files, its claims and their odds.

A *claim* is one sentence of the thesis turned into a check on our numbers (``True`` when
it holds). Claims are evaluated once per seed (or once per image or point set where the
thesis speaks about a data set) and printed as "holds in k of n" with a 95% Wilson score
interval for the share of draws in which the claim holds, beside the thesis' own words.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
from pathlib import Path

from ._runner import MAX_WORKERS

__all__ = [
    "SCHEDULER_HELP",
    "DEFAULT_SEEDS",
    "QUICK_SEEDS",
    "experiment_parser",
    "prepare_out",
    "save_outputs",
    "run_outputs",
    "outputs_of",
    "claim_lines",
    "seed_list",
    "wilson_interval",
    "tally",
    "odds_lines",
    "verdict",
    "share",
    "new_figure",
    "run_seed_units",
]

SCHEDULER_HELP = "serial, processes (default), dask, or tcp://host:port"
#: Seeds over which a claim is checked unless ``--seeds`` says otherwise (full runs / ``--quick``).
DEFAULT_SEEDS = 20
QUICK_SEEDS = 3


#: the most seeds one run checks a claim over (each seed is a unit of work; more is a typo)
MAX_SEEDS = 100_000
#: seeds go to numpy and to scikit-learn's ``random_state``, which takes 0 .. 2**32 - 1
MAX_SEED = 2**32 - 1


def check_run(quick, seed) -> tuple[bool, int]:
    """An experiment's ``run`` options checked: ``quick`` True or False, ``seed`` an int in
    [0, :data:`MAX_SEED`].

    Examples
    --------
    >>> check_run(True, 3)
    (True, 3)
    """
    from .._validation import check_bool, check_int

    return check_bool(quick, name="quick"), check_int(seed, name="seed", low=0, high=MAX_SEED)


def int_in(low: int, high: int | None = None):
    """An argparse ``type``: an int in ``[low, high]``, or argparse's one-line usage error
    worded as the command line's ('must be in [1, 100000]; got 0')."""
    from .._validation import argparse_number

    return argparse_number(int, low=low, high=high)


def scheduler_arg(text: str) -> str:
    """An argparse ``type`` for ``--scheduler``: checked when the options are read, not after
    the first part of a run."""
    from ..exceptions import InputError
    from ._runner import _check_scheduler

    try:
        return _check_scheduler(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).replace("`scheduler` must", "must")) from None


def command_line(main) -> int:
    """What ``python -m centrality_vision.experiments.<module>`` runs: ``main()``, with a bad
    argument or missing data as one line on stderr and exit status 2 (not a traceback)."""
    from ..exceptions import InputError

    try:
        return main()
    except (InputError, FileNotFoundError) as exc:
        message = " ".join(str(exc).split())
        for option in COMMAND_LINE_OPTIONS:  # a parameter's name as the option that gives it
            message = message.replace(f"`{option}`", f"--{option}")
        print(f"error: {message}", file=sys.stderr)
        return 2


#: The options of :func:`experiment_parser`, which a library message names as parameters.
COMMAND_LINE_OPTIONS = ("out", "seed", "seeds", "scheduler", "workers")


def experiment_parser(module: str, doc: str, name: str, *, quick_help=None, seed_help=None, runner=False, seeds=True):
    """The options of ``python -m centrality_vision.experiments.<module>``: --quick, --seed, --out
    (default ``results/<name>``), --seeds (how many seeds the claims are checked over, from
    --seed on) and, for experiments on the shared runner, --scheduler and --workers."""
    parser = argparse.ArgumentParser(
        prog=f"python -m centrality_vision.experiments.{module}", description=doc.splitlines()[0]
    )
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument(
        "--seed",
        type=int_in(0, MAX_SEED),
        default=0,
        help=seed_help or "seed of the run drawn in the figures (default: %(default)s)",
    )
    parser.add_argument("--out", default=f"results/{name}")
    if seeds:
        parser.add_argument(
            "--seeds",
            type=int_in(1, MAX_SEEDS),
            default=None,
            help=f"check the claims over this many seeds, --seed, --seed+1, ... (default: {DEFAULT_SEEDS}, --quick: "
            f"{QUICK_SEEDS})",
        )
    if runner or seeds:
        parser.add_argument("--scheduler", type=scheduler_arg, default="processes", help=SCHEDULER_HELP)
        parser.add_argument("--workers", type=int_in(1, MAX_WORKERS), default=None)
    return parser


def seed_list(seed: int, seeds: int | None, quick: bool) -> list[int]:
    """``seeds`` consecutive seeds from ``seed`` (default :data:`DEFAULT_SEEDS`, or
    :data:`QUICK_SEEDS` when ``quick``).

    Examples
    --------
    >>> seed_list(5, 3, False)
    [5, 6, 7]
    >>> len(seed_list(0, None, False)), len(seed_list(0, None, True))
    (20, 3)
    """
    from .._validation import check_int

    seed = check_int(seed, name="seed", low=0, high=MAX_SEED)
    n = (
        (QUICK_SEEDS if quick else DEFAULT_SEEDS)
        if seeds is None
        else check_int(seeds, name="seeds", low=1, high=MAX_SEEDS)
    )
    if seed + n - 1 > MAX_SEED:
        from ..exceptions import InputError

        raise InputError(f"`seed` + `seeds` must stay below 2**32 (scikit-learn's random_state); got {seed} and {n}.")
    return list(range(seed, seed + n))


def prepare_out(args) -> Path:
    """The output folder of parsed ``args``, created if missing."""
    return make_out_folder(args.out)


def make_out_folder(path) -> Path:
    """``path`` as a folder, created if missing; a file or an unwritable place is a named error."""
    from .._validation import nearest_existing
    from ..exceptions import InputError

    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        ancestor = nearest_existing(out)
        why = f"{str(ancestor)!r} is a file, not a folder" if not ancestor.is_dir() else exc.strerror
        raise InputError(f"`out` must be a folder that can be created; got {str(out)!r} ({why}).") from None
    return out


def save_outputs(out: Path, stem: str, text: str, result) -> None:
    """Print the table and write ``stem.txt`` and ``stem.json`` (``result``: a dict or JSON text)."""
    print(text)
    (out / f"{stem}.txt").write_text(text + "\n")
    record = result if isinstance(result, str) else json.dumps(result, indent=1)
    (out / f"{stem}.json").write_text(record + "\n")


def run_stem(name: str, quick: bool) -> str:
    """``name``, with ``-quick`` for a quick run: the one rule by which quick and full runs'
    files (tables, figures, kept units) keep apart in a shared folder."""
    return f"{name}-quick" if quick else name


def _quick_name(filename: str, quick: bool) -> str:
    if not quick:
        return filename
    path = Path(filename)
    return f"{path.stem}-quick{path.suffix}"


@contextlib.contextmanager
def run_outputs(out: Path, name: str, *, quick: bool):
    """A staging folder for the tables and figures of one run of experiment ``name``.

    Write the run's files into the yielded folder. When the block ends without an error they
    are moved into ``out``, a quick run's with ``-quick`` before the suffix (``fig-5.3.png`` ->
    ``fig-5.3-quick.png``), so a quick and a full run can share one folder without either
    overwriting the other's files. Their names are then listed in ``out/<name>[-quick].files.json``,
    which :func:`outputs_of` (and the report) read: a file left in ``out`` by another run or by
    hand is never taken for this run's. When the block raises, nothing in ``out`` changes.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> with run_outputs(out, "fig-0", quick=True) as stage:
    ...     _ = (stage / "fig-0.txt").write_text("table")
    >>> [path.name for path in outputs_of(out, "fig-0", quick=True)]
    ['fig-0-quick.txt']
    >>> outputs_of(out, "fig-0", quick=False) is None  # no full run here
    True
    """
    stage = out / f".writing-{run_stem(name, quick)}"
    if stage.is_dir() and not stage.is_symlink():  # left by a run that was killed
        shutil.rmtree(stage)
    elif stage.exists() or stage.is_symlink():  # a file (or a link) where the staging folder goes
        stage.unlink()
    stage.mkdir()
    try:
        yield stage
        manifest = out / f"{run_stem(name, quick)}.files.json"
        staged = sorted(stage.iterdir())
        # every place checked before anything moves: a folder in a file's place failed the
        # move half way, after the last run's manifest was gone and some files replaced
        for place in [manifest, *(out / _quick_name(path.name, quick) for path in staged)]:
            if place.is_dir() and not place.is_symlink():
                from ..exceptions import InputError

                raise InputError(f"`out`: {place} is a folder where {name} writes a file; move it and run again.")
        manifest.unlink(missing_ok=True)  # never a list that names files of two runs
        names = []
        for path in staged:
            final = _quick_name(path.name, quick)
            os.replace(path, out / final)
            names.append(final)
        manifest.write_text(json.dumps({"experiment": name, "quick": quick, "files": names}, indent=1) + "\n")
        print(f"wrote {out}/: {', '.join(names)}", file=sys.stderr)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def outputs_of(out, name: str, *, quick: bool) -> list[Path] | None:
    """The tables, results and figures the last quick (or full) run of ``name`` wrote into
    ``out`` (see :func:`run_outputs`), or None when no such run finished there."""
    manifest = Path(out) / f"{run_stem(name, quick)}.files.json"
    try:
        names = json.loads(manifest.read_text())["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not isinstance(names, list) or not all(isinstance(n, str) and n and Path(n).name == n for n in names):
        return None
    return [Path(out) / n for n in names if (Path(out) / n).is_file()]


def with_drawn_seed(seed: int, seeds) -> list[int]:
    """The seeds a multi-seed run checks its claims on: ``seeds`` (default ``[seed]``),
    with ``seed``, the run drawn in the tables and figures, among them."""
    seeds = [seed] if seeds is None else list(seeds)
    return seeds if seed in seeds else [seed, *seeds]


def claims_block(result: dict, sources: dict | None = None) -> list[str]:
    """The claims on the drawn seed and, when checked over several seeds, their odds."""
    lines = [f"Claims on seed {result['seed']} (the run drawn above):", *claim_lines(result["claims"])]
    if result.get("odds"):
        seeds = result["seeds"]
        lines += [f"Claims over {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}):", *odds_lines(result["odds"], sources)]
    return lines


def claim_lines(claims: dict, suffix: str = "") -> list[str]:
    """One ``[holds]`` / ``[does not hold]`` line per claim (one run)."""
    return [f"[{'holds' if holds else 'does not hold'}] {claim}{suffix}" for claim, holds in claims.items()]


def wilson_interval(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval (95% by default) for a share of ``k`` successes in ``n`` trials.

    Examples
    --------
    >>> [round(v, 3) for v in wilson_interval(17, 20)]
    [0.64, 0.948]
    >>> wilson_interval(0, 20)[0], round(wilson_interval(0, 20)[1], 3)
    (0.0, 0.161)
    >>> wilson_interval(27, 27)[1]
    1.0
    """
    if n <= 0:
        return 0.0, 1.0
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # (at k = 0 or n one bound is exactly 0 or 1; rounding left 1 - 1e-16, printed as 99.999999...)
    low = 0.0 if k == 0 else max(0.0, centre - half)
    high = 1.0 if k == n else min(1.0, centre + half)
    return low, high


def tally(draws) -> dict:
    """``{claim: {"k", "n", "low", "high"}}`` from a sequence of ``{claim: bool}`` (one per draw).

    A claim missing from a draw (not defined there) is not counted for it.

    Examples
    --------
    >>> t = tally([{"a": True}, {"a": False}, {"a": True}])
    >>> t["a"]["k"], t["a"]["n"]
    (2, 3)
    """
    import numpy as np

    out = {}
    for draw in draws:
        for claim, holds in draw.items():
            if not isinstance(holds, (bool, np.bool_)):  # bool(nan) is True: a claim is a bool or absent
                raise TypeError(f"claim {claim!r} must be True or False in every draw; got {holds!r}.")
            cell = out.setdefault(claim, {"k": 0, "n": 0})
            cell["k"] += bool(holds)
            cell["n"] += 1
    for cell in out.values():
        cell["low"], cell["high"] = wilson_interval(cell["k"], cell["n"])
    return out


def verdict(cell: dict) -> str:
    """How a tallied claim fares: 'holds' (95% interval above one half), 'fails' (below one
    half) or 'undecided' (too few draws, or about as often as not); 'holds always' / 'never
    holds' when, besides, every draw agrees.

    Examples
    --------
    >>> verdict({"k": 20, "n": 20, "low": 0.84, "high": 1.0}), verdict({"k": 9, "n": 20, "low": 0.26, "high": 0.66})
    ('holds always', 'undecided')
    >>> verdict({"k": 1, "n": 1, "low": 0.21, "high": 1.0})
    'undecided'
    """
    if cell["low"] > 0.5:
        return "holds always" if cell["k"] == cell["n"] else "holds"
    if cell["high"] < 0.5:
        return "never holds" if cell["k"] == 0 else "fails"
    return "undecided"


def percents(*shares: float) -> list[str]:
    """Shares (0..1) as percent strings with the fewest decimals that neither
    round a share strictly between 0 and 1 to "0" or "100" nor make two different shares equal
    (six at most).

    Examples
    --------
    >>> percents(0.64, 0.948), percents(0.9962, 1.0), percents(0.0, 0.0012)
    (['64', '95'], ['99.6', '100.0'], ['0.0', '0.1'])
    """
    for digits in range(7):
        text = [f"{100 * v:.{digits}f}" for v in shares]
        inside = all(v in (0, 1) or float(t) not in (0.0, 100.0) for v, t in zip(shares, text))
        distinct = len(set(text)) == len(set(shares))
        if inside and distinct:
            break
    return text


def share(cell: dict) -> str:
    """``"k of n (95% interval lo-hi%)"``.

    Examples
    --------
    >>> share({"k": 17, "n": 20, "low": 0.64, "high": 0.948})
    'holds in 17 of 20 (95% interval 64-95%)'
    """
    low, high = percents(cell["low"], cell["high"])
    return f"holds in {cell['k']} of {cell['n']} (95% interval {low}-{high}%)"


def odds_lines(odds: dict, thesis: dict | None = None, *, unit: str = "seeds") -> list[str]:
    """One line per tallied claim: ``[holds in k of n seeds (95% interval)] claim -- thesis: "..."``."""
    lines = []
    for claim, cell in odds.items():
        line = f"[{share(cell).replace(' (', f' {unit} (', 1)}] {claim}"
        if thesis and thesis.get(claim):
            line += f' -- thesis: "{thesis[claim]}"'
        lines.append(line)
    return lines


def new_figure(**kwargs):
    """A matplotlib Figure drawn off-screen, with no pyplot and no backend switch.

    ``Figure.savefig`` (used by :func:`centrality_vision.plotting.save_figure`) renders it
    with the Agg canvas; nothing here needs a display or ``matplotlib.use``.
    """
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def run_kept_units(units, out, name: str, *, quick: bool, scheduler, workers, progress, desc: str) -> dict:
    """:func:`~._runner.run_units` with the results kept in ``out/<name>[-quick].jsonl`` (resumable),
    or in a temporary file when ``out`` is None."""
    import tempfile

    from ._runner import run_units

    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        path = folder / f"{run_stem(name, quick)}.jsonl"
        return run_units(units, path, scheduler=scheduler, workers=workers, progress=progress, desc=desc)


def run_seed_units(
    func, seeds, path, *, scheduler="processes", workers=None, progress=True, desc="seeds", volatile=(), **kwargs
) -> list:
    """``func(seed=s, **kwargs)`` for every seed, as units of the shared runner (kept in ``path``;
    ``volatile``: the keyword arguments that do not change a result, see :class:`~._runner.Unit`)."""
    from ._runner import Unit, run_units

    units = [Unit(f"seed-{s}", func, {"seed": s, **kwargs}, volatile=tuple(volatile)) for s in seeds]
    done = run_units(units, path, scheduler=scheduler, workers=workers, progress=progress, desc=desc)
    return [done[u.key] for u in units]
