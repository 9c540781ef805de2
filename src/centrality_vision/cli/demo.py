"""``centrality-vision demo``: the README's first command, a few seconds of the library's main ideas."""

from __future__ import annotations

import argparse
import time

from ._common import add_progress, out_folder, progress_on, pyplot, say
from ._output import write_json

NAME = "demo"
CENTRALITIES = ("degree", "betweenness", "closeness", "eigenvector")
GPD_CENTRALITIES = ("closeness", "betweenness", "degree", "eigenvector")


def add_parser(sub) -> argparse.ArgumentParser:
    parser = sub.add_parser(
        NAME,
        help="Centralities of the bundled fish and a Kimia-99 shape, and CPD against GPD on the fish, with figures.",
        description="Build the Delaunay graph of the bundled CPD fish, compute degree, betweenness, "
        "closeness and eigenvector centrality, and draw the graph coloured by closeness (thesis "
        "fig. 5.1); draw the closeness of a Kimia-99 silhouette's pixel graph (fig. 4.2); register the fish "
        "under a similarity transform with CPD and with GPD (closeness), drawn before and after, and the "
        "per-point alignment error of CPD and of GPD with four centralities (fig. 5.3).",
        epilog="example:\n  centrality-vision demo --out demo-output --shape dog1",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--out", default="demo-output", type=out_folder, help="output folder (default: %(default)s)")
    parser.add_argument(
        "--shape", default="cow1", help="Kimia-99 image for the pixel-graph figure (default: %(default)s)"
    )
    add_progress(parser)
    parser.set_defaults(run=run, _parser=parser)
    return parser


def _first_below(rms, level: float):
    import numpy as np

    hit = np.flatnonzero(np.asarray(rms) <= level * rms[0])
    return int(hit[0]) if hit.size else None


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import __version__
    from .. import centrality as cen
    from ..datasets import load_fish, load_kimia99
    from ..exceptions import InputError
    from ..experiments._common import make_out_folder
    from ..graphs import delaunay_graph, pixel_graph
    from ..plotting import plot_alignment_errors, plot_centrality_image, plot_graph, plot_registration, save_figure
    from ..registration import GPD, RigidCPD

    plt = pyplot()
    started = time.perf_counter()
    try:  # fail on a bad name before any work, and before the output folder is made
        image = load_kimia99().image(args.shape)
    except InputError as exc:
        raise InputError(f"--shape: {exc}".replace("`name` ", "")) from None
    out = make_out_folder(args.out)
    fish = load_fish().fixed
    graph = delaunay_graph(fish)
    values = {name: cen.compute(graph, name) for name in CENTRALITIES}
    say(f"Delaunay graph of the CPD fish: {graph.shape[0]} nodes, {graph.nnz // 2} edges")

    fig, ax = plt.subplots(figsize=(5, 5), layout="constrained")
    plot_graph(
        fish,
        graph,
        values["closeness"],
        ax=ax,
        label="closeness",
        title="Fish, Delaunay graph, closeness (thesis fig. 5.1)",
    )
    save_figure(fig, out / "fish_delaunay_closeness.png")

    fig, axes = plt.subplots(2, 2, figsize=(8, 8.5), layout="constrained")
    for ax, name in zip(axes.ravel(), CENTRALITIES):
        plot_graph(
            fish,
            graph,
            values[name],
            ax=ax,
            label=name,
            title=name,
            node_size=18,
            norm="power" if name == "betweenness" else "linear",
        )
    save_figure(fig, out / "fish_delaunay_centralities.png")

    pixels, nodes = pixel_graph(image)
    shape_closeness = cen.closeness(pixels, progress=progress_on(args))
    fig, ax = plt.subplots(figsize=(5, 4.2), layout="constrained")
    plot_centrality_image(
        shape_closeness,
        nodes,
        image.shape,
        ax=ax,
        label="closeness",
        title=f"{args.shape}: closeness (thesis fig. 4.2)",
    )
    save_figure(fig, out / f"{args.shape}_closeness.png")

    # registration: the fish under a similarity transform, CPD against GPD (thesis fig. 5.3)
    moving = load_fish().moving
    angle = np.radians(50.0)
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    target = 1.5 * moving @ rotation.T + np.array([0.5, -0.3])
    runs = {}
    for name in ("CPD",) + GPD_CENTRALITIES:
        base = RigidCPD(scale=True, tol=1e-8)
        estimator = base if name == "CPD" else GPD(base, centrality=name)
        estimator.fit(moving, target, true_moving=target)
        rms = np.asarray(estimator.history_["error"]) / np.sqrt(moving.shape[0])  # per-point RMS
        runs["CPD" if name == "CPD" else f"GPD ({name})"] = {"estimator": estimator, "rms": rms}
    fig = plt.figure(figsize=(12, 3.6), layout="constrained")
    panels = [
        ("before", moving),
        ("CPD", runs["CPD"]["estimator"].moving_transformed_),
        ("GPD (closeness)", runs["GPD (closeness)"]["estimator"].moving_transformed_),
    ]
    everything = np.vstack([target] + [points for _, points in panels])
    low, high = everything.min(axis=0) - 0.1, everything.max(axis=0) + 0.1
    for k, (title, points) in enumerate(panels, start=1):
        ax = fig.add_subplot(1, 3, k)
        done = "" if title == "before" else f", {runs[title]['estimator'].n_iter_} iterations"
        plot_registration(points, target, ax=ax, title=title + done, legend=k == 1)
        ax.set_xlim(low[0], high[0])  # the same frame in the three panels
        ax.set_ylim(low[1], high[1])
    fig.suptitle("Fish under a rotation of 50 degrees and scale 1.5: registered by CPD and by GPD")
    save_figure(fig, out / "fish_registration.png")
    ax = plot_alignment_errors(
        {label: r["rms"][:40] for label, r in runs.items()},
        ylabel="per-point RMS error",
        title="Fish under a similarity: alignment error (thesis fig. 5.3)",
    )
    save_figure(ax.figure, out / "fish_registration_errors.png")
    to_one_percent = {label: _first_below(r["rms"], 0.01) for label, r in runs.items()}

    np.savez_compressed(out / "fish_delaunay_centralities.npz", points=fish, **values)
    record = {
        "command": NAME,
        "version": __version__,
        "data": "CPD fish (fixed set, 91 points); Kimia-99 " + args.shape,
        "graph": {"kind": "delaunay", "n_nodes": graph.shape[0], "n_edges": graph.nnz // 2},
        "centralities": {
            "weights": False,
            "defaults": "degree raw, betweenness unnormalised, closeness (n-1)/sum d, eigenvector max 1",
        },
        "pixel_graph": {"shape": args.shape, "connectivity": 8, "n_nodes": int(pixels.shape[0])},
        "registration": {
            "moving": "CPD fish (moving set)",
            "transform": "rotation 50 deg, scale 1.5, translation (0.5, -0.3)",
            "estimator": "RigidCPD(scale=True, tol=1e-8), GPD over it on Delaunay graphs",
            "iterations_to_1_percent_error": to_one_percent,
            "final_rms": {label: float(r["rms"][-1]) for label, r in runs.items()},
        },
        "seconds": round(time.perf_counter() - started, 3),
    }
    write_json(out / "demo.json", record)

    top = np.argsort(values["closeness"])[::-1][:5]
    print("fish: the five most central points by closeness")
    print(f"{'node':>5} {'x':>8} {'y':>8} " + " ".join(f"{n:>12}" for n in CENTRALITIES))
    for i in top:
        print(
            f"{i:>5} {fish[i, 0]:>8.3f} {fish[i, 1]:>8.3f} " + " ".join(f"{values[n][i]:>12.4f}" for n in CENTRALITIES)
        )
    print("fish under a similarity transform: iterations until the per-point error is 1% of its start")
    print("  " + ", ".join(f"{label} {n}" for label, n in to_one_percent.items()))
    print(f"wrote {len(list(out.iterdir()))} files to {out}/ in {record['seconds']:.1f} s")
    return 0
