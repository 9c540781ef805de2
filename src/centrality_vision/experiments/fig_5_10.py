"""Thesis fig. 5.10: one sample point set of each of the five classes of Table 5.1.

Set ``--index`` (0-98) of each class (:func:`centrality_vision.experiments.table_5_1.make_set`,
the sets Table 5.1 registers, drawn with the same seed 0 of that experiment) with its
Delaunay graph, the data-graph GPD uses.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

__all__ = ["run", "format_table", "explain", "plot", "main"]


def run(*, quick: bool = False, seed: int = 0, index: int = 0) -> dict:
    """Set ``index`` of each class of Table 5.1 under the experiment's ``seed``."""
    from .._validation import check_int
    from ._common import check_run
    from .table_5_1 import CLASSES, N_POINTS, SETS_PER_CLASS, make_set

    quick, seed = check_run(quick, seed)
    index = check_int(index, name="index", low=0, high=SETS_PER_CLASS - 1)
    n_points = 40 if quick else N_POINTS
    sets = {kind: make_set(kind, index, seed=seed, n_points=n_points) for kind in CLASSES}
    return {"seed": seed, "index": index, "quick": quick, "sets": {k: v.tolist() for k, v in sets.items()}}


def format_table(result: dict) -> str:
    lines = [f"Set {result['index']} of each class (Table 5.1's seed {result['seed']}): points, extent"]
    for kind, pts in result["sets"].items():
        p = np.asarray(pts)
        lines.append(f"{kind:>8}{p.shape[0]:>6} points, extent {np.ptp(p, axis=0).max():.2f}")
    return "\n".join(lines)


def explain(result: dict) -> str:
    counts = {k: len(v) for k, v in result["sets"].items()}
    return (
        "The thesis shows one sample per class without its point counts; ours (the sets Table 5.1 registers) have "
        + ", ".join(f"{k} {n}" for k, n in counts.items())
        + " points. A picture: nothing to check."
    )


def plot(result: dict, path) -> Path:
    from ..graphs import delaunay_graph
    from ..plotting import plot_graph, save_figure
    from ._common import new_figure

    fig = new_figure(figsize=(3.2 * len(result["sets"]), 3.4))
    axes = fig.subplots(1, len(result["sets"]))
    for ax, (kind, pts) in zip(axes, result["sets"].items()):
        p = np.asarray(pts)
        plot_graph(p, delaunay_graph(p), ax=ax, node_size=8, colorbar=False, title=kind)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle("One point set of each class of Table 5.1, with its Delaunay graph (thesis fig. 5.10)")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    from ._common import experiment_parser, int_in, prepare_out, run_outputs, save_outputs
    from .table_5_1 import SETS_PER_CLASS

    parser = experiment_parser(
        "fig_5_10",
        __doc__,
        "fig-5.10",
        quick_help="40 points per set, as table-5.1 --quick",
        seed_help="Table 5.1's seed (default: %(default)s); a picture, nothing to check over seeds",
        seeds=False,
    )
    parser.add_argument(
        "--index",
        type=int_in(0, SETS_PER_CLASS - 1),
        default=0,
        help=f"which set of each class, 0-{SETS_PER_CLASS - 1} (default: %(default)s)",
    )
    args = parser.parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, index=args.index)
    with run_outputs(out, "fig-5.10", quick=args.quick) as stage:
        save_outputs(stage, "fig-5.10", format_table(result), result)
        plot(result, stage / "fig-5.10.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ._common import command_line

    sys.exit(command_line(main))
