"""``centrality-vision match``: MWME matching of two point sets of the same size (thesis ch. 6)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ._common import (
    POINT_FILES,
    add_out,
    add_plot,
    add_point_options,
    options,
    pyplot,
    read_point_file,
    say,
    subparser,
    transform_record,
)
from ._output import parameters_block, write_output

NAME = "match"


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Match two point sets of the same size through their MWME graphs (thesis ch. 6).",
        description=f"MOVING and FIXED are point-set files ({POINT_FILES}) of the same size.\n"
        "Each set gets its minimum-weight maximum-entropy graph, whose nodes have distinct\n"
        "degrees (but two); points of equal degree correspond. Writes the correspondence\n"
        "(moving[i] -> fixed[correspondence[i]]) and the least-squares transform fitted to it.\n"
        "The cost grows as n^3: meant for tens to a few hundred points.",
        example="centrality-vision match moving.txt fixed.txt --method local --out matching.json --plot matching.png",
    )
    parser.add_argument("moving", metavar="MOVING", help="point-set file")
    parser.add_argument("fixed", metavar="FIXED", help="point-set file of the same size")
    add_point_options(parser)
    parser.add_argument(
        "--method",
        choices=("local", "greedy", "exact"),
        default="local",
        help="MWME solver; exact only up to 20 points (default: %(default)s)",
    )
    parser.add_argument(
        "--transform",
        choices=("similarity", "rigid"),
        default="similarity",
        help="transform fitted to the matched points (default: %(default)s)",
    )
    add_out(parser, ".json", ".npz")
    add_plot(parser, "the matching (2D sets)")
    parser.set_defaults(run=run, _parser=parser)
    return parser


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..exceptions import InputError
    from ..matching import mwme_match

    started = time.perf_counter()
    moving = read_point_file(args.moving, args)
    fixed = read_point_file(args.fixed, args)
    if moving.shape != fixed.shape:
        raise InputError(
            f"{args.moving} and {args.fixed}: MWME matching needs two sets of the same size and dimension; "
            f"got shapes {moving.shape} and {fixed.shape}."
        )
    if args.plot and moving.shape[1] != 2:
        raise InputError(f"--plot draws 2D point sets only; got {moving.shape[1]}D points.")
    say(f"MWME matching ({args.method}) of {moving.shape[0]} points in {moving.shape[1]}D")
    correspondence, transform = mwme_match(moving, fixed, method=args.method, scale=args.transform == "similarity")
    correspondence = np.asarray(correspondence, dtype=np.int64)
    moved = transform(moving)
    rms = float(np.sqrt(np.mean(np.sum((moved - fixed[correspondence]) ** 2, axis=1))))
    seconds = time.perf_counter() - started
    say(f"matched in {seconds:.2f} s; RMS residual of the fitted {args.transform} transform: {rms:.6g}")
    transform_parts = transform_record(transform)
    record = {
        "command": NAME,
        "parameters": parameters_block(options(args)),
        "correspondence": correspondence,
        "correspondence_meaning": "moving[i] matches fixed[correspondence[i]]",
        "transform": transform_parts,
        "moving_transformed": moved,
        "rms_residual": rms,
        "seconds": round(seconds, 3),
    }
    arrays = {f"transform_{key}": value for key, value in transform_parts.items()}
    arrays.update(correspondence=correspondence, moving_transformed=moved, rms_residual=rms, seconds=record["seconds"])
    written = write_output(args.out, record, arrays=arrays)
    if args.plot:
        from ..plotting import plot_matching, save_figure

        pyplot()
        ax = plot_matching(
            moving, fixed, correspondence, title=f"MWME matching ({args.method}), RMS residual {rms:.3g}"
        )
        save_figure(ax.figure, args.plot)
        written.append(Path(args.plot))
    say(f"wrote {', '.join(map(str, written))}")
    return 0
