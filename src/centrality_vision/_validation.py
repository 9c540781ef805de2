"""The one place where user inputs are checked and converted.

Every public function passes its data arguments through one of these helpers, so
that errors have one format: the parameter, what was expected, what came in.
Nothing here modifies its input: arrays are copied when they would be changed.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import numbers
from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy import sparse

from ._warnings import warn
from .exceptions import InputError

#: ``n_dims`` for functions that accept points of any (reasonable) dimension.
ANY_DIMS = tuple(range(1, 65))

__all__ = [
    "ANY_DIMS",
    "FOREGROUNDS",
    "as_points",
    "as_graph",
    "as_any_graph",
    "GraphInput",
    "as_binary_image",
    "check_choice",
    "check_int",
    "check_float",
    "counted",
]


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and ``noun`` in the number it takes, for messages: "1 point", "3 points".

    >>> counted(1, "class", "classes"), counted(0, "point")
    ('1 class', '0 points')
    """
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def _describe(value) -> str:
    if isinstance(value, np.ndarray):
        return f"array of shape {value.shape} and dtype {value.dtype}"
    if sparse.issparse(value):
        return f"sparse {type(value).__name__} of shape {value.shape}"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def is_real_dtype(dtype, *, bool_ok: bool = True) -> bool:
    """Whether values of ``dtype`` are real numbers: integers and floats, and booleans
    where ``bool_ok``; not complex numbers, durations (timedelta64 counts as a numpy
    number), dates, text or objects."""
    return np.dtype(dtype).kind in ("biuf" if bool_ok else "iuf")


def as_real_array(value, *, name: str, shape: str = "an array") -> np.ndarray:
    """``value`` as a numpy array of real numbers (not copied; any shape).

    Raises a :class:`TypeError` naming ``name`` for None, text, objects and complex numbers,
    and an :class:`InputError` for ragged nested lists (``shape`` describes what was expected).
    """
    if np.ma.is_masked(value):
        raise TypeError(
            f"`{name}` must be a plain array; got a masked array with masked entries (the mask would be ignored)."
        )
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise InputError(f"`{name}` must be {shape}; got {_describe(value)} ({exc}).") from None
    if np.iscomplexobj(arr):
        raise TypeError(f"`{name}` must hold real numbers; got complex dtype {arr.dtype}.")
    if arr.dtype == object and arr.size and all(isinstance(item, numbers.Real) for item in arr.flat):
        # numbers held as objects (a mixed-type DataFrame's .values, Python ints past int64)
        # are numbers: as floats, as a graph's object array is read (a copy; the input is kept)
        with contextlib.suppress(OverflowError):  # an int past float's range: refused below
            arr = arr.astype(np.float64)
    if not is_real_dtype(arr.dtype):
        raise TypeError(f"`{name}` must hold real numbers; got {_describe(value if arr.dtype == object else arr)}.")
    return arr


def _describe_dims(n_dims) -> str:
    """``"2 or 3"``; a run of more than three dimensions reads ``"1 to 64"``."""
    dims = sorted(n_dims)
    if len(dims) > 3 and dims == list(range(dims[0], dims[-1] + 1)):
        return f"{dims[0]} to {dims[-1]}"
    return " or ".join(str(d) for d in dims)


def as_points(
    points,
    *,
    name: str = "points",
    n_dims: tuple[int, ...] = (2, 3),
    min_points: int = 1,
    allow_duplicates: bool = True,
) -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 array of shape (n_points, n_dims).

    Raises a :class:`TypeError` for non-numeric or boolean input and an :class:`InputError`
    (a ``ValueError``) for a wrong shape, non-finite values, too few points or,
    with ``allow_duplicates=False``, repeated points.
    """
    if sparse.issparse(points):
        raise TypeError(f"`{name}` must be a dense array of shape (n_points, n_dims); got {_describe(points)}.")
    arr = as_real_array(points, name=name, shape="(n_points, n_dims)")
    if arr.dtype == bool:
        raise TypeError(
            f"`{name}` must hold coordinates (real numbers); got an {_describe(arr)} "
            "(a mask? convert with .astype(float) if 0/1 coordinates are meant)."
        )
    if arr.ndim != 2 or arr.shape[1] not in n_dims:
        raise InputError(f"`{name}` must have shape (n_points, {_describe_dims(n_dims)}); got shape {arr.shape}.")
    arr = np.array(arr, dtype=np.float64, order="C", copy=True)
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr).all(axis=1)))
        raise InputError(f"`{name}` must be finite; got {bad} row(s) with NaN or inf.")
    if arr.shape[0] < min_points:
        noun = "point" if min_points == 1 else "points"
        raise InputError(f"`{name}` must have at least {min_points} {noun}; got {arr.shape[0]}.")
    if not allow_duplicates and arr.shape[0] > 1:
        uniq, first, counts = np.unique(arr, axis=0, return_index=True, return_counts=True)
        if uniq.shape[0] != arr.shape[0]:
            dup = uniq[np.argmax(counts)]
            rows = np.flatnonzero((arr == dup).all(axis=1))
            raise InputError(
                f"`{name}` must not contain duplicate points; got {arr.shape[0] - uniq.shape[0]} "
                f"duplicate(s), e.g. rows {rows[0]} and {rows[1]}, both {dup.tolist()}."
            )
    return arr


class GraphInput(NamedTuple):
    """A validated graph: CSR adjacency of edge lengths, node labels, directedness."""

    adjacency: sparse.csr_array
    labels: list | None  # None: the nodes are 0 .. n-1 (scipy or dense input)
    directed: bool


def _from_networkx(graph, name: str):
    import networkx as nx

    labels = list(graph.nodes)
    index = {node: i for i, node in enumerate(labels)}
    rows, cols, lengths = [], [], []
    for u, v, w in graph.edges(data="weight", default=1.0):
        if w is None:  # (numpy reads None as NaN, and the error then spoke of NaN or inf)
            raise TypeError(f"`{name}` must have numeric edge attribute 'weight'; edge ({u!r}, {v!r}) has weight None.")
        rows.append(index[u])
        cols.append(index[v])
        lengths.append(w)
    directed = bool(nx.is_directed(graph))
    return labels, rows, cols, lengths, directed


def _from_igraph(graph, name: str):
    edges = graph.get_edgelist()
    rows = [e[0] for e in edges]
    cols = [e[1] for e in edges]
    lengths = graph.es["weight"] if "weight" in graph.es.attributes() else [1.0] * len(edges)
    if any(w is None for w in lengths):  # an edge added without the attribute others have
        u, v = edges[next(i for i, w in enumerate(lengths) if w is None)]
        raise TypeError(f"`{name}` must have numeric edge attribute 'weight'; edge ({u}, {v}) has weight None.")
    labels = list(graph.vs["name"]) if "name" in graph.vs.attributes() else list(range(graph.vcount()))
    return labels, rows, cols, lengths, bool(graph.is_directed())


def _edge_list_graph(n, rows, cols, lengths, directed: bool, name: str) -> sparse.csr_array:
    """CSR adjacency from an edge list; parallel edges keep their shortest length."""
    try:
        lengths = np.asarray(lengths, dtype=np.float64).reshape(-1)
    except OverflowError:
        raise InputError(f"`{name}` must have finite edge lengths ('weight'); got an int beyond float64.") from None
    except (TypeError, ValueError):
        raise TypeError(
            f"`{name}` must have numeric edge attribute 'weight' (an edge length); got non-numeric values."
        ) from None
    rows = np.asarray(rows, dtype=np.int64).reshape(-1)
    cols = np.asarray(cols, dtype=np.int64).reshape(-1)
    if not directed:
        rows, cols, lengths = (
            np.concatenate([rows, cols]),
            np.concatenate([cols, rows]),
            np.concatenate([lengths, lengths]),
        )
    order = np.lexsort((lengths, cols, rows))  # per (row, col) the shortest first
    rows, cols, lengths = rows[order], cols[order], lengths[order]
    first = np.ones(rows.size, dtype=bool)
    first[1:] = (rows[1:] != rows[:-1]) | (cols[1:] != cols[:-1])
    return sparse.csr_array((lengths[first], (rows[first], cols[first])), shape=(n, n))


def as_any_graph(graph, *, name: str = "graph", allow_directed: bool = False) -> GraphInput:
    """Validate a graph given as a scipy sparse matrix, a dense array, or a networkx or
    igraph graph; return its adjacency of edge lengths, node labels and directedness.

    Conventions: a dense array's zeros are non-edges; a sparse matrix's stored entries
    are edges, explicitly stored zeros included (edges of length 0, as in
    :mod:`scipy.sparse.csgraph`); a networkx or igraph graph's edge attribute
    ``"weight"`` is the length (1 where missing), parallel edges keep the shortest, and
    the node order (and, for igraph, the ``"name"`` attribute) gives the labels.
    Self-loops are dropped. A sparse or dense input that is not symmetric (the same
    entries both ways, each equal to its mirror to 1e-12 of the pair's own size, at any
    scale) is a directed graph, refused unless ``allow_directed``.
    """
    labels = None
    directed = None
    module = type(graph).__module__ or ""
    if module.startswith("networkx") or module.startswith("igraph"):
        convert = _from_networkx if module.startswith("networkx") else _from_igraph
        labels, rows, cols, lengths, directed = convert(graph, name)
        if not labels:
            raise InputError(f"`{name}` must have at least one node; got an empty graph.")
        mat = _edge_list_graph(len(labels), rows, cols, lengths, directed, name)
    elif sparse.issparse(graph):
        if np.iscomplexobj(graph.data if hasattr(graph, "data") else graph):
            raise TypeError(f"`{name}` must hold real edge lengths; got complex dtype {graph.dtype}.")
        try:
            mat = sparse.csr_array(graph, dtype=np.float64, copy=True)
        except (TypeError, ValueError):
            raise TypeError(f"`{name}` must hold real edge lengths; got {_describe(graph)}.") from None
    else:
        if graph is None or np.ma.is_masked(graph):
            raise TypeError(
                f"`{name}` must be a scipy.sparse matrix, a square array of edge lengths, or a networkx "
                f"or igraph graph; got "
                + ("None." if graph is None else "a masked array with masked entries (the mask would be ignored).")
            )

        def not_a_graph() -> TypeError:
            return TypeError(
                f"`{name}` must be a scipy.sparse matrix, a square array of edge lengths, or a networkx "
                f"or igraph graph; got {_describe(graph)}."
            )

        try:
            dense = np.asarray(graph)
        except (TypeError, ValueError):  # ragged nested lists
            raise not_a_graph() from None
        if np.iscomplexobj(dense):
            raise TypeError(f"`{name}` must hold real edge lengths; got complex dtype {dense.dtype}.")
        # text, times and records convert to numbers and mean no length (objects may hold numbers)
        if dense.ndim and dense.dtype != object and not is_real_dtype(dense.dtype):
            raise TypeError(f"`{name}` must hold real edge lengths; got {_describe(dense)}.")
        try:
            dense = dense.astype(np.float64)
        except OverflowError:
            raise InputError(f"`{name}` must hold finite edge lengths; got an int beyond float64.") from None
        except (TypeError, ValueError):
            raise not_a_graph() from None
        if dense.ndim != 2:
            raise InputError(f"`{name}` must be a square 2D adjacency; got shape {dense.shape}.")
        mat = sparse.csr_array(dense)
    if mat.ndim != 2 or mat.shape[0] != mat.shape[1]:
        raise InputError(f"`{name}` must be a square adjacency of shape (n, n); got shape {mat.shape}.")
    if mat.shape[0] == 0:
        raise InputError(f"`{name}` must have at least one node; got shape {mat.shape}.")
    if not np.all(np.isfinite(mat.data)):
        raise InputError(f"`{name}` must have finite edge lengths; got NaN or inf entries.")
    if np.any(mat.data < 0):
        raise InputError(f"`{name}` must have non-negative edge lengths; got min {float(mat.data.min()):g}.")
    # Drop the diagonal but keep explicitly stored zeros: they are edges of length 0.
    mat.sum_duplicates()
    coo = mat.tocoo()
    off = coo.row != coo.col
    mat = sparse.csr_array((coo.data[off], (coo.row[off], coo.col[off])), shape=mat.shape)
    mat.sort_indices()
    if directed is None:
        directed = not _is_symmetric(mat)
        if directed and not allow_directed:
            raise InputError(f"`{name}` must be symmetric (an undirected graph); got an asymmetric adjacency.")
    elif directed and not allow_directed:
        raise InputError(f"`{name}` must be an undirected graph; got a directed {type(graph).__name__}.")
    index_dtype = np.int32 if max(mat.nnz, mat.shape[0]) < 2**31 - 1 else np.int64
    mat.indices = mat.indices.astype(index_dtype, copy=False)
    mat.indptr = mat.indptr.astype(index_dtype, copy=False)
    return GraphInput(mat, labels, bool(directed))


def _is_symmetric(mat: sparse.csr_array) -> bool:
    """Same pattern (stored zeros included), and each value equal to its mirror's to 1e-12
    of the larger of the two (relative to the pair itself: a graph-wide or absolute
    tolerance took the arcs of a graph of small lengths, or the short arcs of a graph with
    long ones, for edges)."""
    t = sparse.csr_array(mat.T)
    t.sort_indices()
    if not (np.array_equal(mat.indptr, t.indptr) and np.array_equal(mat.indices, t.indices)):
        return False
    return bool(np.all(np.abs(mat.data - t.data) <= 1e-12 * np.maximum(np.abs(mat.data), np.abs(t.data))))


def as_graph(graph, *, name: str = "graph") -> sparse.csr_array:
    """Return ``graph`` as a symmetric float64 :class:`scipy.sparse.csr_array`.

    Accepts any scipy sparse matrix or array, a dense square array, or an undirected
    networkx or igraph graph (see :func:`as_any_graph` for the conventions); entries
    are edge lengths. Self-loops are dropped (they lie on no shortest path and have no
    effect on any centrality here). The input is never modified.
    """
    return as_any_graph(graph, name=name).adjacency


FOREGROUNDS = ("auto", "dark", "light")


def _border(mask: np.ndarray) -> np.ndarray:
    """The pixels on the outer frame of a 2D mask, each once."""
    if mask.shape[0] <= 2 or mask.shape[1] <= 2:
        return mask.ravel()
    return np.concatenate([mask[0], mask[-1], mask[1:-1, 0], mask[1:-1, -1]])


def check_threshold(threshold):
    """``threshold`` checked: None, or a finite real number (not a bool)."""
    if threshold is not None and (isinstance(threshold, bool) or not isinstance(threshold, numbers.Real)):
        raise TypeError(f"`threshold` must be a finite real number or None; got {threshold!r}.")
    if threshold is not None and not _finite_real(threshold):
        raise InputError(f"`threshold` must be a finite real number or None; got {threshold!r}.")
    return threshold


def as_binary_image(
    image,
    *,
    name: str = "image",
    foreground: str = "auto",
    threshold: float | None = None,
    check_inverted: bool = False,
) -> np.ndarray:
    """Return a 2D boolean foreground mask (True = the shape) from ``image``.

    Masks
        A boolean image, or a numeric one holding only 0 and 1 with no ``threshold``,
        is a mask: 1/True is the shape (``foreground="dark"`` takes the 0s instead).
    Grey images
        Any other numeric image (e.g. 0/255 silhouettes, grey anti-aliased outlines) is
        split at ``threshold``, by default half its range, ``(min + max) / 2``: pixels
        above are light, the others dark. ``foreground="light"`` or ``"dark"`` says
        which side is the shape; ``foreground="auto"`` takes the side that touches
        fewer pixels of the image border (the background surrounds the shape), and
        on a tie the side with fewer pixels. So dark shapes on white (Kimia) and white
        shapes on black (MPEG-7) both come out as the shape.

    With ``check_inverted=True`` (for inputs meant to be silhouettes), a shape that
    touches more than half of the border pixels (the whole border included) while
    some background is left looks inverted, and a :class:`UserWarning` says so
    (images smaller than 8 x 8 are not judged; with ``"auto"`` on a grey image this
    cannot happen).

    Raises :class:`TypeError` for non-numeric input and
    :class:`~centrality_vision.exceptions.InputError` for a shape other than 2D,
    non-finite values, an unknown ``foreground`` or an image with no shape pixel.
    The input is never modified.

    Examples
    --------
    >>> import numpy as np
    >>> grey = np.full((5, 5), 255, dtype=np.uint8); grey[1:4, 2] = 0  # dark bar on white
    >>> as_binary_image(grey).astype(int)
    array([[0, 0, 0, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 0, 0, 0]])
    >>> bool((as_binary_image(255 - grey) == as_binary_image(grey)).all())  # white on black: same shape
    True
    """
    if sparse.issparse(image):
        raise TypeError(f"`{name}` must be a dense 2D array; got {_describe(image)}.")
    if not isinstance(foreground, str) or foreground not in FOREGROUNDS:
        raise InputError(f"`foreground` must be one of {', '.join(map(repr, FOREGROUNDS))}; got {foreground!r}.")
    arr = as_real_array(image, name=name, shape="a 2D array")  # masked entries, ragged lists: named errors
    if arr.ndim != 2:
        raise InputError(f"`{name}` must be a 2D array; got shape {arr.shape}.")
    if arr.size == 0:
        raise InputError(f"`{name}` must not be empty; got shape {arr.shape}.")
    if arr.dtype != bool and not np.all(np.isfinite(arr)):
        raise InputError(f"`{name}` must be finite; got NaN or inf values.")
    check_threshold(threshold)
    is_mask = arr.dtype == bool or (threshold is None and bool(np.all((arr == 0) | (arr == 1))))
    if is_mask:
        light = arr.astype(bool)  # a new array: the input is never returned
        side = "dark" if foreground == "dark" else "light"
    else:
        values = arr.astype(np.float64, copy=False)
        low, high = float(values.min()), float(values.max())
        if threshold is None and low == high:
            raise InputError(f"`{name}` is uniform (every pixel is {low:g}): there is no shape in it.")
        cut = low / 2 + high / 2 if threshold is None else float(threshold)  # ((low + high) / 2 overflowed at 1e308)
        light = values > cut
        side = foreground
        if side == "auto":
            border = _border(light)
            on_light, on_dark = int(border.sum()), int(border.size - border.sum())
            if on_light != on_dark:
                side = "light" if on_light < on_dark else "dark"
            else:
                side = "light" if 2 * int(light.sum()) <= light.size else "dark"
    mask = light if side == "light" else ~light
    if not mask.any() and threshold is not None and not is_mask:
        # the threshold chose: name it and the image's range (the message blamed the image)
        need = f"below {high:g}, its largest value" if side == "light" else f"at least {low:g}, its smallest value"
        raise InputError(
            f"`threshold` {float(threshold):g} leaves no {side} pixel (the shape) in `{name}`: it must be {need}."
        )
    if not mask.any():
        raise InputError(f"`{name}` must have at least one foreground pixel; got none (shape {arr.shape}).")
    if check_inverted and (is_mask or foreground != "auto") and min(mask.shape) >= 8:
        border = _border(mask)
        if 2 * int(border.sum()) > border.size and not mask.all():
            warn(
                f"`{name}` looks inverted: its shape (foreground) touches {int(border.sum())} of the "
                f"{border.size} border pixels. Pass `foreground='auto'` (grey images), `foreground='dark'` or "
                "`foreground='light'` if the shape is the other side.",
                UserWarning,
            )
    return mask


def _finite_real(value) -> bool:
    """Whether a real number is finite (a Python int beyond float64 is not; numpy's isfinite
    raised a TypeError on ints beyond int64)."""
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def nearest_existing(path: Path) -> Path:
    """The nearest part of ``path`` that exists: itself, else its closest parent (at worst
    the root, or ``.`` for a relative path). A folder to be created is possible only where
    this is a folder, not a file."""
    path = Path(path)
    return next(part for part in (path, *path.parents) if part.exists())


def check_bool(value, *, name: str) -> bool:
    """Check that ``value`` is True or False (numpy's bools too; not any truthy value) and return it."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"`{name}` must be True or False; got {_describe(value)}.")
    return bool(value)


def check_choice(value, choices: Iterable[str], *, name: str) -> str:
    """Check that ``value`` is one of ``choices`` (strings) and return it."""
    choices = tuple(choices)
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"`{name}` must be one of {', '.join(map(repr, choices))}; got {value!r}.")
    return value


# check_int's bound when none is given: counts, sizes and passes beyond it mean nothing,
# and the compiled kernels take int64 (10**20 raised numba's TypingError or OverflowError)
INT_LIMIT = 2**62


def check_int(value, *, name: str, low: int | None = None, high: int | None = None) -> int:
    """Check that ``value`` is an integer in [low, high] (high: ``INT_LIMIT`` if None) and
    return it as ``int``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"`{name}` must be an int; got {value!r} of type {type(value).__name__}.")
    value = int(value)
    high = INT_LIMIT if high is None else high
    if (low is not None and value < low) or value > high:
        lo = "-inf" if low is None else low
        hi = "2^62" if high == INT_LIMIT else high
        raise InputError(f"`{name}` must be an int in [{lo}, {hi}]; got {value}.")
    return value


def shown_bound(value: float) -> str:
    """A range's end as a reader writes it: 0, 1e+06, 4294967295 (not 0.0, 1000000.0 or
    4.29497e+09)."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def check_float(
    value,
    *,
    name: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Check that ``value`` is a finite real number in the given interval and return it."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"`{name}` must be a real number; got {value!r} of type {type(value).__name__}.")
    shown = None
    try:
        value = float(value)
    except OverflowError:  # a Python int beyond float64 (10**400): not finite
        shown, value = f"an int beyond float64 ({_describe(value)})", math.inf if value > 0 else -math.inf
    bad = not np.isfinite(value)
    if low is not None:
        bad |= value <= low if low_open else value < low
    if high is not None:
        bad |= value >= high if high_open else value > high
    if bad:
        # an unbounded side is open: the value must be finite ("(0, inf)", never "(0, inf]")
        lb = "(" if low_open or low is None else "["
        rb = ")" if high_open or high is None else "]"
        lo = "-inf" if low is None else shown_bound(low)
        hi = "inf" if high is None else shown_bound(high)
        raise InputError(f"`{name}` must be a finite number in {lb}{lo}, {hi}{rb}; got {shown or repr(value)}.")
    return value


def argparse_number(kind, *, low=None, low_open=False, high=None, high_open=False):
    """An argparse ``type``: an int or float (``kind``) in a range, or argparse's one-line
    usage error ('must be in [1, inf); got 0'). The command line's options and the
    experiments' ``python -m`` options both use it, so their errors read alike."""

    def check(text: str):
        try:
            value = kind(text)
        except ValueError:
            wanted = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"must be {wanted}; got {text!r}") from None
        if kind is float and not math.isfinite(value):  # the library refuses inf anyway, after the reading
            raise argparse.ArgumentTypeError(f"must be a finite number; got {text!r}")
        too_low = low is not None and (value <= low if low_open else value < low)
        too_high = high is not None and (value >= high if high_open else value > high)
        if too_low or too_high:
            left = "(" if low_open or low is None else "["  # an infinite end is open
            right = ")" if high_open or high is None else "]"
            ends = ("-inf" if low is None else shown_bound(low), "inf" if high is None else shown_bound(high))
            span = f"{left}{ends[0]}, {ends[1]}{right}"
            raise argparse.ArgumentTypeError(f"must be in {span}; got {text}")
        return value

    check.__name__ = "integer" if kind is int else "number"
    return check
