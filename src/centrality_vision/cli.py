"""The ``centrality-vision`` command.

Subcommands by capability; heavy imports happen inside each subcommand, progress and
logs go to stderr, results to files under ``--out``. ``main(argv) -> int`` returns the
exit status (0 success, 2 bad input).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

__all__ = ["main"]

_DEMO_CENTRALITIES = ("degree", "betweenness", "closeness", "eigenvector")


def _demo(args: argparse.Namespace) -> int:
    import numpy as np

    from . import __version__
    from . import centrality as cen
    from .datasets import load_fish, load_kimia99
    from .graphs import delaunay_graph, pixel_graph
    from .plotting import plot_centrality_image, plot_graph, save_figure

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    image = load_kimia99().image(args.shape)  # fail on a bad name before any work
    fish = load_fish().fixed
    graph = delaunay_graph(fish)
    values = {name: cen.compute(graph, name) for name in _DEMO_CENTRALITIES}
    print(f"Delaunay graph of the CPD fish: {graph.shape[0]} nodes, {graph.nnz // 2} edges", file=sys.stderr)

    fig, ax = plt.subplots(figsize=(6, 5))
    plot_graph(fish, graph, values["closeness"], ax=ax, label="closeness", title="Fish, Delaunay graph (thesis fig. 5.1)")
    save_figure(fig, out / "fish_delaunay_closeness.png")

    fig, axes = plt.subplots(2, 2, figsize=(10, 8.5))
    for ax, name in zip(axes.ravel(), _DEMO_CENTRALITIES):
        plot_graph(fish, graph, values[name], ax=ax, label=name, title=name, node_size=18)
    save_figure(fig, out / "fish_delaunay_centralities.png")

    pixels, nodes = pixel_graph(image)
    shape_closeness = cen.closeness(pixels, progress=True)
    fig, ax = plt.subplots(figsize=(5, 4.5))
    plot_centrality_image(shape_closeness, nodes, image.shape, ax=ax, label="closeness", title=f"{args.shape}: closeness (thesis fig. 4.2)")
    save_figure(fig, out / f"{args.shape}_closeness.png")

    np.savez_compressed(out / "fish_delaunay_centralities.npz", points=fish, **values)
    record = {
        "command": "demo",
        "version": __version__,
        "data": "CPD fish (fixed set, 91 points); Kimia-99 " + args.shape,
        "graph": {"kind": "delaunay", "n_nodes": graph.shape[0], "n_edges": graph.nnz // 2},
        "centralities": {"weights": False, "defaults": "degree raw, betweenness unnormalised, closeness (n-1)/sum d, eigenvector max 1"},
        "pixel_graph": {"shape": args.shape, "connectivity": 8, "n_nodes": int(pixels.shape[0])},
        "seconds": round(time.perf_counter() - started, 3),
    }
    (out / "demo.json").write_text(json.dumps(record, indent=2) + "\n")

    top = np.argsort(values["closeness"])[::-1][:5]
    print("fish: the five most central points by closeness")
    print(f"{'node':>5} {'x':>8} {'y':>8} " + " ".join(f"{n:>12}" for n in _DEMO_CENTRALITIES))
    for i in top:
        print(f"{i:>5} {fish[i, 0]:>8.3f} {fish[i, 1]:>8.3f} " + " ".join(f"{values[n][i]:>12.4f}" for n in _DEMO_CENTRALITIES))
    print(f"wrote {len(list(out.iterdir()))} files to {out}/ in {record['seconds']:.1f} s")
    return 0


_EXPERIMENTS = {"table-4.1": "table_4_1", "fig-5.3": "fig_5_3", "fig-6.4": "fig_6_4", "fig-7.4": "fig_7_4"}


def _reproduce(args: argparse.Namespace) -> int:
    from importlib import import_module

    module = import_module(f"centrality_vision.experiments.{_EXPERIMENTS[args.experiment]}")
    argv = ["--out", str(Path(args.out) / args.experiment), "--seed", str(args.seed)]
    if args.quick:
        argv.append("--quick")
    return module.main(argv)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="centrality-vision",
        description="Graph centrality for computer vision (de Sousa, TU Wien, 2015).",
    )
    from . import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo",
        help="Centralities of the bundled fish and a Kimia-99 shape, with figures.",
        description="Build the Delaunay graph of the bundled CPD fish, compute degree, betweenness, "
        "closeness and eigenvector centrality, and draw the graph coloured by closeness (thesis "
        "fig. 5.1); also draw the closeness of a Kimia-99 silhouette's pixel graph (fig. 4.2).",
    )
    demo.add_argument("--out", default="demo-output", help="output folder (default: %(default)s)")
    demo.add_argument("--shape", default="cow1", help="Kimia-99 image for the pixel-graph figure (default: %(default)s)")
    demo.set_defaults(run=_demo)
    reproduce = sub.add_parser(
        "reproduce",
        help="Re-run one of the thesis' experiments and print our numbers beside the thesis'.",
        description="Re-run a thesis experiment; tables and figures are written under --out/<experiment>/.",
    )
    reproduce.add_argument("experiment", choices=sorted(_EXPERIMENTS), help="which table or figure")
    reproduce.add_argument("--quick", action="store_true", help="a small version, for a first look or a test")
    reproduce.add_argument("--seed", type=int, default=0, help="seed of every random choice (default: %(default)s)")
    reproduce.add_argument("--out", default="results", help="output folder (default: %(default)s)")
    reproduce.set_defaults(run=_reproduce)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    from .exceptions import CentralityVisionError

    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.run(args)
    except (CentralityVisionError, ValueError, OSError) as exc:
        print(f"centrality-vision {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"centrality-vision {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
