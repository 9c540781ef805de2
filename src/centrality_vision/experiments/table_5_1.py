"""Thesis 5.4.5, Tables 5.1-5.3: rigid registration of 495 point sets, CPD against GPD.

Five classes of 99 point sets each (SPEC section 7): Gaussian clusters, uniform random,
Gaussian, the outline of a Kimia-99 silhouette and a grid sampled inside it (set i of the
two last classes comes from Kimia-99 image i). Each set Y is registered to a rigidly moved
copy X = R Y + t by rigid CPD and by GPD (Delaunay graphs) with each of the four
centralities. The thesis leaves three choices open; ours, fixed and written into the output:

- point counts: ``N_POINTS`` per set (the grid class keeps every lattice point inside the
  silhouette, spacing chosen for about that many);
- rotation: uniform in [-ROTATION_DEG, ROTATION_DEG]; translation uniform in
  [-0.25, 0.25] x the set's extent per axis;
- convergence: the registration stops by its own test (relative change of the objective
  below ``TOL``, or sigma2 at the floor of coinciding sets) within ``MAX_ITER`` iterations
  AND ends within ``1e-3`` x the extent of the true alignment (RMS). Iterations are counted
  over the sets that converged (Tables 5.1 and 5.2), as in the thesis.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ._common import claim_lines, experiment_parser, prepare_out, save_outputs

__all__ = ["CLASSES", "METHODS", "make_set", "register_set", "run", "format_table", "plot", "main"]

CLASSES = ("cluster", "random", "normal", "contour", "grid")
METHODS = ("betweenness", "closeness", "degree", "eigenvector", "CPD")
N_POINTS = 100
ROTATION_DEG = 60.0
TOL = 1e-6
MAX_ITER = 150
SUCCESS_RMS = 1e-3  # x extent

# Thesis Tables 5.1 (mean), 5.2 (standard deviation), 5.3 (% converged); columns B C D E CPD.
THESIS = {
    "mean": {
        "cluster": (42.72, 22.72, 53.67, 41.95, 60.56),
        "random": (19.94, 15.20, 30.46, 14.56, 37.25),
        "normal": (36.72, 22.08, 50.45, 37.20, 51.54),
        "contour": (23.82, 17.68, 28.49, 20.49, 26.39),
        "grid": (32.60, 26.31, 31.23, 24.71, 34.29),
    },
    "std": {
        "cluster": (4.36, 1.26, 19.89, 17.15, 3.91),
        "random": (1.94, 1.21, 15.97, 0.96, 3.90),
        "normal": (9.33, 3.37, 20.47, 18.22, 13.82),
        "contour": (3.74, 3.66, 5.03, 8.99, 4.27),
        "grid": (18.39, 17.28, 21.08, 13.41, 13.05),
    },
    "converged": {
        "cluster": (100, 100, 81, 86, 100),
        "random": (100, 100, 55, 100, 100),
        "normal": (100, 100, 75, 86, 100),
        "contour": (100, 100, 90, 95, 100),
        "grid": (95, 69, 35, 77, 100),
    },
}


def _unit_extent(points: np.ndarray) -> np.ndarray:
    points = points - points.mean(axis=0)
    return points / np.ptp(points, axis=0).max()


def _kimia_mask(index: int) -> np.ndarray:
    from ..datasets import load_kimia99

    return load_kimia99().images[index]


def make_set(kind: str, index: int, *, seed: int = 0, n_points: int = N_POINTS) -> np.ndarray:
    """Point set ``index`` (0-98) of class ``kind``, centred, extent 1 (deterministic)."""
    rng = np.random.default_rng([seed, CLASSES.index(kind), index])
    if kind == "cluster":
        k = int(rng.integers(3, 7))
        centres = rng.uniform(0, 1, (k, 2))
        which = rng.integers(0, k, n_points)
        pts = centres[which] + rng.normal(0, 0.05, (n_points, 2))
    elif kind == "random":
        pts = rng.uniform(0, 1, (n_points, 2))
    elif kind == "normal":
        pts = rng.normal(0, 1, (n_points, 2))
    elif kind == "contour":
        from ..datasets import contour_points

        pts = contour_points(_kimia_mask(index), n_points)[:, ::-1] * [1.0, -1.0]
    elif kind == "grid":
        mask = _kimia_mask(index)
        step = float(np.sqrt(mask.sum() / n_points))
        offset = rng.uniform(0, step, 2)
        rows = np.arange(offset[0], mask.shape[0] - 0.5, step)
        cols = np.arange(offset[1], mask.shape[1] - 0.5, step)
        rr, cc = np.meshgrid(rows, cols, indexing="ij")
        inside = mask[np.rint(rr).astype(int), np.rint(cc).astype(int)]
        pts = np.column_stack([cc[inside], -rr[inside]])
    else:
        raise ValueError(f"`kind` must be one of {', '.join(map(repr, CLASSES))}; got {kind!r}.")
    return _unit_extent(pts)


def _rigid_copy(points: np.ndarray, rng) -> np.ndarray:
    a = np.radians(rng.uniform(-ROTATION_DEG, ROTATION_DEG))
    rotation = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return points @ rotation.T + rng.uniform(-0.25, 0.25, 2)


def register_set(kind: str, index: int, seed: int = 0, n_points: int = N_POINTS) -> dict:
    """Register set ``index`` of ``kind`` with CPD and the four GPD variants (one runner unit)."""
    import warnings

    from ..exceptions import ConvergenceWarning
    from ..registration import GPD, RigidCPD

    moving = make_set(kind, index, seed=seed, n_points=n_points)
    fixed = _rigid_copy(moving, np.random.default_rng([seed, CLASSES.index(kind), index, 1]))
    out = {"n_points": int(moving.shape[0])}
    for name in METHODS:
        base = RigidCPD(scale=False, tol=TOL, max_iter=MAX_ITER)
        est = base if name == "CPD" else GPD(base, centrality=name, graph="delaunay")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            est.fit(moving, fixed)
        rms = float(np.sqrt(np.mean(np.sum((est.moving_transformed_ - fixed) ** 2, axis=1))))
        out[name] = {"n_iter": int(est.n_iter_), "stopped": bool(est.converged_), "rms": rms,
                     "converged": bool(est.converged_ and rms <= SUCCESS_RMS)}
    return out


def run(*, quick: bool = False, seed: int = 0, out=None, scheduler: str = "processes", workers=None, progress=True) -> dict:
    """All 495 units (``quick``: 4 sets per class), resumable through ``out``/table-5.1.jsonl."""
    from ._runner import Unit, run_units

    n_sets = 4 if quick else 99
    n_points = 40 if quick else N_POINTS
    started = time.perf_counter()
    units = [
        Unit(f"{kind}/{i:02d}", register_set, {"kind": kind, "index": i, "seed": seed, "n_points": n_points})
        for kind in CLASSES for i in range(n_sets)
    ]
    folder = Path(out) if out is not None else Path("results/table-5.1")
    name = "table-5.1-quick" if quick else "table-5.1"
    results = run_units(units, folder / f"{name}.jsonl", scheduler=scheduler, workers=workers, progress=progress, desc="495 registrations")
    summary = {}
    for kind in CLASSES:
        rows = [results[f"{kind}/{i:02d}"] for i in range(n_sets)]
        summary[kind] = {}
        for name_ in METHODS:
            ok = [r[name_]["n_iter"] for r in rows if r[name_]["converged"]]
            summary[kind][name_] = {
                "mean": float(np.mean(ok)) if ok else None,
                "std": float(np.std(ok, ddof=1)) if len(ok) > 1 else None,
                "converged": 100.0 * len(ok) / len(rows),
                "iterations": [r[name_]["n_iter"] for r in rows],
                "succeeded": [r[name_]["converged"] for r in rows],
            }
    return {
        "summary": summary,
        "n_sets": n_sets,
        "n_points": n_points,
        "points_per_set": {kind: [results[f"{kind}/{i:02d}"]["n_points"] for i in range(n_sets)] for kind in CLASSES},
        "rotation_deg": ROTATION_DEG,
        "translation": "uniform in [-0.25, 0.25] x extent per axis",
        "tol": TOL,
        "max_iter": MAX_ITER,
        "success_rms": SUCCESS_RMS,
        "seed": seed,
        "seconds": time.perf_counter() - started,
        "claims": _claims(summary),
    }


def _fastest(summary_row: dict):
    means = {m: v["mean"] for m, v in summary_row.items() if v["mean"] is not None}
    return min(means, key=means.get) if means else None


def _claims(summary: dict) -> dict:
    out = {}
    thesis_fastest = {"cluster": "closeness", "random": "eigenvector", "normal": "closeness", "contour": "closeness", "grid": "eigenvector"}
    for kind in CLASSES:
        ours = _fastest(summary[kind])
        out[f"{kind}: fastest method is {thesis_fastest[kind]} (ours: {ours})"] = ours == thesis_fastest[kind]
        c, cpd = summary[kind]["closeness"]["mean"], summary[kind]["CPD"]["mean"]
        out[f"{kind}: closeness-GPD needs fewer iterations than CPD"] = c is not None and cpd is not None and c < cpd
    out["grid: no centrality converges on every set"] = all(summary["grid"][m]["converged"] < 100 for m in METHODS[:4])
    return out


def format_table(result: dict) -> str:
    s = result["summary"]
    lines = [
        f"{result['n_sets']} sets per class, {result['n_points']} points, rotation uniform in +-{result['rotation_deg']} deg, "
        f"translation {result['translation']}; converged = own stopping test (tol {result['tol']}) within "
        f"{result['max_iter']} iterations and RMS <= {result['success_rms']} x extent. B betweenness, C closeness, "
        "D degree, E eigenvector. Each cell: ours | thesis.",
    ]
    for title, key, fmt in (("Table 5.1: mean iterations (converged sets)", "mean", "{:.1f}"),
                            ("Table 5.2: standard deviation", "std", "{:.1f}"),
                            ("Table 5.3: % converged", "converged", "{:.0f}")):
        lines.append("")
        lines.append(title)
        lines.append(f"{'class':>8}" + "".join(f"{(m if m == 'CPD' else m[:1].upper()):>15}" for m in METHODS))
        for kind in CLASSES:
            cells = []
            for j, m in enumerate(METHODS):
                v = s[kind][m][key]
                ours = "-" if v is None else fmt.format(v)
                cells.append(f"{ours + ' | ' + fmt.format(THESIS[key][kind][j]):>15}")
            lines.append(f"{kind:>8}" + "".join(cells))
    lines.append("")
    lines += claim_lines(result["claims"], " (thesis)")
    return "\n".join(lines)


def plot(result: dict, path) -> Path:
    """Boxplots of the iterations per class and method (converged sets only)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    fig, axes = plt.subplots(1, len(CLASSES), figsize=(3.2 * len(CLASSES), 3.4), sharey=True)
    for ax, kind in zip(axes, CLASSES):
        data = []
        for m in METHODS:
            it = np.asarray(result["summary"][kind][m]["iterations"])
            ok = np.asarray(result["summary"][kind][m]["succeeded"], dtype=bool)
            data.append(it[ok] if ok.any() else np.array([np.nan]))
        ax.boxplot(data, showfliers=True)
        ax.set_xticks(range(1, len(METHODS) + 1), [m if m == "CPD" else m[:1].upper() for m in METHODS])
        ax.set_title(kind)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("iterations to convergence")
    fig.suptitle("Rigid registration of the 495 point sets (thesis Tables 5.1-5.3)")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    args = experiment_parser("table_5_1", __doc__, "table-5.1", runner=True).parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, out=out, scheduler=args.scheduler, workers=args.workers)
    name = "table-5.1-quick" if args.quick else "table-5.1"
    save_outputs(out, name, format_table(result), result)
    plot(result, out / f"{name}.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
