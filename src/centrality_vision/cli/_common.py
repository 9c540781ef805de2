"""What the subcommands share: argument types and options, messages, progress, figures."""

from __future__ import annotations

import argparse
import contextlib
import functools
import math
import sys
from pathlib import Path

from .._validation import argparse_number as number  # (the experiments' options use it too)

__all__ = [
    "GRAPH_KINDS",
    "GPD_GRAPHS",
    "CENTRALITY_NAMES",
    "FIGURE_SUFFIXES",
    "Parser",
    "subparser",
    "number",
    "out_file",
    "add_out",
    "add_plot",
    "add_progress",
    "add_seed",
    "add_point_options",
    "progress_on",
    "quiet_progress",
    "say",
    "options",
    "suffix",
    "pyplot",
    "data_graph",
    "edge_list",
    "transform_record",
    "check_output_places",
]

# Spelled out here so that building the parser imports nothing heavy; tests check them
# against centrality_vision.centrality.CENTRALITIES and centrality_vision.registration.GRAPHS.
GRAPH_KINDS = ("delaunay", "gabriel", "emst", "knn", "complete", "mwme", "mstme")
GPD_GRAPHS = ("delaunay", "gabriel", "emst", "knn", "complete")
CENTRALITY_NAMES = ("degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity", "pagerank", "katz")
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")
# Bounds spelled out for the same reason, checked against centrality_vision.shapes' MAX_BINS
# and NonRigidCPD's KERNEL_RANGE (its beta and lam), and mstme_graph's largest lam
MAX_BINS = 100_000
KERNEL_RANGE = (1e-150, 1e150)
LAM_MAX = 1e300
POINT_FILES = ".csv, .txt, .xyz, .npy, .mat, .ply, .pcd or .obj"


class Parser(argparse.ArgumentParser):
    """argparse, with usage errors on one line (the message and where to find help), that
    also records which options the command line gave (:func:`given`)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see '{self.prog} --help')\n")

    def add_argument(self, *args, **kwargs):
        action = super().add_argument(*args, **kwargs)
        action.__class__ = _recording(type(action))
        return action


@functools.cache
def _recording(action_class: type) -> type:
    """``action_class`` that also adds its ``dest`` to the namespace's ``_given`` set when used."""

    def __call__(self, parser, namespace, values, option_string=None):
        if getattr(namespace, "_given", None) is None:
            namespace._given = set()
        namespace._given.add(self.dest)
        return action_class.__call__(self, parser, namespace, values, option_string)

    return type(action_class.__name__, (action_class,), {"__call__": __call__})


def given(args: argparse.Namespace, dest: str) -> bool:
    """Whether the command line gave the option stored in ``dest`` (its default otherwise)."""
    return dest in (getattr(args, "_given", None) or ())


def refuse_unused(args: argparse.Namespace, applies: dict, chosen: dict) -> None:
    """An InputError for the first option given that the chosen settings do not use.

    ``applies`` maps an option's dest to ``(setting, values)``: the option is used only when
    ``chosen[setting]`` is one of ``values`` (a run that silently ignored the kernel width or
    the centrality the user asked for would look like a success)."""
    from ..exceptions import InputError

    for dest, (setting, values) in applies.items():
        if given(args, dest) and chosen[setting] not in values:
            option, name = "--" + dest.replace("_", "-"), "--" + setting.replace("_", "-")
            wanted = f"{name} {' or '.join(values)}"
            raise InputError(f"{option} is an option of {wanted}; got {name} {chosen[setting]}.")


def subparser(sub, name: str, *, summary: str, description: str, example: str) -> argparse.ArgumentParser:
    """A subcommand whose help shows ``summary``, ``description`` and an example."""
    return sub.add_parser(
        name,
        help=summary,
        description=summary + "\n\n" + description,
        epilog="example:\n  " + example.strip().replace("\n", "\n  "),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def suffix(path) -> str:
    return Path(path).suffix.lower()


def out_file(*suffixes: str):
    """An argparse type: an output path whose suffix is one of ``suffixes``."""

    def check(text: str) -> str:
        if suffix(text) not in suffixes:
            name = Path(text).name
            if name.lower() in suffixes:  # ".json": a hidden file's name, with no suffix
                raise argparse.ArgumentTypeError(f"{text!r} is a name without a stem; give one, e.g. out{name}")
            raise argparse.ArgumentTypeError(f"{text!r} must end in {' or '.join(suffixes)}")
        return text

    check.__name__ = "output file"
    return check


def out_folder(text: str) -> str:
    """An argparse type: an output folder (an empty name wrote into the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"must name a folder; got {text!r}")
    return text


out_folder.__name__ = "output folder"


def add_out(parser: argparse.ArgumentParser, *suffixes: str, what: str = "") -> None:
    kinds = ", ".join(suffixes)
    parser.add_argument(
        "--out", required=True, metavar="FILE", type=out_file(*suffixes), help=f"output file ({kinds}){what}"
    )
    parser.set_defaults(_out_is_file=True)


def add_plot(parser: argparse.ArgumentParser, what: str) -> None:
    kinds = ", ".join(FIGURE_SUFFIXES[:-1])
    parser.add_argument(
        "--plot", metavar="FILE.png", type=out_file(*FIGURE_SUFFIXES), help=f"also draw {what} ({kinds})"
    )


# the input files of the commands (argument name: how the message names it)
_INPUT_FILES = {
    "points": "POINTS",
    "input": "INPUT",
    "moving": "MOVING",
    "fixed": "FIXED",
    "labels": "the --labels file",
    "landmarks": "the --landmarks file",
    "true_moving": "the --true-moving file",
}


def check_output_places(args) -> None:
    """Before any work: every output file of ``args`` (``--out``, its ``.json`` sidecar,
    ``--plot``) can be written. A folder in a file's place, a file where a folder must be
    created, a place that refuses new files, or an input file (which would be overwritten)
    is an :class:`InputError` naming the option, instead of an OS error after the
    computation (or after other outputs were written)."""
    import tempfile

    from .._validation import nearest_existing
    from ..exceptions import InputError

    # an input is known by its file's identity (device, inode) too: a hard link to it, or a
    # second mount of its folder, resolves to another path but would overwrite it all the same
    inputs = {}
    for name in _INPUT_FILES:
        value = getattr(args, name, None)
        if isinstance(value, str) and value and Path(value).is_file():
            inputs[Path(value).resolve()] = _INPUT_FILES[name]
            inputs[_file_identity(Path(value))] = _INPUT_FILES[name]

    # an input folder of images (classify's): an image written into it would be read as a
    # shape by the next run, or replace one
    from ..io import IMAGE_SUFFIXES

    folder = getattr(args, "images_dir", None)
    folder = Path(folder).resolve() if isinstance(folder, str) and folder and Path(folder).is_dir() else None

    places = []
    if getattr(args, "_out_is_file", False) and getattr(args, "out", None):
        out = Path(args.out)
        places.append(("--out", out))
        if out.suffix.lower() not in (".json", ".npz"):
            places.append(("--out (its .json record beside it)", out.with_suffix(".json")))
            _check_sidecar(out, out.with_suffix(".json"))
    if getattr(args, "plot", None):
        places.append(("--plot", Path(args.plot)))
    for option, path in places:
        if path.is_dir():
            raise InputError(f"{option}: {path} is a folder, not a file.")
        same = inputs.get(path.resolve()) or (inputs.get(_file_identity(path)) if path.is_file() else None)
        if same:
            raise InputError(
                f"{option}: {path} is also {same}, an input that writing it would destroy; choose another output file."
            )
        if folder is not None and path.suffix.lower() in IMAGE_SUFFIXES and path.resolve().parent == folder:
            raise InputError(
                f"{option}: {path} is an image in IMAGES_DIR, whose images are the input (writing it would "
                f"{'replace one' if path.exists() else 'add one to the next run'}); choose a place outside it."
            )
        ancestor = nearest_existing(path.parent)
        if not ancestor.is_dir():
            raise InputError(f"{option}: cannot create {path}: {ancestor} is a file, not a folder.")
        try:
            with tempfile.TemporaryFile(dir=ancestor):
                pass
        except OSError as exc:
            raise InputError(f"{option}: cannot write {path}: {ancestor} refuses new files ({exc.strerror}).") from None


def _check_sidecar(out: Path, sidecar: Path) -> None:
    """An InputError when writing the record of ``out`` would replace a file that is not
    ``out``'s own earlier record: the record of another output sharing the stem (``al.csv``
    then ``al.ply``: ``al.csv`` would be left described by the other run), or a file the
    user wrote. A record whose output no longer exists is replaced."""
    import json

    from ..exceptions import InputError

    if not sidecar.is_file():
        return
    try:
        record = json.loads(sidecar.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        record = None
    owner = record.get("file") if isinstance(record, dict) and "command" in record else None
    if owner == out.name or (isinstance(owner, str) and not (out.parent / owner).exists()):
        return
    if isinstance(owner, str):
        what = f"the record of {owner}, another output"
    elif isinstance(record, dict) and "command" in record:
        what = "the output of an earlier run (--out FILE.json)"
    else:
        what = "a file that centrality-vision did not write"
    raise InputError(
        f"--out: the record of {out.name} goes to {sidecar}, which is {what}; writing it would replace that "
        "file. Choose another name for --out (or remove the file)."
    )


def _file_identity(path: Path) -> tuple[int, int]:
    """An existing file's (device, inode): equal for every name of one file."""
    info = path.stat()
    return info.st_dev, info.st_ino


def add_progress(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show progress bars on stderr (default: only when stderr is a terminal)",
    )


def add_seed(parser: argparse.ArgumentParser, what: str) -> None:
    """--seed: a numpy seed in [0, 2^32 - 1], default 0; ``what`` it seeds, for the help."""
    parser.add_argument(
        "--seed",
        type=number(int, low=0, high=2**32 - 1),
        default=0,
        help=f"seed of {what} (default: %(default)s)",
    )


def in_path(text: str) -> str:
    """A positional input path: refused by argparse when empty (``Path("")`` is the
    current folder, which the readers then reported as ".: is a folder")."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file or folder path; got an empty string")
    return text


def _column_list(text: str) -> str:
    """--columns: comma-separated names or indices, none of them empty (checked by argparse)."""
    if not text.strip() or any(not item.strip() for item in text.split(",")):
        raise argparse.ArgumentTypeError(
            f"expected comma-separated column names or 0-based indices, e.g. x,y,z or 1,2; got {text!r}"
        )
    return text


def add_point_options(parser: argparse.ArgumentParser) -> None:
    """--columns and --variable, for commands that read point sets."""
    parser.add_argument(
        "--columns",
        type=_column_list,
        metavar="COLS",
        help="coordinate columns of the point file, by 0-based index (any format) or by name (text with a header, "
        "PLY, PCD), e.g. x,y,z or 1,2 (default: the columns named x, y[, z], else all columns but an index column "
        "and columns of labels)",
    )
    parser.add_argument(
        "--variable", metavar="NAME", help="the array to read from .mat files (default: the only 2D array)"
    )


def progress_on(args: argparse.Namespace) -> bool:
    """--progress / --no-progress, and by default whether stderr is a terminal."""
    chosen = getattr(args, "progress", None)
    if chosen is not None:
        return bool(chosen)
    isatty = getattr(sys.stderr, "isatty", None)
    return bool(isatty and isatty())


@contextlib.contextmanager
def quiet_progress(enabled: bool):
    """With ``enabled`` False, every tqdm bar created meanwhile in this process is disabled.

    The subcommands pass ``progress=`` to the library explicitly; this also covers bars in
    code they call indirectly (experiments, shape caches), so that no bar text reaches a
    log file when progress is off.
    """
    if enabled:
        yield
        return
    from functools import partialmethod

    from tqdm import std

    original = std.tqdm.__init__
    std.tqdm.__init__ = partialmethod(original, disable=True)
    try:
        yield
    finally:
        std.tqdm.__init__ = original


def say(message: str) -> None:
    """Progress and notes go to stderr; stdout is kept for results a user asked to see."""
    print(message, file=sys.stderr)


def options(args: argparse.Namespace, *, applies: dict | None = None, unused=()) -> dict:
    """Every option of the run that applied to it, for the "parameters" block of the outputs.

    ``applies`` (as for :func:`refuse_unused`) and ``unused`` (dests) leave out the options
    this run did not use (``--k`` of a Delaunay graph, ``--lam`` of an image): a record
    lists what made its result."""
    applies = applies or {}
    skipped = set(unused) | {
        dest for dest, (setting, values) in applies.items() if getattr(args, setting, None) not in values
    }
    return {
        key: value
        for key, value in vars(args).items()
        if key not in ("run", "progress") and not key.startswith("_") and key not in skipped
    }


def pyplot():
    """matplotlib.pyplot with the Agg backend: the command line writes files, never opens a window.

    The command line is the one place that chooses the backend; the library never does.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def read_point_file(path, args: argparse.Namespace, **kwargs):
    """``centrality_vision.io.read_points`` with the command's --columns and --variable."""
    from ..io import read_points

    return read_points(path, columns=getattr(args, "columns", None), variable=getattr(args, "variable", None), **kwargs)


def data_graph(points, kind: str, *, k: int, lam: float, source=None, progress: bool = False):
    """The data-graph ``kind`` of ``points``, and a dict of what the builder reports beside it.

    An :class:`InputError` about the points (too few, duplicates, collinear) is raised
    again with ``source``, the file they came from, in front.
    """
    from ..exceptions import InputError

    try:
        return _build_graph(points, kind, k=k, lam=lam, progress=progress)
    except InputError as exc:
        if source is None:
            raise
        raise InputError(f"{source}: {kind} graph: {exc}") from None


def _build_graph(points, kind: str, *, k: int, lam: float, progress: bool):
    from .. import graphs
    from ..exceptions import InputError

    if kind == "knn":
        if k >= points.shape[0]:
            raise InputError(f"--k must be smaller than the number of points ({points.shape[0]}); got {k}.")
        return graphs.knn_graph(points, n_neighbors=k), {}
    if kind == "mwme":
        result = graphs.mwme_graph(points, progress=progress)
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


def add_graph_options(parser: argparse.ArgumentParser, flag: str, *, help_text: str) -> None:
    parser.add_argument(flag, choices=GRAPH_KINDS, default="delaunay", help=help_text + " (default: %(default)s)")
    parser.add_argument(
        "--k", type=number(int, low=1), default=6, help="neighbours per point for the knn graph (default: %(default)s)"
    )
    parser.add_argument(
        "--lam",
        type=number(float, low=0, high=LAM_MAX),
        default=1.0,  # mstme_graph's default (a test holds them equal)
        help="weight of the degree entropy for the mstme graph; 0 gives the EMST (default: %(default)s)",
    )


#: knn_graph's name for ``--k``, for a command's ``_cli_phrases``
GRAPH_PHRASES = {"`n_neighbors`": "`k`"}

#: which ``--kind``/``--graph`` uses ``--k`` and ``--lam``
GRAPH_OPTION_KINDS = {"k": ("knn",), "lam": ("mstme",)}


def edge_list(points, graph):
    """Edges ``i < j`` of a symmetric sparse graph, sorted, with their Euclidean lengths
    (computed without overflow or underflow: squaring the differences gave 0 for points of
    size 1e-300 and inf for 1e300)."""
    import numpy as np
    from scipy import sparse

    from ..graphs._pointsets import _lengths

    upper = sparse.triu(sparse.coo_array(graph), k=1).tocoo()
    order = np.lexsort((upper.col, upper.row))
    i = upper.row[order].astype(np.int64)
    j = upper.col[order].astype(np.int64)
    return i, j, _lengths(points, i, j)


def rms_distance(a, b) -> float:
    """The RMS of the distances between the rows of ``a`` and ``b`` (registration's
    ``alignment_error`` over the root of their number: no square overflows or underflows)."""
    from ..registration import alignment_error

    return alignment_error(a, b) / math.sqrt(len(a))


def transform_record(transform) -> dict:
    """A transform as named arrays: type, rotation/linear, translation, scale, matrix, or the kernel parts."""
    from ..transforms import AffineTransform, NonRigidTransform, RigidTransform, SimilarityTransform

    if isinstance(transform, NonRigidTransform):
        import numpy as np

        dim = transform.control_points.shape[1]

        # the affine part applied before the field and the two origins (z -> p + v + field(v),
        # v = linear (z - o) + translation): without them the record does not reproduce the
        # registration (CPD sets them whenever it normalises the sets); identity and zeros
        # when the transform has none
        def vector(value):
            return np.zeros(dim) if value is None else value

        return {
            "type": "nonrigid",
            "control_points": transform.control_points,
            "coefficients": transform.coefficients,
            "beta": float(transform.beta),
            "linear": np.eye(dim) if transform.linear is None else transform.linear,
            "translation": vector(transform.translation),
            "input_origin": vector(transform.input_origin),
            "output_origin": vector(transform.output_origin),
        }
    if isinstance(transform, AffineTransform):
        return {
            "type": "affine",
            "linear": transform.linear,
            "translation": transform.translation,
            "matrix": transform.matrix,
        }
    if isinstance(transform, SimilarityTransform):
        kind = "rigid" if isinstance(transform, RigidTransform) else "similarity"
        return {
            "type": kind,
            "rotation": transform.rotation,
            "translation": transform.translation,
            "scale": float(transform.scale),
            "matrix": transform.matrix,
        }
    raise TypeError(f"unknown transform type {type(transform).__name__}")  # pragma: no cover
