"""Tests of the bundled-data loaders in centrality_vision.datasets."""

import csv
from importlib import resources

import numpy as np
import pytest

from centrality_vision.datasets import MPEG7, Kimia99, PointSetPair, load_face, load_fish, load_kimia99, load_mpeg7
from centrality_vision.exceptions import InputError

CLASSES = ["airplane", "dude", "fish", "greeble", "hand", "quadruped", "rabbit", "ray", "tool"]


@pytest.fixture(scope="module")
def kimia():
    return load_kimia99()


def _face():
    """The CPD face from the shared data folder; skip where it is not installed (it is GPL-2, not bundled)."""
    try:
        return load_face()
    except FileNotFoundError:
        pytest.skip("the CPD face is not bundled; set $CENTRALITY_VISION_DATA to a folder with cpd/face_*.txt")


# --------------------------------------------------------------------------- point sets


@pytest.mark.parametrize(("loader", "shape"), [(load_fish, (91, 2)), (_face, (392, 3))])
def test_point_set_pair_shapes_and_dtypes(loader, shape):
    data = loader()
    assert isinstance(data, PointSetPair)
    moving, fixed = data  # unpacks as a tuple
    assert moving is data.moving and fixed is data.fixed
    for points in (moving, fixed):
        assert points.shape == shape
        assert points.dtype == np.float64
        assert np.all(np.isfinite(points))


@pytest.mark.parametrize("loader", [load_fish, _face])
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


@pytest.mark.parametrize("loader", [load_fish, _face])
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


@pytest.mark.parametrize("name", ["cow", "Cow1", "cow1.png", ""])
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


# --------------------------------------------------------------------------- data kept out of the wheel


def test_no_gpl_face_inside_the_package():
    folder = resources.files("centrality_vision.datasets").joinpath("data", "cpd")
    assert sorted(entry.name for entry in folder.iterdir() if entry.name.endswith(".txt")) == [
        "fish_source.txt",
        "fish_target.txt",
    ]


def test_load_face_reads_a_given_folder(tmp_path):
    rng = np.random.default_rng(0)
    moving, fixed = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    (tmp_path / "cpd").mkdir()
    np.savetxt(tmp_path / "cpd" / "face_source.txt", moving)
    np.savetxt(tmp_path / "cpd" / "face_target.txt", fixed)
    for folder in (tmp_path, tmp_path / "cpd", str(tmp_path)):
        data = load_face(folder)
        np.testing.assert_allclose(data.moving, moving)
        np.testing.assert_allclose(data.fixed, fixed)


def test_load_face_missing_says_where_it_looked(tmp_path, monkeypatch):
    monkeypatch.setenv("CENTRALITY_VISION_DATA", str(tmp_path / "nothing"))
    with pytest.raises(FileNotFoundError, match="not bundled.*GPL-2.*Looked in"):
        load_face(tmp_path)
    with pytest.raises(TypeError, match="`path` must be a folder path"):
        load_face(3)


def test_load_face_rejects_wrong_columns(tmp_path):
    np.savetxt(tmp_path / "face_source.txt", np.zeros((4, 2)))
    np.savetxt(tmp_path / "face_target.txt", np.zeros((4, 2)))
    with pytest.raises(InputError, match="3 coordinates"):
        load_face(tmp_path)


def _write_gif(path, mask):
    from PIL import Image

    Image.fromarray(np.where(mask, 255, 0).astype(np.uint8)).convert("RGB").save(path)


def test_load_mpeg7_reads_gifs_by_class(tmp_path, monkeypatch):
    square = np.zeros((12, 14), bool)
    square[3:9, 4:10] = True
    bar = np.zeros((10, 10), bool)
    bar[4:6, 1:9] = True
    _write_gif(tmp_path / "apple-1.gif", square)
    _write_gif(tmp_path / "apple-02.gif", square)
    _write_gif(tmp_path / "sea_snake-1.gif", bar)
    data = load_mpeg7(tmp_path)
    assert isinstance(data, MPEG7) and len(data) == 3
    assert data.names.tolist() == ["apple-02", "apple-1", "sea_snake-1"]
    assert data.labels.tolist() == ["apple", "apple", "sea_snake"]
    np.testing.assert_array_equal(data.image("sea_snake-1"), bar)  # white on black: white is the shape
    assert load_mpeg7(tmp_path, classes=["sea_snake"]).names.tolist() == ["sea_snake-1"]
    monkeypatch.setenv("CENTRALITY_VISION_DATA", str(tmp_path))
    assert len(load_mpeg7()) == 3  # $CENTRALITY_VISION_DATA itself holds the GIFs
    with pytest.raises(InputError, match="unknown"):
        load_mpeg7(tmp_path, classes=["pear"])
    with pytest.raises(InputError, match="`classes` must name at least one class"):
        load_mpeg7(tmp_path, classes=[])  # was an empty data set
    _write_gif(tmp_path / "noclass.gif", bar)
    with pytest.raises(InputError, match="<class>-<number>"):
        load_mpeg7(tmp_path)
    with pytest.raises(FileNotFoundError, match="MPEG-7 is not bundled"):
        load_mpeg7(tmp_path / "absent")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("1 2 nan\n4 5 6\n", "NaN or inf, the first at line 1"),
        ("1 2 a\n4 5 6\n", "line 1, column 3: 'a' is not a number"),
    ],
)
def test_load_face_refuses_bad_values_with_the_path(tmp_path, content, message):
    (tmp_path / "face_source.txt").write_text(content)
    (tmp_path / "face_target.txt").write_text("1 2 3\n4 5 6\n")
    with pytest.raises(ValueError, match=message) as info:
        load_face(tmp_path)
    assert "face_source.txt" in str(info.value)


def test_bad_dataset_arguments_are_named():
    with pytest.raises(TypeError, match="`images` must be a sequence"):
        Kimia99(3, [1], [1])
    try:
        load_mpeg7()
    except FileNotFoundError:
        pytest.skip("MPEG-7 is not installed here")
    with pytest.raises(TypeError, match="`classes`"):
        load_mpeg7(classes=123)


def test_load_mpeg7_folder_oddities_found_by_fuzzing(tmp_path):
    square = np.zeros((12, 14), bool)
    square[3:9, 4:10] = True
    upper = tmp_path / "upper"
    upper.mkdir()
    _write_gif(upper / "apple-1.GIF", square)
    _write_gif(upper / "apple-2.GIF", square)
    # a folder of upper-case suffixes was "not found" (the folder search was case-sensitive)
    assert load_mpeg7(upper).names.tolist() == ["apple-1", "apple-2"]
    # a generator of classes was used up by the type check, then refused as empty
    assert len(load_mpeg7(upper, classes=(name for name in ["apple"]))) == 2
    (upper / "apple-3.gif").mkdir()  # a folder named like a GIF is not an image: skipped
    assert len(load_mpeg7(upper)) == 2
    for content in (b"", b"not a gif", (upper / "apple-1.GIF").read_bytes()[:40]):
        damaged = tmp_path / f"damaged{len(content)}"
        damaged.mkdir()
        _write_gif(damaged / "apple-1.gif", square)
        (damaged / "apple-2.gif").write_bytes(content)  # was imageio's OSError without the file's name
        with pytest.raises(InputError, match="apple-2.gif"):
            load_mpeg7(damaged)


def test_a_data_set_built_from_lists_finds_its_images_by_name():
    mask = np.eye(3, dtype=bool)
    data = Kimia99(images=[mask], labels=["a"], names=["x"])
    assert data.image("x") is mask  # a list of names was refused by image() as holding no "x"
    assert isinstance(data.names, np.ndarray) and data.labels.tolist() == ["a"]
    with pytest.raises(TypeError, match="`labels` must hold strings"):
        Kimia99(images=[mask], labels=[1], names=["x"])


def test_loaders_name_wrong_types_as_types():
    """load_mpeg7(classes=b"apple") showed its bytes as [97, 112, 112, 108, 101]; an index to
    Kimia99.image was an unknown name (ValueError) rather than a wrong type."""
    import pytest

    from centrality_vision.datasets import load_kimia99, load_mpeg7

    with pytest.raises(TypeError, match=r"`name` must be an image name \(str\), e.g. 'dog1'; got 5"):
        load_kimia99().image(5)
    try:
        load_mpeg7(classes=["apple"])
    except FileNotFoundError:
        pytest.skip("MPEG-7 is in ../shared/data (not shipped)")
    with pytest.raises(TypeError, match=r"got b'apple'"):
        load_mpeg7(classes=b"apple")
