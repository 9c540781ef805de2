"""``centrality-vision match``: point-set matching through :func:`centrality_vision.matching.match`."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ._common import (
    POINT_FILES,
    add_out,
    add_plot,
    add_point_options,
    add_progress,
    in_path,
    number,
    options,
    pyplot,
    read_point_file,
    refuse_unused,
    rms_distance,
    say,
    subparser,
    transform_record,
)
from ._output import parameters_block, write_output

NAME = "match"

#: The methods of :func:`centrality_vision.matching.match` (checked against ``matching.METHODS`` in the tests).
METHODS = ("robust", "mwme", "shape-context")


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Match two point sets: local MWME signatures + consensus, global MWME, or shape contexts.",
        description=f"MOVING and FIXED are point-set files ({POINT_FILES}).\n"
        "robust (default, 2D): every point's neighbourhood gets its MWME graph as a rotation- and\n"
        "  scale-invariant signature; alike pairs propose similarity transforms, the one most points\n"
        "  agree with wins and is refined. Sets may differ in size, have outliers or missing parts.\n"
        "mwme (2D or 3D): the thesis' global MWME matching (ch. 6): sets of the same size; exact on\n"
        "  copies, fragile under noise. Its cost grows as n^3.\n"
        "shape-context (2D): shape contexts with a one-to-one Hungarian assignment (the baseline).\n"
        "Writes the correspondence (moving[i] -> fixed[correspondence[i]]) and the transform\n"
        "taking MOVING onto FIXED. robust gives each moving point, once transformed, its nearest\n"
        "fixed point within two sampling steps, else -1: a point near a fixed point it does not\n"
        "truly belong to gets that one (several may share it); judge by the transform.",
        example="centrality-vision match moving.txt fixed.txt --method robust --out matching.json --plot matching.png",
    )
    parser.add_argument("moving", type=in_path, metavar="MOVING", help="point-set file")
    parser.add_argument("fixed", type=in_path, metavar="FIXED", help="point-set file (same size for --method mwme)")
    add_point_options(parser)
    parser.add_argument("--method", choices=METHODS, default="robust", help="matching method (default: %(default)s)")
    parser.add_argument(
        "--mwme-solver",
        "--mwme-method",  # its former name
        dest="mwme_solver",
        choices=("local", "greedy", "exact"),
        default="local",
        help="MWME solver for --method mwme; exact only up to 20 points; --mwme-method is its former name "
        "(default: %(default)s)",
    )
    parser.add_argument(
        "--transform",
        choices=("similarity", "rigid"),
        default="similarity",
        help="transform fitted to the matched points (default: %(default)s)",
    )
    parser.add_argument(
        "--refine",
        choices=("icp", "cpd"),
        default="icp",
        help="refinement of --method robust; cpd suits whole sets only (default: %(default)s)",
    )
    parser.add_argument(
        "--n-neighbors",
        type=number(int, low=3, high=19),
        default=8,
        help="--method robust: neighbours in each local MWME signature, 3 to 19; the cost doubles with each "
        "(default: %(default)s)",
    )
    parser.add_argument(
        "--n-candidates",
        type=number(int, low=1, high=1000),
        default=6,
        help="--method robust: likely partners (hence pose hypotheses) per moving point, 1 to 1000 "
        "(default: %(default)s)",
    )
    parser.add_argument(
        "--w",
        type=number(float, low=0.0, high=1.0, high_open=True),
        default=0.3,
        help="--refine cpd: CPD's outlier weight, in [0, 1) (default: %(default)s)",
    )
    add_out(parser, ".json", ".npz")
    add_plot(parser, "the matching (2D sets)")
    add_progress(parser)  # (matching shows no bar of its own; this governs the bars of what it calls)
    # the library's advice in this command's options
    phrases = {
        "`scale=True`": "--transform similarity",
        "`scale=False`": "--transform rigid",
        "`solver='local'`": "--mwme-solver local",
        "`solver='exact'`": "--mwme-solver exact",
    }
    parser.set_defaults(run=run, _parser=parser, _cli_phrases=phrases)
    return parser


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..exceptions import InputError
    from ..matching import match

    applies = {
        "refine": ("method", ("robust",)),
        "n_neighbors": ("method", ("robust",)),
        "n_candidates": ("method", ("robust",)),
        "mwme_solver": ("method", ("mwme",)),
        "w": ("refine", ("cpd",)),
    }
    refuse_unused(args, applies, vars(args))
    started = time.perf_counter()
    moving = read_point_file(args.moving, args)
    fixed = read_point_file(args.fixed, args)
    if args.method == "mwme" and moving.shape != fixed.shape:
        raise InputError(
            f"{args.moving} and {args.fixed}: --method mwme needs two sets of the same size and dimension; "
            f"got shapes {moving.shape} and {fixed.shape} (--method robust or shape-context take sets of "
            "different sizes)."
        )
    if moving.shape[1] != fixed.shape[1]:
        raise InputError(
            f"{args.moving} and {args.fixed}: the sets must have the same dimension; "
            f"got {moving.shape[1]}D and {fixed.shape[1]}D points."
        )
    if args.method != "mwme" and moving.shape[1] != 2:
        raise InputError(
            f"--method {args.method} matches 2D point sets only; got {moving.shape[1]}D points "
            "(--method mwme takes 3D)."
        )
    if args.plot and moving.shape[1] != 2:
        raise InputError(f"--plot draws 2D point sets only; got {moving.shape[1]}D points.")
    say(f"{args.method} matching of {moving.shape[0]} onto {fixed.shape[0]} points in {moving.shape[1]}D")
    result = match(
        moving,
        fixed,
        method=args.method,
        scale=args.transform == "similarity",
        refine=args.refine,
        n_neighbors=args.n_neighbors,
        n_candidates=args.n_candidates,
        w=args.w,
        mwme_solver=args.mwme_solver,
    )
    correspondence = np.asarray(result.correspondence, dtype=np.int64)
    transform = result.transform
    moved = transform(moving)
    matched = correspondence >= 0
    rms = rms_distance(moved[matched], fixed[correspondence[matched]]) if matched.any() else float("nan")
    seconds = time.perf_counter() - started
    say(
        f"matched {int(matched.sum())} of {len(correspondence)} points in {seconds:.2f} s; "
        + (
            f"RMS residual of the matched points under the fitted {args.transform} transform: {rms:.6g}"
            if matched.any()
            else "no RMS residual (no point matched)"
        )
    )
    transform_parts = transform_record(transform)
    record = {
        "command": NAME,
        "parameters": parameters_block(options(args, applies=applies)),
        "method": args.method,
        "correspondence": correspondence,
        "correspondence_meaning": "moving[i] matches fixed[correspondence[i]]; -1: no fixed point within two "
        "sampling steps (robust)",
        "n_matched": int(matched.sum()),
        "transform": transform_parts,
        "moving_transformed": moved,
        "rms_residual": rms if matched.any() else None,
        "seconds": round(seconds, 3),
    }
    arrays = {f"transform_{key}": value for key, value in transform_parts.items()}
    arrays.update(
        correspondence=correspondence,
        n_matched=int(matched.sum()),
        moving_transformed=moved,
        seconds=record["seconds"],
    )
    if matched.any():  # .npz has no null: the key is left out when no point matched (not NaN)
        arrays["rms_residual"] = rms
    written = write_output(args.out, record, arrays=arrays)
    if args.plot:
        from ..plotting import plot_matching, save_figure

        pyplot()
        ax = plot_matching(
            moving,
            fixed,
            correspondence,
            title=f"{args.method} matching: {int(matched.sum())} of {len(correspondence)} matched, "
            f"RMS residual {rms:.3g}",
        )
        save_figure(ax.figure, args.plot)
        written.append(Path(args.plot))
    say(f"wrote {', '.join(map(str, written))}")
    return 0
