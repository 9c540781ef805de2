"""CPD against GPD with each of the thesis' four centralities, on one registration problem.

Shared by the experiments of thesis 5.4.1-5.4.3 (figs. 5.3-5.8): every method records the
alignment error |X - T(Y)| per iteration and the moving set at chosen iterations.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

__all__ = [
    "METHODS",
    "LEVELS",
    "compare_methods",
    "faster_than_cpd",
    "error_at",
    "format_comparison",
    "comparison_text",
    "plot_comparison",
    "seed_summary",
    "comparison_main",
    "odds_sentences",
    "unreached",
]

METHODS = ("betweenness", "closeness", "degree", "eigenvector", "CPD")
LEVELS = (0.1, 0.01, 0.001)


def _first_below(errors: np.ndarray, level: float):
    hit = np.flatnonzero(errors <= level * errors[0])
    return int(hit[0]) if hit.size else None


def compare_methods(moving, fixed, true_moving, make_base, *, snapshots, graph="delaunay") -> dict:
    """Fit CPD (``make_base(callback)``) and GPD over it for each centrality; per-method records."""
    from ..exceptions import ConvergenceWarning
    from ..registration import GPD, Snapshots

    methods = {}
    for name in METHODS:
        snaps = Snapshots(snapshots)
        base = make_base(snaps)
        est = base if name == "CPD" else GPD(base, centrality=name, graph=graph)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            est.fit(moving, fixed, true_moving=true_moving)
        errors = np.asarray(est.history_["error"])
        methods[name] = {
            "errors": errors.tolist(),
            "n_iter": int(est.n_iter_),
            "converged": bool(est.converged_),
            "final_error": float(errors[-1]),
            "below": {str(level): _first_below(errors, level) for level in LEVELS},
            "snapshots": {str(k): v.tolist() for k, v in snaps.frames.items()},
        }
    return methods


def faster_than_cpd(methods: dict, level: float = 0.01) -> dict:
    """The claims "GPD (centrality) reaches ``level`` x the initial error in fewer iterations than CPD"."""
    cpd = methods["CPD"]["below"][str(level)]
    out = {}
    for name in METHODS[:-1]:
        mine = methods[name]["below"][str(level)]
        claim = f"GPD ({name}) reaches {100 * level:g}% of the initial error in fewer iterations than CPD"
        out[claim] = mine is not None and (cpd is None or mine < cpd)
    return out


def comparison_text(header: str, result: dict, figure: str, *, at=(), sources=None) -> str:
    """The printed table of a comparison experiment: header, iteration counts, the thesis, the
    claims on this seed and, when checked over several seeds, their odds."""
    from ._common import claims_block

    lines = [header, *format_comparison(result["methods"], at=at), f"Thesis ({figure}): {result['thesis']}."]
    return "\n".join(lines + claims_block(result, sources))


def seed_summary(result: dict) -> dict:
    """What a multi-seed run keeps of one seed's result: its claims and a few numbers per method."""
    return {
        "claims": result["claims"],
        "below": {name: m["below"] for name, m in result["methods"].items()},
        "n_iter": {name: m["n_iter"] for name, m in result["methods"].items()},
        "converged": {name: m["converged"] for name, m in result["methods"].items()},
        "final_error": {name: m["final_error"] for name, m in result["methods"].items()},
        "error_at_10": error_at(result["methods"], 10),
    }


def unreached(per_seed: list, level: str = "0.01") -> str:
    """'' or ' (never reached within the iteration cap: betweenness in 3 of 20 seeds)'."""
    missed = {m: sum(r["below"][m][level] is None for r in per_seed) for m in METHODS}
    missed = {m: k for m, k in missed.items() if k}
    if not missed:
        return ""
    return (
        " (not reached within the iteration cap: "
        + ", ".join(f"{m} in {k}" for m, k in missed.items())
        + f" of {len(per_seed)} seeds)"
    )


def median_iterations(per_seed: list, cap: int, level: str = "0.01") -> dict:
    """Each method's median number of iterations to reach ``level`` of the initial error, as
    ``(value, exact)``: ``exact`` is False when the median is censored and ``value`` is then a
    lower bound (the median is more than ``value``).

    A seed that never reached the level within the iteration ``cap`` counts as beyond the cap,
    so the median is censored, not taken over the seeds that did reach it (which would make a
    method that often fails look fast). With more than half the seeds beyond the cap the median
    is more than ``cap``; with exactly half (an even count), it is the mean of the largest
    iteration count reached and a count beyond the cap, so more than their mean with ``cap``.

    >>> per_seed = [{"below": {m: {"0.01": k} for m in METHODS}} for k in (4, None, 6, None)]
    >>> median_iterations(per_seed[:3], 150)["CPD"], median_iterations(per_seed[1:], 150)["CPD"]
    ((6.0, True), (150.0, False))
    >>> median_iterations(per_seed, 150)["CPD"]  # exactly half beyond the cap: more than (6 + 150) / 2
    (78.0, False)
    """
    out = {}
    for m in METHODS:
        reached = sorted(float(r["below"][m][level]) for r in per_seed if r["below"][m][level] is not None)
        n, beyond = len(per_seed), len(per_seed) - len(reached)
        if 2 * beyond < n:
            out[m] = (float(np.median(reached + [np.inf] * beyond)), True)
        elif 2 * beyond == n:
            out[m] = ((reached[-1] + cap) / 2, False)
        else:
            out[m] = (float(cap), False)
    return out


def iterations_text(median: tuple) -> str:
    """``'12'``, or ``'more than 78'`` for a censored median (see :func:`median_iterations`)."""
    value, exact = median
    return f"{value:.0f}" if exact else f"more than {value:g}"


def odds_sentences(odds: dict, n_label: str = "seeds") -> list[str]:
    """One sentence per tallied claim, from its numbers: 'It holds in 7 of 20 seeds (35%, 95%
    interval 18-57%): undecided.'"""
    from ._common import percents, verdict

    out = []
    for claim, cell in odds.items():
        rate, low, high = percents(cell["k"] / cell["n"], cell["low"], cell["high"])
        out.append(
            f'"{claim}" holds in {cell["k"]} of {cell["n"]} {n_label} ({rate}%, 95% interval {low}-{high}%): '
            f"{verdict(cell)}."
        )
    return out


def comparison_main(
    argv, *, module: str, doc: str, name: str, run, seed_unit, format_table, plot, add_options=None, options=None
) -> int:
    """``main`` of a comparison experiment: the run of ``--seed`` (tables, figures) and the claims
    over ``--seeds`` seeds, each seed a unit of the shared runner (``OUT/<name>-seeds.jsonl``).

    ``add_options(parser)`` adds the experiment's own options; ``options(args)`` turns them
    into keyword arguments of ``run`` and ``seed_unit`` (it may raise before anything is written).
    """
    from ._common import (
        experiment_parser,
        prepare_out,
        run_outputs,
        run_seed_units,
        run_stem,
        save_outputs,
        seed_list,
        tally,
    )

    parser = experiment_parser(module, doc, name)
    if add_options is not None:
        add_options(parser)
    args = parser.parse_args(argv)
    kwargs = options(args) if options is not None else {}
    seeds = seed_list(args.seed, args.seeds, args.quick)  # (checked before the output folder is made)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, **kwargs)
    records = run_seed_units(
        seed_unit,
        seeds,
        out / f"{run_stem(f'{name}-seeds', args.quick)}.jsonl",
        quick=args.quick,
        scheduler=args.scheduler,
        workers=args.workers,
        desc=f"{name} seeds",
        **kwargs,
    )
    result.update(seeds=seeds, per_seed=records, odds=tally([r["claims"] for r in records]))
    with run_outputs(out, name, quick=args.quick) as stage:
        save_outputs(stage, name, format_table(result), result)
        plot(result, stage)
    return 0


def error_at(methods: dict, iteration: int) -> dict:
    """Each method's alignment error after ``iteration`` iterations (its last one if it stopped earlier)."""
    return {name: m["errors"][min(iteration, len(m["errors"]) - 1)] for name, m in methods.items()}


def format_comparison(methods: dict, *, at=()) -> list[str]:
    if at:
        lines = [
            "Alignment error |X - T(Y)| after a number of iterations:",
            f"{'method':>12}" + "".join(f"{f'it. {k}':>10}" for k in at) + f"{'final':>10}",
        ]
        for name, m in methods.items():
            lines.append(
                f"{name:>12}"
                + "".join(f"{error_at(methods, k)[name]:>10.3f}" for k in at)
                + f"{m['final_error']:>10.3f}"
            )
    else:
        lines = []
    lines += [
        "Iterations until |X - T(Y)| falls below a share of its initial value, and to convergence:",
        f"{'method':>12}"
        + "".join(f"{f'<= {100 * lv:g}%':>10}" for lv in LEVELS)
        + f"{'stopped at':>12}{'final error':>13}",
    ]
    for name, m in methods.items():
        cells = "".join(f"{'-' if m['below'][str(lv)] is None else m['below'][str(lv)]:>10}" for lv in LEVELS)
        done = f"{m['n_iter']}" + ("" if m["converged"] else "*")
        lines.append(f"{name:>12}{cells}{done:>12}{m['final_error']:>13.3e}")
    lines.append("(* stopped at max_iter without meeting the tolerance)")
    return lines


def plot_comparison(
    methods: dict, fixed, folder, *, curve_name, snap_name, snapshots, curve_title, snap_title, max_iter_shown=None
):
    """Error curves (``curve_name``) and snapshots (``snap_name``) as PNG files in ``folder``."""
    from ..plotting import plot_alignment_errors, plot_registration_snapshots, save_figure
    from ._common import new_figure

    folder = Path(folder)
    labels = {name: (name if name == "CPD" else name.capitalize()) for name in methods}
    cut = slice(None) if max_iter_shown is None else slice(0, max_iter_shown + 1)
    errors = {labels[name]: m["errors"][cut] for name, m in methods.items()}
    ax = new_figure(figsize=(5, 3.5)).subplots()
    plot_alignment_errors(errors, ax=ax, title=curve_title)
    first = save_figure(ax.figure, folder / curve_name)
    snaps = {labels[name]: {int(k): np.asarray(v) for k, v in m["snapshots"].items()} for name, m in methods.items()}
    fig = new_figure(figsize=(2.6 * len(methods), 0.6 + 2.6 * len(snapshots)))
    plot_registration_snapshots(np.asarray(fixed), snaps, iterations=snapshots, fig=fig, title=snap_title)
    return [first, save_figure(fig, folder / snap_name)]
