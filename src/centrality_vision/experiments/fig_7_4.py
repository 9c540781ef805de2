"""Thesis 7.3 and figs. 7.3-7.5: how stable are data-graphs when the points move a little?

Protocol (SPEC section 5): eps is the smallest distance between two points of a set. At
noise level r (1..10) every point moves by a uniform random angle and a uniform random
radius in [0, r eps]. A batch is 30 perturbed copies; the stable share of a data-graph is
the fraction of the unperturbed graph's edges present in all 30 perturbed graphs. Repeated
batches give the boxplots of fig. 7.4. Data: the CPD fish and 100-point contour samples of
the Kimia-99 silhouettes cow1 and dog1 (the thesis' examples). Graphs: MSTME (lambda 0.5,
weights divided by the mean MST edge), Delaunay, Gabriel and the Euclidean MST.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ._common import claim_lines, experiment_parser, prepare_out, save_outputs

__all__ = ["GRAPHS", "DATASETS", "perturb", "stable_share", "run", "format_table", "plot_boxplots", "plot_perturbed", "main"]

DATASETS = ("fish", "cow1", "dog1")
GRAPHS = ("mstme", "delaunay", "gabriel", "emst")
N_CONTOUR = 100


def _builders():
    from ..graphs import delaunay_graph, emst_graph, gabriel_graph, mstme_graph

    return {
        "mstme": lambda p: mstme_graph(p, lam=0.5).graph,
        "delaunay": delaunay_graph,
        "gabriel": gabriel_graph,
        "emst": emst_graph,
    }


def load_points(name: str) -> np.ndarray:
    """The fish (fixed set) or a contour sample of a Kimia-99 silhouette."""
    from ..datasets import contour_points, load_fish, load_kimia99

    if name == "fish":
        return load_fish().fixed
    return contour_points(load_kimia99().image(name), N_CONTOUR)


def perturb(points: np.ndarray, radius: float, rng: np.random.Generator) -> np.ndarray:
    """Move every 2D point by a uniform angle and a uniform distance in [0, radius]."""
    angle = rng.uniform(0.0, 2.0 * np.pi, size=points.shape[0])
    step = rng.uniform(0.0, radius, size=points.shape[0])
    return points + np.stack([step * np.cos(angle), step * np.sin(angle)], axis=1)


def _edges(graph) -> set:
    from scipy import sparse

    coo = sparse.triu(graph, k=1).tocoo()
    return set(zip(coo.row.tolist(), coo.col.tolist()))


def stable_share(points, build, radius, n_copies, rng) -> float:
    """Share of the unperturbed graph's edges present in all ``n_copies`` perturbed graphs."""
    reference = _edges(build(points))
    kept = set(reference)
    for _ in range(n_copies):
        kept &= _edges(build(perturb(points, radius, rng)))
    return len(kept) / len(reference)


def stability_batch(name: str, d: int, level: int, batch: int, seed: int, n_copies: int) -> dict:
    """One runner unit: the stable share of every graph for batch ``batch`` of ``level``."""
    from scipy.spatial.distance import pdist

    points = load_points(name)
    eps = float(pdist(points).min())
    builders = _builders()
    out = {}
    for g in GRAPHS:
        rng = np.random.default_rng([seed, d, level, batch])  # same sets for every graph
        out[g] = stable_share(points, builders[g], level * eps, n_copies, rng)
    return out


def run(
    *, quick: bool = False, seed: int = 0, n_batches: int | None = None, n_copies: int = 30, progress: bool = True,
    out=None, scheduler: str = "processes", workers=None,
) -> dict:
    """Stable shares per dataset, graph, noise level and batch.

    Returns a dict with ``shares[dataset][graph]`` of shape (n_levels, n_batches), the
    levels, eps per dataset, and the parameters. Batch ``b`` of level ``r`` of dataset
    ``d`` uses ``default_rng([seed, d, r, b])`` for all graphs, so every graph sees the
    same perturbed sets. Each batch is a unit of the shared runner, kept in
    ``out/fig-7.4[-quick].jsonl`` (a temporary file when ``out`` is None).
    """
    import tempfile

    from scipy.spatial.distance import pdist

    from ._runner import Unit, run_units

    levels = (1, 5, 10) if quick else tuple(range(1, 11))
    n_batches = n_batches or (3 if quick else 10)
    n_copies = 10 if quick else n_copies
    started = time.perf_counter()
    result = {"levels": list(levels), "n_batches": n_batches, "n_copies": n_copies, "seed": seed, "eps": {}, "shares": {}}
    units = [
        Unit(f"{name}/{level}/{b}", stability_batch, {"name": name, "d": d, "level": level, "batch": b, "seed": seed, "n_copies": n_copies})
        for d, name in enumerate(DATASETS) for level in levels for b in range(n_batches)
    ]
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        path = folder / ("fig-7.4-quick.jsonl" if quick else "fig-7.4.jsonl")
        done = run_units(units, path, scheduler=scheduler, workers=workers, progress=progress, desc="stability")
    for name in DATASETS:
        result["eps"][name] = float(pdist(load_points(name)).min())
        result["shares"][name] = {
            g: [[done[f"{name}/{level}/{b}"][g] for b in range(n_batches)] for level in levels] for g in GRAPHS
        }
    result["seconds"] = time.perf_counter() - started
    result["parameters"] = {
        "mstme": "lam=0.5, normalize=True (weights / mean MST edge length), greedy Algorithm 7.1",
        "contour_points": N_CONTOUR,
        "perturbation": "uniform angle, uniform radius in [0, level * eps]",
        "quick": quick,
    }
    fish = result["shares"]["fish"]
    first = {g: float(np.median(fish[g][0])) for g in GRAPHS}
    result["claims"] = {"MSTME (lam 0.5) is more stable than Delaunay at 1 eps on the fish": first["mstme"] > first["delaunay"]}
    return result


def format_table(result: dict) -> str:
    """Median stable share per dataset, graph and noise level."""
    levels = result["levels"]
    lines = [f"median share of edges kept in all {result['n_copies']} perturbed graphs, {result['n_batches']} batches, seed={result['seed']}"]
    head = f"{'set':<6}{'graph':<10}" + "".join(f"{f'{r} eps':>8}" for r in levels)
    lines += [head, "-" * len(head)]
    for name, per_graph in result["shares"].items():
        for g, values in per_graph.items():
            med = np.median(np.asarray(values), axis=1)
            lines.append(f"{name:<6}{g:<10}" + "".join(f"{m:>8.2f}" for m in med))
    lines.append("thesis (fig. 7.4): MSTME more stable than Delaunay on fish and cow1.")
    lines += claim_lines(result["claims"])
    return "\n".join(lines)


def plot_boxplots(result: dict, path) -> Path:
    """Fig. 7.4: boxplots of the stable share against the noise level, a panel per set."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    names = list(result["shares"])
    levels = result["levels"]
    fig, axes = plt.subplots(1, len(names), figsize=(5.5 * len(names), 4), squeeze=False)
    colours = dict(zip(GRAPHS, ["tab:red", "tab:blue", "tab:green", "tab:gray"]))
    width = 0.8 / len(GRAPHS)
    for ax, name in zip(axes[0], names):
        for k, g in enumerate(GRAPHS):
            data = np.asarray(result["shares"][name][g])
            pos = np.arange(len(levels)) + (k - (len(GRAPHS) - 1) / 2) * width
            box = ax.boxplot(data.T, positions=pos, widths=width * 0.9, patch_artist=True, showfliers=False)
            for patch in box["boxes"]:
                patch.set_facecolor(colours[g])
                patch.set_alpha(0.6)
        ax.set_xticks(np.arange(len(levels)), [str(r) for r in levels])
        ax.set_xlabel("noise level (multiples of eps)")
        ax.set_ylabel("share of stable edges")
        ax.set_title(name)
        ax.set_ylim(0, 1.02)
    handles = [plt.Rectangle((0, 0), 1, 1, color=colours[g], alpha=0.6) for g in GRAPHS]
    axes[0, -1].legend(handles, GRAPHS, loc="upper right")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_perturbed(name: str, level: int, path, *, seed: int = 0, n_copies: int = 30) -> Path:
    """Figs. 7.3/7.5: perturbed graphs drawn over each other, stable edges in black."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from scipy.spatial.distance import pdist

    from ..plotting import save_figure

    points = load_points(name)
    eps = float(pdist(points).min())
    builders = _builders()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    for ax, g in zip(axes, ("mstme", "delaunay")):
        rng = np.random.default_rng([seed, level])
        reference = _edges(builders[g](points))
        kept = set(reference)
        for _ in range(n_copies):
            moved = perturb(points, level * eps, rng)
            edges = _edges(builders[g](moved))
            kept &= edges
            ax.add_collection(LineCollection([moved[[i, j]][:, ::-1] for i, j in edges], colors="tab:orange", alpha=0.08, linewidths=0.6))
        ax.add_collection(LineCollection([points[[i, j]][:, ::-1] for i, j in kept], colors="black", linewidths=1.2))
        ax.scatter(points[:, 1], points[:, 0], s=6, color="black")
        ax.set_title(f"{name}, {g}: {len(kept)}/{len(reference)} edges stable at {level} eps")
        ax.set_aspect("equal")
        ax.invert_yaxis()
        ax.autoscale_view()
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    args = experiment_parser("fig_7_4", __doc__, "fig-7.4", quick_help="3 levels, 3 batches of 10 copies", runner=True).parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, out=out, scheduler=args.scheduler, workers=args.workers)
    save_outputs(out, "fig-7.4", format_table(result), result)
    plot_boxplots(result, out / "fig-7.4.png")
    plot_perturbed("fish", 3, out / "fig-7.3-fish.png", seed=args.seed, n_copies=result["n_copies"])
    plot_perturbed("cow1", 3, out / "fig-7.5-cow1.png", seed=args.seed, n_copies=result["n_copies"])
    print(f"wrote {out}/ ({result['seconds']:.0f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
