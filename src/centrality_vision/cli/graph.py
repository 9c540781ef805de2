"""``centrality-vision graph``: the data-graph of a point set, as an edge list."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .._validation import counted
from ._common import (
    GRAPH_OPTION_KINDS,
    GRAPH_PHRASES,
    POINT_FILES,
    add_graph_options,
    add_out,
    add_plot,
    add_point_options,
    add_progress,
    data_graph,
    edge_list,
    in_path,
    options,
    progress_on,
    pyplot,
    read_point_file,
    refuse_unused,
    say,
    subparser,
    suffix,
)
from ._output import parameters_block, write_output

NAME = "graph"


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Build a data-graph (Delaunay, Gabriel, EMST, k-NN, ...) of a point set and write its edges.",
        description=f"POINTS is a point-set file ({POINT_FILES}). The edge list (i, j, length) is\n"
        "written with i < j, nodes numbered by row of POINTS from 0, lengths Euclidean.\n"
        ".json: edges, points and parameters; .npz: arrays 'edges' (m x 2), 'lengths', 'points';\n"
        ".csv: columns i, j, length (the parameters go to NAME.json beside it).\n"
        "mwme and mstme are the thesis' maximum-entropy graphs (ch. 6, 7).",
        example="centrality-vision graph fish.txt --kind delaunay --out fish_delaunay.json --plot fish.png",
    )
    parser.add_argument("points", type=in_path, metavar="POINTS", help="point-set file")
    add_point_options(parser)
    add_graph_options(parser, "--kind", help_text="which graph")
    add_out(parser, ".json", ".npz", ".csv")
    add_plot(parser, "the graph")
    add_progress(parser)
    parser.set_defaults(run=run, _parser=parser, _cli_phrases=GRAPH_PHRASES)
    return parser


def run(args: argparse.Namespace) -> int:
    import numpy as np

    started = time.perf_counter()
    applies = {dest: ("kind", kinds) for dest, kinds in GRAPH_OPTION_KINDS.items()}
    refuse_unused(args, applies, vars(args))
    points = read_point_file(args.points, args)
    say(f"read {counted(points.shape[0], 'point')} in {points.shape[1]}D from {args.points}")
    graph, extra = data_graph(points, args.kind, k=args.k, lam=args.lam, source=args.points, progress=progress_on(args))
    i, j, length = edge_list(points, graph)
    say(f"{args.kind} graph: {points.shape[0]} nodes, {i.size} edges")
    parameters = parameters_block(options(args, applies=applies))
    summary = {"n_nodes": points.shape[0], "n_edges": int(i.size), "total_length": float(length.sum()), **extra}
    record = {"command": NAME, "parameters": parameters, **summary}
    if suffix(args.out) == ".json":
        record.update(edges=[[int(a), int(b), float(c)] for a, b, c in zip(i, j, length)], points=points)
    arrays = {
        "edges": np.column_stack([i, j]),
        "lengths": length,
        "points": points,
        **{key: np.asarray(value) for key, value in summary.items()},
    }
    written = write_output(args.out, record, arrays=arrays, table={"i": i, "j": j, "length": length})
    if args.plot:
        from ..plotting import plot_graph, save_figure

        pyplot()
        title = f"{args.kind} graph of {Path(args.points).name}: {points.shape[0]} nodes, {i.size} edges"
        if args.kind in ("mwme", "mstme"):  # entropy graphs: what matters is the degree of each node
            degree = np.diff(graph.tocsr().indptr)
            ax = plot_graph(points, graph, degree, label="degree", title=title)
        else:
            ax = plot_graph(points, graph, title=title)
        save_figure(ax.figure, args.plot)
        written.append(Path(args.plot))
    say(f"wrote {', '.join(map(str, written))} in {time.perf_counter() - started:.1f} s")
    return 0
