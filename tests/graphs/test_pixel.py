import numpy as np
import pytest

from centrality_vision.graphs import pixel_coordinates, pixel_graph, salt_noise


def _degrees(graph):
    return np.diff(graph.indptr)


def test_block_3x3_degrees_8_connectivity():
    graph, nodes = pixel_graph(np.ones((3, 3), dtype=bool))
    np.testing.assert_array_equal(_degrees(graph).reshape(3, 3), [[3, 5, 3], [5, 8, 5], [3, 5, 3]])
    np.testing.assert_array_equal(nodes, np.arange(9))


def test_block_3x3_degrees_4_connectivity():
    graph, _ = pixel_graph(np.ones((3, 3), dtype=bool), connectivity=4)
    np.testing.assert_array_equal(_degrees(graph).reshape(3, 3), [[2, 3, 2], [3, 4, 3], [2, 3, 2]])


def test_edge_lengths_are_one_and_sqrt2():
    graph, _ = pixel_graph(np.ones((3, 3), dtype=bool))
    dense = graph.toarray()
    assert dense[0, 1] == 1.0 and dense[0, 3] == 1.0
    assert dense[0, 4] == pytest.approx(np.sqrt(2))
    assert set(np.round(graph.data, 12)) == {1.0, round(np.sqrt(2), 12)}
    np.testing.assert_array_equal(dense, dense.T)


def test_nodes_are_row_major_foreground_indices():
    image = np.array([[0, 1, 0], [1, 1, 0], [0, 0, 1]])
    graph, nodes = pixel_graph(image)
    np.testing.assert_array_equal(nodes, np.flatnonzero(image))
    # (0,1)-(1,0) diagonal, (0,1)-(1,1), (1,0)-(1,1), (1,1)-(2,2) diagonal: 4 edges
    assert graph.nnz == 8
    np.testing.assert_array_equal(pixel_coordinates(nodes, image.shape), np.argwhere(image))


def test_threshold_selects_bright_pixels():
    image = np.array([[0.0, 200.0], [50.0, 255.0]])
    graph, nodes = pixel_graph(image, threshold=128)
    np.testing.assert_array_equal(nodes, [1, 3])
    assert graph.nnz == 2


def test_input_not_modified():
    image = np.array([[True, False], [True, True]])
    before = image.copy()
    pixel_graph(image)
    salt_noise(image, 0.5, seed=0)
    np.testing.assert_array_equal(image, before)


@pytest.mark.parametrize(
    ("image", "kwargs", "match"),
    [
        (np.zeros((4, 4), dtype=bool), {}, "at least one foreground pixel"),
        (np.zeros((0, 5)), {}, "must not be empty"),
        (np.ones((2, 2, 2, 2)), {}, "must be a 2D or 3D array"),
        (np.full((2, 2, 2), 2.0), {}, "must be binary"),
        (np.array([[np.nan, 1.0]]), {}, "finite"),
        (np.ones((3, 3), bool), {"connectivity": 6}, "`connectivity` must be 8 or 4 for a 2D image"),
        (np.ones((3, 3, 3), bool), {"connectivity": 8}, "`connectivity` must be 26 or 18 or 6"),
        (np.ones((3, 3)), {"spacing": (1.0, 0.0)}, "`spacing` must be 2 positive"),
    ],
)
def test_bad_images(image, kwargs, match):
    with pytest.raises(ValueError, match=match):
        pixel_graph(image, **kwargs)


def test_non_numeric_image_is_type_error():
    with pytest.raises(TypeError, match="`image`"):
        pixel_graph(np.array([["a", "b"]]))


@pytest.mark.parametrize("rate", [0.0, 0.01, 0.05, 0.1, 0.5, 1.0])
def test_salt_noise_removes_exact_count(rate):
    rng = np.random.default_rng(3)
    image = rng.random((40, 50)) < 0.7
    noisy = salt_noise(image, rate, seed=1)
    n = int(image.sum())
    assert int(image.sum() - noisy.sum()) == int(round(rate * n))
    assert not np.any(noisy & ~image)  # only foreground pixels are removed


def test_salt_noise_is_seeded():
    image = np.ones((30, 30), dtype=bool)
    a = salt_noise(image, 0.1, seed=7)
    b = salt_noise(image, 0.1, seed=7)
    c = salt_noise(image, 0.1, seed=8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    gen = np.random.default_rng(7)
    np.testing.assert_array_equal(salt_noise(image, 0.1, seed=gen), a)


@pytest.mark.parametrize("rate", [-0.1, 1.5, float("nan")])
def test_salt_noise_bad_rate(rate):
    with pytest.raises(ValueError, match="`rate`"):
        salt_noise(np.ones((3, 3), bool), rate, seed=0)


def test_salt_noise_bad_seed():
    with pytest.raises(TypeError, match="`seed`"):
        salt_noise(np.ones((3, 3), bool), 0.1, seed="abc")


@pytest.mark.parametrize("connectivity", [6, 18, 26])
def test_3d_pixel_graph_with_spacing(connectivity):
    volume = np.ones((3, 4, 5), dtype=bool)
    volume[1, 1:3, 1:4] = False
    spacing = (2.5, 1.0, 0.5)
    graph, nodes = pixel_graph(volume, connectivity=connectivity, spacing=spacing)
    coords = pixel_coordinates(nodes, volume.shape) * np.array(spacing)
    rows, cols = graph.nonzero()
    offsets = np.abs(pixel_coordinates(nodes, volume.shape)[rows] - pixel_coordinates(nodes, volume.shape)[cols])
    assert offsets.max() == 1 and offsets.sum(axis=1).max() == {6: 1, 18: 2, 26: 3}[connectivity]
    # Every pair of foreground voxels within the neighbourhood is joined, by its length.
    np.testing.assert_allclose(graph.data, np.linalg.norm(coords[rows] - coords[cols], axis=1))
    grid = pixel_coordinates(nodes, volume.shape)
    steps = np.abs(grid[:, None, :] - grid[None, :, :])
    within = (steps.max(axis=2) == 1) & (steps.sum(axis=2) <= {6: 1, 18: 2, 26: 3}[connectivity])
    expected = int(within.sum())
    assert graph.nnz == expected


@pytest.mark.parametrize("spacing", [(1e300, 1e300), (1e-300, 1.0), (1.0, 1e-200), (3e-170, 4e-170)])
def test_extreme_spacing_gives_the_true_lengths(spacing):
    """skimage squares the spacing (overflow above 1e154, underflow below 1e-162); ours must not."""
    graph, nodes = pixel_graph(np.ones((3, 4), dtype=bool), spacing=spacing)
    reference, _ = pixel_graph(np.ones((3, 4), dtype=bool))  # same structure, unit spacing
    np.testing.assert_array_equal(graph.indices, reference.indices)
    coords = pixel_coordinates(nodes, (3, 4))
    rows = np.repeat(np.arange(graph.shape[0]), np.diff(graph.indptr))
    steps = np.abs(coords[rows] - coords[graph.indices]) * np.asarray(spacing)
    top = steps.max(axis=1)
    expected = top * np.hypot(*(steps / top[:, None]).T)
    np.testing.assert_allclose(graph.data, expected, rtol=1e-14)
    assert graph.data.min() > 0


@pytest.mark.parametrize("spacing", [(1.5e308, 1.5e308), (1.5e308, 1.5e308, 1e-200)], ids=["scaled", "stepwise"])
def test_spacing_whose_lengths_overflow_is_refused(spacing):
    """Diagonals above 1.8e308, on both paths (entries within 1e150 of each other, and not)."""
    with pytest.raises(ValueError, match="`spacing` must lie between"):
        pixel_graph(np.ones((2,) * len(spacing), dtype=bool), spacing=spacing)


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda: pixel_graph(np.ones((3, 3), dtype=bool), spacing="ab"), TypeError, "`spacing` must be 2 positive"),
        (lambda: pixel_coordinates(np.arange(3), None), TypeError, "`shape` must be"),
        (lambda: pixel_coordinates(np.arange(3), (2.5, 2)), TypeError, "`shape` must hold ints"),
    ],
)
def test_bad_spacing_and_shape_are_named(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_foreground_chooses_the_side_in_2d_and_3d():
    # API audit F5: pixel_graph and salt_noise could not choose the side of a grey image
    from centrality_vision.graphs import salt_noise

    image = np.full((8, 8), 200.0)
    image[2:6, 2:6] = 10.0  # a dark 4 x 4 square on a light image
    assert pixel_graph(image, threshold=100)[1].size == 16  # auto: the side off the border
    assert pixel_graph(image, threshold=100, foreground="dark")[1].size == 16
    assert pixel_graph(image, threshold=100, foreground="light")[1].size == 48
    volume = np.stack([image] * 3)
    assert pixel_graph(volume, threshold=100)[1].size == 3 * 48  # 3D auto: above the threshold
    assert pixel_graph(volume, threshold=100, foreground="dark")[1].size == 3 * 16
    assert pixel_graph(volume > 100, foreground="dark")[1].size == 3 * 16  # a mask's False side
    assert int(salt_noise(image, 0.25, seed=0, threshold=100, foreground="light").sum()) == 36
    with pytest.raises(ValueError, match="`foreground` must be one of 'auto', 'dark', 'light'; got 'white'"):
        pixel_graph(volume, threshold=100, foreground="white")


@pytest.mark.parametrize("connectivity", [8, 4])
def test_spacing_keeps_path_sums_within_float64(connectivity):
    """Spacings of 1e306 (40x40 pixels) gave closeness 0 and wrong betweenness from overflowed
    path sums, and subnormal spacings (1e-310) harmonic NaN and betweenness with the diagonal
    rounded to the axis step: such spacings are refused, and at the accepted extremes the
    weighted centralities are the unit-spacing ones, scaled."""
    from centrality_vision import centrality as cen

    mask = np.ones((12, 12), dtype=bool)
    mask[3:9, 6] = False
    n = int(mask.sum())
    biggest = np.finfo(np.float64).max
    for bad in (1e306, 1e-310, 5e-324):
        with pytest.raises(ValueError, match=r"`spacing` must lie between .* for an image of 138 foreground"):
            pixel_graph(mask, connectivity=connectivity, spacing=(bad, bad))
    unit, _ = pixel_graph(mask, connectivity=connectivity)
    high = 0.99 * biggest / (n * n * np.sqrt(2))
    low = 1.01 * max(np.finfo(np.float64).tiny, n / biggest)
    for step in (high, low):
        graph, _ = pixel_graph(mask, connectivity=connectivity, spacing=(step, step))
        np.testing.assert_allclose(
            cen.betweenness(graph, weights=True), cen.betweenness(unit, weights=True), rtol=1e-12
        )
        for name in ("closeness", "harmonic"):
            got = getattr(cen, name)(graph, weights=True) * step  # both go as 1 / length
            np.testing.assert_allclose(got, getattr(cen, name)(unit, weights=True), rtol=1e-12)


@pytest.mark.parametrize("shape", [(5,), (1, 2, 3, 4, 5)])
def test_an_image_of_other_dimension_is_named_as_2d_or_3d(shape):
    """A 1D or 4D image was told it "must be a 2D array", though 3D images are taken (audit 25)."""
    with pytest.raises(ValueError, match=r"`image` must be a 2D or 3D array; got shape"):
        pixel_graph(np.ones(shape, dtype=bool))


def test_a_pixel_or_voxel_at_the_threshold_is_background_in_2d_and_3d():
    """``threshold`` keeps what is above it, in a volume as in an image (a voxel equal to it
    was foreground in 3D only)."""
    image = np.zeros((3, 3))
    image[1, 1], image[1, 2] = 10.0, 5.0
    volume = np.zeros((3, 3, 3))
    volume[1, 1, 1], volume[1, 1, 2] = 10.0, 5.0
    for grid, kept in ((image, 4), (volume, 13)):
        graph, nodes = pixel_graph(grid, threshold=5)
        np.testing.assert_array_equal(nodes, [kept])
        assert graph.shape == (1, 1)
