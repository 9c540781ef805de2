"""Tests of centrality_vision.plotting, on graphs built with scipy directly."""

import subprocess
import sys

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import LineCollection, PathCollection
from scipy import sparse
from scipy.spatial import Delaunay

from centrality_vision.plotting import plot_centrality_image, plot_graph, save_figure


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def delaunay_graph(points):
    """Symmetric CSR adjacency of the Delaunay edges, data = Euclidean lengths."""
    tri = Delaunay(points)
    pairs = set()
    for simplex in tri.simplices:
        for a in range(len(simplex)):
            for b in range(a + 1, len(simplex)):
                i, j = sorted((int(simplex[a]), int(simplex[b])))
                pairs.add((i, j))
    rows, cols = np.array(sorted(pairs)).T
    lengths = np.linalg.norm(points[rows] - points[cols], axis=1)
    n = len(points)
    upper = sparse.coo_array((lengths, (rows, cols)), shape=(n, n))
    return (upper + upper.T).tocsr(), pairs


@pytest.fixture
def planar():
    rng = np.random.default_rng(0)
    points = rng.random((12, 2))
    graph, pairs = delaunay_graph(points)
    return points, graph, pairs


@pytest.fixture
def path3():
    """P3 as a hand-made csr_array: 0 - 1 - 2 with lengths 1 and 2."""
    points = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])
    graph = sparse.csr_array(np.array([[0, 1, 0], [1, 0, 2], [0, 2, 0]], dtype=float))
    return points, graph


# --------------------------------------------------------------------------- plot_graph


def test_plot_graph_draws_each_undirected_edge_once(planar):
    points, graph, pairs = planar
    ax = plot_graph(points, graph, np.arange(len(points), dtype=float))
    lines = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(lines) == 1
    segments = lines[0].get_segments()
    assert len(segments) == len(pairs) == graph.nnz // 2
    drawn = set()
    for seg in segments:
        i, j = (int(np.flatnonzero(np.all(points == p, axis=1))[0]) for p in seg)
        drawn.add(tuple(sorted((i, j))))
    assert drawn == pairs


def test_plot_graph_hand_made_path(path3):
    points, graph = path3
    ax = plot_graph(points, graph)
    segments = sorted(tuple(map(tuple, seg)) for seg in ax.collections[0].get_segments())
    assert segments == [((0.0, 0.0), (1.0, 0.0)), ((1.0, 0.0), (3.0, 0.0))]
    assert ax.get_aspect() == 1.0  # "equal"
    assert len(ax.figure.axes) == 1 and ax.child_axes == []  # no colorbar without values


def test_plot_graph_scatter_colours_map_values(planar):
    points, graph, _ = planar
    values = np.linspace(0.0, 1.0, len(points)) ** 2
    ax = plot_graph(points, graph, values, cmap="plasma", label="betweenness", title="Delaunay")
    ax.figure.canvas.draw()
    scatter = next(c for c in ax.collections if isinstance(c, PathCollection))
    np.testing.assert_array_equal(scatter.get_array(), values)
    np.testing.assert_array_equal(scatter.get_offsets(), points)
    assert scatter.cmap.name == "plasma"
    assert (scatter.norm.vmin, scatter.norm.vmax) == (values.min(), values.max())
    expected = plt.get_cmap("plasma")((values - values.min()) / (values.max() - values.min()))
    np.testing.assert_allclose(scatter.get_facecolors(), expected)
    # colorbar added, with its label; title set
    (colorbar,) = ax.child_axes  # an inset as tall as the drawn Axes
    assert colorbar.get_ylabel() == "betweenness"
    assert colorbar.get_position().height == pytest.approx(ax.get_position().height)
    assert ax.get_title() == "Delaunay"


def test_plot_graph_nodes_above_edges_and_styles(path3):
    points, graph = path3
    ax = plot_graph(points, graph, [1, 2, 1], node_size=12, edge_color="red", edge_width=2.5, colorbar=False)
    lines, nodes = ax.collections
    assert lines.get_zorder() < nodes.get_zorder()
    np.testing.assert_allclose(lines.get_linewidths(), [2.5])
    np.testing.assert_allclose(lines.get_colors(), [[1, 0, 0, 1]])
    np.testing.assert_allclose(nodes.get_sizes(), [12])
    assert len(ax.figure.axes) == 1 and ax.child_axes == []


def test_plot_graph_on_given_axes(path3):
    points, graph = path3
    fig, ax = plt.subplots()
    assert plot_graph(points, graph, ax=ax) is ax


def test_plot_graph_3d():
    rng = np.random.default_rng(1)
    points = rng.random((10, 3))
    graph, pairs = delaunay_graph(points)
    ax = plot_graph(points, graph, points[:, 2], label="height")
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    assert ax.name == "3d"
    lines = [c for c in ax.collections if isinstance(c, Line3DCollection)]
    assert len(lines) == 1
    assert len(lines[0]._segments3d) == len(pairs) == graph.nnz // 2
    ax.figure.canvas.draw()  # renders without error


def test_plot_graph_does_not_modify_inputs(planar):
    points, graph, _ = planar
    values = np.arange(len(points), dtype=float)
    before = points.copy(), graph.copy(), values.copy()
    plot_graph(points, graph, values)
    np.testing.assert_array_equal(points, before[0])
    assert (graph != before[1]).nnz == 0
    np.testing.assert_array_equal(values, before[2])


def test_plot_graph_graph_with_no_edges():
    ax = plot_graph([[0, 0], [1, 1]], sparse.csr_array((2, 2)))
    assert len(ax.collections[0].get_segments()) == 0


@pytest.mark.parametrize(
    ("points", "graph", "values", "match"),
    [
        (
            np.zeros((3, 4)),
            sparse.csr_array((3, 3)),
            None,
            r"`points` must have shape \(n_points, 2 or 3\); got shape \(3, 4\)",
        ),
        ([[0, 0], [np.nan, 1], [2, 2]], sparse.csr_array((3, 3)), None, r"`points` must be finite"),
        (
            np.zeros((3, 2)),
            sparse.csr_array((4, 4)),
            None,
            r"`graph` must have shape .* = \(3, 3\) .*got shape \(4, 4\)",
        ),
        (np.zeros((3, 2)), sparse.csr_array((3, 4)), None, r"`graph` must be a square adjacency .*got shape \(3, 4\)"),
        (np.zeros((3, 2)), sparse.csr_array((3, 3)), [1.0, 2.0], r"`values` must have shape \(3,\).*got shape \(2,\)"),
        (
            np.zeros((3, 2)),
            sparse.csr_array((3, 3)),
            [[1.0, 2.0, 3.0]],
            r"`values` must have shape \(3,\).*got shape \(1, 3\)",
        ),
        (np.zeros((3, 2)), sparse.csr_array((3, 3)), [1.0, np.inf, 3.0], r"`values` must be finite; got 1"),
    ],
)
def test_plot_graph_bad_inputs(points, graph, values, match):
    with pytest.raises(ValueError, match=match):
        plot_graph(points, graph, values)


def test_plot_graph_bad_options(path3):
    points, graph = path3
    with pytest.raises(ValueError, match=r"`node_size` must be .*got -1\.0"):
        plot_graph(points, graph, node_size=-1)
    with pytest.raises(ValueError, match=r"`edge_width` must be .*got nan"):
        plot_graph(points, graph, edge_width=float("nan"))
    fig = plt.figure()
    ax3d = fig.add_subplot(projection="3d")
    with pytest.raises(ValueError, match=r"`ax` must be a 2D Axes for points of shape \(n_points, 2\); got a 3D Axes"):
        plot_graph(points, graph, ax=ax3d)
    _, ax2d = plt.subplots()
    with pytest.raises(ValueError, match=r"`ax` must be a 3D Axes"):
        plot_graph(np.c_[points, np.zeros(3)], graph, ax=ax2d)
    with pytest.raises(TypeError, match=r"`ax` must be a matplotlib Axes"):
        plot_graph(points, graph, ax="axes")


# --------------------------------------------------------------------------- plot_centrality_image


def test_centrality_image_masks_background_and_places_values():
    mask = np.array(
        [
            [0, 1, 1, 0],
            [0, 1, 0, 0],
            [1, 1, 1, 0],
        ],
        dtype=bool,
    )
    nodes = np.flatnonzero(mask)  # row-major, as pixel_graph returns
    values = np.arange(1.0, nodes.size + 1)
    ax = plot_centrality_image(values, nodes, mask.shape, label="closeness", title="shape")
    shown = ax.images[0].get_array()
    assert isinstance(shown, np.ma.MaskedArray)
    assert shown.shape == mask.shape
    np.testing.assert_array_equal(np.ma.getmaskarray(shown), ~mask)
    np.testing.assert_array_equal(shown[mask], values)
    assert shown[0, 2] == values[1] and shown[2, 0] == values[3]
    assert ax.child_axes[0].get_ylabel() == "closeness"
    assert ax.get_title() == "shape"
    norm = ax.images[0].norm
    assert (norm.vmin, norm.vmax) == (1.0, float(nodes.size))


def test_centrality_image_finite_background_is_shown():
    ax = plot_centrality_image([3.0, 4.0], [0, 3], (2, 2), background=0.0, colorbar=False)
    shown = ax.images[0].get_array()
    assert not np.ma.getmaskarray(shown).any()
    np.testing.assert_array_equal(shown, [[3.0, 0.0], [0.0, 4.0]])
    assert len(ax.figure.axes) == 1 and ax.child_axes == []


def test_centrality_image_on_given_axes_and_inputs_unchanged():
    values = np.array([1.0, 2.0])
    nodes = np.array([2, 1])
    fig, ax = plt.subplots()
    assert plot_centrality_image(values, nodes, (1, 3), ax=ax) is ax
    np.testing.assert_array_equal(values, [1.0, 2.0])
    np.testing.assert_array_equal(nodes, [2, 1])
    shown = ax.images[0].get_array()
    np.testing.assert_array_equal(shown.filled(-1), [[-1, 2.0, 1.0]])


@pytest.mark.parametrize(
    ("values", "nodes", "shape", "match"),
    [
        (
            [1.0, 2.0],
            [0, 1, 2],
            (2, 2),
            r"`values` must have shape \(3,\), one value per row of `nodes`; got shape \(2,\)",
        ),
        ([1.0, 2.0], [0, 4], (2, 2), r"`nodes` must be flat pixel indices in \[0, 3\] .*got 1 out of range, e.g. 4"),
        ([1.0, 2.0], [-1, 0], (2, 2), r"`nodes` must be flat pixel indices in \[0, 3\] .*e.g. -1"),
        ([1.0, 2.0], [1, 1], (2, 2), r"`nodes` must not repeat a pixel; got 1"),
        ([1.0], [[0]], (2, 2), r"`nodes` must be a 1D array .*got shape \(1, 1\)"),
        ([], [], (2, 2), r"`nodes` must hold at least one"),
        ([1.0], [0], (4,), r"`shape` must be a tuple of two positive ints .*got \(4,\)"),
        ([1.0], [0], (2, 2, 2), r"`shape` must be a tuple of two positive ints .*got \(2, 2, 2\)"),
        ([1.0], [0], (0, 2), r"`shape` must be a tuple of two positive ints"),
        ([1.0], [0], (2.0, 2), r"`shape` must be a tuple of two positive ints"),
        ([np.nan], [0], (2, 2), r"`values` must be finite"),
    ],
)
def test_centrality_image_bad_inputs(values, nodes, shape, match):
    with pytest.raises(ValueError, match=match):
        plot_centrality_image(values, nodes, shape)


def test_centrality_image_bad_types():
    with pytest.raises(TypeError, match=r"`nodes` must hold integer"):
        plot_centrality_image([1.0], [0.5], (2, 2))
    with pytest.raises(TypeError, match=r"`background` must be a real number"):
        plot_centrality_image([1.0], [0], (2, 2), background="white")
    fig = plt.figure()
    with pytest.raises(ValueError, match=r"`ax` must be a 2D Axes for an image; got a 3D Axes"):
        plot_centrality_image([1.0], [0], (2, 2), ax=fig.add_subplot(projection="3d"))


# --------------------------------------------------------------------------- save_figure


def test_save_figure_writes_png_and_closes(tmp_path, path3):
    points, graph = path3
    ax = plot_graph(points, graph, [1, 2, 1])
    fig = ax.figure
    out = save_figure(fig, tmp_path / "new" / "nested" / "graph.png", dpi=40)
    assert out == tmp_path / "new" / "nested" / "graph.png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not plt.fignum_exists(fig.number)


def test_save_figure_accepts_str_path(tmp_path):
    ax = plot_centrality_image([1.0, 2.0], [0, 3], (2, 2))
    out = save_figure(ax.figure, str(tmp_path / "image.png"))
    assert out.is_file()


def test_save_figure_bad_inputs(tmp_path):
    _, ax = plt.subplots()
    with pytest.raises(TypeError, match=r"`fig` must be a matplotlib Figure"):
        save_figure(ax, tmp_path / "x.png")
    with pytest.raises(ValueError, match=r"`dpi` must be a finite number in \(0, 10000\]; got 0\.0"):
        save_figure(ax.figure, tmp_path / "x.png", dpi=0)
    with pytest.raises(ValueError, match=r"`dpi` must be a finite number in \(0, 10000\]"):
        save_figure(ax.figure, tmp_path / "x.png", dpi=1e5)  # (was a MemoryError from the renderer)
    with pytest.raises(TypeError, match=r"`path` must be a str or os.PathLike"):
        save_figure(ax.figure, 3)
    # matplotlib would append '.png' to these, writing a file the returned path does not name
    with pytest.raises(ValueError, match=r"`path` must be a file, not a folder"):
        save_figure(ax.figure, tmp_path)
    with pytest.raises(ValueError, match=r"`path` must end in a format suffix"):
        save_figure(ax.figure, tmp_path / "out")
    with pytest.raises(ValueError, match=r"`path` must end in a format suffix"):
        save_figure(ax.figure, tmp_path / "out.xyz")
    assert not list(tmp_path.iterdir()) and not (tmp_path.parent / f"{tmp_path.name}.png").exists()


def test_plotting_numbers_are_checked_by_name():
    from centrality_vision.plotting import plot_alignment_errors, plot_matching, plot_registration_snapshots

    x = np.random.default_rng(0).random((5, 2))
    with pytest.raises(ValueError, match="`node_size`"):
        plot_graph(x, sparse.csr_array((5, 5)), node_size=1e40)  # (drawing it stalled the renderer)
    with pytest.raises(TypeError, match="`max_lines`"):
        plot_matching(x, x, np.arange(5), max_lines=np.nan)
    with pytest.raises(TypeError, match=r"`snapshots\['A'\] key`"):
        plot_registration_snapshots(x, {"A": {"x": x}})
    with pytest.raises(TypeError, match="`iterations`"):
        plot_registration_snapshots(x, {"A": {0: x, 1: x}}, iterations=["a"])
    with pytest.raises(TypeError, match=r"`errors\['a'\]`"):
        plot_alignment_errors({"a": 3.0})
    with pytest.raises(ValueError, match=r"`errors\['a'\]` must have shape \(2,\), one value per iteration; got"):
        plot_alignment_errors({"a": [[1.0, 2.0], [3.0, 4.0]]})  # (it said "one value per row of errors['a']")
    with pytest.raises(ValueError, match=r"`errors\['a'\]` must be >= 0"):
        plot_alignment_errors({"a": [-1.0, -2.0]})
    with pytest.raises(ValueError, match="`n_points`"):
        plot_alignment_errors({"a": [1.0]}, n_points=10**400)
    with pytest.raises(ValueError, match="`shape` must have at most"):
        plot_centrality_image([1.0], [0], (100_000, 100_000))  # (a MemoryError of 80 GB)


# --------------------------------------------------------------------------- lazy import


def test_importing_plotting_does_not_import_matplotlib():
    code = (
        "import sys\n"
        "import centrality_vision, centrality_vision.plotting, centrality_vision.datasets\n"
        "bad = sorted(m for m in sys.modules if m == 'matplotlib' or m.startswith('matplotlib.'))\n"
        "assert not bad, bad\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr


def test_registration_snapshots_fixed_rows_final_row_and_legend():
    from centrality_vision.plotting import plot_registration_snapshots

    x = np.random.default_rng(0).random((15, 2))
    fig = plot_registration_snapshots(x, {"A": {0: x, 3: x + 0.1}, "B": {0: x}}, iterations=[0, 3])
    assert len(fig.axes) == 6  # rows 0, 3 and final; columns A, B
    # B stopped at iteration 0: its row-3 panel shows that frame and says so
    assert fig.axes[3].get_title() == "B: stopped at 0"
    assert [ax.get_ylabel() for ax in fig.axes[::2]] == ["iteration 0", "iteration 3", "final"]
    assert fig.axes[4].get_title() == "A: final (3 it.)"
    np.testing.assert_array_equal(fig.axes[4].collections[1].get_offsets(), x + 0.1)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["fixed", "moving"]
    # by default, rows are the iterations every method recorded, not each one's last
    fig2 = plot_registration_snapshots(x, {"A": {0: x, 2: x, 7: x}, "B": {0: x, 2: x, 4: x}}, final=False)
    assert [ax.get_ylabel() for ax in fig2.axes[::2]] == ["iteration 0", "iteration 2"]


def test_registration_panels_3d_equal_aspect_small_markers():
    from centrality_vision.plotting import plot_registration, plot_registration_snapshots

    cloud = np.random.default_rng(1).random((10, 3)) * [10, 1, 1]
    ax = plot_registration(cloud, cloud + 0.5)
    span = np.ptp(np.vstack([cloud, cloud + 0.5]), axis=0)
    box = np.asarray(ax.get_box_aspect())
    assert ax.name == "3d" and np.allclose(box / box.max(), span / span.max())
    assert box[0] > 3 * box[1]  # the long axis is drawn long
    assert max(ax.collections[0].get_sizes()) < 10
    fig3 = plot_registration_snapshots(cloud, {"A": {1: np.zeros((4, 3))}})
    assert fig3.axes[0].name == "3d"
    with pytest.raises(ValueError, match="3D Axes"):
        plot_registration(cloud, cloud, ax=plt.figure().add_subplot())


def test_alignment_errors_log_axis_distinct_styles_and_per_point_rms():
    from centrality_vision.plotting import plot_alignment_errors

    ax = plot_alignment_errors({"A": [3.0, 1.0], "B": [3.0, 2.0, 0.5], "C": [3.0, 2.0, 0.0]}, n_points=9)
    assert [line.get_xdata().tolist() for line in ax.lines] == [[0, 1], [0, 1, 2], [0, 1, 2]]
    assert ax.lines[1].get_ydata().tolist() == [1.0, 2.0 / 3.0, 0.5 / 3.0]  # |.| / sqrt(9)
    assert ax.get_yscale() == "log" and ax.get_ylabel() == "per-point RMS error"
    styles = {(line.get_linestyle(), line.get_marker()) for line in ax.lines}
    assert len(styles) == 3  # no two methods drawn alike
    assert plot_alignment_errors({"A": [1.0, 2.0]}, log=False).get_yscale() == "linear"
    with pytest.raises(TypeError, match="errors"):
        plot_alignment_errors([1.0, 2.0])
    with pytest.raises(ValueError, match="true_moving"):
        plot_alignment_errors({"A": None})


def test_snapshots_bad_inputs():
    from centrality_vision.plotting import plot_registration_snapshots

    x = np.random.default_rng(0).random((15, 2))
    with pytest.raises(TypeError, match="snapshots"):
        plot_registration_snapshots(x, {})
    with pytest.raises(ValueError, match="snapshots"):
        plot_registration_snapshots(x, {"A": {0: np.zeros((3, 3))}})


@pytest.mark.parametrize("norm", ["log", "power"])
def test_centrality_norms_spread_skewed_values(norm):
    values = np.array([0.0, 1.0, 10.0, 100.0, 1000.0])
    ax = plot_centrality_image(values, np.arange(5), (1, 5), norm=norm)
    shown = ax.images[0].norm(values[2:4])
    linear = values[2:4] / 1000.0
    assert np.all(np.asarray(shown) > 3 * linear)  # the middle values get visibly lighter colours
    ax2 = plot_graph(np.random.default_rng(0).random((5, 2)), sparse.csr_array((5, 5)), values, norm=norm)
    assert type(ax2.collections[1].norm).__name__ == ("LogNorm" if norm == "log" else "PowerNorm")


def test_norm_bad_values():
    with pytest.raises(ValueError, match="`norm` must be one of"):
        plot_centrality_image([1.0, 2.0], [0, 1], (1, 2), norm="sqrt")
    with pytest.raises(ValueError, match="at least one value > 0"):
        plot_centrality_image([0.0, 0.0], [0, 1], (1, 2), norm="log")


def test_matching_shows_matches_not_a_hairball():
    from centrality_vision.plotting import plot_matching

    rng = np.random.default_rng(0)
    x = rng.random((120, 2))
    perm = rng.permutation(120)
    dense = sparse.csr_array(np.ones((120, 120)) - np.eye(120))  # 7140 edges
    ax = plot_matching(x[perm], x, perm, moving_graph=dense, fixed_graph=dense)
    lines = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(lines) == 1 and len(lines[0].get_segments()) == 60  # the sampled matches only
    assert any("not drawn" in t.get_text() for t in ax.get_legend().get_texts())
    moving_dots, fixed_dots = [c for c in ax.collections if isinstance(c, PathCollection)]
    # matched points share a colour
    np.testing.assert_allclose(moving_dots.get_facecolors(), fixed_dots.get_facecolors()[perm])
    with pytest.raises(ValueError, match="correspondence"):
        plot_matching(x, x, np.arange(5))


def test_rowcol_points_are_drawn_the_way_the_image_looks():
    from centrality_vision.plotting import plot_matching, plot_registration

    # an L of pixels: rows 0-2 in column 0, then row 2 to the right
    rowcol = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    graph = sparse.csr_array((5, 5))
    ax = plot_graph(rowcol, graph, rowcol=True)
    np.testing.assert_array_equal(ax.collections[1].get_offsets(), rowcol[:, ::-1])  # x = column, y = row
    assert ax.yaxis_inverted()  # row 0 at the top
    assert plot_registration(rowcol, rowcol, rowcol=True).yaxis_inverted()
    assert plot_matching(rowcol, rowcol, np.arange(5), rowcol=True).yaxis_inverted()
    assert not plot_graph(rowcol, graph).yaxis_inverted()
    with pytest.raises(ValueError, match="rowcol=True"):
        plot_graph(np.zeros((3, 3)) + np.arange(3)[:, None], sparse.csr_array((3, 3)), rowcol=True)


def test_coordinates_beyond_what_matplotlib_can_lay_out_are_named():
    """Near 1.8e308 matplotlib's limits and ticks overflow (warnings, or errors at draw time)."""
    from centrality_vision.plotting import plot_registration, plot_registration_snapshots

    x = np.random.default_rng(0).random((5, 2))
    with pytest.raises(ValueError, match=r"`points` must lie within \+-1e\+307"):
        plot_graph(x * 1.7e308, sparse.csr_array((5, 5)))
    with pytest.raises(ValueError, match=r"`moving` must lie within"):
        plot_registration(x * 1.7e308, x)
    with pytest.raises(ValueError, match=r"`snapshots\['A'\]\[0\]` must lie within"):
        plot_registration_snapshots(x, {"A": {0: x * 1.7e308, 1: x}})
    plot_graph(x * 1e306, sparse.csr_array((5, 5)))  # large but drawable


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int64])
def test_centrality_image_takes_pixel_indices_of_any_integer_type(dtype):
    from centrality_vision.plotting import plot_centrality_image

    # uint8 indices wrapped around in the crop arithmetic: a mirrored view of empty space
    ax = plot_centrality_image([1.0, 2.0], np.array([1, 2], dtype=dtype), (4, 4))
    assert ax.get_xlim() == (-0.5, 3.5) and ax.get_ylim() == (3.5, -0.5)
    plt.close(ax.figure)
    wide = plot_centrality_image([1.0, 2.0], np.array([100, 120], dtype=dtype), (1, 300))  # int8 overflowed
    assert wide.get_xlim() == (96.5, 123.5)
    plt.close(wide.figure)


def test_plot_matching_checks_its_graphs_and_axes():
    from centrality_vision.exceptions import InputError
    from centrality_vision.plotting import plot_matching

    points = np.random.default_rng(3).random((7, 2))
    match = np.arange(7)
    cases = [
        ({"moving_graph": np.ones((5, 5))}, InputError, r"`moving_graph` must have shape \(7, 7\)"),  # drawn anyway
        ({"fixed_graph": np.ones((9, 9))}, InputError, r"`fixed_graph` must have shape \(7, 7\)"),  # an IndexError
        ({"fixed_graph": "g"}, TypeError, "`fixed_graph`"),
        ({"ax": "x"}, TypeError, "`ax` must be a matplotlib Axes"),
    ]
    for kwargs, error, message in cases:
        with pytest.raises(error, match=message):
            plot_matching(points, points, match, **kwargs)
    fig = plt.figure()
    with pytest.raises(InputError, match="`ax` must be a 2D Axes"):
        plot_matching(points, points, match, ax=fig.add_subplot(projection="3d"))
    plt.close(fig)


def test_values_too_large_to_scale_and_bad_error_curves_are_named():
    from centrality_vision.exceptions import InputError
    from centrality_vision.plotting import plot_alignment_errors, plot_centrality_image, plot_graph

    points = np.random.default_rng(0).random((6, 2))
    graph = sparse.csr_array(np.ones((6, 6)) - np.eye(6))
    cases = [  # matplotlib's "Axis limits cannot be NaN or Inf", naming nothing
        (lambda: plot_graph(points, graph, [-1.7e308, 1.7e308, 0, 0, 0, 0]), "`values` must lie within"),
        (lambda: plot_centrality_image([-1.7e308, 1.7e308], [0, 1], (1, 2)), "`values` must lie within"),
        (lambda: plot_alignment_errors({"A": [1e308, 1.7e308]}), r"`errors\['A'\]` must lie within"),
        (lambda: plot_alignment_errors({"A": [1.0, np.nan]}), r"`errors\['A'\]` must be finite"),  # named `values`
    ]
    for call, message in cases:
        with pytest.raises(InputError, match=message):
            call()
    plt.close("all")


def test_save_figure_expands_the_home_folder(tmp_path, monkeypatch):
    from centrality_vision.plotting import save_figure

    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    fig = plt.figure()
    written = save_figure(fig, "~/figs/a.png", dpi=20)
    assert written == tmp_path / "home" / "figs" / "a.png" and written.is_file()
    assert not (tmp_path / "~").exists()  # a folder literally named "~" was made


def test_inputs_found_by_fuzzing_are_drawn_without_warnings_or_named(tmp_path):
    import io
    import warnings

    from centrality_vision.exceptions import InputError
    from centrality_vision.plotting import plot_alignment_errors, plot_registration_snapshots

    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    graph = sparse.csr_array([[0, 1, 1], [1, 0, 0], [1, 0, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib's overflow warnings, at the limits drawn
        for ax in (
            plot_graph(points, graph, [1e-200, 1e200, 0], norm="log"),
            plot_alignment_errors({"a": [1e200, 1e-200, 0.0]}),
            plot_centrality_image([1.0, 2.0], [0, 1], (2, 2), background=1e307),
        ):
            ax.figure.savefig(io.BytesIO(), format="png")
    cases = [
        # overflow in matplotlib's ticks, or its "Invalid vmin or vmax"
        (lambda: plot_graph(points, graph, [1e-300, 1e300, 0], norm="log"), InputError, r"'log' draws positive"),
        (lambda: plot_graph(points, graph, [5e-324, 1e-323, 0], norm="log"), InputError, r"'log' draws positive"),
        (lambda: plot_alignment_errors({"a": [1e307, 1.0]}), InputError, r"must be 0 or within .* on a log axis"),
        (lambda: plot_alignment_errors({"a": [1e-320, 5e-324]}), InputError, r"on a log axis"),  # a ylim of 0
        (lambda: plot_centrality_image([1.0], [0], (1, 2), background=1e308), InputError, "`background` must be NaN"),
        (lambda: plot_alignment_errors({"a": sparse.csr_array(np.ones((1, 3)))}), TypeError, r"`errors\['a'\]`"),
        (lambda: plot_alignment_errors({"a": [[1.0], [2.0, 3.0]]}), InputError, r"`errors\['a'\]` must be an array"),
        (lambda: plot_registration_snapshots(points, {"CPD": {0: points}}, fig="x"), TypeError, "`fig` must be"),
    ]
    for call, error, message in cases:
        with pytest.raises(error, match=message):
            call()
    plot_alignment_errors({"a": [1e307, 1.0]}, log=False)  # a linear axis draws them
    blocker = tmp_path / "afile"
    blocker.write_text("")
    with pytest.raises(InputError, match="is a file"):  # mkdir's FileExistsError
        save_figure(plt.figure(), blocker / "sub" / "fig.png")


def test_styles_and_switches_are_checked_by_name(path3):
    # found by a fuzz run: matplotlib's messages without the parameter, and any truthy
    # value taken for True (colorbar="no" drew a colorbar)
    points, graph = path3
    with pytest.raises(ValueError, match=r"`cmap` must name a matplotlib colormap .*got 'viridiss'"):
        plot_graph(points, graph, values=[1, 2, 3], cmap="viridiss")
    with pytest.raises(TypeError, match=r"`cmap` must be a colormap name"):
        plot_graph(points, graph, values=[1, 2, 3], cmap=3)
    with pytest.raises(ValueError, match=r"`edge_color` must be a matplotlib colour .*got 'grayish'"):
        plot_graph(points, graph, edge_color="grayish")
    with pytest.raises(TypeError, match=r"`colorbar` must be True or False; got"):
        plot_graph(points, graph, values=[1, 2, 3], colorbar="no")
    with pytest.raises(TypeError, match=r"`rowcol` must be True or False"):
        plot_graph(points, graph, rowcol=1)
    with pytest.raises(TypeError, match=r"`crop` must be True or False"):
        plot_centrality_image([1.0], [0], (2, 2), crop="yes")
    plt.close("all")


def test_float32_background_and_all_zero_errors_draw_without_warnings():
    import warnings

    from centrality_vision.plotting import plot_alignment_errors

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ax = plot_centrality_image(np.float32([1.0]), [0], (2, 2), background=np.float32(0))
        assert ax.images[0].get_array()[0, 1] == 0.0
        ax = plot_alignment_errors({"CPD": [0.0, 0.0, 0.0]})  # already aligned
        ax.figure.canvas.draw()
        assert ax.get_yscale() == "linear"
    plt.close("all")


def test_plot_registration_takes_moving_then_fixed_like_every_fit():
    # audit: it took (fixed, moving), the one function in the package that did, so
    # plot_registration(*load_fish()) swapped the two sets' labels and markers without a word
    from centrality_vision.plotting import plot_registration

    rng = np.random.default_rng(2)
    moving, fixed = rng.random((7, 2)), rng.random((9, 2)) + 3.0
    ax = plot_registration(moving, fixed)
    by_label = {c.get_label(): np.asarray(c.get_offsets()) for c in ax.collections}
    np.testing.assert_array_equal(by_label["moving"], moving)
    np.testing.assert_array_equal(by_label["fixed"], fixed)


def test_a_refused_plot_leaves_no_figure_and_draws_nothing_on_the_callers_axes():
    """The figure was made before the norm or the series were checked: each refused call left
    one open, and with ``ax`` given the series before the bad one were already drawn."""
    import matplotlib.pyplot as plt

    from centrality_vision.plotting import plot_alignment_errors, plot_centrality_image

    before = set(plt.get_fignums())
    mask = np.zeros((5, 5), dtype=bool)
    mask[1:4, 1:4] = True
    nodes = np.flatnonzero(mask)
    for call in (
        lambda: plot_centrality_image(np.ones(nodes.size), nodes, mask.shape, norm="bogus"),
        lambda: plot_centrality_image(np.zeros(nodes.size), nodes, mask.shape, norm="log"),
        lambda: plot_alignment_errors({"a": [1.0, 0.5], "b": None}),
        lambda: plot_alignment_errors({"a": [-1.0]}),
    ):
        with pytest.raises(ValueError):
            call()
    assert set(plt.get_fignums()) == before
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match=r"`errors\['b'\]` must be >= 0"):
        plot_alignment_errors({"a": [1.0, 0.5], "b": [-2.0]}, ax=ax)
    assert len(ax.lines) == 0
    with pytest.raises(TypeError, match="`log` must be True or False"):
        plot_alignment_errors({"a": [1.0, 0.1]}, log="no", ax=ax)
    plt.close(fig)
