"""The thesis' experiments, one module each, printing our numbers beside the thesis'.

:data:`REGISTRY` is the one list of experiments, read by the command line
(``centrality-vision reproduce <name>``) and by the report
(:mod:`centrality_vision.experiments.report`): each :class:`Experiment` names its module,
the thesis figures and tables it reproduces and whether its units go through the shared
runner. :data:`EXPERIMENTS` (name -> module name) and :data:`RUNNER_EXPERIMENTS` are
derived from it, for code that only needs those; :func:`run_experiment` runs one experiment
the way the command line does.

Each module has ``run(quick=..., seed=...) -> dict``, ``format_table(result) -> str``,
``main(argv) -> int`` (``python -m centrality_vision.experiments.<module>``) and
``explain(result) -> str``, the paragraph of the report written from the result's own
numbers. ``main`` takes ``--quick``, ``--seed``, ``--seeds N`` (how many seeds the thesis'
claims are checked over), ``--out`` and, where units run on the runner, ``--scheduler``
and ``--workers``. Figures are drawn on :class:`matplotlib.figure.Figure` objects and
saved with the Agg canvas: no module switches the matplotlib backend.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "Experiment",
    "REGISTRY",
    "EXPERIMENTS",
    "RUNNER_EXPERIMENTS",
    "SEEDS_EXPERIMENTS",
    "check_options",
    "experiment_argv",
    "run_experiment",
]


@dataclass(frozen=True)
class Experiment:
    """One entry of :data:`REGISTRY`.

    Attributes
    ----------
    name : str
        Command-line name, also the output sub-folder (``results/<name>/``).
    module : str
        Module name under :mod:`centrality_vision.experiments`.
    title : str
        One line for listings.
    reproduces : tuple of str
        Thesis figures ("fig. 5.3") and tables ("Table 5.1") whose data it recomputes.
    runner : bool
        Its units run on the shared runner (``--scheduler``, ``--workers``).
    seeds : bool
        Its claims are checked over several seeds (``--seeds``); the others check theirs on
        every image or point of one run, or have nothing random.

    Examples
    --------
    >>> entry = REGISTRY["fig-5.3"]
    >>> entry.module, entry.reproduces, entry.runner, entry.seeds
    ('fig_5_3', ('fig. 5.3', 'fig. 5.4'), True, True)
    >>> [e.name for e in REGISTRY.values() if not e.runner][:3]
    ['table-2.1', 'fig-5.1', 'fig-5.10']
    """

    name: str
    module: str
    title: str
    reproduces: tuple = ()
    runner: bool = True
    seeds: bool = True


REGISTRY = {
    e.name: e
    for e in (
        Experiment(
            "table-2.1",
            "table_2_1",
            "the four centralities of the 6-node graph",
            ("Table 2.1", "fig. 2.12"),
            runner=False,
            seeds=False,
        ),
        Experiment(
            "fig-4.2",
            "fig_4_2",
            "centralities of Kimia-99 shapes, noiseless and noisy, and their histograms",
            ("fig. 4.1", "fig. 4.2", "fig. 4.3", "fig. 4.4", "fig. 4.5", "fig. 4.6"),
            seeds=False,
        ),
        Experiment(
            "table-4.1", "table_4_1", "shape classification on Kimia-99 under salt noise", ("Table 4.1", "fig. 4.8")
        ),
        Experiment(
            "fig-5.1",
            "fig_5_1",
            "GPD's prior and posterior of one fixed point",
            ("fig. 5.1", "fig. 5.2"),
            runner=False,
            seeds=False,
        ),
        Experiment(
            "fig-5.3", "fig_5_3", "the fish under a similarity transform, CPD against GPD", ("fig. 5.3", "fig. 5.4")
        ),
        Experiment("fig-5.5", "fig_5_5", "the 3D face, affine with missing points", ("fig. 5.5", "fig. 5.6")),
        Experiment(
            "fig-5.7", "fig_5_7", "the fish, non-rigid with outliers and missing points", ("fig. 5.7", "fig. 5.8")
        ),
        Experiment(
            "fig-5.10",
            "fig_5_10",
            "sample point sets of the five classes of Table 5.1",
            ("fig. 5.10",),
            runner=False,
            seeds=False,
        ),
        Experiment(
            "table-5.1",
            "table_5_1",
            "495 point sets of five classes, CPD against GPD",
            ("Table 5.1", "Table 5.2", "Table 5.3"),
        ),
        Experiment(
            "fig-6.1",
            "fig_6_1",
            "worked examples of ch. 6: six-vertex entropies, Table 6.1",
            ("fig. 6.1", "fig. 6.3", "Table 6.1"),
            runner=False,
            seeds=False,
        ),
        Experiment("fig-6.4", "fig_6_4", "MWME matching of Kimia-99 outlines", ("fig. 6.4",)),
        Experiment("fig-7.1", "fig_7_1", "MST against MSTME on five points", ("fig. 7.1",), runner=False, seeds=False),
        Experiment(
            "fig-7.4",
            "fig_7_4",
            "stability of data-graphs under perturbation",
            ("fig. 7.2", "fig. 7.3", "fig. 7.4", "fig. 7.5"),
        ),
    )
}

#: Command-line name -> module name under :mod:`centrality_vision.experiments` (from :data:`REGISTRY`).
EXPERIMENTS = {name: e.module for name, e in REGISTRY.items()}
#: The experiments whose units run on the shared runner (they accept ``--scheduler``/``--workers``).
RUNNER_EXPERIMENTS = tuple(name for name, e in REGISTRY.items() if e.runner)
#: The experiments whose claims are checked over several seeds (they accept ``--seeds``).
SEEDS_EXPERIMENTS = tuple(name for name, e in REGISTRY.items() if e.seeds)


def check_options(*, quick=False, seed=0, seeds=None, scheduler=None, workers=None) -> dict:
    """The options shared by :func:`experiment_argv`, :func:`run_experiment` and
    :func:`~centrality_vision.experiments.report.run_all`, checked: ``quick`` True or False,
    ``seed`` an int in [0, 2**32 - 1], ``seeds`` None or an int in [1, 100000], ``scheduler``
    None or a scheduler name, ``workers`` None or an int in [1, 1024]. A bad one is a named
    ``TypeError`` or :class:`~centrality_vision.exceptions.InputError`.

    Parameters
    ----------
    quick : bool, default=False
        The experiments' quick (smaller) runs.
    seed : int in [0, 2**32 - 1], default=0
        Seed of the run drawn in the figures.
    seeds : int in [1, 100000], optional
        How many seeds the thesis' claims are checked over.
    scheduler : {"serial", "processes", "dask"} or "tcp://host:port", optional
        Where the units run (a Dask scheduler's address: a host and a port in 1..65535).
    workers : int in [1, 1024], optional
        Processes or Dask workers.

    Returns
    -------
    dict
        The checked values under the keys ``"quick"``, ``"seed"``, ``"seeds"``, ``"scheduler"``
        and ``"workers"``.

    Examples
    --------
    >>> check_options(quick=True, seeds=4, scheduler="serial")
    {'quick': True, 'seed': 0, 'seeds': 4, 'scheduler': 'serial', 'workers': None}
    >>> check_options(workers=0)
    Traceback (most recent call last):
    ...
    centrality_vision.exceptions.InputError: `workers` must be an int in [1, 1024]; got 0.
    """
    from .._validation import check_int
    from ._common import MAX_SEEDS, check_run, seed_list
    from ._runner import MAX_WORKERS, _check_scheduler

    quick, seed = check_run(quick, seed)
    seeds = None if seeds is None else check_int(seeds, name="seeds", low=1, high=MAX_SEEDS)
    if seeds is not None:
        seed_list(seed, seeds, quick)  # (seed + seeds must stay within 2**32 as well)
    return {
        "quick": quick,
        "seed": seed,
        "seeds": seeds,
        "scheduler": None if scheduler is None else _check_scheduler(scheduler),
        "workers": None if workers is None else check_int(workers, name="workers", low=1, high=MAX_WORKERS),
    }


def experiment_argv(
    name: str,
    out,
    *,
    quick: bool = False,
    seed: int = 0,
    seeds: int | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
) -> list[str]:
    """The command line of experiment ``name``'s ``main`` for these options (checked by
    :func:`check_options`; ``seeds`` only for :data:`SEEDS_EXPERIMENTS`, ``scheduler`` and
    ``workers`` only for :data:`RUNNER_EXPERIMENTS`).

    Parameters
    ----------
    name : str
        A key of :data:`REGISTRY`, e.g. ``"fig-5.3"``.
    out : str or os.PathLike
        The output folder (``--out``).
    quick, seed, seeds, scheduler, workers :
        As in :func:`check_options`; those an experiment does not take are left out, and so
        are ``quick=False`` and the options that are None.

    Returns
    -------
    list of str
        ``--out`` and ``--seed`` first, then ``--quick``, ``--seeds``, ``--scheduler`` and
        ``--workers`` where given.

    Examples
    --------
    >>> experiment_argv("fig-5.3", "out/fig-5.3", quick=True, seeds=4)
    ['--out=out/fig-5.3', '--seed=0', '--quick', '--seeds=4']
    """
    import os

    if not isinstance(name, str) or name not in REGISTRY:
        from ..exceptions import InputError

        raise InputError(f"`name` must be one of {', '.join(REGISTRY)}; got {name!r}.")
    if not isinstance(out, (str, os.PathLike)):
        raise TypeError(f"`out` must be a folder path (str or os.PathLike); got {type(out).__name__}.")
    options = check_options(quick=quick, seed=seed, seeds=seeds, scheduler=scheduler, workers=workers)
    # (--out=PATH: a folder whose name starts with '-' is not read as another option)
    argv = [f"--out={os.fspath(out)}", f"--seed={options['seed']}"]
    if options["quick"]:
        argv.append("--quick")
    if options["seeds"] is not None and REGISTRY[name].seeds:
        argv.append(f"--seeds={options['seeds']}")
    if REGISTRY[name].runner:
        if options["scheduler"] is not None:
            argv.append(f"--scheduler={options['scheduler']}")
        if options["workers"] is not None:
            argv.append(f"--workers={options['workers']}")
    return argv


def run_experiment(
    name: str,
    out,
    *,
    quick: bool = False,
    seed: int = 0,
    seeds: int | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
) -> int:
    """Run experiment ``name`` into folder ``out`` (its files go to ``out`` itself) and return
    its exit status; what ``centrality-vision reproduce <name>`` does.

    ``seeds`` is how many seeds the thesis' claims are checked over (``--seeds N`` of
    ``reproduce``; default 20, 3 with ``quick``); it goes to the experiments of
    :data:`SEEDS_EXPERIMENTS` and is ignored by the others. ``scheduler``/``workers`` go to the
    experiments of :data:`RUNNER_EXPERIMENTS` and are ignored by the others (they are
    instant). For ``reproduce all`` see :func:`centrality_vision.experiments.report.run_all`,
    which takes the same options.

    Parameters
    ----------
    name : str
        A key of :data:`REGISTRY`, e.g. ``"fig-5.3"``.
    out : str or os.PathLike
        The output folder, created when missing.
    quick, seed, seeds, scheduler, workers :
        As in :func:`check_options`.

    Returns
    -------
    int
        The exit status of the experiment's ``main``: 0 when it finishes (errors are raised).

    Examples
    --------
    Table 2.1 (about a second), its table printed and its files written to ``out``:

    >>> import os, tempfile
    >>> out = tempfile.mkdtemp()  # doctest: +SKIP
    >>> run_experiment("table-2.1", out, quick=True)  # doctest: +SKIP
    Table 2.1 (each cell: ours | thesis)
    ...
    0
    >>> sorted(os.listdir(out))  # doctest: +SKIP
    ['table-2.1-quick.files.json', 'table-2.1-quick.json', 'table-2.1-quick.png', 'table-2.1-quick.txt']

    A name not in :data:`REGISTRY` is refused before anything runs:

    >>> run_experiment("fig-9.9", "out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    centrality_vision.exceptions.InputError: `name` must be one of table-2.1, fig-4.2, ...; got 'fig-9.9'.
    """
    from importlib import import_module

    argv = experiment_argv(name, out, quick=quick, seed=seed, seeds=seeds, scheduler=scheduler, workers=workers)
    return import_module(f"{__name__}.{REGISTRY[name].module}").main(argv)
