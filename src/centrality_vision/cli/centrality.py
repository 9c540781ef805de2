"""``centrality-vision centrality``: the centrality of every point of a point set or pixel of a shape."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .._validation import counted
from ._common import (
    CENTRALITY_NAMES,
    GRAPH_OPTION_KINDS,
    GRAPH_PHRASES,
    POINT_FILES,
    add_graph_options,
    add_out,
    add_plot,
    add_point_options,
    add_progress,
    data_graph,
    given,
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

NAME = "centrality"
_WITH_PROGRESS = ("betweenness", "closeness", "harmonic", "eccentricity")
_DEGREE_LIKE = ("degree", "eigenvector", "pagerank", "katz")  # the measures that take --strengths
_PROGRESS_FROM = 2000  # nodes; smaller graphs finish before a progress bar is useful


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Centrality of every point of a point set, or of every foreground pixel of a binary image.",
        description=f"INPUT is a point set ({POINT_FILES}), joined by --graph into a data-graph,\n"
        "or an image (.png, .bmp, .gif, .tif, .jpg, ...), whose foreground pixels are joined to\n"
        "their 8 (or 4) neighbours (thesis ch. 4). Images are thresholded at half their range\n"
        "(or --threshold); by default the shape is the side that covers less of the border.\n"
        "Path-based centralities count hops unless --weights is given. Output rows: node, coordinates\n"
        "(x, y[, z] for points; row, col for pixels, row 0 at the top), one column per centrality.\n"
        ".csv/.npy: that table (the parameters go to NAME.json beside it);\n"
        ".json/.npz: the same columns by name, plus the parameters.",
        example="centrality-vision centrality fish.txt --centrality closeness --out fish_closeness.csv\n"
        "centrality-vision centrality cow1.png --centrality all --out cow1.json --plot cow1-centrality.png",
    )
    parser.add_argument("input", type=in_path, metavar="INPUT", help="point-set file or image")
    parser.add_argument(
        "--centrality",
        "--measure",  # its former name (register and classify say --centrality)
        dest="centrality",
        choices=CENTRALITY_NAMES + ("all",),
        default="closeness",
        help="which centrality; 'all' computes every one; --measure is its former name (default: %(default)s)",
    )
    add_point_options(parser)
    add_graph_options(parser, "--graph", help_text="data-graph for point sets")
    parser.add_argument(
        "--connectivity",
        type=int,
        choices=(8, 4),
        default=8,
        help="pixel neighbourhood for images (default: %(default)s)",
    )
    parser.add_argument(
        "--foreground",
        choices=("auto", "dark", "light"),
        default="auto",
        help="which side of the threshold is the shape in images (default: %(default)s)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=None,
        help="grey level between background and shape (default: half the image's range)",
    )
    parser.add_argument(
        "--weights",
        action="store_true",
        help="path-based measures (betweenness, closeness, harmonic, eccentricity): shortest paths "
        "by Euclidean edge length instead of hop counts",
    )
    parser.add_argument(
        "--strengths",
        action="store_true",
        help="degree-like measures (degree, eigenvector, pagerank, katz): sum the edge lengths "
        "instead of counting edges",
    )
    add_out(parser, ".json", ".csv", ".npy", ".npz")
    add_plot(parser, "the values (graph or image)")
    parser.add_argument(
        "--norm",
        choices=("auto", "linear", "log", "power"),
        default="auto",
        help="colour scale of the figure; auto: power (square root) for betweenness, whose "
        "values span orders of magnitude, linear for the others (default: %(default)s)",
    )
    add_progress(parser)
    parser.set_defaults(
        run=run,
        _parser=parser,
        # the library's names for INPUT, and its wording for an unset --threshold
        _cli_aliases={"points": "input", "image": "input"},
        _cli_phrases={"a finite real number or None": "a finite real number", **GRAPH_PHRASES},
    )
    return parser


# the options that apply to one kind of INPUT only (argument name: option)
_POINT_OPTIONS = {"columns": "--columns", "variable": "--variable", "graph": "--graph", "k": "--k", "lam": "--lam"}
_IMAGE_OPTIONS = {"connectivity": "--connectivity", "foreground": "--foreground", "threshold": "--threshold"}


def _refuse_options_of_the_other_input(args: argparse.Namespace, is_image: bool) -> None:
    """An option of point sets given with an image, or of images with a point set, is an
    error (they were ignored without a word)."""
    from ..exceptions import InputError

    other = _POINT_OPTIONS if is_image else _IMAGE_OPTIONS
    given = [option for name, option in other.items() if getattr(args, name) != args._parser.get_default(name)]
    if given:
        kinds = ("point sets", "an image") if is_image else ("images", "a point set")
        verb = "applies" if len(given) == 1 else "apply"
        raise InputError(f"{', '.join(given)} {verb} to {kinds[0]}; INPUT {args.input} is {kinds[1]}.")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import centrality as cen
    from ..exceptions import InputError
    from ..io import IMAGE_SUFFIXES, POINT_SUFFIXES, read_shape

    started = time.perf_counter()
    names = CENTRALITY_NAMES if args.centrality == "all" else (args.centrality,)
    kind = suffix(args.input)
    if kind not in IMAGE_SUFFIXES + POINT_SUFFIXES:
        raise InputError(
            f"{args.input}: INPUT must be an image ({', '.join(IMAGE_SUFFIXES)}) or a point set "
            f"({', '.join(POINT_SUFFIXES)}); got suffix {Path(args.input).suffix!r}."
        )
    is_image = kind in IMAGE_SUFFIXES
    _refuse_options_of_the_other_input(args, is_image)
    applies = {
        "weights": ("centrality", (*_WITH_PROGRESS, "all")),
        "strengths": ("centrality", (*_DEGREE_LIKE, "all")),
        **{dest: ("graph", kinds) for dest, kinds in GRAPH_OPTION_KINDS.items()},
    }
    refuse_unused(args, applies, vars(args))
    if given(args, "norm") and args.plot is None:
        raise InputError(f"--norm is the colour scale of --plot; got --norm {args.norm} without --plot.")
    if is_image:
        from ..graphs import pixel_graph

        mask = read_shape(args.input, foreground=args.foreground, threshold=args.threshold)
        graph, nodes = pixel_graph(mask, connectivity=args.connectivity)
        rows, cols = np.unravel_index(nodes, mask.shape)
        coordinates = {"row": rows.astype(np.int64), "col": cols.astype(np.int64)}
        info = {"input_kind": "image", "image_shape": list(mask.shape), "n_foreground": int(mask.sum())}
        say(f"read a {mask.shape[0]}x{mask.shape[1]} image with {int(mask.sum())} foreground pixels from {args.input}")
    else:
        points = read_point_file(args.input, args)
        say(f"read {counted(points.shape[0], 'point')} in {points.shape[1]}D from {args.input}")
        graph, extra = data_graph(
            points, args.graph, k=args.k, lam=args.lam, source=args.input, progress=progress_on(args)
        )
        coordinates = dict(zip("xyz", points.T))
        nodes = None
        info = {"input_kind": "points", **extra}
    n_nodes = graph.shape[0]
    info.update(n_nodes=n_nodes, n_edges=int(graph.nnz // 2))
    show = progress_on(args) and (args.progress is True or n_nodes >= _PROGRESS_FROM)
    values = {}
    for name in names:
        if name in _WITH_PROGRESS:  # the path-based measures
            extra_options = {"weights": args.weights, "progress": show}
        else:
            extra_options = {"strengths": args.strengths}
        tic = time.perf_counter()
        values[name] = np.asarray(cen.compute(graph, name, **extra_options), dtype=np.float64)
        say(f"{name}: {n_nodes} nodes in {time.perf_counter() - tic:.2f} s")
    node = np.arange(n_nodes, dtype=np.int64)
    unused = _POINT_OPTIONS if is_image else _IMAGE_OPTIONS
    record = {"command": NAME, "parameters": parameters_block(options(args, applies=applies, unused=unused)), **info}
    if suffix(args.out) == ".json":
        record.update(node=node, coordinates=coordinates, centrality=values)
    columns = {"node": node, **coordinates, **values}
    if args.plot:  # first: a plot that cannot be drawn (--norm log of no positive value) leaves no output
        _plot(
            args,
            names,
            values,
            graph=graph,
            coordinates=coordinates,
            is_image=is_image,
            shape=info.get("image_shape"),
            nodes=nodes,
        )
    written = write_output(args.out, record, arrays=columns, table=columns)
    if args.plot:
        written.append(Path(args.plot))
    say(f"wrote {', '.join(map(str, written))} in {time.perf_counter() - started:.1f} s")
    return 0


def _plot(args, names, values, *, graph, coordinates, is_image, shape, nodes) -> None:
    import numpy as np

    from ..plotting import plot_centrality_image, plot_graph, save_figure

    plt = pyplot()
    columns = min(3, len(names))
    rows = -(-len(names) // columns)
    three_d = not is_image and len(coordinates) == 3
    fig, axes = plt.subplots(
        rows,
        columns,
        figsize=(4.5 * columns, 4 * rows),
        squeeze=False,
        layout="constrained",
        subplot_kw={"projection": "3d"} if three_d else None,
    )
    for ax, name in zip(axes.ravel(), names):
        norm = args.norm if args.norm != "auto" else ("power" if name == "betweenness" else "linear")
        if is_image:
            plot_centrality_image(values[name], nodes, tuple(shape), ax=ax, label=name, title=name, norm=norm)
        else:
            points = np.column_stack(list(coordinates.values()))
            plot_graph(
                points,
                graph,
                values[name],
                ax=ax,
                label=name,
                title=name,
                node_size=18 if not three_d else 6,
                norm=norm,
            )
    for ax in axes.ravel()[len(names) :]:
        ax.remove()  # a hidden 3D panel broke the constrained layout (no tight bbox)
    fig.suptitle(Path(args.input).name)
    save_figure(fig, args.plot)
