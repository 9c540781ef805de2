"""Thesis Table 2.1: degree, closeness, betweenness and eigenvector centrality of a 6-node graph.

The thesis prints the table, not the graph's edge list; these edges give the printed degrees
and reproduce every value of the table: edges a-b, b-c, b-d, b-e, c-d, c-f, d-e, e-f. We print our
values beside the thesis' (to two decimals) and draw the graph coloured by each centrality.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ._common import claim_lines, experiment_parser, prepare_out, run_outputs, save_outputs

__all__ = ["NODES", "EDGES", "THESIS", "graph", "run", "format_table", "explain", "plot", "main"]

NODES = "abcdef"
EDGES = ("ab", "bc", "bd", "be", "cd", "cf", "de", "ef")
THESIS = {
    "degree": (1, 4, 3, 3, 3, 2),
    "closeness": (0.50, 0.83, 0.71, 0.71, 0.71, 0.56),
    "betweenness": (0.00, 4.33, 1.50, 0.33, 1.50, 0.33),
    "eigenvector": (0.34, 1.00, 0.85, 0.91, 0.85, 0.57),
}
# a drawing of the graph (positions only matter for the figure)
POSITIONS = np.array([[0.0, 1.0], [1.0, 1.0], [2.0, 2.0], [2.0, 1.0], [2.0, 0.0], [3.0, 1.0]])


def graph():
    """The Table 2.1 graph as a symmetric CSR adjacency (unit edge lengths)."""
    from scipy import sparse

    rows = [NODES.index(e[0]) for e in EDGES]
    cols = [NODES.index(e[1]) for e in EDGES]
    upper = sparse.coo_array((np.ones(len(EDGES)), (rows, cols)), shape=(6, 6))
    return sparse.csr_array(upper + upper.T)


def run(*, quick: bool = False, seed: int = 0) -> dict:
    from ..centrality import compute
    from ._common import check_run

    quick, seed = check_run(quick, seed)

    g = graph()
    ours = {name: compute(g, name).tolist() for name in THESIS}
    match = {
        name: bool(np.array_equal(np.round(ours[name], 2), np.asarray(THESIS[name], dtype=float))) for name in THESIS
    }
    return {
        "nodes": list(NODES),
        "edges": list(EDGES),
        "ours": ours,
        "thesis": {k: list(v) for k, v in THESIS.items()},
        "seed": seed,
        "claims": {f"{name} equals Table 2.1 to two decimals": ok for name, ok in match.items()},
    }


def format_table(result: dict) -> str:
    lines = ["Table 2.1 (each cell: ours | thesis)", f"{'node':>12}" + "".join(f"{n:>14}" for n in result["nodes"])]
    for name, values in result["ours"].items():
        lines.append(
            f"{name:>12}" + "".join(f"{f'{v:.2f} | {t:.2f}':>14}" for v, t in zip(values, result["thesis"][name]))
        )
    lines += claim_lines(result["claims"])
    return "\n".join(lines)


def explain(result: dict) -> str:
    """The report's paragraph, written from ``result``'s numbers."""
    ours, thesis = result["ours"], result["thesis"]
    worst = max(abs(round(v, 2) - t) for name in ours for v, t in zip(ours[name], thesis[name]))
    equal = [name for name, ok in zip(ours, result["claims"].values()) if ok]
    differ = [name for name in ours if name not in equal]
    text = f"{len(equal)} of {len(ours)} centralities equal the thesis' table to two decimals"
    text += f" ({', '.join(equal)})" if equal else ""
    text += f"; {', '.join(differ)} differ" if differ else ""
    return (
        text + f"; the largest difference after rounding is {worst:.2f}. The graph has no random part: one run decides."
    )


def plot(result: dict, path) -> Path:
    from ..plotting import plot_graph, save_figure
    from ._common import new_figure

    fig = new_figure(figsize=(14, 3.2))
    axes = fig.subplots(1, 4)
    g = graph()
    for ax, (name, values) in zip(axes, result["ours"].items()):
        plot_graph(POSITIONS, g, np.asarray(values), ax=ax, title=name)
        for i, label in enumerate(result["nodes"]):
            ax.annotate(label, POSITIONS[i], xytext=(4, 4), textcoords="offset points")
    fig.suptitle("Thesis Table 2.1: the four centralities of the 6-node graph")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    args = experiment_parser(
        "table_2_1",
        __doc__,
        "table-2.1",
        quick_help="the same (the experiment is instant)",
        seed_help="recorded; nothing is random",
        seeds=False,
    ).parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed)
    with run_outputs(out, "table-2.1", quick=args.quick) as stage:
        save_outputs(stage, "table-2.1", format_table(result), result)
        plot(result, stage / "table-2.1.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ._common import command_line

    sys.exit(command_line(main))
