"""Thesis 6.5 and fig. 6.4: matching point sets by the degrees of their MWME graphs.

For every Kimia-99 silhouette, 50 points sampled along its outline are moved by a random
similarity transform (rotation in [0, 2 pi), scale in [0.5, 2], translation in [-100, 100]^2),
shuffled, and matched back to the original with :func:`centrality_vision.matching.mwme_match`.
Accuracy is the share of points matched to their true partner. Then Gaussian noise of
standard deviation sigma * eps (eps: the smallest distance between two sample points) is
added to the moved points, to show how the matching degrades.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ._common import claim_lines, experiment_parser, prepare_out, save_outputs

__all__ = ["NOISE", "run", "format_table", "plot", "main"]

NOISE = (0.0, 0.01, 0.05, 0.1, 0.25, 0.5)
N_POINTS = 50


def _random_similarity(points, rng):
    angle = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return rng.uniform(0.5, 2.0) * points @ rot.T + rng.uniform(-100, 100, size=2)


def match_image(index: int, seed: int, method: str, noise) -> list:
    """One runner unit: matching accuracy of image ``index`` at each noise level."""
    from scipy.spatial.distance import pdist

    from ..datasets import contour_points, load_kimia99
    from ..matching import mwme_match

    fixed = contour_points(load_kimia99().images[index], N_POINTS)
    eps = float(pdist(fixed).min())
    accuracy = []
    for col, sigma in enumerate(noise):
        rng = np.random.default_rng([seed, index, col])
        perm = rng.permutation(N_POINTS)
        moved = _random_similarity(fixed[perm], rng)
        moved = moved + rng.normal(0.0, sigma * eps, size=moved.shape) if sigma else moved
        correspondence, _ = mwme_match(moved, fixed, method=method)
        accuracy.append(float(np.mean(correspondence == perm)))
    return accuracy


def run(
    *, quick: bool = False, seed: int = 0, method: str = "local", progress: bool = True, out=None,
    scheduler: str = "processes", workers=None,
) -> dict:
    """Matching accuracy per image and noise level; ``quick`` uses every 11th image.

    Each image is a unit of the shared runner, kept in ``out/fig-6.4[-quick].jsonl`` (a
    temporary file when ``out`` is None).
    """
    import tempfile

    from ..datasets import load_kimia99
    from ._runner import Unit, run_units

    data = load_kimia99()
    index = list(range(0, len(data), 11)) if quick else list(range(len(data)))
    noise = NOISE[:3] if quick else NOISE
    started = time.perf_counter()
    units = [Unit(f"{i:02d}", match_image, {"index": i, "seed": seed, "method": method, "noise": list(noise)}) for i in index]
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        path = folder / ("fig-6.4-quick.jsonl" if quick else "fig-6.4.jsonl")
        done = run_units(units, path, scheduler=scheduler, workers=workers, progress=progress, desc="mwme matching")
    accuracy = np.array([done[f"{i:02d}"] for i in index])
    return {
        "names": [str(data.names[i]) for i in index],
        "noise": list(noise),
        "accuracy": accuracy.tolist(),
        "mean_accuracy": accuracy.mean(axis=0).tolist(),
        "seed": seed,
        "method": method,
        "n_points": N_POINTS,
        "seconds": time.perf_counter() - started,
        "claims": {"mwme_match recovers >= 95% of correspondences without noise": float(accuracy[:, 0].mean()) >= 0.95},
    }


def format_table(result: dict) -> str:
    acc = np.asarray(result["accuracy"])
    lines = [
        f"MWME matching of {acc.shape[0]} Kimia-99 outlines, {result['n_points']} points each, method={result['method']}, seed={result['seed']}",
        f"{'noise sigma / eps':>18}{'mean':>8}{'median':>8}{'worst':>8}{'all correct':>13}",
    ]
    for j, sigma in enumerate(result["noise"]):
        col = acc[:, j]
        lines.append(f"{sigma:>18.2f}{col.mean():>8.3f}{np.median(col):>8.3f}{col.min():>8.3f}{np.mean(col == 1.0):>13.2f}")
    lines += claim_lines(result["claims"])
    return "\n".join(lines)


def plot(result: dict, path, *, example: str = "cow1", seed: int = 0) -> Path:
    """An example matching (fig. 6.4) and the accuracy against noise."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..datasets import contour_points, load_kimia99
    from ..graphs import mwme_graph
    from ..matching import mwme_match
    from ..plotting import plot_matching, save_figure

    fixed = contour_points(load_kimia99().image(example), N_POINTS)[:, ::-1] * [1, -1]
    rng = np.random.default_rng(seed)
    moved = _random_similarity(fixed[rng.permutation(N_POINTS)], rng)
    correspondence, _ = mwme_match(moved, fixed, method=result["method"])
    fig, (left, right) = plt.subplots(1, 2, figsize=(14, 5), gridspec_kw={"width_ratios": [2, 1]})
    plot_matching(
        moved, fixed, correspondence,
        moving_graph=mwme_graph(moved, method=result["method"]).graph,
        fixed_graph=mwme_graph(fixed, method=result["method"]).graph,
        ax=left, title=f"{example}: MWME graphs and matches (thesis fig. 6.4)",
    )
    acc = np.asarray(result["accuracy"])
    right.errorbar(result["noise"], acc.mean(axis=0), yerr=acc.std(axis=0), marker="o", capsize=3)
    right.set_xlabel("noise sigma (multiples of eps)")
    right.set_ylabel("share of correct matches")
    right.set_ylim(0, 1.05)
    right.set_title("accuracy over all outlines")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    parser = experiment_parser("fig_6_4", __doc__, "fig-6.4", runner=True)
    parser.add_argument("--method", choices=("local", "greedy"), default="local")
    args = parser.parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, method=args.method, out=out, scheduler=args.scheduler, workers=args.workers)
    save_outputs(out, "fig-6.4", format_table(result), result)
    plot(result, out / "fig-6.4.png", seed=args.seed)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
