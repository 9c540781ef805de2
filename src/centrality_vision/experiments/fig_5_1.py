"""Thesis figs. 5.1 and 5.2: GPD's centrality prior and posterior for one fixed point, against CPD's.

The fish (91 points) and its copy under the similarity transform of fig-5.3's seed get
Delaunay graphs and normalised closeness centralities. For one fixed point x_n (the most
central, the thesis' pink node) we draw:

- fig. 5.1: the fixed graph coloured by closeness with x_n marked; the prior of every moving
  point y_m for x_n under CPD (uniform, 1/M) and under GPD (thesis eq. 5.1,
  ``P(m | x_n) ∝ h(m) exp(-(v(y_m) - v(x_n))^2 / (2 phi^2))``); and the posteriors of both at
  CPD's initial sigma^2 (w = 0: ``P(m | x_n) ∝ prior(m) exp(-|x_n - T(y_m)|^2 / (2 sigma^2))``,
  T the identity, i.e. before the first iteration).
- fig. 5.2: the histogram of the moving set's closeness with the Gaussian centred at v(x_n),
  and the GPD prior of every moving point as bars.

The thesis observes that the centrality alone ranks the correct partner among the ten most
likely points; we check that on every fixed point, and whether GPD's posterior gives the
true partner more mass than CPD's.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..exceptions import InputError

__all__ = ["CLAIMS", "prior_and_posterior", "partner_ranks", "run", "format_table", "explain", "plot", "main"]

TOP = 10
RANK = f"the true partner is among the {TOP} most likely moving points under GPD's prior alone"
MASS = "GPD's posterior (initial sigma^2) gives the true partner more mass than CPD's"
CLAIMS = {
    RANK: "based only on the centrality, one could find the correct match in the first ten more likely nodes",
    MASS: "by integrating it to CPD, we expect that the algorithm will converge faster",
}


def _softmax(s: np.ndarray) -> np.ndarray:
    e = np.exp(s - s.max(axis=0))
    return e / e.sum(axis=0)


def prior_and_posterior(moving, fixed, *, centrality: str = "closeness", graph: str = "delaunay") -> dict:
    """Priors and posteriors (M x N, columns sum to 1) of CPD and GPD, and the centralities.

    GPD's prior is ``exp(CentralityPrior.matrix())`` normalised over the moving points
    (thesis eq. 5.1); the posteriors use CPD's initial sigma^2, no outlier term and the
    identity transform.
    """
    from ..centrality import compute
    from ..graphs import delaunay_graph
    from ..registration import centrality_prior, initial_sigma2, normalize_centrality

    if graph != "delaunay":
        raise InputError(f"`graph` must be 'delaunay'; got {graph!r}.")
    v_moving = normalize_centrality(compute(delaunay_graph(moving), centrality))
    v_fixed = normalize_centrality(compute(delaunay_graph(fixed), centrality))
    prior = centrality_prior(v_moving, v_fixed)
    log_gpd = prior.matrix()
    sigma2 = initial_sigma2(moving, fixed)
    spatial = -np.sum((moving[:, None, :] - fixed[None, :, :]) ** 2, axis=2) / (2.0 * sigma2)
    m = moving.shape[0]
    return {
        "v_moving": v_moving,
        "v_fixed": v_fixed,
        "phi2": 1.0 / (2.0 * prior.inv2phi2) if prior.inv2phi2 else 0.0,
        "sigma2": sigma2,
        "prior_cpd": np.full((m, fixed.shape[0]), 1.0 / m),
        "prior_gpd": _softmax(log_gpd),
        "posterior_cpd": _softmax(spatial),
        "posterior_gpd": _softmax(spatial + log_gpd),
    }


def partner_ranks(prior) -> list[int]:
    """Rank of moving point ``i`` among all moving points under column ``i`` of ``prior`` (the
    prior of each moving point for fixed point ``i``, whose true partner is moving point ``i``).

    1 is the most likely. Ties count against the partner: its rank is the number of moving
    points at least as likely, so a partner tied with others is not called "among the ten"
    when only some of the tied points fit.

    >>> partner_ranks(np.array([[0.5, 0.2], [0.5, 0.8]]))
    [2, 1]
    """
    prior = np.asarray(prior)
    return [int(np.sum(prior[:, i] >= prior[i, i])) for i in range(prior.shape[1])]


def run(*, quick: bool = False, seed: int = 0) -> dict:
    """The problem of fig-5.3's seed ``seed``; priors, posteriors and the per-point claims."""
    from ._common import check_run, tally
    from .fig_5_3 import problem

    quick, seed = check_run(quick, seed)

    moving, fixed, transform = problem(seed)
    pp = prior_and_posterior(moving, fixed)
    n = fixed.shape[0]  # fixed[i] is the image of moving[i]
    ranks = partner_ranks(pp["prior_gpd"])
    per_point = [
        {RANK: r <= TOP, MASS: bool(pp["posterior_gpd"][i, i] > pp["posterior_cpd"][i, i])} for i, r in enumerate(ranks)
    ]
    chosen = int(np.argmax(pp["v_fixed"]))
    return {
        "seed": seed,
        "quick": quick,
        "transform": transform,
        "moving": moving.tolist(),
        "fixed": fixed.tolist(),
        "chosen": chosen,
        "sigma2": pp["sigma2"],
        "phi2": pp["phi2"],
        "v_moving": pp["v_moving"].tolist(),
        "v_fixed": pp["v_fixed"].tolist(),
        "column": {k: pp[k][:, chosen].tolist() for k in ("prior_cpd", "prior_gpd", "posterior_cpd", "posterior_gpd")},
        "ranks": ranks,
        "true_mass": {k: [float(pp[k][i, i]) for i in range(n)] for k in ("posterior_cpd", "posterior_gpd")},
        "odds": tally(per_point),
    }


def format_table(result: dict) -> str:
    from ._common import odds_lines

    ranks = np.asarray(result["ranks"])
    c = result["chosen"]
    col = result["column"]
    lines = [
        f"Fish, fig-5.3's transform of seed {result['seed']}; Delaunay graphs, normalised closeness; phi^2 = "
        f"{result['phi2']:.4f}, initial sigma^2 = {result['sigma2']:.4f}.",
        f"Chosen fixed point x_{c} (highest closeness): rank of its true partner under GPD's prior "
        f"{result['ranks'][c]}; "
        f"prior of the partner CPD {col['prior_cpd'][c]:.4f}, GPD {col['prior_gpd'][c]:.4f}; posterior CPD "
        f"{col['posterior_cpd'][c]:.4f}, GPD {col['posterior_gpd'][c]:.4f}.",
        f"Rank of the true partner under GPD's prior over all {ranks.size} fixed points: median "
        f"{np.median(ranks):.0f}, "
        f"worst {ranks.max()}.",
        f"Claims per fixed point ({ranks.size} points):",
        *odds_lines(result["odds"], CLAIMS, unit="points"),
    ]
    return "\n".join(lines)


def explain(result: dict) -> str:
    """The report's paragraph, written from ``result``'s numbers."""
    from ._compare import odds_sentences

    ranks = np.asarray(result["ranks"])
    gain = np.asarray(result["true_mass"]["posterior_gpd"]) / np.asarray(result["true_mass"]["posterior_cpd"])
    return " ".join(
        [
            "The thesis shows one point of one fish; we compute the prior for every fixed point of the fish against "
            "its "
            "similarity-transformed copy. The true partner's rank under the prior alone has median "
            f"{np.median(ranks):.0f} "
            f"(worst {ranks.max()} of {ranks.size}); GPD's posterior at the initial sigma^2 gives it a median "
            f"{np.median(gain):.2f}x the mass CPD's does.",
            *odds_sentences(result["odds"], "points"),
        ]
    )


def plot(result: dict, folder) -> list[Path]:
    """fig-5.1.png (graph, priors, posteriors on the points) and fig-5.2.png (histogram and prior bars)."""
    from ..graphs import delaunay_graph
    from ..plotting import plot_graph, save_figure
    from ._common import new_figure

    folder = Path(folder)
    moving, fixed = np.asarray(result["moving"]), np.asarray(result["fixed"])
    c = result["chosen"]
    col = result["column"]
    fig = new_figure(figsize=(16, 7.5))
    axes = fig.subplots(2, 3)
    plot_graph(
        fixed,
        delaunay_graph(fixed),
        np.asarray(result["v_fixed"]),
        ax=axes[0, 0],
        cmap="cool",
        title="(a) fixed set X: Delaunay graph, closeness",
        label="closeness",
    )
    axes[0, 0].scatter(*fixed[c], s=180, facecolors="none", edgecolors="red", linewidths=2)
    graph = delaunay_graph(moving)
    panels = [
        ((0, 1), "prior_cpd", f"(b) CPD prior P(m | x_{c}) = 1/M"),
        ((0, 2), "prior_gpd", f"(c) GPD prior P(m | x_{c}) (eq. 5.1)"),
        ((1, 1), "posterior_cpd", "CPD posterior, initial sigma^2"),
        ((1, 2), "posterior_gpd", "GPD posterior, initial sigma^2"),
    ]
    for (r, k), key, title in panels:
        plot_graph(moving, graph, np.asarray(col[key]), ax=axes[r, k], cmap="viridis", title=title, label="probability")
        axes[r, k].scatter(*moving[c], s=180, facecolors="none", edgecolors="red", linewidths=2)
    axes[1, 0].set_axis_off()
    axes[1, 0].text(
        0,
        0.5,
        f"red circle: x_{c} in X (a) and its true partner y_{c} in Y (b-e)\n"
        f"rank of y_{c} under GPD's prior: {result['ranks'][c]}",
        fontsize=10,
    )
    fig.suptitle("GPD's centrality prior and posterior for one fixed point, against CPD's (thesis fig. 5.1)")
    fig.tight_layout()
    first = save_figure(fig, folder / "fig-5.1.png")

    fig = new_figure(figsize=(12, 4))
    left, right = fig.subplots(1, 2)
    v = np.asarray(result["v_moving"])
    left.hist(v, bins=10, range=(0, 1), color="0.6", density=True, label="closeness of Y (10 bins)")
    grid = np.linspace(0, 1, 300)
    phi2 = result["phi2"]
    vx = result["v_fixed"][c]
    if phi2 > 0:
        left.plot(
            grid,
            np.exp(-((grid - vx) ** 2) / (2 * phi2)) / np.sqrt(2 * np.pi * phi2),
            color="red",
            label=f"Gaussian at v(x_{c}) = {vx:.2f}, phi^2 = {phi2:.3f}",
        )
    left.set_xlabel("normalised closeness")
    left.legend(fontsize=8)
    left.set_title("(a) histogram of the moving set's closeness")
    order = np.argsort(v)
    right.bar(
        np.arange(v.size), np.asarray(col["prior_gpd"])[order], color=[("red" if i == c else "0.4") for i in order]
    )
    right.set_xlabel("moving points, by closeness")
    right.set_ylabel(f"P(m | x_{c})")
    right.set_title("(b) GPD prior of every moving point (true partner in red)")
    fig.suptitle("Thesis fig. 5.2")
    fig.tight_layout()
    return [first, save_figure(fig, folder / "fig-5.2.png")]


def main(argv=None) -> int:
    from ._common import experiment_parser, prepare_out, run_outputs, save_outputs

    args = experiment_parser(
        "fig_5_1",
        __doc__,
        "fig-5.1",
        quick_help="the same (instant)",
        seed_help="the transform of fig-5.3's seed (default: %(default)s); the claims are checked on every fixed point",
        seeds=False,
    ).parse_args(argv)
    out = prepare_out(args)
    result = run(quick=args.quick, seed=args.seed)
    with run_outputs(out, "fig-5.1", quick=args.quick) as stage:
        save_outputs(stage, "fig-5.1", format_table(result), result)
        plot(result, stage)
    return 0


if __name__ == "__main__":  # pragma: no cover
    from ._common import command_line

    sys.exit(command_line(main))
