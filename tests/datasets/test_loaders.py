"""Tests of the bundled-data loaders in centrality_vision.datasets."""

import csv
from importlib import resources

import numpy as np
import pytest

from centrality_vision.datasets import Kimia99, PointSetPair, load_face, load_fish, load_kimia99
from centrality_vision.exceptions import InputError

CLASSES = ["airplane", "dude", "fish", "greeble", "hand", "quadruped", "rabbit", "ray", "tool"]


@pytest.fixture(scope="module")
def kimia():
    return load_kimia99()


# --------------------------------------------------------------------------- point sets


@pytest.mark.parametrize(("loader", "shape"), [(load_fish, (91, 2)), (load_face, (392, 3))])
def test_point_set_pair_shapes_and_dtypes(loader, shape):
    data = loader()
    assert isinstance(data, PointSetPair)
    moving, fixed = data  # unpacks as a tuple
    assert moving is data.moving and fixed is data.fixed
    for points in (moving, fixed):
        assert points.shape == shape
        assert points.dtype == np.float64
        assert np.all(np.isfinite(points))


@pytest.mark.parametrize("loader", [load_fish, load_face])
def test_moving_differs_from_fixed(loader):
    moving, fixed = loader()
    assert not np.allclose(moving, fixed)


def test_fish_rows_match_the_source_and_target_files():
    folder = resources.files("centrality_vision.datasets").joinpath("data", "cpd")
    moving, fixed = load_fish()
    first_source = [float(v) for v in folder.joinpath("fish_source.txt").read_text().split("\n")[0].split()]
    first_target = [float(v) for v in folder.joinpath("fish_target.txt").read_text().split("\n")[0].split()]
    np.testing.assert_array_equal(moving[0], first_source)
    np.testing.assert_array_equal(fixed[0], first_target)


@pytest.mark.parametrize("loader", [load_fish, load_face])
def test_point_loaders_return_independent_arrays(loader):
    first = loader()
    expected = first.moving.copy(), first.fixed.copy()
    first.moving[:] = 0.0
    first.fixed[...] += 1.0
    second = loader()
    assert second.moving is not first.moving and second.fixed is not first.fixed
    np.testing.assert_array_equal(second.moving, expected[0])
    np.testing.assert_array_equal(second.fixed, expected[1])


# --------------------------------------------------------------------------- Kimia-99


def test_kimia99_sizes_and_types(kimia):
    assert isinstance(kimia, Kimia99)
    assert len(kimia) == len(kimia.images) == 99
    assert kimia.labels.shape == kimia.names.shape == (99,)
    assert kimia.labels.dtype.kind == "U" and kimia.names.dtype.kind == "U"


def test_kimia99_has_nine_classes_of_eleven(kimia):
    classes, counts = np.unique(kimia.labels, return_counts=True)
    assert classes.tolist() == CLASSES
    assert counts.tolist() == [11] * 9


def test_kimia99_images_are_binary_with_shape_and_background(kimia):
    for name, mask in zip(kimia.names, kimia.images):
        assert mask.dtype == np.bool_, name
        assert mask.ndim == 2, name
        assert mask.any(), f"{name} has no foreground"
        assert not mask.all(), f"{name} has no background"
        # dark shape on a white page: the border is background
        assert mask.sum() < mask.size / 2, name
        assert not mask[0].all() and not mask[-1].all(), name


def test_kimia99_sorted_by_file_name_with_labels_from_csv(kimia):
    folder = resources.files("centrality_vision.datasets").joinpath("data", "kimia99")
    with folder.joinpath("labels.csv").open("r", newline="") as handle:
        rows = sorted(csv.DictReader(handle), key=lambda row: row["file"])
    assert kimia.names.tolist() == [row["file"].removesuffix(".png") for row in rows]
    assert kimia.labels.tolist() == [row["label"] for row in rows]


def test_kimia99_known_names(kimia):
    assert {"cow1", "dog1", "hand", "f16"} <= set(kimia.names.tolist())
    assert kimia.labels[kimia.names == "cow1"].tolist() == ["quadruped"]
    assert kimia.labels[kimia.names == "dog1"].tolist() == ["quadruped"]
    cow = kimia.image("cow1")
    assert cow is kimia.images[int(np.flatnonzero(kimia.names == "cow1")[0])]
    assert cow.shape == (106, 120)


def test_kimia99_threshold_keeps_antialiased_grey_pixels_dark_only():
    # fgen5cp.png has grey pixels (values 210-215, light): they must be background.
    from io import BytesIO

    from skimage.io import imread

    folder = resources.files("centrality_vision.datasets").joinpath("data", "kimia99")
    pixels = imread(BytesIO(folder.joinpath("fgen5cp.png").read_bytes()))
    assert len(np.unique(pixels)) > 2
    np.testing.assert_array_equal(load_kimia99().image("fgen5cp"), pixels < 128)


def test_kimia99_returns_independent_writable_images():
    first = load_kimia99()
    before = first.image("cow1").copy()
    assert first.image("cow1").flags.writeable
    first.image("cow1")[:] = True
    first.images[0][:] = False
    first.labels[0] = "changed"
    second = load_kimia99()
    np.testing.assert_array_equal(second.image("cow1"), before)
    assert second.images[0].any()
    assert second.labels[0] == "fish"
    assert second.images[0] is not first.images[0]


@pytest.mark.parametrize("name", ["cow", "Cow1", "cow1.png", "", 3])
def test_kimia99_unknown_name(kimia, name):
    with pytest.raises(InputError, match=r"`name` must be one of the 99 image names .*'bonefishes'.*got"):
        kimia.image(name)
    with pytest.raises(ValueError, match=repr(name).replace(".", r"\.")):
        kimia.image(name)


def test_kimia99_repr_is_short(kimia):
    text = repr(kimia)
    assert text.startswith("Kimia99(n_images=99")
    assert len(text) < 200


def test_kimia99_rejects_misaligned_fields():
    with pytest.raises(ValueError, match=r"same length; got 1, 2 and 1"):
        Kimia99(images=[np.ones((2, 2), bool)], labels=np.array(["a", "b"]), names=np.array(["x"]))
