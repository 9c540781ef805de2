"""The ``centrality-vision`` command.

Subcommands by capability: ``graph`` (data-graph of a point set), ``centrality`` (of a
point set's data-graph or an image's pixel graph), ``register`` (CPD, GPD, ICP),
``match`` (MWME matching), ``classify`` (centrality histograms + naive Bayes), plus
``demo`` and ``reproduce``. Heavy imports happen inside each subcommand; progress,
notes and warnings go to stderr, one line each; results go to ``--out`` (files are
read and written by :mod:`centrality_vision._io`), always with the run's parameters.
``main(argv) -> int`` returns the exit status (0 success, 2 bad input); usage errors
exit with status 2 and a one-line message, as argparse does.
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

    # registration: the fish under a similarity transform, CPD against closeness-GPD (fig. 5.3)
    from .experiments._compare import compare_methods
    from .plotting import plot_alignment_errors
    from .registration import RigidCPD

    moving = load_fish().moving
    angle = np.radians(50.0)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    moved = 1.5 * moving @ rot.T + np.array([0.5, -0.3])
    runs = compare_methods(moving, moved, moved, lambda cb: RigidCPD(scale=True, tol=1e-8, callback=cb), snapshots=(3, 6, 9))
    ax = plot_alignment_errors(
        {(k if k == "CPD" else f"GPD ({k})"): v["errors"][:25] for k, v in runs.items()},
        title="Fish under a similarity: alignment error (thesis fig. 5.3)",
    )
    save_figure(ax.figure, out / "fish_registration_errors.png")
    to_one_percent = {k: v["below"]["0.01"] for k, v in runs.items()}

    np.savez_compressed(out / "fish_delaunay_centralities.npz", points=fish, **values)
    record = {
        "command": "demo",
        "version": __version__,
        "data": "CPD fish (fixed set, 91 points); Kimia-99 " + args.shape,
        "graph": {"kind": "delaunay", "n_nodes": graph.shape[0], "n_edges": graph.nnz // 2},
        "centralities": {"weights": False, "defaults": "degree raw, betweenness unnormalised, closeness (n-1)/sum d, eigenvector max 1"},
        "pixel_graph": {"shape": args.shape, "connectivity": 8, "n_nodes": int(pixels.shape[0])},
        "registration": {
            "moving": "CPD fish (moving set)", "transform": "rotation 50 deg, scale 1.5, translation (0.5, -0.3)",
            "estimator": "RigidCPD(scale=True, tol=1e-8), GPD on Delaunay graphs",
            "iterations_to_1_percent_error": to_one_percent,
        },
        "seconds": round(time.perf_counter() - started, 3),
    }
    (out / "demo.json").write_text(json.dumps(record, indent=2) + "\n")

    top = np.argsort(values["closeness"])[::-1][:5]
    print("fish: the five most central points by closeness")
    print(f"{'node':>5} {'x':>8} {'y':>8} " + " ".join(f"{n:>12}" for n in _DEMO_CENTRALITIES))
    for i in top:
        print(f"{i:>5} {fish[i, 0]:>8.3f} {fish[i, 1]:>8.3f} " + " ".join(f"{values[n][i]:>12.4f}" for n in _DEMO_CENTRALITIES))
    print("fish under a similarity transform: iterations until the alignment error is 1% of its start")
    print("  " + ", ".join(f"{'CPD' if k == 'CPD' else 'GPD ' + k} {v}" for k, v in to_one_percent.items()))
    print(f"wrote {len(list(out.iterdir()))} files to {out}/ in {record['seconds']:.1f} s")
    return 0


def _experiments() -> dict:
    from .experiments import EXPERIMENTS

    return EXPERIMENTS


def _reproduce(args: argparse.Namespace) -> int:
    from importlib import import_module

    if args.experiment == "all":
        from .experiments.report import run_all

        path = run_all(args.out, quick=args.quick, seed=args.seed, scheduler=args.scheduler)
        print(f"wrote {path}")
        return 0
    module = import_module(f"centrality_vision.experiments.{_experiments()[args.experiment]}")
    argv = ["--out", str(Path(args.out) / args.experiment), "--seed", str(args.seed)]
    if args.quick:
        argv.append("--quick")
    if args.scheduler is not None:
        from .experiments.report import RUNNER_EXPERIMENTS

        if args.experiment not in RUNNER_EXPERIMENTS:
            from .exceptions import InputError

            raise InputError(
                f"`--scheduler` applies to {', '.join(RUNNER_EXPERIMENTS)} (and all); got it for {args.experiment}."
            )
        argv += ["--scheduler", args.scheduler]
    return module.main(argv)


# --------------------------------------------------------------------------------------
# Shared pieces of the capability subcommands (graph, centrality, register, match, classify)
# --------------------------------------------------------------------------------------

# Spelled out here so that building the parser imports nothing heavy; tests check them
# against centrality_vision.centrality.CENTRALITIES and centrality_vision.registration.GRAPHS.
GRAPH_KINDS = ("delaunay", "gabriel", "emst", "knn", "complete", "mwme", "mstme")
GPD_GRAPHS = ("delaunay", "gabriel", "emst", "knn", "complete")
CENTRALITY_NAMES = ("degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity")
_WITH_PROGRESS = ("betweenness", "closeness", "harmonic", "eccentricity")
_PROGRESS_FROM = 2000  # nodes; smaller graphs finish before a progress bar is useful


def _say(message: str) -> None:
    """Progress and notes go to stderr; stdout is kept for results a user asked to see."""
    print(message, file=sys.stderr)


def _options(args: argparse.Namespace) -> dict:
    """Every option of the run, for the "parameters" block of the outputs."""
    return {key: value for key, value in vars(args).items() if key != "run" and not key.startswith("_")}


def _suffix(path) -> str:
    return Path(path).suffix.lower()


def _out_file(*suffixes: str):
    """An argparse type: an output path whose suffix is one of ``suffixes``."""

    def check(text: str) -> str:
        if _suffix(text) not in suffixes:
            raise argparse.ArgumentTypeError(f"{text!r} must end in {' or '.join(suffixes)}")
        return text

    check.__name__ = "output file"
    return check


_FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def _number(kind, *, low=None, low_open=False, high=None, high_open=False):
    """An argparse type: an int or float in a range."""

    def check(text: str):
        try:
            value = kind(text)
        except ValueError:
            wanted = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"must be {wanted}; got {text!r}") from None
        if kind is float and value != value:
            raise argparse.ArgumentTypeError(f"must be a number; got {text!r}")
        too_low = low is not None and (value <= low if low_open else value < low)
        too_high = high is not None and (value >= high if high_open else value > high)
        if too_low or too_high:
            left = "(" if low_open else "["
            right = ")" if high_open else "]"
            span = f"{left}{'-inf' if low is None else low}, {'inf' if high is None else high}{right}"
            raise argparse.ArgumentTypeError(f"must be in {span}; got {text}")
        return value

    check.__name__ = "integer" if kind is int else "number"
    return check


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only: never open a window
    import matplotlib.pyplot as plt

    return plt


def _data_graph(points, kind: str, *, k: int, lam: float, source=None):
    """The data-graph ``kind`` of ``points``, and a dict of what the builder reports beside it.

    An :class:`InputError` about the points (too few, duplicates, collinear) is raised
    again with ``source``, the file they came from, in front.
    """
    from .exceptions import InputError

    try:
        return _build_graph(points, kind, k=k, lam=lam)
    except InputError as exc:
        if source is None:
            raise
        raise InputError(f"{source}: {kind} graph: {exc}") from None


def _build_graph(points, kind: str, *, k: int, lam: float):
    from . import graphs

    if kind == "knn":
        if k >= points.shape[0]:
            from .exceptions import InputError

            raise InputError(f"--k must be smaller than the number of points ({points.shape[0]}); got {k}.")
        return graphs.knn_graph(points, k=k), {}
    if kind == "mwme":
        result = graphs.mwme_graph(points)
        return result.graph, {"cost": float(result.cost), "degrees": result.degrees}
    if kind == "mstme":
        result = graphs.mstme_graph(points, lam=lam)
        extra = {"cost": float(result.cost), "weight": float(result.weight), "entropy": float(result.entropy)}
        return result.graph, extra
    builder = {
        "delaunay": graphs.delaunay_graph,
        "gabriel": graphs.gabriel_graph,
        "emst": graphs.emst_graph,
        "complete": graphs.complete_graph,
    }[kind]
    return builder(points), {}


def _edge_list(points, graph):
    """Edges ``i < j`` of a symmetric sparse graph, sorted, with their Euclidean lengths."""
    import numpy as np
    from scipy import sparse

    upper = sparse.triu(sparse.coo_array(graph), k=1).tocoo()
    order = np.lexsort((upper.col, upper.row))
    i = upper.row[order].astype(np.int64)
    j = upper.col[order].astype(np.int64)
    return i, j, np.linalg.norm(points[i] - points[j], axis=1)


def _add_graph_options(parser: argparse.ArgumentParser, flag: str, *, help_text: str) -> None:
    parser.add_argument(flag, choices=GRAPH_KINDS, default="delaunay", help=help_text + " (default: %(default)s)")
    parser.add_argument(
        "--k", type=_number(int, low=1), default=6, help="neighbours per point for the knn graph (default: %(default)s)"
    )
    parser.add_argument(
        "--lam", type=_number(float, low=0), default=0.5,
        help="weight of the degree entropy for the mstme graph; 0 gives the EMST (default: %(default)s)",
    )


# --------------------------------------------------------------------------------------
# graph
# --------------------------------------------------------------------------------------


def _graph(args: argparse.Namespace) -> int:
    import numpy as np

    from ._io import parameters_block, read_points, write_json, write_npz, write_table

    started = time.perf_counter()
    points = read_points(args.points)
    _say(f"read {points.shape[0]} points in {points.shape[1]}D from {args.points}")
    graph, extra = _data_graph(points, args.kind, k=args.k, lam=args.lam, source=args.points)
    i, j, length = _edge_list(points, graph)
    _say(f"{args.kind} graph: {points.shape[0]} nodes, {i.size} edges")
    parameters = parameters_block(_options(args))
    summary = {"n_nodes": points.shape[0], "n_edges": int(i.size), "total_length": float(length.sum()), **extra}
    suffix = _suffix(args.out)
    if suffix == ".json":
        record = {"command": "graph", "parameters": parameters, **summary,
                  "edges": [[int(a), int(b), float(c)] for a, b, c in zip(i, j, length)], "points": points}
        write_json(args.out, record)
    elif suffix == ".npz":
        write_npz(args.out, {"edges": np.column_stack([i, j]), "lengths": length, "points": points,
                             **{key: np.asarray(value) for key, value in summary.items()}}, parameters)
    else:
        write_table(args.out, {"i": i, "j": j, "length": length}, parameters)
    if args.plot:
        from .plotting import plot_graph, save_figure

        _pyplot()
        ax = plot_graph(points, graph, title=f"{args.kind} graph of {Path(args.points).name}")
        save_figure(ax.figure, args.plot)
    _say(f"wrote {args.out}" + (f" and {args.plot}" if args.plot else "") + f" in {time.perf_counter() - started:.1f} s")
    return 0


# --------------------------------------------------------------------------------------
# centrality
# --------------------------------------------------------------------------------------


def _centrality(args: argparse.Namespace) -> int:
    import numpy as np

    from . import centrality as cen
    from ._io import IMAGE_SUFFIXES, parameters_block, read_image, read_points, write_json, write_npz, write_table

    started = time.perf_counter()
    names = CENTRALITY_NAMES if args.measure == "all" else (args.measure,)
    is_image = _suffix(args.input) in IMAGE_SUFFIXES
    info: dict = {}
    if is_image:
        from .graphs import pixel_graph

        mask = read_image(args.input, foreground=args.foreground)
        graph, nodes = pixel_graph(mask, connectivity=args.connectivity)
        rows, cols = np.unravel_index(nodes, mask.shape)
        coordinates = {"row": rows.astype(np.int64), "col": cols.astype(np.int64)}
        info = {"input_kind": "image", "image_shape": list(mask.shape), "n_foreground": int(mask.sum())}
        _say(f"read a {mask.shape[0]}x{mask.shape[1]} image with {int(mask.sum())} foreground pixels from {args.input}")
    else:
        points = read_points(args.input)
        _say(f"read {points.shape[0]} points in {points.shape[1]}D from {args.input}")
        graph, extra = _data_graph(points, args.graph, k=args.k, lam=args.lam, source=args.input)
        coordinates = dict(zip("xyz", points.T))
        nodes = None
        info = {"input_kind": "points", **extra}
    n_nodes = graph.shape[0]
    info.update(n_nodes=n_nodes, n_edges=int(graph.nnz // 2))
    values = {}
    for name in names:
        options = {"weights": args.weights}
        if name in _WITH_PROGRESS and n_nodes >= _PROGRESS_FROM:
            options["progress"] = True
        tic = time.perf_counter()
        values[name] = np.asarray(cen.compute(graph, name, **options), dtype=np.float64)
        _say(f"{name}: {n_nodes} nodes in {time.perf_counter() - tic:.2f} s")
    parameters = parameters_block(_options(args))
    suffix = _suffix(args.out)
    node = np.arange(n_nodes, dtype=np.int64)
    if suffix == ".json":
        write_json(args.out, {"command": "centrality", "parameters": parameters, **info,
                              "node": node, "coordinates": coordinates, "centrality": values})
    elif suffix == ".npz":
        write_npz(args.out, {"node": node, **coordinates, **values}, parameters)
    else:
        write_table(args.out, {"node": node, **coordinates, **values}, parameters)
    if args.plot:
        _plot_centrality(args, names, values, graph=graph, coordinates=coordinates, is_image=is_image,
                         shape=info.get("image_shape"), nodes=nodes)
    _say(f"wrote {args.out}" + (f" and {args.plot}" if args.plot else "") + f" in {time.perf_counter() - started:.1f} s")
    return 0


def _plot_centrality(args, names, values, *, graph, coordinates, is_image, shape, nodes) -> None:
    import numpy as np

    from .plotting import plot_centrality_image, plot_graph, save_figure

    plt = _pyplot()
    columns = min(3, len(names))
    rows = -(-len(names) // columns)
    three_d = not is_image and len(coordinates) == 3
    fig, axes = plt.subplots(rows, columns, figsize=(4.5 * columns, 4 * rows), squeeze=False,
                             subplot_kw={"projection": "3d"} if three_d else None)
    for ax, name in zip(axes.ravel(), names):
        if is_image:
            plot_centrality_image(values[name], nodes, tuple(shape), ax=ax, label=name, title=name)
        else:
            points = np.column_stack(list(coordinates.values()))
            plot_graph(points, graph, values[name], ax=ax, label=name, title=name, node_size=18)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle(Path(args.input).name)
    save_figure(fig, args.plot)


# --------------------------------------------------------------------------------------
# register
# --------------------------------------------------------------------------------------


def _registration_estimator(args: argparse.Namespace):
    from .exceptions import InputError
    from .registration import GPD, ICP, AffineCPD, NonRigidCPD, RigidCPD

    if args.method == "icp":
        if args.transform not in ("rigid", "similarity"):
            raise InputError(
                f"ICP fits rigid or similarity transforms only; got --transform {args.transform}. "
                "Use --method cpd or gpd for affine and nonrigid."
            )
        return ICP(scale=args.transform == "similarity", max_iter=args.max_iter, tol=args.tol)
    common = {"w": args.w, "max_iter": args.max_iter, "tol": args.tol}
    if args.transform in ("rigid", "similarity"):
        base = RigidCPD(scale=args.transform == "similarity", **common)
    elif args.transform == "affine":
        base = AffineCPD(**common)
    else:
        base = NonRigidCPD(beta=args.beta, lam=args.lam, **common)
    if args.method == "cpd":
        return base
    return GPD(base, centrality=args.centrality, graph=args.graph, kappa=args.kappa, k=args.k)


def _transform_record(transform) -> dict:
    from .transforms import AffineTransform, NonRigidTransform, RigidTransform, SimilarityTransform

    if isinstance(transform, NonRigidTransform):
        return {"type": "nonrigid", "control_points": transform.control_points,
                "coefficients": transform.coefficients, "beta": float(transform.beta)}
    if isinstance(transform, AffineTransform):
        return {"type": "affine", "linear": transform.linear, "translation": transform.translation,
                "matrix": transform.matrix}
    if isinstance(transform, SimilarityTransform):
        kind = "rigid" if isinstance(transform, RigidTransform) else "similarity"
        return {"type": kind, "rotation": transform.rotation, "translation": transform.translation,
                "scale": float(transform.scale), "matrix": transform.matrix}
    raise TypeError(f"unknown transform type {type(transform).__name__}")  # pragma: no cover


def _register(args: argparse.Namespace) -> int:
    import numpy as np

    from ._io import parameters_block, read_points, write_json, write_npz
    from .exceptions import InputError

    started = time.perf_counter()
    estimator = _registration_estimator(args)  # a bad combination fails before any reading
    moving = read_points(args.moving)
    fixed = read_points(args.fixed)
    if moving.shape[1] != fixed.shape[1]:
        raise InputError(
            f"{args.moving} and {args.fixed}: the point sets must have the same dimension; "
            f"got {moving.shape[1]} and {fixed.shape[1]} columns."
        )
    true_moving = None
    if args.true_moving is not None:
        true_moving = read_points(args.true_moving)
        if true_moving.shape != moving.shape:
            raise InputError(
                f"{args.true_moving}: --true-moving must have the shape of the moving set {moving.shape}; "
                f"got {true_moving.shape}."
            )
    label = f"{args.method.upper()} ({args.transform})"
    if args.method == "gpd":
        label = f"GPD ({args.transform}, {args.centrality}, {args.graph})"
    _say(f"{label}: moving {args.moving} ({moving.shape[0]} points), fixed {args.fixed} ({fixed.shape[0]} points), "
         f"{moving.shape[1]}D")
    estimator.fit(moving, fixed, true_moving=true_moving)
    seconds = time.perf_counter() - started
    status = "converged" if estimator.converged_ else "stopped at --max-iter without converging"
    _say(f"{label}: {status} after {estimator.n_iter_} iterations in {seconds:.2f} s")

    history = {key: (None if value is None else np.asarray(value)) for key, value in estimator.history_.items()}
    sigma2 = getattr(estimator, "sigma2_", None)
    final_error = None if history.get("error") is None or history["error"].size == 0 else float(history["error"][-1])
    parameters = parameters_block(_options(args))
    transform = _transform_record(estimator.transform_)
    result = {
        "estimator": " ".join(repr(estimator).split()),
        "transform": transform,
        "moving_transformed": estimator.moving_transformed_,
        "n_iter": int(estimator.n_iter_),
        "converged": bool(estimator.converged_),
        "sigma2": None if sigma2 is None else float(sigma2),
        "final_error": final_error,
        "history": history,
        "correspondence": np.asarray(estimator.correspondence_, dtype=np.int64),
        "correspondence_meaning": "for each fixed point, the index of the moving point it is matched to"
        + ("" if args.method == "icp" else " (the most probable; -1 for an outlier)"),
        "warnings": list(getattr(args, "_warnings", [])),
        "seconds": round(seconds, 3),
    }
    if args.method == "gpd":
        result["moving_centrality"] = estimator.moving_centrality_
        result["fixed_centrality"] = estimator.fixed_centrality_
    if _suffix(args.out) == ".json":
        write_json(args.out, {"command": "register", "parameters": parameters, **result})
    else:
        arrays = {f"transform_{key}": value for key, value in transform.items()}
        arrays.update({f"history_{key}": value for key, value in history.items()})
        arrays.update({key: value for key, value in result.items() if key not in ("transform", "history", "warnings")})
        arrays["warnings"] = np.array(result["warnings"], dtype=str)
        write_npz(args.out, arrays, parameters)
    if args.plot:
        _plot_registration(args, estimator, fixed, label)
    _say(f"wrote {args.out}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def _plot_registration(args, estimator, fixed, label) -> None:
    from .plotting import plot_alignment_errors, save_figure

    plt = _pyplot()
    if args.true_moving is not None:
        ax = plot_alignment_errors({label: estimator.history_["error"]}, title="alignment error per iteration")
        save_figure(ax.figure, args.plot)
        return
    moved = estimator.moving_transformed_
    three_d = fixed.shape[1] == 3
    fig = plt.figure(figsize=(5.5, 5))
    ax = fig.add_subplot(projection="3d" if three_d else None)
    ax.scatter(*fixed.T, s=14, c="tab:blue", label=f"fixed ({Path(args.fixed).name})")
    ax.scatter(*moved.T, s=14, c="tab:red", marker="x", label=f"moving, aligned ({Path(args.moving).name})")
    if not three_d:
        ax.set_aspect("equal")
    ax.legend(fontsize=8)
    ax.set_title(label)
    save_figure(fig, args.plot)


# --------------------------------------------------------------------------------------
# match
# --------------------------------------------------------------------------------------


def _match(args: argparse.Namespace) -> int:
    import numpy as np

    from ._io import parameters_block, read_points, write_json, write_npz
    from .exceptions import InputError
    from .matching import mwme_match

    started = time.perf_counter()
    moving = read_points(args.moving)
    fixed = read_points(args.fixed)
    if moving.shape != fixed.shape:
        raise InputError(
            f"{args.moving} and {args.fixed}: MWME matching needs two sets of the same size and dimension; "
            f"got shapes {moving.shape} and {fixed.shape}."
        )
    if args.plot and moving.shape[1] != 2:
        raise InputError(f"--plot draws 2D point sets only; got {moving.shape[1]}D points.")
    _say(f"MWME matching ({args.method}) of {moving.shape[0]} points in {moving.shape[1]}D")
    correspondence, transform = mwme_match(moving, fixed, method=args.method, scale=args.transform == "similarity")
    correspondence = np.asarray(correspondence, dtype=np.int64)
    moved = transform(moving)
    rms = float(np.sqrt(np.mean(np.sum((moved - fixed[correspondence]) ** 2, axis=1))))
    seconds = time.perf_counter() - started
    _say(f"matched in {seconds:.2f} s; RMS residual of the fitted {args.transform} transform: {rms:.6g}")
    record = {
        "correspondence": correspondence,
        "correspondence_meaning": "moving[i] matches fixed[correspondence[i]]",
        "transform": _transform_record(transform),
        "moving_transformed": moved,
        "rms_residual": rms,
        "seconds": round(seconds, 3),
    }
    parameters = parameters_block(_options(args))
    if _suffix(args.out) == ".json":
        write_json(args.out, {"command": "match", "parameters": parameters, **record})
    else:
        arrays = {f"transform_{key}": value for key, value in record.pop("transform").items()}
        write_npz(args.out, {**arrays, **record}, parameters)
    if args.plot:
        from .plotting import plot_matching, save_figure

        _pyplot()
        ax = plot_matching(moving, fixed, correspondence, title=f"MWME matching ({args.method})")
        save_figure(ax.figure, args.plot)
    _say(f"wrote {args.out}" + (f" and {args.plot}" if args.plot else ""))
    return 0


# --------------------------------------------------------------------------------------
# classify
# --------------------------------------------------------------------------------------


def _label_of(path: Path) -> str:
    """Kimia style: ``cow1.png`` -> ``cow``; a name made only of digits keeps them."""
    import re

    return re.sub(r"\d+$", "", path.stem) or path.stem


def _read_labels(path) -> dict:
    import csv

    from .exceptions import InputError

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file.")
    with path.open("r", encoding="utf-8", newline="") as handle:
        reader = csv.DictReader(handle)
        if reader.fieldnames is None or not {"file", "label"} <= set(reader.fieldnames):
            raise InputError(f"{path}: a labels file must be a CSV with columns 'file' and 'label'; got {reader.fieldnames}.")
        return {row["file"]: row["label"] for row in reader}


def _classify(args: argparse.Namespace) -> int:
    import numpy as np

    from ._io import parameters_block, read_image, write_json
    from .exceptions import InputError

    started = time.perf_counter()
    folder = Path(args.images_dir)
    if not folder.is_dir():
        raise InputError(f"{folder}: no such folder.")
    files = sorted(path for path in folder.iterdir() if path.suffix.lower() == ".png" and path.is_file())
    if not files:
        raise InputError(f"{folder}: holds no .png images.")
    if args.labels:
        label_of = _read_labels(args.labels)
        missing = [path.name for path in files if path.name not in label_of]
        if missing:
            raise InputError(f"{args.labels}: no label for {len(missing)} image(s), e.g. {missing[0]!r}.")
        labels = np.array([label_of[path.name] for path in files])
    else:
        labels = np.array([_label_of(path) for path in files])
    images = [read_image(path, foreground=args.foreground) for path in files]
    classes, counts = np.unique(labels, return_counts=True)
    _say(f"read {len(files)} images in {classes.size} classes from {folder}")
    if classes.size < 2:
        raise InputError(f"{folder}: classification needs at least 2 classes; every image is labelled {str(classes[0])!r}.")
    smallest = int(counts.min())
    if smallest < 2:
        lonely = [str(name) for name in classes[counts == 1]]
        raise InputError(
            f"{folder}: every class needs at least 2 images for cross-validation; "
            f"{len(lonely)} class(es) have 1, e.g. {lonely[0]!r}."
        )
    n_splits = min(args.folds, smallest)
    note = None
    if n_splits < args.folds:
        note = (f"the smallest class ({str(classes[np.argmin(counts)])!r}) has {smallest} images, "
                f"fewer than --folds {args.folds}: using {n_splits} folds")
        _say("note: " + note)

    from sklearn.base import clone
    from sklearn.model_selection import StratifiedKFold
    from sklearn.naive_bayes import GaussianNB
    from sklearn.pipeline import make_pipeline

    from .shapes import CentralityHistogram

    model = make_pipeline(CentralityHistogram(centrality=args.centrality, bins=args.bins), GaussianNB())
    splitter = StratifiedKFold(n_splits=n_splits, shuffle=True, random_state=args.seed)
    predicted = np.empty(labels.size, dtype=labels.dtype)
    fold_of = np.empty(labels.size, dtype=np.int64)
    scores = []
    for fold, (train, test) in enumerate(splitter.split(np.zeros(labels.size), labels)):
        fitted = clone(model).fit([images[i] for i in train], labels[train])
        predicted[test] = fitted.predict([images[i] for i in test])
        fold_of[test] = fold
        scores.append(float(np.mean(predicted[test] == labels[test])))
        _say(f"fold {fold + 1}/{n_splits}: accuracy {scores[-1]:.3f} ({test.size} images)")
    accuracy = float(np.mean(scores))
    _say(f"accuracy {accuracy:.3f} +- {float(np.std(scores)):.3f} over {n_splits} folds "
         f"({time.perf_counter() - started:.1f} s)")
    index = {name: k for k, name in enumerate(classes)}
    confusion = np.zeros((classes.size, classes.size), dtype=np.int64)
    for truth, guess in zip(labels, predicted):
        confusion[index[truth], index[guess]] += 1
    histogram_params = {key: value for key, value in model.steps[0][1].get_params().items() if key != "progress"}
    write_json(args.out, {
        "command": "classify",
        "parameters": parameters_block({**_options(args), "histogram": histogram_params, "classifier": "GaussianNB()"},
                                       seed=args.seed),
        "cross_validation": {"splitter": "StratifiedKFold(shuffle=True)", "n_splits": n_splits, "note": note},
        "accuracy": accuracy,
        "accuracy_std": float(np.std(scores)),
        "fold_accuracy": scores,
        "classes": classes.tolist(),
        "class_counts": counts,
        "confusion": confusion,
        "confusion_meaning": "confusion[i][j]: images of class i predicted as class j",
        "images": [{"file": path.name, "label": str(truth), "predicted": str(guess), "fold": int(fold)}
                   for path, truth, guess, fold in zip(files, labels, predicted, fold_of)],
        "seconds": round(time.perf_counter() - started, 3),
    })
    print(f"accuracy {accuracy:.3f} ({n_splits}-fold cross-validation, {len(files)} images, {classes.size} classes)")
    _say(f"wrote {args.out}")
    return 0


# --------------------------------------------------------------------------------------
# the parser
# --------------------------------------------------------------------------------------


class _Parser(argparse.ArgumentParser):
    """argparse, with usage errors on one line (the message and where to find help)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see '{self.prog} --help')\n")


def _subparser(sub, name: str, *, summary: str, description: str, example: str) -> argparse.ArgumentParser:
    return sub.add_parser(
        name,
        help=summary,
        description=summary + "\n\n" + description,
        epilog="example:\n  " + example.strip().replace("\n", "\n  "),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def _add_out(parser: argparse.ArgumentParser, *suffixes: str) -> None:
    kinds = ", ".join(suffixes)
    parser.add_argument("--out", required=True, metavar="FILE", type=_out_file(*suffixes), help=f"output file ({kinds})")


def _add_plot(parser: argparse.ArgumentParser, what: str) -> None:
    kinds = ", ".join(_FIGURE_SUFFIXES[:-1])
    parser.add_argument("--plot", metavar="FILE.png", type=_out_file(*_FIGURE_SUFFIXES), help=f"also draw {what} ({kinds})")


def _add_capabilities(sub) -> None:
    graph = _subparser(
        sub, "graph",
        summary="Build a data-graph (Delaunay, Gabriel, EMST, k-NN, ...) of a point set and write its edges.",
        description="POINTS is a .txt or .csv file (one point per line, 2 or 3 coordinates separated by\n"
        "commas or spaces, an optional header line) or a .npy array. The edge list (i, j, length)\n"
        "is written with i < j, nodes numbered by row of POINTS from 0, lengths Euclidean.\n"
        ".json: edges, points and parameters; .npz: arrays 'edges' (m x 2), 'lengths', 'points';\n"
        ".csv: columns i, j, length. mwme and mstme are the thesis' maximum-entropy graphs (ch. 6, 7).",
        example="centrality-vision graph fish.txt --kind delaunay --out fish_delaunay.json --plot fish.png",
    )
    graph.add_argument("points", metavar="POINTS", help="point set file (.txt, .csv or .npy)")
    _add_graph_options(graph, "--kind", help_text="which graph")
    _add_out(graph, ".json", ".npz", ".csv")
    _add_plot(graph, "the graph")
    graph.set_defaults(run=_graph, _parser=graph)

    centrality = _subparser(
        sub, "centrality",
        summary="Centrality of every point of a point set, or of every foreground pixel of a binary image.",
        description="INPUT is a point set (.txt, .csv, .npy), joined by --graph into a data-graph, or a .png\n"
        "image, whose foreground pixels are joined to their 8 (or 4) neighbours (thesis ch. 4).\n"
        "Images are thresholded at half their range; by default the shape is the side that covers\n"
        "less of the border (dark on white or white on black both work). Centralities count hops\n"
        "unless --weights is given. Output rows: node, coordinates (x, y[, z] or row, col), values.\n"
        ".csv/.npy: that table (.npy's column names and parameters go to NAME.parameters.json);\n"
        ".json/.npz: the same columns by name, plus the parameters.",
        example="centrality-vision centrality fish.txt --measure closeness --out fish_closeness.csv\n"
        "centrality-vision centrality cow1.png --measure all --out cow1.json --plot cow1.png",
    )
    centrality.add_argument("input", metavar="INPUT", help="point set (.txt, .csv, .npy) or binary image (.png)")
    centrality.add_argument("--measure", choices=CENTRALITY_NAMES + ("all",), default="closeness",
                            help="which centrality; 'all' computes every one (default: %(default)s)")
    _add_graph_options(centrality, "--graph", help_text="data-graph for point sets")
    centrality.add_argument(
        "--connectivity", type=int, choices=(8, 4), default=8, help="pixel neighbourhood for images (default: %(default)s)"
    )
    centrality.add_argument("--foreground", choices=("auto", "dark", "light"), default="auto",
                            help="which side of the threshold is the shape in images (default: %(default)s)")
    centrality.add_argument("--weights", action="store_true", help="use Euclidean edge lengths instead of hop counts")
    _add_out(centrality, ".json", ".csv", ".npy", ".npz")
    _add_plot(centrality, "the values (graph or image)")
    centrality.set_defaults(run=_centrality, _parser=centrality)

    register = _subparser(
        sub, "register",
        summary="Align a moving point set onto a fixed one (CPD, GPD or ICP) and write the transform.",
        description="MOVING and FIXED are point sets (.txt, .csv, .npy) of the same dimension (2 or 3); they\n"
        "need not have the same number of points. cpd is Coherent Point Drift, gpd the thesis'\n"
        "Graph-based Point Drift (CPD whose matching also compares a centrality of each point in\n"
        "a data-graph, ch. 5), icp Iterative Closest Point (rigid or similarity only).\n"
        "--true-moving: where each moving point truly belongs in the fixed frame; the alignment\n"
        "error is then recorded per iteration (and plotted with --plot).\n"
        "Output: the transform, the aligned moving set, iterations, convergence, the history of\n"
        "objective/sigma2/error, the correspondences and every parameter (.json or .npz).",
        example="centrality-vision register fish_moving.txt fish_fixed.txt --method gpd --transform nonrigid \\\n"
        "    --centrality closeness --out aligned.json --plot aligned.png",
    )
    register.add_argument("moving", metavar="MOVING", help="point set to move (.txt, .csv or .npy)")
    register.add_argument("fixed", metavar="FIXED", help="point set to align onto (.txt, .csv or .npy)")
    register.add_argument(
        "--method", choices=("cpd", "gpd", "icp"), default="cpd", help="registration method (default: %(default)s)"
    )
    register.add_argument("--transform", choices=("rigid", "similarity", "affine", "nonrigid"), default="similarity",
                          help="transform family; similarity = rigid + isotropic scale (default: %(default)s)")
    register.add_argument("--centrality", choices=CENTRALITY_NAMES, default="closeness",
                          help="GPD only: centrality of the points (default: %(default)s)")
    register.add_argument("--graph", choices=GPD_GRAPHS, default="delaunay",
                          help="GPD only: data-graph the centrality is computed on (default: %(default)s)")
    register.add_argument("--k", type=_number(int, low=1), default=6,
                          help="GPD only: neighbours for --graph knn (default: %(default)s)")
    register.add_argument("--kappa", type=_number(float, low=0, low_open=True, high=1), default=0.5,
                          help="GPD only: geometry-vs-centrality balance, 1 = plain CPD (default: %(default)s)")
    register.add_argument("--w", type=_number(float, low=0, high=1, high_open=True), default=0.0,
                          help="CPD/GPD: weight of the outlier component, in [0, 1) (default: %(default)s)")
    register.add_argument("--max-iter", type=_number(int, low=1), default=150,
                          help="most iterations (default: %(default)s)")
    register.add_argument("--tol", type=_number(float, low=0, low_open=True), default=1e-5,
                          help="stop when the objective changes by less than this, relatively (default: %(default)s)")
    register.add_argument("--beta", type=_number(float, low=0, low_open=True), default=2.0,
                          help="nonrigid: width of the Gaussian kernel (default: %(default)s)")
    register.add_argument("--lam", type=_number(float, low=0, low_open=True), default=2.0,
                          help="nonrigid: smoothness weight (default: %(default)s)")
    register.add_argument("--true-moving", metavar="FILE",
                          help="true positions of the moving points, to record the alignment error")
    _add_out(register, ".json", ".npz")
    _add_plot(register, "the error curve (with --true-moving) or the fixed and aligned points")
    register.set_defaults(run=_register, _parser=register)

    match = _subparser(
        sub, "match",
        summary="Match two point sets of the same size through their MWME graphs (thesis ch. 6).",
        description="Each set gets its minimum-weight maximum-entropy graph, whose nodes have distinct\n"
        "degrees (but two); points of equal degree correspond. Writes the correspondence\n"
        "(moving[i] -> fixed[correspondence[i]]) and the least-squares transform fitted to it.\n"
        "The cost grows as n^3: meant for tens to a few hundred points.",
        example="centrality-vision match moving.txt fixed.txt --method local --out matching.json",
    )
    match.add_argument("moving", metavar="MOVING", help="point set (.txt, .csv or .npy)")
    match.add_argument("fixed", metavar="FIXED", help="point set of the same size (.txt, .csv or .npy)")
    match.add_argument("--method", choices=("local", "greedy", "exact"), default="local",
                       help="MWME solver; exact only up to 20 points (default: %(default)s)")
    match.add_argument("--transform", choices=("similarity", "rigid"), default="similarity",
                       help="transform fitted to the matched points (default: %(default)s)")
    _add_out(match, ".json", ".npz")
    _add_plot(match, "the matching (2D sets)")
    match.set_defaults(run=_match, _parser=match)

    classify = _subparser(
        sub, "classify",
        summary="Cross-validated shape classification of a folder of silhouettes by centrality histograms.",
        description="Every .png in IMAGES_DIR is read as a binary silhouette; its label is the file name\n"
        "without extension and trailing digits (cow1.png -> cow), or comes from --labels.\n"
        "Features: the normalised histogram of a pixel-graph centrality (thesis ch. 4);\n"
        "classifier: Gaussian naive Bayes; accuracy by stratified k-fold cross-validation\n"
        "(shuffled with --seed). If the smallest class has fewer images than --folds, the\n"
        "number of folds is reduced to its size (a note says so); every class needs 2 images.",
        example="centrality-vision classify kimia99/ --labels kimia99/labels.csv --centrality closeness \\\n"
        "    --out kimia.json",
    )
    classify.add_argument("images_dir", metavar="IMAGES_DIR", help="folder of .png silhouettes")
    classify.add_argument("--labels", metavar="FILE.csv", help="CSV with columns file,label (instead of the file names)")
    classify.add_argument("--centrality", choices=CENTRALITY_NAMES + ("all",), default="closeness",
                          help="centrality whose histogram is the feature; 'all' concatenates four (default: %(default)s)")
    classify.add_argument("--bins", type=_number(int, low=1), default=40, help="histogram bins (default: %(default)s)")
    classify.add_argument("--folds", type=_number(int, low=2), default=5,
                          help="cross-validation folds (default: %(default)s)")
    classify.add_argument("--seed", type=int, default=0, help="seed of the fold shuffling (default: %(default)s)")
    classify.add_argument("--foreground", choices=("auto", "dark", "light"), default="auto",
                          help="which side of the threshold is the shape (default: %(default)s)")
    _add_out(classify, ".json")
    classify.set_defaults(run=_classify, _parser=classify)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="centrality-vision",
        description="Graph centrality for computer vision (de Sousa, TU Wien, 2015).",
    )
    from . import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo",
        help="Centralities of the bundled fish and a Kimia-99 shape, and CPD against GPD on the fish, with figures.",
        description="Build the Delaunay graph of the bundled CPD fish, compute degree, betweenness, "
        "closeness and eigenvector centrality, and draw the graph coloured by closeness (thesis "
        "fig. 5.1); draw the closeness of a Kimia-99 silhouette's pixel graph (fig. 4.2); register the fish "
        "under a similarity transform with CPD and with GPD for four centralities (fig. 5.3).",
    )
    demo.add_argument("--out", default="demo-output", help="output folder (default: %(default)s)")
    demo.add_argument("--shape", default="cow1", help="Kimia-99 image for the pixel-graph figure (default: %(default)s)")
    demo.set_defaults(run=_demo, _parser=demo)
    reproduce = sub.add_parser(
        "reproduce",
        help="Re-run one of the thesis' experiments and print our numbers beside the thesis'.",
        description="Re-run a thesis experiment; tables and figures are written under --out/<experiment>/. "
        "'all' runs every experiment and writes --out/report.md with every table and figure.",
    )
    reproduce.add_argument("experiment", choices=[*_experiments(), "all"], help="which table or figure, or all of them with a report")
    reproduce.add_argument("--quick", action="store_true", help="a small version, for a first look or a test")
    reproduce.add_argument("--seed", type=int, default=0, help="seed of every random choice (default: %(default)s)")
    reproduce.add_argument("--out", default="results", help="output folder (default: %(default)s)")
    reproduce.add_argument(
        "--scheduler",
        default=None,
        help="where the units of table-4.1, table-5.1, fig-6.4 and fig-7.4 run: serial, processes (default), dask (a local cluster started "
        "for the run) or tcp://host:port (a running Dask scheduler); finished units are kept and skipped on a re-run",
    )
    reproduce.set_defaults(run=_reproduce, _parser=reproduce)
    _add_capabilities(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 success, 2 bad input, 130 interrupted).

    Usage errors exit through :class:`SystemExit` (status 2), as argparse does. Errors in
    the input files or values (:class:`~centrality_vision.exceptions.InputError`,
    ``ValueError``, ``OSError`` such as a missing file) are printed as one line on stderr
    and give status 2; warnings are printed as one line each.
    """
    import warnings

    from .exceptions import CentralityVisionError

    parser = _parser()
    args, extras = parser.parse_known_args(argv)
    if extras:  # argparse would blame the top-level parser; name the subcommand instead
        getattr(args, "_parser", parser).error(f"unrecognized arguments: {' '.join(extras)}")
    if args.command is None:
        parser.print_help()
        return 0
    prog = f"centrality-vision {args.command}"
    args._warnings = []

    def show(message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())
        args._warnings.append(f"{category.__name__}: {text}")
        print(f"{prog}: warning: {text}", file=sys.stderr)

    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("always", category=UserWarning)  # shown on one line, never raised
            warnings.showwarning = show
            return args.run(args)
    except (CentralityVisionError, ValueError, OSError) as exc:
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"{prog}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
