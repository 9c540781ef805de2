"""Thesis fig. 7.1: the Euclidean MST against the MSTME on five points.

The points (0,0), (1,0), (0,1), (-1,0), (0,-1) with raw Euclidean weights: the MST is the
star (weight 4, degree entropy 0.72 bits), while at lambda = 1 the MSTME has degrees
(3, 2, 1, 1, 1), weight 3 + sqrt 2 = 4.41, entropy 1.37 and cost 3.04 < 4 - 0.72. We check
the greedy Algorithm 7.1 against an exhaustive search over all 125 spanning trees (Cayley),
print both beside the thesis and draw the three graphs of the figure (MST, MSTME, Delaunay).
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np

from ._common import claim_lines, experiment_parser, prepare_out, run_outputs, save_outputs

__all__ = ["POINTS", "run", "claims", "explain", "format_table", "plot", "main"]

POINTS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
LAM = 1.0
THESIS = {"mst": {"weight": 4.0, "entropy": 0.72}, "mstme": {"weight": 4.41, "entropy": 1.37, "cost": 3.04}}


def _entropy(degrees) -> float:
    _, counts = np.unique(degrees, return_counts=True)
    p = counts / counts.sum()
    return float(-(p * np.log2(p)).sum())


def _is_tree(n: int, edges) -> bool:
    """n - 1 edges form a spanning tree iff they close no cycle (union-find)."""
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra == rb:
            return False
        parent[ra] = rb
    return True


def exhaustive(points: np.ndarray, lam: float) -> dict:
    """The best spanning tree by brute force over all edge subsets of size n - 1 (tiny n only)."""
    n = len(points)
    pairs = list(itertools.combinations(range(n), 2))
    best = None
    for edges in itertools.combinations(pairs, n - 1):
        if not _is_tree(n, edges):
            continue
        degrees = np.bincount(np.asarray(edges).ravel(), minlength=n)
        weight = float(sum(np.linalg.norm(points[a] - points[b]) for a, b in edges))
        cost = weight - lam * _entropy(degrees)
        if best is None or cost < best["cost"] - 1e-12:
            best = {
                "edges": [list(e) for e in edges],
                "weight": weight,
                "entropy": _entropy(degrees),
                "cost": cost,
                "degrees": sorted(degrees.tolist(), reverse=True),
            }
    return best


def run(*, quick: bool = False, seed: int = 0) -> dict:
    from ..centrality import degree
    from ..graphs import mstme_graph
    from ._common import check_run

    quick, seed = check_run(quick, seed)

    mst = mstme_graph(POINTS, lam=0.0, normalize="none")
    greedy = mstme_graph(POINTS, lam=LAM, normalize="none")
    brute = exhaustive(POINTS, LAM)

    def record(result):
        return {
            "weight": result.weight,
            "entropy": result.entropy,
            "cost": result.cost,
            "degrees": sorted(degree(result.graph).astype(int).tolist(), reverse=True),
        }

    # every tree's cost under the figure's lambda (mst.cost is the plain tree's, at lambda 0)
    ours = {"mst": record(mst) | {"cost": mst.weight - LAM * mst.entropy}, "mstme": record(greedy), "exhaustive": brute}
    result = {"points": POINTS.tolist(), "lam": LAM, "ours": ours, "thesis": THESIS, "seed": seed}
    result["claims"] = claims(result)
    result["explanation"] = explain(result)
    return result


def claims(result: dict) -> dict:
    """The figure's numbers, checked against ours (two decimals, as the thesis prints them)."""
    ours, thesis = result["ours"], result["thesis"]
    mst, tree = ours["mst"], ours["mstme"]
    return {
        "the MST is the star: weight 4, H = 0.72": bool(
            round(mst["weight"], 2) == thesis["mst"]["weight"] and round(mst["entropy"], 2) == thesis["mst"]["entropy"]
        ),
        "the greedy MSTME has degrees (3, 2, 1, 1, 1), weight 4.41, H 1.37, cost 3.04": bool(
            tree["degrees"] == [3, 2, 1, 1, 1]
            and [round(tree[k], 2) for k in ("weight", "entropy", "cost")]
            == [thesis["mstme"][k] for k in ("weight", "entropy", "cost")]
        ),
        "the greedy MSTME is the exhaustive optimum": bool(abs(tree["cost"] - ours["exhaustive"]["cost"]) < 1e-9),
    }


def explain(result: dict) -> str:
    """What the figure shows, computed from ``result``."""
    mst, tree, brute = result["ours"]["mst"], result["ours"]["mstme"], result["ours"]["exhaustive"]
    lam = result["lam"]
    return (
        f"With raw weights and lambda = {lam:g}, the MST (weight {mst['weight']:.2f}, H {mst['entropy']:.2f}, "
        f"cost {mst['cost']:.2f}) loses to a tree {tree['weight'] - mst['weight']:.2f} longer "
        f"whose degrees {tuple(tree['degrees'])} are more diverse (H {tree['entropy']:.2f}, cost {tree['cost']:.2f}); "
        f"the greedy Algorithm 7.1 finds it and it is the best of all 125 spanning trees "
        f"(exhaustive cost {brute['cost']:.2f})."
    )


def format_table(result: dict) -> str:
    o, t = result["ours"], result["thesis"]
    lines = [
        f"Fig. 7.1: five points, raw Euclidean weights, lambda = {result['lam']} (ours | thesis)",
        f"{'tree':>12}{'weight':>16}{'entropy':>16}{'cost':>16}  degrees",
        f"{'MST':>12}{o['mst']['weight']:>9.2f} | {t['mst']['weight']:.2f}"
        f"{o['mst']['entropy']:>9.2f} | {t['mst']['entropy']:.2f}{o['mst']['cost']:>16.2f}  {o['mst']['degrees']}",
        f"{'MSTME':>12}{o['mstme']['weight']:>9.2f} | {t['mstme']['weight']:.2f}{o['mstme']['entropy']:>9.2f} | "
        f"{t['mstme']['entropy']:.2f}{o['mstme']['cost']:>9.2f} | {t['mstme']['cost']:.2f}  {o['mstme']['degrees']}",
        f"{'exhaustive':>12}{o['exhaustive']['weight']:>16.2f}{o['exhaustive']['entropy']:>16.2f}"
        f"{o['exhaustive']['cost']:>16.2f}  {o['exhaustive']['degrees']}",
    ]
    lines += claim_lines(result["claims"])
    lines += ["", result.get("explanation") or explain(result)]
    return "\n".join(lines)


def plot(result: dict, path) -> Path:
    from matplotlib.figure import Figure

    from ..graphs import delaunay_graph, mstme_graph
    from ..plotting import plot_graph, save_figure

    fig = Figure(figsize=(10, 3.4))
    axes = fig.subplots(1, 3)
    o = result["ours"]
    graphs = (
        (mstme_graph(POINTS, lam=0.0, normalize="none").graph, f"MST: H = {o['mst']['entropy']:.2f}"),
        (mstme_graph(POINTS, lam=LAM, normalize="none").graph, f"MSTME: H = {o['mstme']['entropy']:.2f}"),
        (delaunay_graph(POINTS), "Delaunay"),
    )
    for ax, (g, title) in zip(axes, graphs):
        plot_graph(POINTS, g, ax=ax, title=title)
    fig.suptitle("Thesis fig. 7.1")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    args = experiment_parser(
        "fig_7_1",
        __doc__,
        "fig-7.1",
        quick_help="the same (the experiment is instant)",
        seed_help="recorded; nothing is random",
        seeds=False,
    ).parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed)
    with run_outputs(out, "fig-7.1", quick=args.quick) as stage:
        save_outputs(stage, "fig-7.1", format_table(result), result)
        plot(result, stage / "fig-7.1.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ._common import command_line

    sys.exit(command_line(main))
