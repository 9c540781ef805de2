"""Thesis 5.4.5, Tables 5.1-5.3: rigid registration of 495 point sets, CPD against GPD.

Five classes of 99 point sets each: Gaussian clusters, uniform random,
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
Every CPD here uses the exact E-step (``method='dense'``: every pair of points; the sets are small).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..exceptions import InputError
from ._common import experiment_parser, prepare_out, run_outputs, save_outputs

__all__ = ["CLASSES", "METHODS", "CLAIMS", "make_set", "register_set", "run", "format_table", "explain", "plot", "main"]

CLASSES = ("cluster", "random", "normal", "contour", "grid")
METHODS = ("betweenness", "closeness", "degree", "eigenvector", "CPD")
N_POINTS = 100
#: point sets per class (set i of the silhouette classes comes from Kimia-99 image i)
SETS_PER_CLASS = 99
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
        raise InputError(f"`kind` must be one of {', '.join(map(repr, CLASSES))}; got {kind!r}.")
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
        base = RigidCPD(scale=False, tol=TOL, max_iter=MAX_ITER, method="dense")
        est = base if name == "CPD" else GPD(base, centrality=name, graph="delaunay")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            est.fit(moving, fixed)
        rms = float(np.sqrt(np.mean(np.sum((est.moving_transformed_ - fixed) ** 2, axis=1))))
        out[name] = {
            "n_iter": int(est.n_iter_),
            "stopped": bool(est.converged_),
            "rms": rms,
            "converged": bool(est.converged_ and rms <= SUCCESS_RMS),
        }
    return out


def _summary(rows: list) -> dict:
    """Tables 5.1-5.3 cells of one class: mean and std of the iterations of converged sets, % converged."""
    out = {}
    for name in METHODS:
        ok = [r[name]["n_iter"] for r in rows if r[name]["converged"]]
        out[name] = {
            "mean": float(np.mean(ok)) if ok else None,
            "std": float(np.std(ok, ddof=1)) if len(ok) > 1 else None,
            "converged": 100.0 * len(ok) / len(rows),
            "iterations": [r[name]["n_iter"] for r in rows],
            "succeeded": [r[name]["converged"] for r in rows],
        }
    return out


def run(
    *,
    quick: bool = False,
    seed: int = 0,
    seeds=None,
    out=None,
    scheduler: str = "processes",
    workers=None,
    progress=True,
    n_sets: int | None = None,
) -> dict:
    """All 495 units of each seed (``quick``: 4 sets of 40 points per class), resumable through
    ``out``/table-5.1[-quick].jsonl (a temporary file when ``out`` is None).

    The tables are those of ``seed``; the claims are checked on every seed of ``seeds``
    (default: ``[seed]``), and the per-set claims on every set of every seed. ``n_sets``
    overrides the sets per class (99, or 4 when ``quick``), for tests.
    """

    from ._common import check_run, run_kept_units, tally
    from ._runner import Unit

    quick, seed = check_run(quick, seed)

    seeds = [seed] if seeds is None else list(seeds)
    if seed not in seeds:
        seeds = [seed, *seeds]
    n_sets = n_sets or (4 if quick else SETS_PER_CLASS)
    n_points = 40 if quick else N_POINTS
    started = time.perf_counter()
    units = [
        Unit(f"{s}/{kind}/{i:02d}", register_set, {"kind": kind, "index": i, "seed": s, "n_points": n_points})
        for s in seeds
        for kind in CLASSES
        for i in range(n_sets)
    ]
    results = run_kept_units(
        units,
        out,
        "table-5.1",
        quick=quick,
        scheduler=scheduler,
        workers=workers,
        progress=progress,
        desc=f"{len(units)} registrations",
    )
    by_seed = {
        s: {kind: _summary([results[f"{s}/{kind}/{i:02d}"] for i in range(n_sets)]) for kind in CLASSES} for s in seeds
    }
    summary = by_seed[seed]
    per_seed_claims = [_claims(by_seed[s]) for s in seeds]
    per_set_claims = [
        _set_claims(kind, results[f"{s}/{kind}/{i:02d}"]) for s in seeds for kind in CLASSES for i in range(n_sets)
    ]
    return {
        "summary": summary,
        "n_sets": n_sets,
        "n_points": n_points,
        "points_per_set": {
            kind: [results[f"{seed}/{kind}/{i:02d}"]["n_points"] for i in range(n_sets)] for kind in CLASSES
        },
        "rotation_deg": ROTATION_DEG,
        "translation": "uniform in [-0.25, 0.25] x extent per axis",
        "tol": TOL,
        "max_iter": MAX_ITER,
        "success_rms": SUCCESS_RMS,
        "seed": seed,
        "seeds": seeds,
        "quick": quick,
        "seconds": time.perf_counter() - started,
        "claims": per_seed_claims[seeds.index(seed)],
        "speedup": {str(s): _speedups(by_seed[s]) for s in seeds},
        "best_set_speedup": {kind: _best_set_speedup(by_seed[seed][kind]) for kind in CLASSES},
        "odds": tally(per_seed_claims),
        "set_odds": tally(per_set_claims),
    }


#: The fastest method per class in the thesis' Table 5.1 (its bold cells).
THESIS_FASTEST = {kind: METHODS[int(np.argmin(THESIS["mean"][kind]))] for kind in CLASSES}


def _ratio(row: dict, method: str):
    a, b = row["CPD"]["mean"], row[method]["mean"]
    return None if a is None or b is None or b == 0 else a / b


def _speedups(summary: dict) -> dict:
    """CPD's mean iterations / each GPD variant's, per class (the thesis' "x times faster")."""
    return {kind: {m: _ratio(summary[kind], m) for m in METHODS[:-1]} for kind in CLASSES}


def _best_set_speedup(row: dict):
    """The largest CPD / closeness iteration ratio over the sets where both converged."""
    pairs = [
        (c, g)
        for c, g, ok_c, ok_g in zip(
            row["CPD"]["iterations"],
            row["closeness"]["iterations"],
            row["CPD"]["succeeded"],
            row["closeness"]["succeeded"],
        )
        if ok_c and ok_g and g > 0
    ]
    return max(c / g for c, g in pairs) if pairs else None


def _fastest(summary_row: dict):
    """The method with the fewest mean iterations, or None when none converged or the least
    mean is shared (a tie is no method's win, as in the other experiments' claims)."""
    means = {m: v["mean"] for m, v in summary_row.items() if v["mean"] is not None}
    if not means:
        return None
    least = min(means.values())
    winners = [m for m, v in means.items() if v == least]
    return winners[0] if len(winners) == 1 else None


CLUSTER_266 = "cluster: closeness-GPD is more than 2x faster than CPD (ratio of mean iterations)"
RANDOM_2X = "random: closeness- and eigenvector-GPD are each more than 2x faster than CPD (ratio of mean iterations)"
GRID = "grid: no centrality converges on every set"
DEGREE = "degree-GPD converges on fewer sets than CPD in every class"
#: Each claim we check -> the thesis' words it stands for.
CLAIMS = {
    **{
        f"{kind}: fastest method is {THESIS_FASTEST[kind]}": "The fastest algorithm in average is highlighted in "
        "bold (Table 5.1)"
        for kind in CLASSES
    },
    **{
        f"{kind}: closeness-GPD needs fewer iterations than CPD (mean)": "In general, Closeness centrality obtained "
        "the fastest "
        "convergence among all algorithms"
        for kind in CLASSES
    },
    CLUSTER_266: "the closeness centrality was in average 2.66 times faster than CPD",
    RANDOM_2X: "Eigenvector and closeness centralities were the fastest ones, more than 2 times faster than CPD in "
    "average",
    GRID: "when the point set comes from grid sampling, no centrality was able to converge 100%",
    DEGREE: "Degree and eigenvector centralities did not succeed to converge on all sets",
}
SET_CLAIMS = {
    f"{kind} set: closeness-GPD converges in fewer iterations than CPD (both converged)": "In general, Closeness "
    "centrality obtained the fastest convergence among all algorithms"
    for kind in CLASSES
}


def _claims(summary: dict) -> dict:
    out = {}
    for kind in CLASSES:
        out[f"{kind}: fastest method is {THESIS_FASTEST[kind]}"] = _fastest(summary[kind]) == THESIS_FASTEST[kind]
    for kind in CLASSES:
        c, cpd = summary[kind]["closeness"]["mean"], summary[kind]["CPD"]["mean"]
        out[f"{kind}: closeness-GPD needs fewer iterations than CPD (mean)"] = (
            c is not None and cpd is not None and c < cpd
        )
    ratio = _speedups(summary)
    out[CLUSTER_266] = (ratio["cluster"]["closeness"] or 0) > 2
    out[RANDOM_2X] = (ratio["random"]["closeness"] or 0) > 2 and (ratio["random"]["eigenvector"] or 0) > 2
    out[GRID] = all(summary["grid"][m]["converged"] < 100 for m in METHODS[:4])
    out[DEGREE] = all(summary[k]["degree"]["converged"] < summary[k]["CPD"]["converged"] for k in CLASSES)
    return out


def _set_claims(kind: str, record: dict) -> dict:
    c, cpd = record["closeness"], record["CPD"]
    if not (c["converged"] and cpd["converged"]):
        return {}
    return {
        f"{kind} set: closeness-GPD converges in fewer iterations than CPD (both converged)": c["n_iter"]
        < cpd["n_iter"]
    }


def format_table(result: dict) -> str:
    from ._common import odds_lines

    s = result["summary"]
    lines = [
        f"{result['n_sets']} sets per class, {result['n_points']} points, rotation uniform in "
        f"+-{result['rotation_deg']} deg, "
        f"translation {result['translation']}; converged = own stopping test (tol {result['tol']}) within "
        f"{result['max_iter']} iterations and RMS <= {result['success_rms']} x extent. B betweenness, C closeness, "
        f"D degree, E eigenvector. Tables of seed {result['seed']}; each cell: ours | thesis.",
    ]
    for title, key, fmt in (
        ("Table 5.1: mean iterations (converged sets)", "mean", "{:.1f}"),
        ("Table 5.2: standard deviation", "std", "{:.1f}"),
        ("Table 5.3: % converged", "converged", "{:.0f}"),
    ):
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
    lines += [
        "",
        "Speed-up: CPD's mean iterations / each GPD variant's (the thesis' \"x times faster\"); ours (median over "
        f"{len(result['seeds'])} seeds, min-max) | thesis (from its Table 5.1)",
        f"{'class':>8}" + "".join(f"{m[:1].upper():>27}" for m in METHODS[:-1]),
    ]
    for kind in CLASSES:
        cells = []
        for j, m in enumerate(METHODS[:-1]):
            vals = [r[kind][m] for r in result["speedup"].values() if r[kind][m] is not None]
            thesis = THESIS["mean"][kind][-1] / THESIS["mean"][kind][j]
            ours = f"{np.median(vals):.2f} ({min(vals):.2f}-{max(vals):.2f})" if vals else "-"
            cells.append(f"{ours + ' | ' + f'{thesis:.2f}':>27}")
        lines.append(f"{kind:>8}" + "".join(cells))
    best = result["best_set_speedup"]["cluster"]
    lines.append(
        f"Best single cluster set (seed {result['seed']}), CPD / closeness iterations: "
        + ("-" if best is None else f"{best:.2f}")
        + ' | thesis: "approximately 3 times faster"'
    )
    lines += [
        "",
        f"Claims over {len(result['seeds'])} seeds (each seed draws all {5 * result['n_sets']} sets and transforms "
        "anew):",
    ]
    lines += odds_lines(result["odds"], CLAIMS)
    lines += ["", "Claims per point set (every set of every seed where both methods converged):"]
    lines += odds_lines(result["set_odds"], SET_CLAIMS, unit="sets")
    return "\n".join(lines)


def explain(result: dict) -> str:
    """The report's paragraph, written from ``result``'s numbers."""
    from ._common import verdict
    from ._compare import odds_sentences

    s = result["summary"]
    lower = sum(
        s[k][m]["mean"] is not None and s[k][m]["mean"] < THESIS["mean"][k][j]
        for k in CLASSES
        for j, m in enumerate(METHODS)
    )
    ratio = {
        k: np.median(
            [r[k]["closeness"] for r in result["speedup"].values() if r[k]["closeness"] is not None] or [np.nan]
        )
        for k in CLASSES
    }
    parts = [
        f"On seed {result['seed']}, {lower} of {len(CLASSES) * len(METHODS)} mean-iteration cells are below the "
        "thesis' "
        f"(our sets have {result['n_points']} points and noise-free copies; the thesis does not state its point "
        "counts, "
        "rotations or stopping rule).",
        "CPD needs "
        + ", ".join(
            f"{ratio[k]:.2f}x (thesis {THESIS['mean'][k][-1] / THESIS['mean'][k][1]:.2f}x) on {k}" for k in CLASSES
        )
        + " the mean iterations of closeness-GPD (median over seeds).",
    ]
    parts += odds_sentences(result["odds"])
    set_odds = result["set_odds"]
    if set_odds:
        held = [c for c, cell in set_odds.items() if verdict(cell) in ("holds", "holds always")]
        parts.append(
            f"Per point set, closeness-GPD beats CPD with a 95% interval above one half on {len(held)} of "
            f"{len(set_odds)} classes: "
            + "; ".join(f"{c.split(' set:')[0]} {cell['k']} of {cell['n']}" for c, cell in set_odds.items())
            + "."
        )
    return " ".join(parts)


def plot(result: dict, path) -> Path:
    """Boxplots of the iterations per class and method (converged sets only)."""
    from ..plotting import save_figure
    from ._common import new_figure

    fig = new_figure(figsize=(3.2 * len(CLASSES), 3.4))
    axes = fig.subplots(1, len(CLASSES), sharey=True)
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
    fig.suptitle(f"Rigid registration of the 495 point sets, seed {result['seed']} (thesis Tables 5.1-5.3)")
    fig.tight_layout()
    return save_figure(fig, path)


def main(argv=None) -> int:
    from ._common import seed_list

    args = experiment_parser("table_5_1", __doc__, "table-5.1", runner=True).parse_args(argv)
    seeds = seed_list(args.seed, args.seeds, args.quick)  # (checked before the output folder is made)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed, seeds=seeds, out=out, scheduler=args.scheduler, workers=args.workers)
    with run_outputs(out, "table-5.1", quick=args.quick) as stage:
        save_outputs(stage, "table-5.1", format_table(result), result)
        plot(result, stage / "table-5.1.png")
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ._common import command_line

    sys.exit(command_line(main))
