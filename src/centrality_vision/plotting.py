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

from ._validation import (
    _describe,
    as_graph,
    as_points,
    check_bool,
    check_float,
    check_int,
    is_real_dtype,
    nearest_existing,
)
from .exceptions import InputError

__all__ = [
    "plot_graph",
    "plot_centrality_image",
    "plot_matching",
    "plot_registration",
    "plot_registration_snapshots",
    "plot_alignment_errors",
    "save_figure",
]

_NORMS = ("linear", "log", "power")
#: Positive values a logarithmic colour scale or axis can draw (matplotlib overflows beyond).
_LOG_RANGE = (1e-200, 1e200)


def _norm(norm, values: np.ndarray):
    """A matplotlib ``Normalize`` for ``norm``: "linear" (None), "log", "power" (square root) or one given.

    Centralities such as betweenness span orders of magnitude: on a linear scale all but
    the largest few values share the darkest colour. "log" spaces decades evenly (values
    at or below 0 are drawn in the lowest colour, as the smallest positive value; the
    positive values must lie within [1e-200, 1e200], where matplotlib can draw the scale);
    "power" takes the square root, which keeps zeros.
    """
    from matplotlib import colors

    if norm is None or (isinstance(norm, str) and norm == "linear"):
        return None
    if isinstance(norm, colors.Normalize):
        return norm
    if norm == "log":
        positive = values[values > 0]
        if positive.size == 0:
            raise InputError("`norm` 'log' needs at least one value > 0; got none (use 'power' or 'linear').")
        # matplotlib's log colour bar overflows in its ticks beyond about 1e250 and refuses
        # limits near 1e-300 ("Invalid vmin or vmax")
        if positive.min() < _LOG_RANGE[0] or positive.max() > _LOG_RANGE[1]:
            raise InputError(
                f"`norm` 'log' draws positive values within [{_LOG_RANGE[0]:g}, {_LOG_RANGE[1]:g}]; got "
                f"[{float(positive.min())!r}, {float(positive.max())!r}] (rescale them, or use 'power' or 'linear')."
            )
        return colors.LogNorm(vmin=float(positive.min()), vmax=float(values.max()), clip=True)
    if norm == "power":
        low, high = float(values.min()), float(values.max())
        return colors.PowerNorm(gamma=0.5, vmin=low, vmax=high if high > low else low + 1)
    raise InputError(f"`norm` must be one of {', '.join(map(repr, _NORMS))} or a matplotlib Normalize; got {norm!r}.")


_MAX_COORDINATE = 1e307  # matplotlib's limits and ticks overflow for coordinates near float64's 1.8e308


def _check_cmap(cmap):
    """``cmap`` as a matplotlib colormap (a name or a Colormap), or an error naming it."""
    import matplotlib
    from matplotlib.colors import Colormap

    if isinstance(cmap, Colormap):
        return cmap
    if not isinstance(cmap, str):
        raise TypeError(f"`cmap` must be a colormap name or a matplotlib Colormap; got {_describe(cmap)}.")
    if cmap not in matplotlib.colormaps:
        raise InputError(f"`cmap` must name a matplotlib colormap (e.g. 'viridis'); got {cmap!r}.")
    return matplotlib.colormaps[cmap]


def _check_color(color, *, name: str):
    from matplotlib.colors import is_color_like

    if not is_color_like(color):
        raise InputError(f"`{name}` must be a matplotlib colour (e.g. '0.6' or 'red'); got {color!r}.")
    return color


def _plot_points(points, *, name: str, n_dims: tuple, rowcol: bool = False, min_points: int = 1) -> np.ndarray:
    """Validated points to draw (see :func:`as_points`), within +-1e307, as (x, y) when ``rowcol``."""
    rowcol = check_bool(rowcol, name="rowcol")
    points = as_points(points, name=name, n_dims=n_dims, min_points=min_points)
    if points.size and np.abs(points).max() > _MAX_COORDINATE:
        raise InputError(
            f"`{name}` must lie within +-{_MAX_COORDINATE:g} to be drawn (matplotlib's axis limits overflow "
            f"beyond); got a coordinate of {np.abs(points).max():.3g}. Rescale the points."
        )
    return _image_axes(points, rowcol, name)


def _image_axes(points: np.ndarray, rowcol: bool, name: str) -> np.ndarray:
    """(row, col) pixel coordinates as (x, y) = (col, row); the caller then points the y axis down."""
    if not rowcol:
        return points
    if points.shape[1] != 2:
        raise InputError(f"`rowcol=True` needs 2D `{name}` (row, col); got {points.shape[1]} columns.")
    return points[:, ::-1]


def _row_zero_on_top(ax) -> None:
    if not ax.yaxis_inverted():
        ax.invert_yaxis()


def _colorbar(ax, mappable, label, *, three_d: bool):
    """A colorbar as tall as the drawn Axes: beside an equal-aspect 2D Axes it sits in an inset
    that follows the Axes' box, so it does not stretch past a short plot."""
    if three_d:
        return ax.figure.colorbar(mappable, ax=ax, label=label, shrink=0.7, pad=0.1)
    cax = ax.inset_axes((1.04, 0.0, 0.045, 1.0))
    return ax.figure.colorbar(mappable, cax=cax, label=label)


def _equal_3d(ax, points: np.ndarray) -> None:
    """Equal scale on the three axes of a 3D Axes (matplotlib's "equal" aspect is per-box), small ticks."""
    span = np.ptp(points, axis=0)
    span = np.where(span > 0, span, max(float(span.max()), 1.0) * 0.05)
    ax.set_box_aspect(tuple(span / span.max()))
    from matplotlib.ticker import MaxNLocator

    for axis, length in zip((ax.xaxis, ax.yaxis, ax.zaxis), span / span.max()):
        axis.set_major_locator(MaxNLocator(nbins=max(2, int(round(5 * length))), prune="both"))
    ax.tick_params(labelsize=7, pad=0)


#: Largest magnitude a plotted value may have: the span of two such values stays finite.
_MAX_VALUE = 1e307


def _as_values(values, *, n: int, other: str | None, name: str = "values") -> np.ndarray:
    """``values`` as a finite float64 array of shape (n,); ``other`` names what fixes n (None:
    a series of its own length, one value per iteration), ``name`` the argument an error names."""
    if sparse.issparse(values):
        raise TypeError(f"`{name}` must be a dense array of shape (n,); got {_describe(values)}.")
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError):  # ragged nested lists: numpy's "inhomogeneous shape"
        raise InputError(f"`{name}` must be an array of shape ({n},); got {_describe(values)}.") from None
    if np.iscomplexobj(arr):
        raise TypeError(f"`{name}` must hold real numbers; got complex dtype {arr.dtype}.")
    if not is_real_dtype(arr.dtype):
        raise TypeError(f"`{name}` must hold real numbers; got {_describe(arr)}.")
    if arr.shape != (n,):
        per = "one value per iteration" if other is None else f"one value per row of `{other}`"
        raise InputError(f"`{name}` must have shape ({n},), {per}; got shape {arr.shape}.")
    arr = arr.astype(np.float64)  # always a copy
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InputError(f"`{name}` must be finite; got {bad} NaN or inf value(s).")
    # a colour or axis scale spans max - min, which overflows beyond half the float64 range
    if arr.size and float(np.max(np.abs(arr))) > _MAX_VALUE:
        raise InputError(f"`{name}` must lie within +-{_MAX_VALUE:g} to be drawn; got {float(np.max(np.abs(arr))):g}.")
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
    node_size: float | None = None,
    edge_color="0.6",
    edge_width: float = 0.8,
    colorbar: bool = True,
    label: str | None = None,
    title: str | None = None,
    norm=None,
    rowcol: bool = False,
):
    """Draw a graph over its points, nodes coloured by a value such as a centrality.

    Each undirected edge (stored twice in ``graph``) is drawn once, as one segment of a
    :class:`~matplotlib.collections.LineCollection` (a
    :class:`~mpl_toolkits.mplot3d.art3d.Line3DCollection` for 3D points), below a
    scatter of the nodes. 2D plots have equal aspect; 3D plots use a 3D Axes, created
    when ``ax`` is None, with the same scale on all three axes.

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
    node_size : float, optional
        Marker area in points squared, >= 0; by default 30 in 2D and 6 in 3D, where
        hundreds of points would otherwise merge into a blob.
    edge_color : color, default="0.6"
        Colour of the edges (any matplotlib colour; the default is a mid grey).
    edge_width : float, default=0.8
        Line width of the edges in points, >= 0. Graphs with more than 3 edges per node
        (k-NN with large k, MWME, complete graphs) get translucent edges, so that the
        nodes and the density of the edges stay visible.
    colorbar : bool, default=True
        Add a colorbar for ``values`` (ignored when ``values`` is None).
    label : str, optional
        Label of the colorbar.
    title : str, optional
        Title of the Axes.
    norm : {"linear", "log", "power"} or matplotlib.colors.Normalize, optional
        Colour scale of ``values``: linear (the default), logarithmic, or the square root
        ("power"), for values that span orders of magnitude such as betweenness.
    rowcol : bool, default=False
        The points are 2D (row, col) pixel coordinates, e.g. from
        :func:`~centrality_vision.datasets.contour_points`: they are drawn with the
        column across and row 0 at the top, the way the image looks (not transposed).

    Returns
    -------
    ax : matplotlib.axes.Axes
        The Axes drawn on; ``ax.collections`` holds the edges then the nodes.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from scipy import sparse
    >>> points = [[0, 0], [1, 0], [0, 1]]
    >>> graph = sparse.csr_array([[0, 1, 1], [1, 0, 0], [1, 0, 0]])  # a path 1 - 0 - 2
    >>> ax = plot_graph(points, graph, [2, 1, 1], label="degree")
    >>> len(ax.collections[0].get_segments())  # one segment per undirected edge
    2
    >>> plt.close(ax.figure)
    """
    points = _plot_points(points, name="points", n_dims=(2, 3), rowcol=rowcol)
    n, n_dims = points.shape
    graph = as_graph(graph, name="graph")
    if graph.shape != (n, n):
        raise InputError(
            f"`graph` must have shape (n_points, n_points) = ({n}, {n}) to match `points`; got shape {graph.shape}."
        )
    if values is not None:
        values = _as_values(values, n=n, other="points")
    three_d = n_dims == 3
    node_size = check_float(
        (6 if three_d else 30) if node_size is None else node_size, name="node_size", low=0, high=_MAX_MARKER_AREA
    )
    edge_width = check_float(edge_width, name="edge_width", low=0)
    cmap = _check_cmap(cmap)
    edge_color = _check_color(edge_color, name="edge_color")
    colorbar = check_bool(colorbar, name="colorbar")
    color_norm = None if values is None else _norm(norm, values)
    if ax is not None:
        _check_ax(ax, three_d=three_d, why=f"for points of shape (n_points, {n_dims})")

    import matplotlib.pyplot as plt

    if ax is None:
        fig = plt.figure(layout="constrained")
        ax = fig.add_subplot(projection="3d" if three_d else None)

    # Each undirected edge once: the upper triangle, read straight from the CSR arrays.
    rows = np.repeat(np.arange(n), np.diff(graph.indptr))
    cols = np.asarray(graph.indices, dtype=np.intp)
    upper = rows < cols
    segments = np.stack([points[rows[upper]], points[cols[upper]]], axis=1)  # (n_edges, 2, n_dims)
    n_edges = int(np.count_nonzero(upper))
    alpha = 1.0 if n_edges <= 3 * n else max(0.05, 3 * n / n_edges)
    line_style = dict(colors=edge_color, linewidths=edge_width, alpha=alpha, zorder=1)
    if three_d:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection

        if n_edges:  # matplotlib's 3D collection cannot be empty (it concatenates the segments)
            ax.add_collection3d(Line3DCollection(segments, **line_style))
    else:
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(segments, **line_style))

    coords = points.T
    if values is None:
        nodes = ax.scatter(*coords, s=node_size, c="C0", zorder=2, **({"depthshade": False} if three_d else {}))
    else:
        nodes = ax.scatter(
            *coords,
            s=node_size,
            c=values,
            cmap=cmap,
            norm=color_norm,
            zorder=2,
            **({"depthshade": False} if three_d else {}),
        )
        if colorbar:
            _colorbar(ax, nodes, label, three_d=three_d)
    if three_d:
        _equal_3d(ax, points)
    else:
        ax.set_aspect("equal")
        ax.autoscale_view()
        if rowcol:
            _row_zero_on_top(ax)
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
    if int(dims[0]) * int(dims[1]) > _MAX_PIXELS:
        raise InputError(
            f"`shape` must have at most {_MAX_PIXELS:.0e} pixels (the image is drawn from a dense array); "
            f"got {int(dims[0])} x {int(dims[1])}."
        )
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
    # a small or unsigned type (uint8, int16) wrapped around in the row/column arithmetic
    return arr.astype(np.intp)


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
    norm=None,
    crop: bool = True,
):
    """Show the centrality of a pixel graph's nodes as an image (as in thesis fig. 4.2).

    Pixel ``nodes[i]`` of an image of ``shape`` gets the value ``values[i]``; all
    other pixels get ``background``, which by default is NaN and so masked: drawn
    blank, outside the colour scale. Row 0 of the image is at the top, as in the file.

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
    norm : {"linear", "log", "power"} or matplotlib.colors.Normalize, optional
        Colour scale: linear (the default), logarithmic, or the square root ("power").
        Betweenness on a pixel graph is large on a few pixels and near zero elsewhere;
        "power" or "log" show its structure.
    crop : bool, default=True
        Show only the nodes' bounding box (with a margin of 3 pixels) rather than the
        whole image, most of which is background in a silhouette file.

    Returns
    -------
    ax : matplotlib.axes.Axes
        The Axes drawn on; ``ax.images[0].get_array()`` is the masked image shown.

    Examples
    --------
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
    background = float(background)  # (a float32 compared with 1e307 overflowed, with a warning)
    if np.isinf(background) or abs(background) > _MAX_VALUE:  # (the colour bar's range overflowed)
        raise InputError(f"`background` must be NaN or within +-{_MAX_VALUE:g}; got {background!r}.")
    cmap = _check_cmap(cmap)
    colorbar = check_bool(colorbar, name="colorbar")
    crop = check_bool(crop, name="crop")
    if ax is not None:
        _check_ax(ax, three_d=False, why="for an image")

    import matplotlib.pyplot as plt

    image = np.full(size, float(background))
    image[nodes] = values
    image = np.ma.masked_invalid(image.reshape(shape))
    color_norm = _norm(norm, image.compressed())  # (checked before a figure is made: none left open)
    if ax is None:
        fig = plt.figure(layout="constrained")
        ax = fig.add_subplot()
    shown = ax.imshow(image, cmap=cmap, norm=color_norm, interpolation="nearest")
    if crop:
        rows, cols = np.divmod(nodes, shape[1])
        ax.set_xlim(max(cols.min() - 3, 0) - 0.5, min(cols.max() + 3, shape[1] - 1) + 0.5)
        ax.set_ylim(min(rows.max() + 3, shape[0] - 1) + 0.5, max(rows.min() - 3, 0) - 0.5)  # row 0 at the top
    ax.set_axis_off()
    if colorbar:
        _colorbar(ax, shown, label, three_d=False)
    if title is not None:
        ax.set_title(title)
    return ax


_MAX_PIXELS = 10**9  # a dense float64 image of 8 GB: beyond it, no figure is worth drawing
_MAX_MARKER_AREA = 1e6  # points^2: a marker of ~14 inches across; larger ones stall the renderer
_MAX_DPI = 10_000.0  # (a figure of a few inches at more dpi is beyond what renderers allocate)


def save_figure(fig, path: str | os.PathLike, *, dpi: float = 150) -> Path:
    """Save ``fig`` to ``path``, creating missing parent folders, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (e.g. ``ax.figure``).
    path : str or os.PathLike
        Output file; its suffix (``.png``, ``.pdf``, ``.svg``, ...) picks the format and must
        be one the figure's canvas can write.
    dpi : float, default=150
        Resolution in dots per inch, in (0, 10000].

    Returns
    -------
    path : pathlib.Path
        The path written.

    Examples
    --------
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
    dpi = check_float(dpi, name="dpi", low=0, low_open=True, high=_MAX_DPI)
    import matplotlib.pyplot as plt

    path = Path(path).expanduser()  # "~/figs/a.png" is the home folder's, not a folder named "~"
    formats = fig.canvas.get_supported_filetypes()
    if path.is_dir():
        raise InputError(f"`path` must be a file, not a folder; got {str(path)!r} (add a name, e.g. 'figure.png').")
    if path.suffix.lower().lstrip(".") not in formats:
        raise InputError(
            f"`path` must end in a format suffix ({', '.join('.' + f for f in sorted(formats))}); got {str(path)!r}."
        )
    folder = nearest_existing(path.parent)
    if not folder.is_dir():  # (mkdir's FileExistsError)
        raise InputError(f"`path` must be in a folder; got {str(path)!r}, whose {str(folder)!r} is a file.")
    path.parent.mkdir(parents=True, exist_ok=True)
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    # a constrained layout already fits everything in; a second, "tight" pass only costs time
    tight = not isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)
    fig.savefig(path, dpi=dpi, bbox_inches="tight" if tight else None)
    plt.close(fig)
    return path


def plot_matching(
    moving,
    fixed,
    correspondence,
    *,
    moving_graph=None,
    fixed_graph=None,
    ax=None,
    title=None,
    max_lines: int = 60,
    max_edges: int | None = None,
    rowcol: bool = False,
):
    """Two 2D point sets side by side and their matching (thesis fig. 6.4).

    ``moving`` is drawn on the left and ``fixed`` shifted to its right. Matched points
    share a colour: ``moving[i]`` and ``fixed[correspondence[i]]`` get the colour of
    ``i``'s place along the moving set, so a correct matching shows the same colour
    sequence on both sides. At most ``max_lines`` matches (evenly spread over the
    moving set) are also joined by a line, so the figure stays readable for hundreds
    of points. The graphs, if given, are drawn faintly underneath, unless they have
    more than ``max_edges`` edges (an MWME graph has about n^2/4: a hairball that hides
    the matching); a note in the legend says when a graph was left out.

    Parameters
    ----------
    moving, fixed : array_like of shape (n, 2)
    correspondence : array_like of int, shape (n,)
        ``moving[i]`` matches ``fixed[correspondence[i]]``; -1 marks a moving point
        without partner (drawn grey, no line). Fixed points no moving point matches are
        drawn white.
    moving_graph, fixed_graph : sparse array of shape (n, n), optional
    ax : matplotlib Axes, optional
    title : str, optional
    max_lines : int, default=60
        Most match lines drawn (0 for none).
    max_edges : int, optional
        Most edges of a graph drawn; by default 3 n (a planar graph's size).
    rowcol : bool, default=False
        The sets are (row, col) pixel coordinates: drawn with row 0 at the top.

    Returns
    -------
    ax : matplotlib Axes

    Examples
    --------
    >>> x = np.random.default_rng(0).random((10, 2))
    >>> ax = plot_matching(x, x[::-1], np.arange(10)[::-1], max_lines=4)
    >>> len(ax.collections[0].get_segments())  # four of the ten matches drawn as lines
    4
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    moving = _plot_points(moving, name="moving", n_dims=(2,), rowcol=rowcol)
    fixed = _plot_points(fixed, name="fixed", n_dims=(2,), rowcol=rowcol)
    correspondence = np.asarray(correspondence)
    n = moving.shape[0]
    if correspondence.shape != (n,) or not np.issubdtype(correspondence.dtype, np.integer):
        raise InputError(
            f"`correspondence` must be an integer array of shape ({n},); got {correspondence.shape} "
            f"of dtype {correspondence.dtype}."
        )
    if correspondence.size and (correspondence.min() < -1 or correspondence.max() >= fixed.shape[0]):
        raise InputError(
            f"`correspondence` must index into `fixed` (0 .. {fixed.shape[0] - 1}) or be -1 (unmatched); "
            f"got values from {correspondence.min()} to {correspondence.max()}."
        )
    max_lines = check_int(max_lines, name="max_lines", low=0)
    max_edges = 3 * n if max_edges is None else check_int(max_edges, name="max_edges", low=0)
    graphs = {}
    for name, graph, size in (("moving_graph", moving_graph, n), ("fixed_graph", fixed_graph, fixed.shape[0])):
        if graph is None:
            continue
        graphs[name] = as_graph(graph, name=name)
        if graphs[name].shape != (size, size):
            points = name.split("_")[0]
            raise InputError(
                f"`{name}` must have shape ({size}, {size}), one node per point of `{points}`; "
                f"got shape {graphs[name].shape}."
            )
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 5), layout="constrained")
    else:
        _check_ax(ax, three_d=False, why="for a matching of 2D points")
    span = np.ptp(np.vstack([moving, fixed]), axis=0)
    right = fixed + np.array([moving[:, 0].max() - fixed[:, 0].min() + 0.3 * max(span[0], 1e-12), 0.0])
    colours = plt.get_cmap("hsv")(np.linspace(0, 0.9, n)) if n else np.empty((0, 4))
    matched = np.flatnonzero(correspondence >= 0)
    colours[correspondence < 0] = (0.6, 0.6, 0.6, 1.0)  # unmatched moving points in grey
    n_matched = len(matched)
    shown = (
        matched[np.unique(np.linspace(0, n_matched - 1, min(max_lines, n_matched)).round().astype(int))]
        if n_matched and max_lines > 0
        else []
    )
    ax.add_collection(
        LineCollection(
            np.stack([moving[shown], right[correspondence[shown]]], axis=1) if len(shown) else np.empty((0, 2, 2)),
            colors=colours[shown] if len(shown) else "0.5",
            linewidths=0.6,
            alpha=0.7,
            zorder=2,
        )
    )
    for pts, name in ((moving, "moving"), (right, "fixed")):
        if f"{name}_graph" not in graphs:
            continue
        coo = sparse.triu(graphs[f"{name}_graph"], k=1).tocoo()
        if coo.nnz > max_edges:
            ax.plot([], [], " ", label=f"{name} graph: {coo.nnz} edges, not drawn")
            continue
        ax.add_collection(
            LineCollection(np.stack([pts[coo.row], pts[coo.col]], axis=1), colors="0.8", linewidths=0.4, zorder=1)
        )
    fixed_colours = np.full((fixed.shape[0], 4), (1.0, 1.0, 1.0, 1.0))  # fixed points without partner in white
    fixed_colours[correspondence[matched]] = colours[matched]
    ax.scatter(moving[:, 0], moving[:, 1], s=14, c=colours, edgecolors="k", linewidths=0.3, zorder=3, label="moving")
    ax.scatter(
        right[:, 0],
        right[:, 1],
        s=14,
        c=fixed_colours,
        marker="s",
        edgecolors="k",
        linewidths=0.3,
        zorder=3,
        label="fixed (matched point in the same colour)",
    )
    ax.set_aspect("equal")
    ax.autoscale_view()
    if rowcol:
        _row_zero_on_top(ax)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=2, fontsize=8, frameon=False)
    if title:
        ax.set_title(title)
    return ax


def plot_registration(
    moving, fixed, *, ax=None, title=None, moving_label="moving", fixed_label="fixed", legend=True, rowcol=False
):
    """One panel of a registration: the moving set (blue circles) and the fixed set (red stars).

    Use it twice for a before/after pair. 2D panels have equal aspect; 3D panels (a 3D
    Axes, created when ``ax`` is None) have the same scale on every axis and small
    markers. The sets come in the order of every ``fit(moving, fixed)``.

    .. versionchanged:: 0.1.0
       The order was ``(fixed, moving)``; it is now ``(moving, fixed)``, as everywhere else.

    Parameters
    ----------
    moving : array_like of shape (M, D), D in {2, 3}
        E.g. the moving set before registration, or ``estimator.moving_transformed_``.
    fixed : array_like of shape (N, D)
    ax : matplotlib Axes, optional
    title : str, optional
    moving_label, fixed_label : str, default="moving", "fixed"
    legend : bool, default=True
    rowcol : bool, default=False
        2D (row, col) pixel coordinates: drawn with row 0 at the top.

    Returns
    -------
    ax : matplotlib Axes

    Examples
    --------
    >>> x = np.random.default_rng(0).random((20, 3))
    >>> ax = plot_registration(x + 0.1, x, title="before")
    >>> ax.name, len(ax.collections)
    ('3d', 2)
    """
    import matplotlib.pyplot as plt

    moving = _plot_points(moving, name="moving", n_dims=(2, 3), rowcol=rowcol)
    fixed = _plot_points(fixed, name="fixed", n_dims=(moving.shape[1],), rowcol=rowcol)
    three_d = fixed.shape[1] == 3
    if ax is None:
        fig = plt.figure(figsize=(4.5, 4.2), layout="constrained")
        ax = fig.add_subplot(projection="3d" if three_d else None)
    else:
        _check_ax(ax, three_d=three_d, why=f"for {fixed.shape[1]}D points")
    size = 5 if three_d else 14
    extra = {"depthshade": False} if three_d else {}
    if three_d:
        ax.computed_zorder = False  # the moving set stays above the fixed one, whatever the depth
    ax.scatter(*fixed.T, marker="*", s=size * 1.6, color="tab:red", label=fixed_label, zorder=1, **extra)
    ax.scatter(
        *moving.T,
        marker="o",
        s=size,
        facecolors="none",
        edgecolors="tab:blue",
        linewidths=0.7,
        label=moving_label,
        zorder=2,
        **extra,
    )
    if three_d:
        _equal_3d(ax, np.vstack([fixed, moving]))
    else:
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        if rowcol:
            _row_zero_on_top(ax)
    if legend:
        ax.legend(fontsize=7, loc="best")
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def plot_registration_snapshots(fixed, snapshots, *, iterations=None, fig=None, title=None, final=True):
    """A grid of registrations: one column per method, one row per iteration (thesis figs. 5.4, 5.5).

    Every method is shown at the same iterations (the rows), so the columns compare
    like with like; a method that stopped before an iteration shows its last state, with
    the iteration it is from in its title. With ``final`` a last row shows each method's
    final state. One legend (fixed: red stars, moving: blue circles) serves the grid.

    Parameters
    ----------
    fixed : array_like of shape (N, D), D in {2, 3}
        Drawn as red stars in every panel.
    snapshots : dict
        ``{method label: {iteration: moving points (M, D)}}``, e.g. from
        :class:`centrality_vision.registration.Snapshots`; drawn as blue circles.
    iterations : sequence of int, optional
        Rows to draw; by default the iterations recorded by every method (or, if they
        share none, by any method), without each method's final frame.
    fig : matplotlib Figure, optional
    title : str, optional
    final : bool, default=True
        Add a row with each method's last recorded state.

    Returns
    -------
    fig : matplotlib.figure.Figure

    Examples
    --------
    >>> x = np.random.default_rng(0).random((20, 2))
    >>> fig = plot_registration_snapshots(x, {"CPD": {0: x + 0.2, 1: x + 0.1, 2: x}, "GPD": {0: x + 0.2, 1: x}})
    >>> len(fig.axes)  # rows: iteration 0 (recorded by both) and the final states; two columns
    4
    """
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    if fig is not None and not isinstance(fig, Figure):  # (an AttributeError on add_subplot)
        raise TypeError(f"`fig` must be a matplotlib Figure or None; got {_describe(fig)}.")
    fixed = _plot_points(fixed, name="fixed", n_dims=(2, 3))
    dim = fixed.shape[1]
    if not isinstance(snapshots, dict) or not snapshots:
        raise TypeError(
            f"`snapshots` must be a non-empty dict {{label: {{iteration: points}}}}; got {_describe(snapshots)}."
        )
    frames = {}
    for label, record in snapshots.items():
        if not isinstance(record, dict) or not record:
            raise InputError(
                f"`snapshots[{label!r}]` must be a non-empty dict {{iteration: points}}; got {_describe(record)}."
            )
        frames[label] = {
            check_int(k, name=f"snapshots[{label!r}] key", low=0): _plot_points(
                v, name=f"snapshots[{label!r}][{k}]", n_dims=(dim,)
            )
            for k, v in record.items()
        }
    if iterations is None:
        inner = [set(record) - {max(record)} for record in frames.values()]
        rows = sorted(set.intersection(*inner)) or sorted(set.union(*inner))
    else:
        if isinstance(iterations, (str, bytes)) or not hasattr(iterations, "__iter__"):
            raise TypeError(f"`iterations` must be a sequence of ints; got {_describe(iterations)}.")
        rows = [check_int(i, name="iterations", low=0) for i in iterations]
    if not rows and not final:
        raise InputError("`iterations` must name at least one iteration.")
    cols = list(frames)
    n_rows = len(rows) + bool(final)
    if fig is None:
        span = np.ptp(fixed, axis=0)
        aspect = float(span[1] / span[0]) if dim == 2 and span[0] > 0 else 1.0
        fig = plt.figure(figsize=(2.6 * len(cols), 0.9 + 2.6 * min(max(aspect, 0.4), 1.5) * n_rows))
    kw = {"projection": "3d", "computed_zorder": False} if dim == 3 else {}
    extra = {"depthshade": False} if dim == 3 else {}
    size = 4 if dim == 3 else 10
    # every panel on the same limits, so that the panels compare like with like
    shown_sets = [fixed] + [record[k] for record in frames.values() for k in record]
    low, high = np.min([p.min(axis=0) for p in shown_sets], axis=0), np.max([p.max(axis=0) for p in shown_sets], axis=0)
    pad = 0.04 * np.maximum(high - low, 1e-12)
    low, high = low - pad, high + pad
    for r in range(n_rows):
        iteration = rows[r] if r < len(rows) else None
        for c, label in enumerate(cols):
            ax = fig.add_subplot(n_rows, len(cols), r * len(cols) + c + 1, **kw)
            record = frames[label]
            last = max(record)
            if iteration is None:
                shown = last
                heading = f"{label}: final ({last} it.)"
            else:
                shown = max((k for k in record if k <= iteration), default=min(record))
                heading = label if shown == iteration else f"{label}: stopped at {shown}"
                if r > 0 and shown == iteration:
                    heading = ""
            moving = record[shown]
            ax.scatter(*fixed.T, marker="*", s=size * 1.4, color="tab:red", zorder=1, **extra)
            ax.scatter(
                *moving.T,
                marker="o",
                s=size,
                facecolors="none",
                edgecolors="tab:blue",
                linewidths=0.6,
                zorder=2,
                **extra,
            )
            ax.set_xlim(low[0], high[0])
            ax.set_ylim(low[1], high[1])
            if dim == 2:
                ax.set_aspect("equal")
            else:
                ax.set_zlim(low[2], high[2])
                _equal_3d(ax, np.vstack([low, high]))
                ax.set_zticks([])
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(heading, fontsize=8)
            row_name = "final" if iteration is None else f"iteration {iteration}"
            if c == 0 and dim == 3:
                ax.text2D(-0.1, 0.5, row_name, transform=ax.transAxes, rotation=90, va="center", fontsize=8)
            elif c == 0:
                ax.set_ylabel(row_name, fontsize=8)
    handles = [
        Line2D([], [], marker="*", color="tab:red", ls="", label="fixed"),
        Line2D([], [], marker="o", mfc="none", mec="tab:blue", ls="", label="moving"),
    ]
    fig.legend(handles=handles, loc="upper right", ncol=2, fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, x=0.02, ha="left", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    return fig


_LINE_STYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)))
_MARKERS = ("o", "s", "^", "D", "v", "x")


def plot_alignment_errors(errors, *, ax=None, title=None, log=True, n_points=None, ylabel=None):
    """Alignment error per iteration for several methods on one plot (thesis figs. 5.3, 5.6, 5.8).

    Each method gets its own colour, line style and marker (placed every few
    iterations), so lines that coincide stay distinguishable; the error axis is
    logarithmic by default, where convergence rates are straight lines and the late
    iterations are not squashed onto zero (values <= 0 are left out of a log axis; errors
    that are all 0 are drawn on a linear one).

    Parameters
    ----------
    errors : dict
        ``{method label: sequence of errors}``, entry ``k`` after ``k`` iterations.
    ax : matplotlib Axes, optional
    title : str, optional
    log : bool, default=True
        Logarithmic error axis; its positive errors must lie within [1e-200, 1e200], where
        matplotlib can lay it out (``log=False`` draws any finite errors).
    n_points : int, optional
        If given, ``errors`` are Frobenius norms ``|X - T(Y)|`` over ``n_points``
        points (e.g. ``estimator.history_["error"]``) and are drawn as the per-point
        RMS error ``|X - T(Y)| / sqrt(n_points)``, which does not grow with the size
        of the set.
    ylabel : str, optional
        Label of the error axis (by default it says which error is drawn).

    Returns
    -------
    ax : matplotlib Axes

    Examples
    --------
    >>> ax = plot_alignment_errors({"CPD": [4.0, 2.0, 1.0], "GPD (closeness)": [4.0, 1.0, 0.5]}, n_points=4)
    >>> len(ax.lines), ax.get_yscale(), ax.lines[0].get_ydata().tolist()
    (2, 'log', [2.0, 1.0, 0.5])
    """
    import matplotlib.pyplot as plt

    if not isinstance(errors, dict) or not errors:
        raise TypeError(f"`errors` must be a non-empty dict {{label: errors per iteration}}; got {_describe(errors)}.")
    scale = 1.0
    if n_points is not None:
        n_points = check_int(n_points, name="n_points", low=1, high=2**53)
        scale = 1.0 / np.sqrt(n_points)
    log = check_bool(log, name="log")
    if ax is not None:
        _check_ax(ax, three_d=False, why="for error curves")
    # every series is checked before anything is drawn: a bad one left an open figure, or half
    # the curves on the caller's axes
    curves = []
    top, low = 0.0, np.inf
    for label, values in errors.items():
        if values is None:
            raise InputError(f"`errors[{label!r}]` is None: fit with `true_moving=` to record alignment errors.")
        if not hasattr(values, "__len__") or sparse.issparse(values):  # (a sparse array's len() raised)
            raise TypeError(f"`errors[{label!r}]` must be a sequence of errors per iteration; got {_describe(values)}.")
        v = _as_values(values, n=len(values), other=None, name=f"errors[{label!r}]") * scale
        if np.any(v < 0):
            raise InputError(f"`errors[{label!r}]` must be >= 0 (errors); got a minimum of {float(v.min()):.3g}.")
        positive = v[v > 0]
        if log and positive.size and (positive.min() < _LOG_RANGE[0] or positive.max() > _LOG_RANGE[1]):
            # (matplotlib's log axis overflowed, or its lower limit underflowed to 0)
            raise InputError(
                f"`errors[{label!r}]` must be 0 or within [{_LOG_RANGE[0]:g}, {_LOG_RANGE[1]:g}] on a log axis; got "
                f"[{float(positive.min())!r}, {float(positive.max())!r}] (rescale them, or pass log=False)."
            )
        top = max(top, float(v.max(initial=0.0)))
        low = min(low, float(positive.min(initial=np.inf)))
        curves.append((label, v))
    if ax is None:
        _, ax = plt.subplots(figsize=(5.5, 3.8), layout="constrained")
    for k, (label, v) in enumerate(curves):
        every = max(1, v.size // 8)
        ax.plot(
            np.arange(v.size),
            v,
            label=str(label),
            lw=1.4,
            color=f"C{k % 10}",
            ls=_LINE_STYLES[k % len(_LINE_STYLES)],
            marker=_MARKERS[k % len(_MARKERS)],
            ms=4,
            markevery=(k % every, every),
            alpha=0.9,
        )
    ax.set_xlabel("iteration")
    if ylabel is None:
        ylabel = "per-point RMS error" if n_points is not None else "alignment error"
    ax.set_ylabel(ylabel)
    if log and np.isfinite(low):  # (errors all 0, already aligned: a linear axis, to show them)
        ax.set_yscale("log", nonpositive="mask")
        if top > 0:  # rounding-level tails (1e-16) would squash the curves
            ax.set_ylim(bottom=max(low, top * 1e-10) / 2, top=top * 2)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    if title:
        ax.set_title(title, fontsize=10)
    return ax
