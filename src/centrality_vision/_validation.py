"""The one place where user inputs are checked and converted.

Every public function passes its data arguments through one of these helpers, so
that errors have one format: the parameter, what was expected, what came in.
Nothing here modifies its input: arrays are copied when they would be changed.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable

import numpy as np
from scipy import sparse

from .exceptions import InputError

#: ``n_dims`` for functions that accept points of any (reasonable) dimension.
ANY_DIMS = tuple(range(1, 65))

__all__ = ["ANY_DIMS", "as_points", "as_graph", "as_binary_image", "check_choice", "check_int", "check_float"]


def _describe(value) -> str:
    if isinstance(value, np.ndarray):
        return f"array of shape {value.shape} and dtype {value.dtype}"
    if sparse.issparse(value):
        return f"sparse {type(value).__name__} of shape {value.shape}"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def as_points(
    points,
    *,
    name: str = "points",
    n_dims: tuple[int, ...] = (2, 3),
    min_points: int = 1,
    allow_duplicates: bool = True,
) -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 array of shape (n_points, n_dims).

    Raises a :class:`TypeError` for non-numeric input and an :class:`InputError`
    (a ``ValueError``) for a wrong shape, non-finite values, too few points or,
    with ``allow_duplicates=False``, repeated points.
    """
    if sparse.issparse(points):
        raise TypeError(f"`{name}` must be a dense array of shape (n_points, n_dims); got {_describe(points)}.")
    try:
        arr = np.asarray(points)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise InputError(f"`{name}` must be an array of shape (n_points, n_dims); got {_describe(points)} ({exc}).") from None
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise TypeError(f"`{name}` must hold real numbers; got {_describe(arr)}.")
    if np.iscomplexobj(arr):
        raise TypeError(f"`{name}` must hold real numbers; got complex dtype {arr.dtype}.")
    if arr.ndim != 2 or arr.shape[1] not in n_dims:
        dims = " or ".join(str(d) for d in n_dims)
        raise InputError(f"`{name}` must have shape (n_points, {dims}); got shape {arr.shape}.")
    arr = np.array(arr, dtype=np.float64, order="C", copy=True)
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr).all(axis=1)))
        raise InputError(f"`{name}` must be finite; got {bad} row(s) with NaN or inf.")
    if arr.shape[0] < min_points:
        raise InputError(f"`{name}` must have at least {min_points} points; got {arr.shape[0]}.")
    if not allow_duplicates and arr.shape[0] > 1:
        uniq, first, counts = np.unique(arr, axis=0, return_index=True, return_counts=True)
        if uniq.shape[0] != arr.shape[0]:
            dup = uniq[np.argmax(counts)]
            raise InputError(
                f"`{name}` must not contain duplicate points; got {arr.shape[0] - uniq.shape[0]} "
                f"duplicate(s), e.g. {dup.tolist()}."
            )
    return arr


def as_graph(graph, *, name: str = "graph") -> sparse.csr_array:
    """Return ``graph`` as a symmetric float64 :class:`scipy.sparse.csr_array`.

    Accepts any scipy sparse matrix or array, or a dense square array; entries are edge
    lengths, zero means no edge. Self-loops are dropped (they lie on no shortest path and
    have no effect on any centrality here). The input is never modified.
    """
    if sparse.issparse(graph):
        mat = sparse.csr_array(graph, dtype=np.float64, copy=True)
    else:
        try:
            dense = np.asarray(graph, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(
                f"`{name}` must be a scipy.sparse matrix or a square array of edge lengths; got {_describe(graph)}."
            ) from None
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
        raise InputError(f"`{name}` must have non-negative edge lengths; got min {mat.data.min()!r}.")
    mat.setdiag(0)
    mat.eliminate_zeros()
    mat.sum_duplicates()
    mat.sort_indices()
    diff = mat - mat.T
    if diff.nnz and np.max(np.abs(diff.data)) > 1e-12 * max(1.0, float(np.max(mat.data, initial=0.0))):
        raise InputError(f"`{name}` must be symmetric (an undirected graph); got an asymmetric adjacency.")
    index_dtype = np.int32 if max(mat.nnz, mat.shape[0]) < 2**31 - 1 else np.int64
    mat.indices = mat.indices.astype(index_dtype, copy=False)
    mat.indptr = mat.indptr.astype(index_dtype, copy=False)
    return mat


def as_binary_image(image, *, name: str = "image", threshold: float | None = None) -> np.ndarray:
    """Return a 2D boolean foreground mask (True = foreground) from ``image``.

    Boolean images and images whose values are all 0 or 1 are taken as they are.
    Other numeric images need ``threshold``: foreground is ``image > threshold``.
    """
    if sparse.issparse(image):
        raise TypeError(f"`{name}` must be a dense 2D array; got {_describe(image)}.")
    arr = np.asarray(image)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise TypeError(f"`{name}` must be a numeric or boolean 2D array; got {_describe(arr)}.")
    if arr.ndim != 2:
        raise InputError(f"`{name}` must be a 2D array; got shape {arr.shape}.")
    if arr.size == 0:
        raise InputError(f"`{name}` must not be empty; got shape {arr.shape}.")
    if arr.dtype != bool and not np.all(np.isfinite(arr)):
        raise InputError(f"`{name}` must be finite; got NaN or inf values.")
    if threshold is not None:
        mask = arr > threshold
    elif arr.dtype == bool:
        mask = arr.copy()
    else:
        values = np.unique(arr)
        if not np.all(np.isin(values, (0, 1))):
            shown = values[:5].tolist()
            raise InputError(
                f"`{name}` must be binary (bool or only 0 and 1) unless `threshold` is given; "
                f"got {values.size} distinct values, e.g. {shown}."
            )
        mask = arr == 1
    if not mask.any():
        raise InputError(f"`{name}` must have at least one foreground pixel; got none (shape {arr.shape}).")
    return mask


def check_choice(value, choices: Iterable[str], *, name: str) -> str:
    """Check that ``value`` is one of ``choices`` (strings) and return it."""
    choices = tuple(choices)
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"`{name}` must be one of {', '.join(map(repr, choices))}; got {value!r}.")
    return value


def check_int(value, *, name: str, low: int | None = None, high: int | None = None) -> int:
    """Check that ``value`` is an integer in [low, high] and return it as ``int``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"`{name}` must be an int; got {value!r} of type {type(value).__name__}.")
    value = int(value)
    if (low is not None and value < low) or (high is not None and value > high):
        lo = "-inf" if low is None else low
        hi = "inf" if high is None else high
        raise InputError(f"`{name}` must be an int in [{lo}, {hi}]; got {value}.")
    return value


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
    value = float(value)
    bad = not np.isfinite(value)
    if low is not None:
        bad |= value <= low if low_open else value < low
    if high is not None:
        bad |= value >= high if high_open else value > high
    if bad:
        lb = "(" if low_open else "["
        rb = ")" if high_open else "]"
        lo = "-inf" if low is None else low
        hi = "inf" if high is None else high
        raise InputError(f"`{name}` must be a finite number in {lb}{lo}, {hi}{rb}; got {value!r}.")
    return value
