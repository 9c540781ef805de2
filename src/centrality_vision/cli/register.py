"""``centrality-vision register``: align a moving point set onto a fixed one (CPD, GPD, ICP)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .._validation import counted
from ._common import (
    CENTRALITY_NAMES,
    GPD_GRAPHS,
    KERNEL_RANGE,
    POINT_FILES,
    add_out,
    add_plot,
    add_point_options,
    add_progress,
    add_seed,
    given,
    in_path,
    number,
    options,
    progress_on,
    pyplot,
    read_point_file,
    refuse_unused,
    rms_distance,
    say,
    subparser,
    suffix,
    transform_record,
)
from ._output import parameters_block, write_output

NAME = "register"
POINT_OUTPUTS = (".csv", ".txt", ".xyz", ".npy", ".mat", ".ply", ".pcd", ".obj")


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Align a moving point set onto a fixed one (CPD, GPD or ICP) and write the result.",
        description=f"MOVING and FIXED are point-set files ({POINT_FILES}) of the same dimension\n"
        "(2 or 3); they need not have the same number of points. cpd is Coherent Point Drift,\n"
        "gpd the thesis' Graph-based Point Drift (CPD whose matching also compares a centrality\n"
        "of each point in a data-graph, ch. 5), icp Iterative Closest Point (rigid or similarity).\n"
        "--true-moving: where each moving point truly belongs in the fixed frame (a row of NaN\n"
        "marks a point with no true position, e.g. an outlier); the per-point RMS alignment\n"
        "error over the other points is then recorded per iteration (and plotted with --plot).\n"
        "--out .json/.npz: the transform, the aligned moving set, iterations, convergence, the\n"
        "history of objective/sigma2/error, the correspondences and every parameter. A nonrigid\n"
        "transform maps z to output_origin + v + sum_m coefficients[m] exp(-|v - control_points[m]|^2\n"
        "/ (2 beta^2)), v = linear (z - input_origin) + translation. With --w auto the record holds\n"
        "the estimated outlier weight (w); with --landmarks, the pairs and their distances after\n"
        "the fit.\n"
        f"--out a point-set file ({', '.join(POINT_OUTPUTS)}): the aligned moving set, and all the\n"
        "rest in NAME.json beside it.\n"
        "Far from the answer (beyond about 70 degrees) CPD ends in a wrong pose: --init global\n"
        "searches the rotations first, or --landmarks pins a few known pairs. With clutter or\n"
        "missing parts, --w auto (or 0.1-0.3); --n-neighbors 10 when the sets start roughly aligned.",
        example="centrality-vision register fish_moving.txt fish_fixed.txt --method gpd --transform nonrigid \\\n"
        "    --centrality closeness --out aligned.csv --plot aligned.png\n"
        "centrality-vision register scan.ply model.ply --method cpd --transform rigid --init global \\\n"
        "    --w auto --out aligned.ply",
    )
    parser.add_argument("moving", type=in_path, metavar="MOVING", help="point set to move")
    parser.add_argument("fixed", type=in_path, metavar="FIXED", help="point set to align onto")
    add_point_options(parser)
    parser.add_argument(
        "--method", choices=("cpd", "gpd", "icp"), default="cpd", help="registration method (default: %(default)s)"
    )
    parser.add_argument(
        "--transform",
        choices=("rigid", "similarity", "affine", "nonrigid"),
        default="similarity",
        help="transform family; similarity = rigid + isotropic scale (default: %(default)s)",
    )
    parser.add_argument(
        "--centrality",
        choices=CENTRALITY_NAMES,
        default="closeness",
        help="GPD only: centrality of the points (default: %(default)s)",
    )
    parser.add_argument(
        "--graph",
        choices=GPD_GRAPHS,
        default="delaunay",
        help="GPD only: data-graph the centrality is computed on (default: %(default)s)",
    )
    parser.add_argument(
        "--k", type=number(int, low=1), default=6, help="GPD only: neighbours for --graph knn (default: %(default)s)"
    )
    parser.add_argument(
        "--kappa",
        type=number(float, low=0, low_open=True, high=1),
        default=0.5,
        help="GPD only: geometry-vs-centrality balance, 1 = plain CPD (default: %(default)s)",
    )
    parser.add_argument(
        "--w",
        type=_outlier_weight,
        default=0.0,
        help="CPD/GPD: weight of the outlier component, in [0, 1), or auto: estimated during the fit "
        "(default: %(default)s)",
    )
    parser.add_argument(
        "--init",
        choices=("none", "global"),
        default="none",
        help="CPD/GPD: starting pose; none = the centroids aligned (the files' own pose with "
        "--n-neighbors), global = a search over every rotation first, for sets in any pose "
        "(default: %(default)s)",
    )
    add_seed(parser, "--init global's search")
    parser.add_argument(
        "--n-neighbors",
        type=number(int, low=1),
        metavar="K",
        help="CPD/GPD: each moving point explains only its K nearest fixed points (robust to clutter "
        "and missing parts when the sets start roughly aligned; e.g. 10) (default: every fixed point)",
    )
    parser.add_argument(
        "--landmarks",
        metavar="FILE",
        help="CPD/GPD: pairs of 0-based rows 'i j', one per line (text or CSV, a header allowed), "
        "pinning moving point i to fixed point j",
    )
    parser.add_argument(
        "--max-distance",
        type=number(float, low=0, low_open=True),
        help="ICP only: pairs farther apart than this, in the files' units, are ignored (default: none)",
    )
    parser.add_argument(
        "--trim",
        type=number(float, low=0, high=1, high_open=True),
        help="ICP only: fraction of the farthest pairs ignored at each iteration, about the share of "
        "moving points with no partner (default: 0)",
    )
    parser.add_argument(
        "--metric",
        choices=("point_to_point", "point_to_plane"),
        help="ICP only: point_to_plane uses normals from the fixed set's local PCA (point to line in 2D) and "
        "fits a rigid motion (with --transform rigid) (default: point_to_point)",
    )
    parser.add_argument(
        "--max-iter",
        type=number(int, low=1),
        default=None,
        help="most iterations (default: the method's own, 150 for CPD and GPD, 100 for ICP)",
    )
    parser.add_argument(
        "--tol",
        type=number(float, low=0, low_open=True),
        default=None,
        help="stop when the objective changes by less than this, relatively (default: the method's own, "
        "1e-5 for CPD and GPD, 1e-6 for ICP)",
    )
    parser.add_argument(
        "--beta",
        type=number(float, low=KERNEL_RANGE[0], high=KERNEL_RANGE[1]),
        default=2.0,
        help="nonrigid: width of the Gaussian kernel (default: %(default)s)",
    )
    parser.add_argument(
        "--lam",
        type=number(float, low=KERNEL_RANGE[0], high=KERNEL_RANGE[1]),
        default=2.0,
        help="nonrigid: smoothness weight (default: %(default)s)",
    )
    parser.add_argument(
        "--true-moving",
        metavar="FILE",
        help="true positions of the moving points (NaN rows allowed), to record the alignment error",
    )
    add_out(parser, ".json", ".npz", *POINT_OUTPUTS)
    add_plot(parser, "the fixed set and the moving set before and after, and the error curve with --true-moving")
    add_progress(parser)
    parser.set_defaults(run=run, _parser=parser)
    return parser


def _outlier_weight(text: str):
    """--w: a number in [0, 1) or 'auto'."""
    if text.strip().lower() == "auto":
        return "auto"
    try:
        return number(float, low=0, high=1, high_open=True)(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be a number in [0, 1) or auto; got {text!r}") from None


# the options of one family of methods, and their values when not given
_CPD = ("cpd", "gpd")
# the options each method or transform uses: any other given is refused, not ignored (a run
# without the landmarks, the global search or the centrality asked for looks like a success)
_APPLIES = {
    **dict.fromkeys(("w", "init", "n_neighbors", "landmarks"), ("method", _CPD)),
    **dict.fromkeys(("centrality", "graph", "k", "kappa"), ("method", ("gpd",))),
    **dict.fromkeys(("max_distance", "trim", "metric"), ("method", ("icp",))),
    **dict.fromkeys(("beta", "lam"), ("transform", ("nonrigid",))),
    "seed": ("init", ("global",)),  # the only random choice of a registration
}


def _method_defaults(args: argparse.Namespace) -> None:
    """Options not given: the estimator's own defaults (ICP's ``--max-iter`` and ``--tol`` differ
    from CPD's; one CLI default for both ran ICP with CPD's limits), kept in ``args`` so that
    the record shows the values the run used, not null."""
    import inspect

    from ..registration import ICP, RigidCPD

    signature = inspect.signature(ICP if args.method == "icp" else RigidCPD).parameters
    names = ("max_iter", "tol", "trim", "metric") if args.method == "icp" else ("max_iter", "tol")
    for name in names:
        if getattr(args, name) is None:
            setattr(args, name, signature[name].default)


def _estimator(args: argparse.Namespace, callback):
    from ..exceptions import InputError
    from ..registration import GPD, ICP, AffineCPD, NonRigidCPD, RigidCPD

    refuse_unused(args, _APPLIES, {"method": args.method, "transform": args.transform, "init": args.init})
    if given(args, "k") and args.graph != "knn":
        raise InputError(f"--k is an option of --graph knn; got --graph {args.graph}.")
    if args.method == "icp":
        if args.transform not in ("rigid", "similarity"):
            raise InputError(
                f"ICP fits rigid or similarity transforms only; got --transform {args.transform}. "
                "Use --method cpd or gpd for affine and nonrigid."
            )
        if args.metric == "point_to_plane" and args.transform != "rigid":
            raise InputError(
                f"--metric point_to_plane fits a rigid motion; got --transform {args.transform}. "
                "Use --transform rigid with it."
            )
        return ICP(
            scale=args.transform == "similarity",
            max_iter=args.max_iter,
            tol=args.tol,
            max_distance=args.max_distance,
            trim=args.trim,
            metric=args.metric,
            callback=callback,
        )
    common = {
        "w": args.w,
        "max_iter": args.max_iter,
        "tol": args.tol,
        "init": "global" if args.init == "global" else None,
        "random_state": args.seed,
        "n_neighbors": args.n_neighbors,
        "callback": callback,
    }
    if args.transform in ("rigid", "similarity"):
        base = RigidCPD(scale=args.transform == "similarity", **common)
    elif args.transform == "affine":
        base = AffineCPD(**common)
    else:
        base = NonRigidCPD(beta=args.beta, lam=args.lam, **common)
    if args.method == "cpd":
        return base
    return GPD(base, centrality=args.centrality, graph=args.graph, kappa=args.kappa, graph_neighbors=args.k)


class _Watch:
    """The callback of the run: a progress bar over iterations and the per-point RMS error."""

    def __repr__(self) -> str:  # in the recorded estimator: the same for identical runs (no address)
        return "<the command's progress and error recorder>"

    def __init__(self, *, total: int, label: str, show: bool, true_moving=None):
        import numpy as np

        self.rms: list[float] = []
        self.true_moving = true_moving
        self.known = None if true_moving is None else ~np.isnan(true_moving).any(axis=1)
        self.bar = None
        if show:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc=label, unit="iter", leave=False)

    def __call__(self, info) -> None:
        import numpy as np

        moved = np.asarray(info.moving_transformed)
        if self.true_moving is not None:
            self.rms.append(rms_distance(moved[self.known], self.true_moving[self.known]))
        if self.bar is not None and info.iteration > 0:
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _read_landmarks(path):
    """The (L, 2) integer rows of a --landmarks file (the library checks the ranges)."""
    import numpy as np

    from ..exceptions import InputError
    from ..io import read_points
    from ..io._points import _COLUMNS_HINT

    try:
        pairs = read_points(path)
    except InputError as exc:  # (--columns picks the coordinates of MOVING and FIXED, not these)
        raise InputError(f"--landmarks: {str(exc).replace(_COLUMNS_HINT, '')}") from None
    if pairs.shape[1] != 2:
        raise InputError(
            f"--landmarks {path}: expected two columns, a moving row and a fixed row per line; "
            f"got {counted(pairs.shape[1], 'column')}."
        )
    fraction = pairs[pairs != np.round(pairs)]
    if fraction.size:
        raise InputError(f"--landmarks {path}: the rows must be whole numbers; got {fraction[0]:g}.")
    if np.abs(pairs).max() >= 2**62:
        raise InputError(f"--landmarks {path}: a row number must be below 2^62; got {np.abs(pairs).max():g}.")
    return pairs.astype(np.int64)


def _fixed_to_moving(estimator):
    """For each fixed point its moving point (``fixed_to_moving_``; ``correspondence_`` before the rename)."""
    found = getattr(estimator, "fixed_to_moving_", None)
    return estimator.correspondence_ if found is None else found


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..exceptions import InputError

    started = time.perf_counter()
    _method_defaults(args)
    _estimator(args, None)  # a bad combination fails before any reading
    moving = read_point_file(args.moving, args)
    fixed = read_point_file(args.fixed, args)
    if moving.shape[1] != fixed.shape[1]:
        raise InputError(
            f"{args.moving} and {args.fixed}: the point sets must have the same dimension; "
            f"got {moving.shape[1]} and {fixed.shape[1]} columns."
        )
    smaller = min(moving.shape[0], fixed.shape[0])
    if args.method == "gpd" and args.graph == "knn" and args.k >= smaller:
        # the library would take the complete graph instead, and the record say k=args.k
        raise InputError(
            f"--k must be smaller than the number of points of each set ({moving.shape[0]} and "
            f"{fixed.shape[0]}); got {args.k}."
        )
    if suffix(args.out) in (".ply", ".pcd", ".obj") and moving.shape[1] != 3:
        raise InputError(
            f"--out {args.out}: {suffix(args.out)} files hold 3D points; got 2D sets (write .csv, .txt, .npy or .mat)."
        )
    landmarks = None if args.landmarks is None else _read_landmarks(args.landmarks)
    true_moving = None
    if args.true_moving is not None:
        true_moving = read_point_file(args.true_moving, args, nan_rows=True)
        if true_moving.shape != moving.shape:
            raise InputError(
                f"{args.true_moving}: --true-moving must have the shape of the moving set {moving.shape}; "
                f"got {true_moving.shape}."
            )
        if np.isnan(true_moving).all():
            raise InputError(f"{args.true_moving}: every row is NaN; no point has a true position.")
    label = f"{args.method.upper()} ({args.transform})"
    if args.method == "gpd":
        label = f"GPD ({args.transform}, {args.centrality}, {args.graph})"
    # the library's words for what the command calls otherwise: its classes (RigidCPD is
    # also --transform similarity) and its fitted attribute
    args._cli_phrases = {
        "`transform_`": "the fitted transform",
        **{f"{name} stopped": f"{label} stopped" for name in ("RigidCPD", "AffineCPD", "NonRigidCPD", "ICP")},
        **{f"{name}: ": f"{label}: " for name in ("RigidCPD", "AffineCPD", "NonRigidCPD", "ICP")},
    }
    say(
        f"{label}: moving {args.moving} ({counted(moving.shape[0], 'point')}), "
        f"fixed {args.fixed} ({counted(fixed.shape[0], 'point')}), "
        f"{moving.shape[1]}D"
    )
    watch = _Watch(total=args.max_iter, label=label, show=progress_on(args), true_moving=true_moving)
    estimator = _estimator(args, watch)
    try:
        if landmarks is None:
            estimator.fit(moving, fixed)
        else:
            estimator.fit(moving, fixed, landmarks=landmarks)
    finally:
        watch.close()
    seconds = time.perf_counter() - started
    if estimator.converged_:
        status = "converged"
    elif estimator.n_iter_ >= args.max_iter:  # the method's own limit when not given (_method_defaults)
        status = "stopped at --max-iter without converging"
    else:  # a collapse or a non-finite step ended it: its warning says which
        status = "stopped early without converging (see the warning above)"
    say(f"{label}: {status} after {estimator.n_iter_} iterations in {seconds:.2f} s")

    history = {
        key: (None if value is None or all(v is None for v in value) else np.asarray(value))
        for key, value in estimator.history_.items()
        if key != "error"
    }
    history["alignment_rms"] = np.asarray(watch.rms) if true_moving is not None else None
    sigma2 = getattr(estimator, "sigma2_", None)
    transform = transform_record(estimator.transform_)
    record = {
        "command": NAME,
        "parameters": parameters_block(options(args, applies=_APPLIES, unused=() if args.graph == "knn" else ("k",))),
        "estimator": " ".join(repr(estimator).split()),
        "transform": transform,
        "n_iter": int(estimator.n_iter_),
        "converged": bool(estimator.converged_),
        "sigma2": None if sigma2 is None else float(sigma2),
        "final_alignment_rms": watch.rms[-1] if watch.rms else None,
        "n_true_points": None if true_moving is None else int(watch.known.sum()),
        "history": history,
        "fixed_to_moving": np.asarray(_fixed_to_moving(estimator), dtype=np.int64),
        "fixed_to_moving_meaning": "for each fixed point, the index of the moving point it is matched to"
        + ("" if args.method == "icp" else " (the most probable; -1 for an outlier)"),
        "warnings": list(getattr(args, "_warnings", [])),
        "seconds": round(seconds, 3),
    }
    w_fitted = getattr(estimator, "w_", None)
    if w_fitted is not None:
        record["w"] = float(w_fitted)
    if landmarks is not None:
        pinned = estimator.moving_transformed_[landmarks[:, 0]] - fixed[landmarks[:, 1]]
        record["landmarks"] = landmarks
        record["landmark_distances"] = np.sqrt(np.sum(pinned**2, axis=1))
    if args.method == "gpd":
        record["moving_centrality"] = estimator.moving_centrality_
        record["fixed_centrality"] = estimator.fixed_centrality_
    aligned = estimator.moving_transformed_
    if suffix(args.out) in (".json", ".npz"):
        record["moving_transformed"] = aligned
    arrays = {f"transform_{key}": value for key, value in transform.items()}
    arrays.update({f"history_{key}": value for key, value in history.items()})
    arrays.update(
        {
            key: value
            for key, value in record.items()
            if key not in ("transform", "history", "warnings", "parameters", "command")
        }
    )
    arrays["warnings"] = np.array(record["warnings"], dtype=str)
    written = write_output(args.out, record, arrays=arrays, points=aligned)
    if args.plot:
        # "before" is the MOVING file as given (the callback's first state is CPD's start,
        # already centred on the fixed set, which is not what the user passed)
        _plot(args, fixed, moving, aligned, watch.rms, label)
        written.append(Path(args.plot))
    say(f"wrote {', '.join(map(str, written))}")
    return 0


def _plot(args, fixed, before, after, rms, label) -> None:
    from ..plotting import plot_alignment_errors, plot_registration, save_figure

    plt = pyplot()
    three_d = fixed.shape[1] == 3
    n_panels = 3 if rms else 2
    fig = plt.figure(figsize=(4.2 * n_panels, 4.2), layout="constrained")
    kw = {"projection": "3d"} if three_d else {}
    axes = [fig.add_subplot(1, n_panels, k + 1, **kw) for k in range(2)]
    plot_registration(
        before,
        fixed,
        ax=axes[0],
        title="before",
        moving_label=f"moving ({Path(args.moving).name})",
        fixed_label=f"fixed ({Path(args.fixed).name})",
    )
    plot_registration(
        after,
        fixed,
        ax=axes[1],
        title="after",
        moving_label="moving, aligned",
        fixed_label=f"fixed ({Path(args.fixed).name})",
    )
    import numpy as np

    everything = np.vstack([fixed, before, after])
    pad = 0.04 * np.ptp(everything, axis=0)
    low, high = everything.min(axis=0) - pad, everything.max(axis=0) + pad
    for ax in axes:  # the same frame before and after
        ax.set_xlim(low[0], high[0])
        ax.set_ylim(low[1], high[1])
        if three_d:
            ax.set_zlim(low[2], high[2])
    if rms:
        ax = fig.add_subplot(1, n_panels, 3)
        plot_alignment_errors({label: rms}, ax=ax, title="alignment error", ylabel="per-point RMS error")
    fig.suptitle(label)
    save_figure(fig, args.plot)
