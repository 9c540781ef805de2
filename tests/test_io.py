import json

import numpy as np
import pytest

from centrality_vision._io import read_image, read_points, sidecar_path, to_jsonable, write_json, write_npz, write_table
from centrality_vision.exceptions import InputError


def _write_png(path, pixels):
    from skimage.io import imsave

    imsave(path, np.asarray(pixels, dtype=np.uint8), check_contrast=False)
    return path


@pytest.mark.parametrize(
    "text",
    [
        "0 0\n1 0.5\n2 1\n",
        "0,0\n1,0.5\n2,1\n",
        "x,y\n0,0\n1, 0.5\n2,1\n",
        "# a comment\n\n0\t0\n1   0.5\n\n2 1\n",
    ],
)
def test_read_points_text_layouts(tmp_path, text):
    path = tmp_path / "p.csv"
    path.write_text(text)
    assert read_points(path).tolist() == [[0.0, 0.0], [1.0, 0.5], [2.0, 1.0]]


def test_read_points_npy_and_3d(tmp_path):
    points = np.arange(12, dtype=np.int32).reshape(4, 3)
    np.save(tmp_path / "p.npy", points)
    got = read_points(tmp_path / "p.npy")
    assert got.dtype == np.float64 and np.array_equal(got, points)


@pytest.mark.parametrize(
    ("name", "content", "match"),
    [
        ("missing.txt", None, "no such file"),
        ("p.dat", "0 0\n", "must be a .txt, .csv, .npy file"),
        ("p.txt", "", "holds no points"),
        ("p.txt", "# only a comment\n", "holds no points"),
        ("p.txt", "0 0 0 0\n1 1 1 1\n", "2 or 3 columns .* got 4"),
        ("p.txt", "0\n1\n", "got 1"),
        ("p.txt", "0 0\n1 1 1\n", "line 2 has 3 values"),
        ("p.txt", "0 0\nnan 1\n3 3\n", "NaN or inf, the first at line 2"),
        ("p.csv", "x,y\n0,0\n1,,1\n", "line 3 is not a row of numbers"),
        ("p.csv", "0,0\n1,a\n", "line 2 is not a row of numbers"),
        ("p.csv", "x,y,z\n0,0\n", "header has 3 names"),
    ],
)
def test_read_points_bad_files_name_the_file(tmp_path, name, content, match):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises(InputError, match=match) as info:
        read_points(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message


def test_read_points_bad_npy(tmp_path):
    (tmp_path / "junk.npy").write_bytes(b"not numpy")
    with pytest.raises(InputError, match="not a readable .npy"):
        read_points(tmp_path / "junk.npy")
    np.save(tmp_path / "flat.npy", np.arange(4.0))
    with pytest.raises(InputError, match=r"2D array .* got shape \(4,\)"):
        read_points(tmp_path / "flat.npy")
    np.save(tmp_path / "nan.npy", np.array([[0.0, 0.0], [np.nan, 1.0]]))
    with pytest.raises(InputError, match="first at row 1"):
        read_points(tmp_path / "nan.npy")


def test_read_image_thresholds_and_finds_the_shape(tmp_path):
    dark_on_white = np.full((6, 7), 255)
    dark_on_white[2:4, 2:5] = 10
    mask = read_image(_write_png(tmp_path / "a.png", dark_on_white))
    assert mask.dtype == bool and mask.sum() == 6 and mask[2:4, 2:5].all()
    white_on_black = 255 - dark_on_white
    assert np.array_equal(read_image(_write_png(tmp_path / "b.png", white_on_black)), mask)
    assert np.array_equal(read_image(tmp_path / "a.png", foreground="light"), ~mask)
    rgb = np.repeat(dark_on_white[:, :, None], 3, axis=2)
    assert np.array_equal(read_image(_write_png(tmp_path / "c.png", rgb)), mask)


@pytest.mark.parametrize(
    ("content", "match"),
    [(b"not a png", "not a readable image"), (b"", "empty"), (b"\x89PNG\r\n\x1a\n broken", "not a readable image")],
)
def test_read_image_bad_files(tmp_path, content, match):
    path = tmp_path / "bad.png"
    path.write_bytes(content)
    with pytest.raises(InputError, match=match):
        read_image(path)


def test_read_image_uniform_and_missing(tmp_path):
    with pytest.raises(InputError, match="uniform"):
        read_image(_write_png(tmp_path / "u.png", np.full((4, 4), 7)))
    with pytest.raises(InputError, match="no such file"):
        read_image(tmp_path / "none.png")
    (tmp_path / "u.txt").write_text("0 0\n")
    with pytest.raises(InputError, match=r"must be a \.png"):
        read_image(tmp_path / "u.txt")


def test_to_jsonable_converts_numpy_and_non_finite():
    value = {"a": np.arange(2), "b": np.float32(0.5), "c": [np.nan, np.inf, 1.0], "d": (np.int64(3), None)}
    assert to_jsonable(value) == {"a": [0, 1], "b": 0.5, "c": [None, None, 1.0], "d": [3, None]}


def test_writers_carry_the_parameters(tmp_path):
    parameters = {"kind": "knn", "k": 3}
    write_json(tmp_path / "sub" / "r.json", {"parameters": parameters, "x": np.eye(2)})
    assert json.loads((tmp_path / "sub" / "r.json").read_text()) == {"parameters": parameters, "x": [[1.0, 0.0], [0.0, 1.0]]}

    write_npz(tmp_path / "r.npz", {"x": np.arange(3), "skipped": None}, parameters)
    with np.load(tmp_path / "r.npz", allow_pickle=False) as saved:
        assert sorted(saved.files) == ["parameters", "x"]
        assert json.loads(str(saved["parameters"])) == parameters

    columns = {"node": np.arange(3), "value": np.array([0.5, 1.0, 1.5])}
    write_table(tmp_path / "t.csv", columns, parameters)
    lines = (tmp_path / "t.csv").read_text().splitlines()
    assert json.loads(lines[0].removeprefix("# parameters: ")) == parameters
    assert lines[1:] == ["node,value", "0,0.5", "1,1.0", "2,1.5"]
    assert np.array_equal(np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=2)[:, 1], columns["value"])

    write_table(tmp_path / "t.npy", columns, parameters)
    assert np.array_equal(np.load(tmp_path / "t.npy"), np.column_stack([np.arange(3), columns["value"]]))
    side = json.loads(sidecar_path(tmp_path / "t.npy").read_text())
    assert side == {"columns": ["node", "value"], "parameters": parameters}
