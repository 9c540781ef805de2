"""Figures: graphs over point sets, and centralities shown as images.

matplotlib is imported inside the functions, so importing this module (or the
package) does not import it. Every function draws on the Axes it is given, or on a
new figure when ``ax`` is None, and returns the Axes; :func:`save_figure` writes a
figure to disk and closes it.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse

from ._validation import _describe, as_graph, as_points, check_float
from .exceptions import InputError

__all__ = [
    "plot_graph",
    "plot_centrality_image",
    "plot_matching",
    "plot_registration_snapshots",
    "plot_alignment_errors",
    "save_figure",
]


def _as_values(values, *, n: int, other: str) -> np.ndarray:
    """``values`` as a finite float64 array of shape (n,); ``other`` names what fixes n."""
    if sparse.issparse(values):
        raise TypeError(f"`values` must be a dense array of shape (n,); got {_describe(values)}.")
    arr = np.asarray(values)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise TypeError(f"`values` must hold real numbers; got {_describe(arr)}.")
    if np.iscomplexobj(arr):
        raise TypeError(f"`values` must hold real numbers; got complex dtype {arr.dtype}.")
    if arr.shape != (n,):
        raise InputError(f"`values` must have shape ({n},), one value per row of `{other}`; got shape {arr.shape}.")
    arr = arr.astype(np.float64)  # always a copy
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InputError(f"`values` must be finite; got {bad} NaN or inf value(s).")
    return arr


def _check_ax(ax, *, three_d: bool, why: str) -> None:
    from matplotlib.axes import Axes

    if not isinstance(ax, Axes):
        raise TypeError(f"`ax` must be a matplotlib Axes or None; got {_describe(ax)}.")
    is_3d = getattr(ax, "name", "") == "3d"
    if is_3d != three_d:
        wanted = "a 3D Axes (projection='3d')" if three_d else "a 2D Axes"
        got = "a 3D Axes" if is_3d else f"a 2D Axes ({type(ax).__name__})"
        raise InputError(f"`ax` must be {wanted} {why}; got {got}.")


def plot_graph(
    points: ArrayLike,
    graph,
    values: ArrayLike | None = None,
    *,
    ax=None,
    cmap="viridis",
    node_size: float = 30,
    edge_color="0.6",
    edge_width: float = 0.8,
    colorbar: bool = True,
    label: str | None = None,
    title: str | None = None,
):
    """Draw a graph over its points, nodes coloured by a value such as a centrality.

    Each undirected edge (stored twice in ``graph``) is drawn once, as one segment of a
    :class:`~matplotlib.collections.LineCollection` (a
    :class:`~mpl_toolkits.mplot3d.art3d.Line3DCollection` for 3D points), below a
    scatter of the nodes. 2D plots have equal aspect; 3D plots use a 3D Axes, created
    when ``ax`` is None.

    Parameters
    ----------
    points : array_like of shape (n_points, 2) or (n_points, 3)
        Node coordinates, finite; row i is node i.
    graph : scipy.sparse array or matrix of shape (n_points, n_points)
        Symmetric adjacency whose stored values are edge lengths (a dense square array
        is accepted too; zero means no edge).
    values : array_like of shape (n_points,), optional
        Finite value of each node, mapped to colours through ``cmap`` (e.g. a centrality).
        If None, all nodes are drawn in one colour and no colorbar is added.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on: 2D for 2D points, 3D (``projection="3d"``) for 3D points.
        If None, a new figure and Axes are created.
    cmap : str or matplotlib.colors.Colormap, default="viridis"
        Colormap of the node colours.
    node_size : float, default=30
        Marker area in points squared, >= 0.
    edge_color : color, default="0.6"
        Colour of the edges (any matplotlib colour; the default is a mid grey).
    edge_width : float, default=0.8
        Line width of the edges in points, >= 0.
    colorbar : bool, default=True
        Add a colorbar for ``values`` (ignored when ``values`` is None).
    label : str, optional
        Label of the colorbar.
    title : str, optional
        Title of the Axes.

    Returns
    -------
    ax : matplotlib.axes.Axes
        The Axes drawn on; ``ax.collections`` holds the edges then the nodes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> from scipy import sparse
    >>> points = [[0, 0], [1, 0], [0, 1]]
    >>> graph = sparse.csr_array([[0, 1, 1], [1, 0, 0], [1, 0, 0]])  # a path 1 - 0 - 2
    >>> ax = plot_graph(points, graph, [2, 1, 1], label="degree")
    >>> len(ax.collections[0].get_segments())  # one segment per undirected edge
    2
    >>> plt.close(ax.figure)
    """
    points = as_points(points, name="points", n_dims=(2, 3), min_points=1)
    n, n_dims = points.shape
    graph = as_graph(graph, name="graph")
    if graph.shape != (n, n):
        raise InputError(
            f"`graph` must have shape (n_points, n_points) = ({n}, {n}) to match `points`; got shape {graph.shape}."
        )
    if values is not None:
        values = _as_values(values, n=n, other="points")
    node_size = check_float(node_size, name="node_size", low=0)
    edge_width = check_float(edge_width, name="edge_width", low=0)
    three_d = n_dims == 3
    if ax is not None:
        _check_ax(ax, three_d=three_d, why=f"for points of shape (n_points, {n_dims})")

    import matplotlib.pyplot as plt

    if ax is None:
        fig = plt.figure()
        ax = fig.add_subplot(projection="3d" if three_d else None)

    # Each undirected edge once: the upper triangle, read straight from the CSR arrays.
    rows = np.repeat(np.arange(n), np.diff(graph.indptr))
    cols = np.asarray(graph.indices, dtype=np.intp)
    upper = rows < cols
    segments = np.stack([points[rows[upper]], points[cols[upper]]], axis=1)  # (n_edges, 2, n_dims)
    line_style = dict(colors=edge_color, linewidths=edge_width, zorder=1)
    if three_d:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection

        ax.add_collection3d(Line3DCollection(segments, **line_style))
    else:
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(segments, **line_style))

    coords = points.T
    if values is None:
        nodes = ax.scatter(*coords, s=node_size, c="C0", zorder=2, **({"depthshade": False} if three_d else {}))
    else:
        nodes = ax.scatter(
            *coords, s=node_size, c=values, cmap=cmap, zorder=2, **({"depthshade": False} if three_d else {})
        )
        if colorbar:
            ax.figure.colorbar(nodes, ax=ax, label=label, shrink=0.75 if three_d else 1.0)
    ax.set_aspect("equal")
    if not three_d:
        ax.autoscale_view()
    if title is not None:
        ax.set_title(title)
    return ax


def _check_shape(shape) -> tuple[int, int]:
    try:
        dims = tuple(shape)
    except TypeError:
        dims = None
    if (
        dims is None
        or len(dims) != 2
        or not all(isinstance(d, (int, np.integer)) and not isinstance(d, bool) and d >= 1 for d in dims)
    ):
        raise InputError(f"`shape` must be a tuple of two positive ints (n_rows, n_cols); got {_describe(shape)}.")
    return int(dims[0]), int(dims[1])


def _check_nodes(nodes, *, size: int, shape: tuple[int, int]) -> np.ndarray:
    if sparse.issparse(nodes):
        raise TypeError(f"`nodes` must be a 1D array of pixel indices; got {_describe(nodes)}.")
    arr = np.asarray(nodes)
    if arr.ndim == 1 and arr.size == 0:
        raise InputError("`nodes` must hold at least one pixel index; got an empty array.")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"`nodes` must hold integer (flat, row-major) pixel indices; got {_describe(arr)}.")
    if arr.ndim != 1:
        raise InputError(f"`nodes` must be a 1D array of shape (n_nodes,); got shape {arr.shape}.")
    if arr.size and (arr.min() < 0 or arr.max() >= size):
        bad = arr[(arr < 0) | (arr >= size)]
        raise InputError(
            f"`nodes` must be flat pixel indices in [0, {size - 1}] for an image of `shape` {shape}; "
            f"got {bad.size} out of range, e.g. {int(bad[0])}."
        )
    if np.unique(arr).size != arr.size:
        raise InputError(f"`nodes` must not repeat a pixel; got {arr.size - np.unique(arr).size} repeated index(es).")
    return arr


def plot_centrality_image(
    values: ArrayLike,
    nodes: ArrayLike,
    shape,
    *,
    ax=None,
    cmap="viridis",
    background: float = np.nan,
    colorbar: bool = True,
    label: str | None = None,
    title: str | None = None,
):
    """Show the centrality of a pixel graph's nodes as an image (as in thesis fig. 4.2).

    Pixel ``nodes[i]`` of an image of ``shape`` gets the value ``values[i]``; all
    other pixels get ``background``, which by default is NaN and so masked: drawn
    blank, outside the colour scale.

    Parameters
    ----------
    values : array_like of shape (n_nodes,)
        Finite value of each node, e.g. a centrality.
    nodes : array_like of int, shape (n_nodes,)
        Flat (row-major) index into the image of each node's pixel, without repeats;
        this is the second value returned by ``pixel_graph(image)``.
    shape : tuple of int
        ``(n_rows, n_cols)`` of the image, e.g. ``image.shape``.
    ax : matplotlib.axes.Axes, optional
        2D Axes to draw on. If None, a new figure and Axes are created.
    cmap : str or matplotlib.colors.Colormap, default="viridis"
        Colormap of the values.
    background : float, default=np.nan
        Value of the pixels that are not nodes. NaN leaves them blank; a finite value
        is drawn through ``cmap`` and counts in the colour scale.
    colorbar : bool, default=True
        Add a colorbar.
    label : str, optional
        Label of the colorbar.
    title : str, optional
        Title of the Axes.

    Returns
    -------
    ax : matplotlib.axes.Axes
        The Axes drawn on; ``ax.images[0].get_array()`` is the masked image shown.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> ax = plot_centrality_image([0.5, 1.0, 0.5], [1, 4, 7], (3, 3), label="closeness")
    >>> ax.images[0].get_array()
    masked_array(
      data=[[--, 0.5, --],
            [--, 1.0, --],
            [--, 0.5, --]],
      mask=[[ True, False,  True],
            [ True, False,  True],
            [ True, False,  True]],
      fill_value=1e+20)
    >>> plt.close(ax.figure)
    """
    shape = _check_shape(shape)
    size = shape[0] * shape[1]
    nodes = _check_nodes(nodes, size=size, shape=shape)
    values = _as_values(values, n=nodes.size, other="nodes")
    if isinstance(background, bool) or not isinstance(background, (int, float, np.integer, np.floating)):
        raise TypeError(f"`background` must be a real number (NaN for blank); got {_describe(background)}.")
    if np.isinf(background):
        raise InputError(f"`background` must be finite or NaN; got {background!r}.")
    if ax is not None:
        _check_ax(ax, three_d=False, why="for an image")

    import matplotlib.pyplot as plt

    if ax is None:
        fig = plt.figure()
        ax = fig.add_subplot()

    image = np.full(size, float(background))
    image[nodes] = values
    image = np.ma.masked_invalid(image.reshape(shape))
    shown = ax.imshow(image, cmap=cmap, interpolation="nearest")
    ax.set_axis_off()
    if colorbar:
        ax.figure.colorbar(shown, ax=ax, label=label)
    if title is not None:
        ax.set_title(title)
    return ax


def save_figure(fig, path: str | os.PathLike, *, dpi: float = 150) -> Path:
    """Save ``fig`` to ``path``, creating missing parent folders, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (e.g. ``ax.figure``).
    path : str or os.PathLike
        Output file; its suffix (``.png``, ``.pdf``, ``.svg``, ...) picks the format.
    dpi : float, default=150
        Resolution in dots per inch, > 0.

    Returns
    -------
    path : pathlib.Path
        The path written.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import tempfile, pathlib
    >>> ax = plot_centrality_image([1.0, 2.0], [0, 3], (2, 2))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     out = save_figure(ax.figure, pathlib.Path(folder) / "figs" / "c.png", dpi=50)
    ...     out.is_file()
    True
    """
    from matplotlib.figure import Figure

    if not isinstance(fig, Figure):
        raise TypeError(f"`fig` must be a matplotlib Figure (e.g. `ax.figure`); got {_describe(fig)}.")
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"`path` must be a str or os.PathLike; got {_describe(path)}.")
    dpi = check_float(dpi, name="dpi", low=0, low_open=True)
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_matching(moving, fixed, correspondence, *, moving_graph=None, fixed_graph=None, ax=None, title=None):
    """Two 2D point sets side by side, their graphs, and lines joining matched points (thesis fig. 6.4).

    ``moving`` is drawn on the left and ``fixed`` shifted to its right; line ``i`` joins
    ``moving[i]`` and ``fixed[correspondence[i]]``. Returns the Axes.
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    moving = as_points(moving, name="moving", n_dims=(2,))
    fixed = as_points(fixed, name="fixed", n_dims=(2,))
    correspondence = np.asarray(correspondence)
    if correspondence.shape != (moving.shape[0],) or not np.issubdtype(correspondence.dtype, np.integer):
        raise ValueError(
            f"`correspondence` must be an integer array of shape ({moving.shape[0]},); got {correspondence.shape} "
            f"of dtype {correspondence.dtype}."
        )
    if correspondence.size and (correspondence.min() < 0 or correspondence.max() >= fixed.shape[0]):
        raise ValueError(f"`correspondence` must index into `fixed` (0 .. {fixed.shape[0] - 1}); got out-of-range values.")
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 5))
    span = np.ptp(np.vstack([moving, fixed]), axis=0)
    right = fixed + np.array([moving[:, 0].max() - fixed[:, 0].min() + 0.3 * max(span[0], 1e-12), 0.0])
    for pts, graph in ((moving, moving_graph), (right, fixed_graph)):
        if graph is not None:
            coo = sparse.triu(sparse.csr_array(graph), k=1).tocoo()
            ax.add_collection(LineCollection(np.stack([pts[coo.row], pts[coo.col]], axis=1), colors="0.75", linewidths=0.5))
    ax.add_collection(
        LineCollection(np.stack([moving, right[correspondence]], axis=1), colors="tab:orange", linewidths=0.8, alpha=0.8)
    )
    ax.scatter(moving[:, 0], moving[:, 1], s=12, color="tab:blue", zorder=3, label="moving")
    ax.scatter(right[:, 0], right[:, 1], s=12, color="tab:green", zorder=3, label="fixed")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.legend(loc="upper right")
    if title:
        ax.set_title(title)
    return ax


def plot_registration_snapshots(fixed, snapshots, *, iterations=None, fig=None, title=None):
    """A grid of registrations: one column per method, one row per iteration (thesis figs. 5.4, 5.5).

    Parameters
    ----------
    fixed : array_like of shape (N, D), D in {2, 3}
        Drawn as red stars in every panel.
    snapshots : dict
        ``{method label: {iteration: moving points (M, D)}}``, e.g. from
        :class:`centrality_vision.registration.Snapshots`; drawn as blue circles.
    iterations : sequence of int, optional
        Rows to draw; by default every iteration any method recorded. A method that stopped
        earlier shows its last recorded state, titled with the iteration it is from.
    fig : matplotlib Figure, optional
    title : str, optional

    Returns
    -------
    fig : matplotlib.figure.Figure

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> x = np.random.default_rng(0).random((20, 2))
    >>> fig = plot_registration_snapshots(x, {"CPD": {1: x + 0.1, 2: x}, "GPD": {1: x}})
    >>> len(fig.axes)
    4
    """
    import matplotlib.pyplot as plt

    fixed = as_points(fixed, name="fixed", n_dims=(2, 3))
    dim = fixed.shape[1]
    if not isinstance(snapshots, dict) or not snapshots:
        raise TypeError(f"`snapshots` must be a non-empty dict {{label: {{iteration: points}}}}; got {_describe(snapshots)}.")
    frames = {}
    for label, record in snapshots.items():
        if not isinstance(record, dict) or not record:
            raise InputError(f"`snapshots[{label!r}]` must be a non-empty dict {{iteration: points}}; got {_describe(record)}.")
        frames[label] = {int(k): as_points(v, name=f"snapshots[{label!r}][{k}]", n_dims=(dim,)) for k, v in record.items()}
    rows = sorted({k for record in frames.values() for k in record}) if iterations is None else [int(i) for i in iterations]
    if not rows:
        raise InputError("`iterations` must name at least one iteration.")
    cols = list(frames)
    if fig is None:
        span = np.ptp(fixed, axis=0)
        aspect = float(span[1] / span[0]) if dim == 2 and span[0] > 0 else 1.0
        fig = plt.figure(figsize=(2.6 * len(cols), 0.6 + 2.6 * min(max(aspect, 0.4), 1.5) * len(rows)))
    kw = {"projection": "3d"} if dim == 3 else {}
    for r, iteration in enumerate(rows):
        for c, label in enumerate(cols):
            ax = fig.add_subplot(len(rows), len(cols), r * len(cols) + c + 1, **kw)
            record = frames[label]
            shown = max((k for k in record if k <= iteration), default=min(record))
            moving = record[shown]
            ax.scatter(*fixed.T, marker="*", s=14, color="tab:red", label="fixed")
            ax.scatter(*moving.T, marker="o", s=10, facecolors="none", edgecolors="tab:blue", label="moving")
            if dim == 2:
                ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            if dim == 3:
                ax.set_zticks([])
            heading = f"{label}: {shown}" if shown != iteration else label
            ax.set_title(heading if r == 0 or shown != iteration else "", fontsize=9)
            if c == 0 and dim == 3:
                ax.text2D(-0.1, 0.5, f"iteration {iteration}", transform=ax.transAxes, rotation=90, va="center")
            elif c == 0:
                ax.set_ylabel(f"iteration {iteration}")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_alignment_errors(errors, *, ax=None, title=None, log=False):
    """Alignment error per iteration for several methods on one plot (thesis figs. 5.3, 5.6, 5.8).

    Parameters
    ----------
    errors : dict
        ``{method label: sequence of errors}``, entry ``k`` after ``k`` iterations
        (e.g. ``estimator.history_["error"]``).
    ax : matplotlib Axes, optional
    title : str, optional
    log : bool, default=False
        Logarithmic error axis.

    Returns
    -------
    ax : matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> ax = plot_alignment_errors({"CPD": [4.0, 2.0, 1.0], "GPD (closeness)": [4.0, 1.0, 0.5]})
    >>> len(ax.lines)
    2
    """
    import matplotlib.pyplot as plt

    if not isinstance(errors, dict) or not errors:
        raise TypeError(f"`errors` must be a non-empty dict {{label: errors per iteration}}; got {_describe(errors)}.")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    else:
        _check_ax(ax, three_d=False, why="for error curves")
    for label, values in errors.items():
        if values is None:
            raise InputError(f"`errors[{label!r}]` is None: fit with `true_moving=` to record alignment errors.")
        v = _as_values(values, n=len(values), other=f"errors[{label!r}]")
        ax.plot(np.arange(v.size), v, label=str(label), lw=1.5)
    ax.set_xlabel("iteration")
    ax.set_ylabel(r"$\|X - T(Y)\|$")
    if log:
        ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title)
    return ax
