"""Audit round 31 (io, datasets, experiments): each case was a silent answer or an error that
named the wrong thing."""

import numpy as np
import pytest
import scipy.io

from centrality_vision.datasets import Kimia99, contour_points, load_face
from centrality_vision.exceptions import InputError
from centrality_vision.io import read_points, write_points

_PLY_HEADER = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"


def test_an_ascii_ply_with_more_lines_than_declared_is_refused(tmp_path):
    """The third vertex line was dropped without a word."""
    path = tmp_path / "x.ply"
    path.write_text(_PLY_HEADER + "end_header\n1 2 3\n4 5 6\n7 8 9\n")
    with pytest.raises(InputError, match=r"declares 2 lines \(2 vertex\) but the body holds 3"):
        read_points(path)
    path.write_text(_PLY_HEADER + "end_header\n1 2 3\n4 5 6\n\n")  # a blank line at the end is no row
    np.testing.assert_array_equal(read_points(path), [[1, 2, 3], [4, 5, 6]])
    faces = "element face 1\nproperty list uchar int vertex_indices\n"
    path.write_text(_PLY_HEADER + faces + "end_header\n1 2 3\n4 5 6\n3 0 1 0\n")
    np.testing.assert_array_equal(read_points(path), [[1, 2, 3], [4, 5, 6]])


@pytest.mark.parametrize(
    ("text", "line", "hint"),
    [("1 2 # note\n3 4\n", 1, True), ("1 2 # note\n3 4\n5 6\n", 1, True), ("1 2\n3 4\n5 6 7\n", 3, False)],
)
def test_rows_of_unequal_length_name_the_odd_line(tmp_path, text, line, hint):
    """A comment after the first line's values made line 2 the one blamed."""
    path = tmp_path / "c.txt"
    path.write_text(text)
    with pytest.raises(InputError, match=rf"line {line} has") as error:
        read_points(path)
    assert ("a comment takes a line of its own" in str(error.value)) == hint


def test_load_face_reads_what_read_points_reads_and_names_a_wrong_path(tmp_path):
    source = np.random.default_rng(0).normal(size=(20, 3))
    (tmp_path / "face_source.txt").write_bytes(
        b"\xef\xbb\xbf" + "\n".join(f"{a} {b} {c}" for a, b, c in source).encode()
    )
    (tmp_path / "face_target.txt").write_text("x,y,z\n" + "\n".join(f"{a},{b},{c}" for a, b, c in source[::-1]))
    face = load_face(tmp_path)  # a byte-order mark and a header with commas: numpy's loadtxt refused both
    np.testing.assert_array_equal(face.moving, source)
    np.testing.assert_array_equal(face.fixed, source[::-1])
    with pytest.raises(InputError, match=r"`path` must be a folder holding face_source.txt; got the file"):
        load_face(tmp_path / "face_source.txt")  # was a FileNotFoundError saying the data is not bundled
    with pytest.raises(InputError, match="got an empty path"):
        load_face("")  # was the current folder
    (tmp_path / "face_target.txt").unlink()
    with pytest.raises(FileNotFoundError, match="holds face_source.txt but not face_target.txt"):
        load_face(tmp_path)
    (tmp_path / "face_target.txt").write_text("1 2\n3 4\n")
    with pytest.raises(InputError, match="face_target.txt"):
        load_face(tmp_path)


def test_contour_points_bounds_n_points():
    mask = np.zeros((9, 9), dtype=bool)
    mask[2:7, 2:7] = True
    with pytest.raises(InputError, match=r"`n_points` must be an int in \[3, 10000000\]"):
        contour_points(mask, 10**12)  # asked numpy for 7 TiB


def test_write_points_names_ragged_rows_and_a_nul_in_the_path(tmp_path):
    with pytest.raises(InputError, match="`points` must be rows of equal length"):
        write_points(tmp_path / "o.csv", [[1, 2], [3]])
    with pytest.raises(InputError, match="`path` must be a file name without NUL"):
        write_points(str(tmp_path / "a\x00.csv"), [[1, 2]])


def test_a_mat_file_without_a_usable_array_lists_its_variables(tmp_path):
    path = tmp_path / "c.mat"
    scipy.io.savemat(path, {"p": np.ones((3, 2)) + 1j, "q": np.ones((2, 2, 2))})
    with pytest.raises(InputError, match=r"holds no 2D real numeric array.*'p': .*complex.*'q': .*\(2, 2, 2\)"):
        read_points(path)


def test_a_pcd_of_no_points_says_so(tmp_path):
    path = tmp_path / "z.pcd"
    path.write_text(
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA ascii\n"
    )
    with pytest.raises(InputError, match=r"holds no points \(its header declares 0\)"):
        read_points(path)


@pytest.mark.parametrize("image", ["abc", np.zeros((3, 3)), np.zeros((3, 3, 2), dtype=bool)], ids=repr)
def test_kimia99_holds_2d_masks_only(image):
    with pytest.raises(TypeError, match="`images` must hold 2D bool masks; got .* at index 0"):
        Kimia99(images=[image], labels=["a"], names=["x"])
