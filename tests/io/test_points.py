"""read_points / write_points: files written by the formats' own libraries, and round trips."""

import struct
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from centrality_vision.exceptions import InputError
from centrality_vision.io import WRITE_SUFFIXES, read_points, write_points

RNG = np.random.default_rng(0)
CLOUD = RNG.random((7, 3)) * 10 - 5
FLAT = RNG.random((6, 2))


# ------------------------------------------------------------------ written by other tools


def test_ply_written_by_plyfile_ascii_and_binary_with_an_intensity(tmp_path):
    plyfile = pytest.importorskip("plyfile")
    vertex = np.zeros(7, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("intensity", "f4")])
    vertex["x"], vertex["y"], vertex["z"] = CLOUD.T
    vertex["intensity"] = np.arange(7)
    for text in (True, False):
        path = tmp_path / f"cloud_{text}.ply"
        plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex")], text=text).write(str(path))
        assert np.allclose(read_points(path), CLOUD, rtol=0, atol=1e-12)
        picked = read_points(path, columns=["z", "intensity"])
        assert np.allclose(picked, np.column_stack([CLOUD[:, 2], np.arange(7)]))


@pytest.mark.parametrize("text", [True, False])
def test_ply_properties_in_any_order_and_columns_by_file_position(tmp_path, text):
    # meshio's ASCII reader took the first three properties as x, y, z: a file storing
    # y before x came back with its axes mixed, silently
    plyfile = pytest.importorskip("plyfile")
    vertex = np.zeros(7, dtype=[("y", "f8"), ("red", "u1"), ("x", "f8"), ("z", "f8")])
    vertex["x"], vertex["y"], vertex["z"] = CLOUD.T
    vertex["red"] = np.arange(7)
    faces = np.array([([0, 1, 2],), ([2, 3, 4],)], dtype=[("vertex_indices", "i4", (3,))])
    elements = [plyfile.PlyElement.describe(vertex, "vertex"), plyfile.PlyElement.describe(faces, "face")]
    path = tmp_path / "mixed.ply"
    plyfile.PlyData(elements, text=text).write(str(path))
    written = plyfile.PlyData.read(str(path))["vertex"]
    assert np.allclose(read_points(path), np.column_stack([written["x"], written["y"], written["z"]]), atol=1e-12)
    # indices count the file's properties in its order, as for text and PCD files
    assert np.allclose(read_points(path, columns=[2, 0, 3]), CLOUD, atol=1e-12)
    assert np.allclose(read_points(path, columns=[1, 3]), np.column_stack([np.arange(7), CLOUD[:, 2]]))


@pytest.mark.parametrize("order", ["<", ">"])
def test_binary_ply_in_2d_and_with_an_element_before_the_vertices(tmp_path, order):
    # meshio needs x, y and z: a binary file of x and y was refused with its internal error
    plyfile = pytest.importorskip("plyfile")
    vertex = np.zeros(6, dtype=[("x", order + "f4"), ("y", order + "f8"), ("label", order + "u2")])
    vertex["x"], vertex["y"], vertex["label"] = FLAT[:, 0], FLAT[:, 1], np.arange(6)
    camera = np.array([(1.5, 7)], dtype=[("view", order + "f8"), ("id", order + "i2")])
    elements = [plyfile.PlyElement.describe(camera, "camera"), plyfile.PlyElement.describe(vertex, "vertex")]
    path = tmp_path / "flat.ply"
    endian = {"<": "little", ">": "big"}[order]
    plyfile.PlyData(elements, text=False, byte_order=order).write(str(path))
    assert endian in path.read_bytes()[:80].decode()
    expected = np.column_stack([FLAT[:, 0].astype(np.float32), FLAT[:, 1]])
    np.testing.assert_array_equal(read_points(path, n_dims=2), expected)
    np.testing.assert_array_equal(read_points(path, columns=[2, 0]), np.column_stack([np.arange(6), expected[:, 0]]))
    truncated = tmp_path / "truncated.ply"
    truncated.write_bytes(path.read_bytes()[:-5])
    with pytest.raises(InputError, match="declares 6 vertices"):
        read_points(truncated, n_dims=2)


def test_ascii_ply_with_another_element_before_the_vertices(tmp_path):
    path = tmp_path / "cam.ply"
    path.write_bytes(
        b"ply\nformat ascii 1.0\nelement camera 1\nproperty float view_x\nproperty list uchar int ids\n"
        b"element vertex 2\nproperty float z\nproperty float x\nproperty float y\nend_header\n"
        b"9 2 7 7\n3 1 2\n6 4 5\n"
    )
    assert np.array_equal(read_points(path), [[1, 2, 3], [4, 5, 6]])


@pytest.mark.parametrize(
    ("body", "match"),
    [
        (b"1 2\n4 5 6\n", r"vertex 0 is not a row of the header's 3 vertex properties: '1 2'"),
        (b"1 2 3 4\n4 5 6\n", "vertex 0 is not a row"),
        (b"1 2 3\n", "declares 2 vertices but the file holds 1"),
        (b"1 2 x\n4 5 6\n", "vertex 0 is not a row"),
    ],
)
def test_ascii_ply_rows_that_do_not_match_the_header(tmp_path, body, match):
    path = tmp_path / "rows.ply"
    head = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
    head += b"end_header\n"
    path.write_bytes(head + body)
    with pytest.raises(InputError, match=match):
        read_points(path)


@pytest.mark.parametrize(
    ("row", "expected"),
    [(b"2 7 7 1 2 3\n", [[1, 2, 3]]), (b"0 1 2 3\n", [[1, 2, 3]]), (b"-1 1 2 3\n", None), (b"3 7 7 1 2 3\n", None)],
)
def test_ascii_ply_vertex_with_a_list_property(tmp_path, row, expected):
    path = tmp_path / "list.ply"
    head = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar int ids\n"
    head += b"property float x\nproperty float y\nproperty float z\nend_header\n"
    path.write_bytes(head + row)
    if expected is None:
        with pytest.raises(InputError, match="vertex 0 is not a row of the header's 4 vertex properties"):
            read_points(path)
    else:
        assert np.array_equal(read_points(path), expected)


@pytest.mark.slow  # importing Open3D takes seconds
def test_pcd_written_by_open3d_ascii_and_binary(tmp_path):
    o3d = pytest.importorskip("open3d")
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(CLOUD)
    for ascii_ in (True, False):
        path = tmp_path / f"cloud_{ascii_}.pcd"
        assert o3d.io.write_point_cloud(str(path), cloud, write_ascii=ascii_)
        # Open3D stores float32 (binary) or ten significant digits (ASCII)
        assert np.allclose(read_points(path), CLOUD, rtol=1e-6, atol=1e-6)


def test_pcd_binary_with_padding_and_an_rgb_field(tmp_path):
    """A PCL-style binary file built byte by byte from the format description."""
    records = np.zeros(3, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<u4"), ("_", "u1", (4,))])
    records["x"], records["y"], records["z"] = [1, 2, 3], [4, 5, 6], [7, 8, 9]
    header = (
        "VERSION .7\nFIELDS x y z rgb _\nSIZE 4 4 4 4 1\nTYPE F F F U U\nCOUNT 1 1 1 1 4\n"
        "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA binary\n"
    )
    path = tmp_path / "pcl.pcd"
    path.write_bytes(header.encode() + records.tobytes())
    assert read_points(path).tolist() == [[1, 4, 7], [2, 5, 8], [3, 6, 9]]


def test_obj_written_by_meshio_and_an_obj_with_faces_and_normals(tmp_path):
    meshio = pytest.importorskip("meshio")
    meshio.write_points_cells(tmp_path / "cloud.obj", CLOUD, [])
    assert np.array_equal(read_points(tmp_path / "cloud.obj"), CLOUD)
    (tmp_path / "mesh.obj").write_text(
        "# a triangle\nv 0 0 0 1.0\nv 1 0 0\nv 0 1 0 0.5 0.5 0.5\nvn 0 0 1\nf 1//1 2//1 3//1\n"
    )
    assert read_points(tmp_path / "mesh.obj").tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


def test_mat_written_by_scipy_with_a_named_variable(tmp_path):
    from scipy.io import savemat

    savemat(tmp_path / "one.mat", {"X": FLAT})
    assert np.array_equal(read_points(tmp_path / "one.mat"), FLAT)
    savemat(tmp_path / "two.mat", {"X": FLAT, "Y": CLOUD, "note": "fish"})
    assert np.array_equal(read_points(tmp_path / "two.mat", variable="Y"), CLOUD)
    with pytest.raises(InputError, match="name the variable .* X, Y"):
        read_points(tmp_path / "two.mat")
    with pytest.raises(InputError, match="no variable 'Z'"):
        read_points(tmp_path / "two.mat", variable="Z")


# Level-5 MAT files are parsed by centrality-vision itself (scipy's loadmat can crash on a
# damaged file), so each array must come back exactly as loadmat reads it.
_MAT_DTYPES = ["f8", "f4", "i1", "u1", "i2", "u2", "i4", "u4", "i8", "u8"]


@settings(max_examples=60, deadline=None)
@given(
    data=st.data(),
    dtype=st.sampled_from(_MAT_DTYPES),
    n_rows=st.integers(1, 9),
    n_dims=st.sampled_from([2, 3]),
    compressed=st.booleans(),
)
def test_mat_arrays_of_every_type_read_as_loadmat_reads_them(tmp_path_factory, data, dtype, n_rows, n_dims, compressed):
    from scipy.io import loadmat, savemat

    info = np.iinfo(dtype) if dtype[0] in "iu" else None
    elements = (
        st.integers(int(info.min), int(info.max))
        if info
        else st.floats(width=32 if dtype == "f4" else 64, allow_nan=False, allow_infinity=False)
    )
    points = data.draw(arrays(np.dtype(dtype), (n_rows, n_dims), elements=elements))
    others = {"note": "fish", "cell": np.array([np.ones(2), "ab"], dtype=object), "st": {"x": np.ones((2, 2))}}
    others |= {"cube": np.ones((2, 2, 2)), "z": np.array([[1 + 2j]]), "mask": np.eye(2, dtype=bool)}  # not candidates
    path = tmp_path_factory.mktemp("mat") / "p.mat"
    savemat(path, {"P": points, **others}, do_compression=compressed)
    read = read_points(path)
    assert np.array_equal(read, np.asarray(loadmat(path)["P"], dtype=np.float64))
    assert np.array_equal(read, points.astype(np.float64))


@pytest.mark.parametrize(
    ("variable", "what"),
    [
        ("note", "a MATLAB char array"),
        ("cell", "a MATLAB cell array of shape \\(1, 2\\)"),
        ("st", "a MATLAB struct of shape \\(1, 1\\)"),
        ("cube", "a MATLAB double array of shape \\(2, 2, 2\\)"),
        ("z", "a MATLAB complex double array of shape \\(1, 1\\)"),
        ("mask", "a MATLAB logical array of shape \\(2, 2\\)"),  # a mask, not coordinates (as in the API)
    ],
)
def test_a_mat_variable_that_is_not_a_2d_real_array_is_named_in_the_error(tmp_path, variable, what):
    from scipy.io import savemat

    contents = {"P": FLAT, "note": "fish", "cell": np.array([np.ones(2), "ab"], dtype=object)}
    contents |= {"st": {"x": np.ones((2, 2))}, "cube": np.ones((2, 2, 2)), "z": np.array([[1 + 2j]])}
    contents |= {"mask": np.eye(2, dtype=bool)}
    savemat(tmp_path / "p.mat", contents)
    with pytest.raises(InputError, match=f"variable '{variable}' must be a 2D real numeric array; got {what}"):
        read_points(tmp_path / "p.mat", variable=variable)


def test_mat_files_written_by_matlab_read_as_loadmat_reads_them():
    # scipy ships about a hundred MAT files written by MATLAB 4 to 8 on several platforms
    # (big- and little-endian, compressed, with cells, structs, objects, function handles)
    import warnings
    from pathlib import Path

    import scipy.io
    from scipy.io import loadmat
    from scipy.io.matlab import matfile_version

    from centrality_vision.io._points import _Mat5

    folder = Path(scipy.io.__file__).parent / "matlab" / "tests" / "data"
    files = sorted(folder.glob("*.mat"))
    if not files:
        pytest.skip("this scipy was installed without its test data")
    checked = 0
    for path in files:
        try:
            if matfile_version(path)[0] != 1:
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                reference = loadmat(path)
        except Exception:  # a file scipy's own tests expect to fail
            continue
        ours = {v.name: v for v in _Mat5(path, path.read_bytes()).variables() if v.name}
        assert set(ours) == {key for key in reference if not key.startswith("__")}, path.name
        for name, variable in ours.items():
            ref, values = reference[name], variable.values
            readable = isinstance(ref, np.ndarray) and ref.ndim == 2 and not np.iscomplexobj(ref)
            # logical arrays (loadmat gives them as uint8) are masks, not coordinates
            readable = readable and np.issubdtype(ref.dtype, np.number) and "logical" not in variable.what
            assert readable == (values is not None), (path.name, name)
            if readable:
                assert np.array_equal(values.astype(np.float64), ref.astype(np.float64)), (path.name, name)
        checked += 1
    assert checked > 50


def test_xyz_and_txt_written_by_numpy(tmp_path):
    np.savetxt(tmp_path / "cloud.xyz", CLOUD)
    np.savetxt(tmp_path / "tabs.txt", FLAT, delimiter="\t", header="some comment")
    assert np.array_equal(read_points(tmp_path / "cloud.xyz"), CLOUD)
    assert np.array_equal(read_points(tmp_path / "tabs.txt"), FLAT)


@pytest.mark.parametrize(
    "options",
    [{}, {"index": False}, {"sep": ";"}, {"sep": ";", "decimal": ","}, {"sep": "\t"}, {"sep": " ", "index": False}],
)
def test_csv_written_by_pandas(tmp_path, options):
    pandas = pytest.importorskip("pandas")
    frame = pandas.DataFrame({"x": CLOUD[:, 0], "y": CLOUD[:, 1], "z": CLOUD[:, 2], "intensity": np.arange(7)})
    path = tmp_path / "cloud.csv"
    frame.to_csv(path, **options)
    assert np.array_equal(read_points(path), CLOUD)
    assert np.array_equal(read_points(path, columns="x,intensity"), np.column_stack([CLOUD[:, 0], np.arange(7)]))


def test_npy_written_by_numpy_in_fortran_order_and_int(tmp_path):
    np.save(tmp_path / "f.npy", np.asfortranarray(CLOUD))
    np.save(tmp_path / "i.npy", np.arange(12, dtype=np.int32).reshape(4, 3))
    assert np.array_equal(read_points(tmp_path / "f.npy"), CLOUD)
    assert read_points(tmp_path / "i.npy").dtype == np.float64


# ------------------------------------------------------------------ text layouts and columns


@pytest.mark.parametrize(
    "text",
    [
        "0 0\n1 0.5\n2 1\n",
        "0,0\n1,0.5\n2,1\n",
        "x,y\n0,0\n1, 0.5\n2,1\n",
        "# a comment\n\n0\t0\n1   0.5\n\n2 1\n",
        "\ufeff0,0\n1,0.5\n2,1\n",  # a byte-order mark keeps the first row
        "\ufeffX;Y\n0;0\n1;0,5\n2;1\n",
        '"x","y"\n"0","0"\n"1","0.5"\n"2","1"\n',
        ",x,y\n0,0,0\n1,1,0.5\n2,2,1\n",  # pandas' index column
        "id x y\n7 0 0\n8 1 0.5\n9 2 1\n",
    ],
)
def test_text_layouts(tmp_path, text):
    path = tmp_path / "p.csv"
    path.write_text(text, encoding="utf-8")
    assert read_points(path).tolist() == [[0.0, 0.0], [1.0, 0.5], [2.0, 1.0]]


def test_columns_by_index_and_case_insensitive_names(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("A,X,Y,Z\n1,2,3,4\n5,6,7,8\n")
    assert read_points(path).tolist() == [[2, 3, 4], [6, 7, 8]]
    assert read_points(path, columns=[0, 3]).tolist() == [[1, 4], [5, 8]]
    assert read_points(path, columns=["a", "x"]).tolist() == [[1, 2], [5, 6]]
    headerless = tmp_path / "q.txt"
    headerless.write_text("1 2 3 4\n5 6 7 8\n")
    with pytest.raises(InputError, match="got 4 columns; pick the coordinates with `columns`"):
        read_points(headerless)
    assert read_points(headerless, columns="1,2,3").tolist() == [[2, 3, 4], [6, 7, 8]]
    with pytest.raises(InputError, match="names no columns"):
        read_points(headerless, columns=["x", "y"])
    with pytest.raises(InputError, match="index 4 is out of range"):
        read_points(headerless, columns=[0, 4])
    with pytest.raises(InputError, match="index -1 is out of range"):  # was "names '-1', which is not a column"
        read_points(path, columns="-1,0")
    with pytest.raises(InputError, match="'w', which is not a column"):
        read_points(path, columns=["x", "w"])
    with pytest.raises(InputError, match="must not repeat"):
        read_points(path, columns=[1, 1])
    with pytest.raises(InputError, match="must not hold an empty name"):  # a TypeError before
        read_points(path, columns="x,,y")


def test_a_header_that_repeats_a_name_is_refused_where_the_name_is_used(tmp_path):
    # the first of two columns called x was taken, silently
    path = tmp_path / "p.csv"
    path.write_text("x,y,X\n1,2,3\n4,5,6\n")
    with pytest.raises(InputError, match=r"names 2 columns 'x' \(indices 0, 2\).*0-based index"):
        read_points(path)
    with pytest.raises(InputError, match=r"names 2 columns 'x'"):
        read_points(path, columns=["y", "x"])
    assert read_points(path, columns=["y", 2]).tolist() == [[2, 3], [5, 6]]
    assert read_points(path, columns=[2, "y"]).tolist() == [[3, 2], [6, 5]]


def test_nan_rows_only_when_asked_and_only_whole_rows(tmp_path):
    path = tmp_path / "p.txt"
    path.write_text("0 0\nnan nan\n1 1\n")
    with pytest.raises(InputError, match="first at line 2"):
        read_points(path)
    got = read_points(path, nan_rows=True)
    assert np.isnan(got[1]).all() and got[[0, 2]].tolist() == [[0, 0], [1, 1]]
    path.write_text("0 0\nnan 1\n1 1\n")
    with pytest.raises(InputError, match="entirely NaN are allowed"):
        read_points(path, nan_rows=True)


# ------------------------------------------------------------------ bad files


@pytest.mark.parametrize(
    ("name", "content", "match"),
    [
        ("missing.txt", None, "no such file"),
        ("p.dat", "0 0\n", "must be a .txt, .csv"),
        ("p.txt", "", "holds no points"),
        ("p.txt", "# only a comment\n", "holds no points"),
        ("p.csv", "x,y\n", "only the header"),
        ("p.txt", "0 0 0 0\n1 1 1 1\n", "2 or 3 coordinates; got 4"),
        ("p.txt", "0\n1\n", "got 1"),
        ("p.txt", "0 0\n1 1 1\n", "line 2 has 3 values"),
        ("p.txt", "0 0\nnan 1\n3 3\n", "NaN or inf, the first at line 2"),
        ("p.csv", "x,y\n0,0\n1,,1\n", "line 3 has 3 values, the header 2"),
        ("p.csv", "0,0\n1,a\n", "line 2, column 2: 'a' is not a number"),
        ("p.csv", "O.5,1\n0,0\n1,1\n", "line 1, column 1: 'O.5' is not a number"),  # a typo is not a header
        ("p.csv", "x,y,z\n0,0\n", "line 2 has 2 values, the header 3"),
        ("p.csv", "0x10,1\n2,3\n", "'0x10' is not a number"),
        ("p.obj", "v 1 2\n", "line 1 is not a vertex"),
        ("p.pcd", "FIELDS x y z\nPOINTS 2\nDATA ascii\n1 2 3\n", "declares 2 points but the file holds 1"),
        (
            "p.pcd",
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 1\nDATA binary_compressed\n",
            "compressed",
        ),
        ("p.ply", "not a ply\n", "not a PLY file"),
        (
            "p.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n1 2 3\n",
            "declares 3 vertices",
        ),
        ("p.mat", "MATLAB nonsense", "not a readable .mat"),
    ],
)
def test_bad_files_name_the_file_on_one_line(tmp_path, name, content, match):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises(InputError, match=match) as info:
        read_points(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message


def test_npy_headers_are_checked_before_loading(tmp_path):
    (tmp_path / "junk.npy").write_bytes(b"not numpy")
    with pytest.raises(InputError, match="not a readable .npy"):
        read_points(tmp_path / "junk.npy")
    np.save(tmp_path / "flat.npy", np.arange(4.0))
    with pytest.raises(InputError, match=r"2D array .* got shape \(4,\)"):
        read_points(tmp_path / "flat.npy")
    # a header claiming 10**12 rows over 48 bytes of data: refused, nothing allocated
    data = tmp_path / "huge.npy"
    np.save(data, np.zeros((3, 2)))
    raw = data.read_bytes().replace(b"(3, 2)", b"(1000000000000, 2)".ljust(6))
    header_len = raw.index(b"\n") + 1
    fixed = raw[:8] + (header_len - 10).to_bytes(2, "little") + raw[10:header_len]
    data.write_bytes(fixed[:header_len] + raw[header_len:])
    with pytest.raises(InputError, match=r"\(1000000000000, 2\).* holds 48 bytes"):
        read_points(data)
    np.save(tmp_path / "obj.npy", np.array([[1, None]], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="numeric array; got dtype object"):
        read_points(tmp_path / "obj.npy")


def test_ply_binary_header_with_a_huge_count_is_refused_without_allocating(tmp_path):
    path = tmp_path / "huge.ply"
    path.write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
        b"property float x\nproperty float y\nproperty float z\nend_header\n" + bytes(12)
    )
    with pytest.raises(InputError, match="declares 1000000000000 vertices but the file holds only 12 bytes"):
        read_points(path)


def test_bad_arguments():
    with pytest.raises(TypeError, match="`path` must be a str"):
        read_points(3)
    with pytest.raises(TypeError, match="`columns` must hold"):
        read_points("p.txt", columns=[1.5])
    with pytest.raises(TypeError, match="`variable` must be a str"):
        read_points("p.txt", variable=1)


# ------------------------------------------------------------------ writing


@pytest.mark.parametrize("suffix", WRITE_SUFFIXES)
def test_every_written_format_round_trips_exactly(tmp_path, suffix):
    points = CLOUD if suffix in (".ply", ".pcd", ".obj") else FLAT
    path = write_points(tmp_path / "sub" / f"p{suffix}", points)
    assert np.array_equal(read_points(path), points)


def test_written_csv_is_read_by_pandas_with_default_arguments(tmp_path):
    pandas = pytest.importorskip("pandas")
    frame = pandas.read_csv(write_points(tmp_path / "p.csv", CLOUD))
    assert list(frame.columns) == ["x", "y", "z"] and np.array_equal(frame.to_numpy(), CLOUD)


@pytest.mark.slow  # importing Open3D takes seconds
def test_written_files_are_read_by_their_own_libraries(tmp_path):
    meshio = pytest.importorskip("meshio")
    o3d = pytest.importorskip("open3d")
    from scipy.io import loadmat

    assert np.array_equal(meshio.read(write_points(tmp_path / "p.ply", CLOUD)).points, CLOUD)
    assert np.array_equal(meshio.read(write_points(tmp_path / "p.obj", CLOUD)).points, CLOUD)
    assert np.allclose(np.asarray(o3d.io.read_point_cloud(str(write_points(tmp_path / "p.pcd", CLOUD))).points), CLOUD)
    assert np.array_equal(loadmat(write_points(tmp_path / "p.mat", FLAT))["points"], FLAT)


def test_nan_rows_round_trip_in_text_and_are_refused_by_3d_formats(tmp_path):
    points = FLAT.copy()
    points[2] = np.nan
    got = read_points(write_points(tmp_path / "p.csv", points), nan_rows=True)
    assert np.array_equal(got, points, equal_nan=True)
    with pytest.raises(InputError, match="`points` must be 3D"):
        write_points(tmp_path / "p.ply", FLAT)
    with pytest.raises(InputError, match="cannot mark missing points"):
        write_points(tmp_path / "p.pcd", np.vstack([CLOUD, np.full(3, np.nan)]))
    with pytest.raises(InputError, match="row 0 is not"):
        write_points(tmp_path / "p.csv", [[np.nan, 1.0]])
    with pytest.raises(InputError, match="must end in one of"):
        write_points(tmp_path / "p.xlsx", FLAT)


@settings(max_examples=25, deadline=None)
@given(
    points=arrays(
        np.float64,
        st.tuples(st.integers(1, 8), st.sampled_from([2, 3])),
        elements=st.floats(-1e300, 1e300, allow_nan=False, allow_infinity=False),
    ),
    suffix=st.sampled_from([".csv", ".txt", ".xyz", ".npy", ".mat"]),
)
def test_round_trip_property(tmp_path_factory, points, suffix):
    path = write_points(tmp_path_factory.mktemp("rt") / f"p{suffix}", points)
    assert np.array_equal(read_points(path), points)


@pytest.mark.parametrize(
    ("n_dims", "error", "message"),
    [
        (None, TypeError, "`n_dims` must be a sequence of ints"),
        ("2", TypeError, "`n_dims` must be a sequence of ints"),
        ([2.0], TypeError, "`n_dims` must be a sequence of ints"),
        ([True], TypeError, "`n_dims` must be a sequence of ints"),
        ([], ValueError, "`n_dims` must hold at least one"),
        ([0], ValueError, "`n_dims` must hold at least one"),
    ],
)
def test_read_points_checks_n_dims(tmp_path, n_dims, error, message):
    np.savetxt(tmp_path / "p.csv", np.arange(10.0).reshape(5, 2), delimiter=",")
    with pytest.raises(error, match=message):
        read_points(tmp_path / "p.csv", n_dims=n_dims)
    assert read_points(tmp_path / "p.csv", n_dims=2).shape == (5, 2)  # one int is one allowed count
    with pytest.raises(TypeError, match="`nan_rows` must be True or False"):
        read_points(tmp_path / "p.csv", nan_rows="yes")


@pytest.mark.parametrize("suffix", WRITE_SUFFIXES)
def test_write_points_refuses_an_empty_set_it_could_not_read_back(tmp_path, suffix):
    with pytest.raises(ValueError, match="`points` must hold at least one point"):
        write_points(tmp_path / f"e{suffix}", np.zeros((0, 3)))
    assert not list(tmp_path.iterdir())


def test_a_binary_pcd_without_points_holds_width_times_height(tmp_path):
    # found by a fuzz run: the count fell back to WIDTH alone, so 12 points were cut to 4
    header = b"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 3\nDATA binary\n"
    path = tmp_path / "organised.pcd"
    path.write_bytes(header + np.arange(36, dtype="<f4").tobytes())
    np.testing.assert_array_equal(read_points(path), np.arange(36.0).reshape(12, 3))


@pytest.mark.parametrize("suffix", [".NPY", ".MAT", ".Npy"])
def test_write_points_keeps_an_upper_case_suffix(tmp_path, suffix):
    # numpy and scipy appended their lower-case suffix: points.NPY became points.NPY.npy
    path = write_points(tmp_path / f"points{suffix}", FLAT)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"points{suffix}"]
    np.testing.assert_array_equal(read_points(path), FLAT)


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_with_list_properties_in_and_before_the_vertex_element(tmp_path, fmt):
    # meshio's binary reader refused a list inside the vertex element with a KeyError.
    # The file is written here byte by byte: plyfile writes the scalars of an element
    # with lists in the machine's byte order whatever the header says.
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    header = (
        f"ply\nformat {fmt} 1.0\nelement face 2\nproperty list uchar int vertex_indices\nproperty uchar flag\n"
        "element vertex 7\nproperty double x\nproperty list uchar short tags\nproperty float y\nproperty double z\n"
        "end_header\n"
    ).encode()
    faces = [([0, 1, 2], 3), ([0, 1, 2, 3, 4], 4)]
    y = CLOUD[:, 1].astype(np.float32)
    vertices = [(CLOUD[k, 0], list(range(k % 3)), y[k], CLOUD[k, 2]) for k in range(7)]
    if order is None:
        lines = [f"{len(idx)} {' '.join(map(str, idx))} {flag}" for idx, flag in faces]
        lines += [f"{float(x)!r} {len(t)} {' '.join(map(str, t))} {float(v)!r} {float(z)!r}" for x, t, v, z in vertices]
        body = ("\n".join(lines) + "\n").encode()
    else:
        parts = [struct.pack(f"{order}B{len(idx)}iB", len(idx), *idx, flag) for idx, flag in faces]
        parts += [struct.pack(f"{order}dB{len(t)}hfd", x, len(t), *t, v, z) for x, t, v, z in vertices]
        body = b"".join(parts)
    path = tmp_path / "lists.ply"
    path.write_bytes(header + body)
    expected = np.column_stack([CLOUD[:, 0], y, CLOUD[:, 2]])
    np.testing.assert_array_equal(read_points(path), expected)
    np.testing.assert_array_equal(read_points(path, columns=[2, 0]), expected[:, [2, 0]])
    if order is not None:
        cut = tmp_path / "cut.ply"
        cut.write_bytes(header + body[:-3])
        with pytest.raises(InputError, match="cut.ply: the file ends inside its elements"):
            read_points(cut)


def test_a_ply_list_counted_by_a_float_is_refused(tmp_path):
    path = tmp_path / "bad.ply"
    path.write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty list float int n\nproperty float x\n"
        b"property float y\nproperty float z\nend_header\n" + bytes(16)
    )
    with pytest.raises(InputError, match="bad.ply: not a readable PLY file .a damaged property line"):
        read_points(path)


@pytest.mark.parametrize("word", ["1_000", "\u0661\u0662", "\uff11"])
@pytest.mark.parametrize("suffix", [".txt", ".csv", ".obj", ".ply", ".pcd"])
def test_digit_separators_and_other_scripts_digits_are_not_numbers(tmp_path, word, suffix):
    # Python's float() (and numpy's) read "1_000" as 1000 and Arabic-Indic or full-width
    # digits as numbers; a point file never means them
    row = f"{word} 2 3"
    body = {
        ".txt": row,
        ".csv": row.replace(" ", ","),
        ".obj": f"v {row}",
        ".ply": f"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
        f"end_header\n{row}",
        ".pcd": f"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n{row}",
    }[suffix]
    path = tmp_path / f"p{suffix}"
    path.write_text(body + "\n", encoding="utf-8")
    with pytest.raises(InputError, match=f"p\\{suffix}"):
        read_points(path)
    path.write_text(body.replace(word, "1000") + "\n", encoding="utf-8")
    assert read_points(path)[0, 0] == 1000


@pytest.mark.parametrize(
    ("array", "said"),
    [
        (np.eye(3, dtype=bool), "must hold coordinates \\(real numbers\\); got dtype bool \\(a mask\\?\\)"),
        (np.arange(6).reshape(3, 2).astype("m8[s]"), "must hold a numeric array; got dtype timedelta64"),
        (np.arange(6).reshape(3, 2).astype("M8[D]"), "must hold a numeric array; got dtype datetime64"),
    ],
)
def test_an_npy_of_masks_or_times_is_not_read_as_coordinates(tmp_path, array, said):
    # fuzz round 6 (L7): a bool .npy was read as 0/1 points, which the API refuses
    np.save(tmp_path / "p.npy", array)
    with pytest.raises(InputError, match=said):
        read_points(tmp_path / "p.npy")


def test_a_binary_ply_whose_last_list_runs_past_the_end_is_refused(tmp_path):
    # found by fuzz round 7: the last vertex's list was not checked against the file's end
    header = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        b"property list uint int idx\nend_header\n"
    )
    first = struct.pack("<ffI", 1.0, 2.0, 0)
    for last in (struct.pack("<ffI", 3.0, 4.0, 5) + b"\0" * 4, struct.pack("<ffI", 3.0, 4.0, 4_000_000_000)):
        (tmp_path / "short.ply").write_bytes(header + first + last)
        with pytest.raises(InputError, match="the file ends inside its elements"):
            read_points(tmp_path / "short.ply")
    (tmp_path / "whole.ply").write_bytes(header + first + struct.pack("<ffI", 3.0, 4.0, 1) + b"\0" * 4)
    np.testing.assert_array_equal(read_points(tmp_path / "whole.ply"), [[1.0, 2.0], [3.0, 4.0]])


def test_a_ply_comment_that_mentions_end_header_does_not_end_the_header(tmp_path):
    (tmp_path / "c.ply").write_bytes(
        b"ply\nformat ascii 1.0\ncomment written before end_header was known\nelement vertex 3\n"
        b"property float x\nproperty float y\nend_header\n0 0\n1 0\n0 1\n"
    )
    np.testing.assert_array_equal(read_points(tmp_path / "c.ply"), [[0, 0], [1, 0], [0, 1]])


@pytest.mark.parametrize(
    "line",
    [b"element normal 2.0", b"element vertex -1", b"element normal", b"element normal 2 3", b"element n \xc2\xb2"],
)
def test_a_damaged_ply_element_line_is_refused(tmp_path, line):
    # "element normal 2.0" was dropped and its property given to the vertices: the binary
    # body was then read with 16-byte records, [[1, 2, 3], [5, 6, 7]] instead of [[1, 2, 3], [4, 5, 6]]
    path = tmp_path / "bad.ply"
    path.write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        b"property float z\n" + line + b"\nproperty float nx\nend_header\n" + struct.pack("<8f", *range(1, 9))
    )
    with pytest.raises(InputError, match=r"bad\.ply: not a readable PLY file \(a damaged element line"):
        read_points(path)


def test_a_ply_with_a_property_before_any_element_or_two_vertex_elements_is_refused(tmp_path):
    head = b"ply\nformat ascii 1.0\n"
    vertex = b"element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
    (tmp_path / "early.ply").write_bytes(head + b"property float w\n" + vertex + b"end_header\n1 2 3\n")
    with pytest.raises(InputError, match=r"early\.ply: not a readable PLY file \(a property line before any element"):
        read_points(tmp_path / "early.ply")
    (tmp_path / "two.ply").write_bytes(head + vertex + vertex + b"end_header\n1 2 3\n4 5 6\n")
    with pytest.raises(InputError, match=r"two\.ply: the PLY file must have one vertex element; got 2"):
        read_points(tmp_path / "two.ply")


def test_an_npy_with_a_negative_shape_or_long_doubles_past_float64_names_the_file(tmp_path):
    data = tmp_path / "neg.npy"
    np.save(data, np.zeros((3, 2)))
    data.write_bytes(data.read_bytes().replace(b"(3, 2)", b"(-3,-2)".ljust(6)[:6]))  # (numpy's bare ValueError)
    with pytest.raises(InputError, match=r"neg\.npy: not a readable \.npy array"):
        read_points(data)
    if np.finfo(np.longdouble).max > np.finfo(np.float64).max:  # (long double is float64 on some platforms)
        big = np.ones((2, 2), dtype=np.longdouble)
        big[0, 0] = np.longdouble(10) ** 400
        np.save(tmp_path / "big.npy", big)
        with pytest.raises(InputError, match=r"big\.npy: holds float\d+ values beyond the float64 range"):
            read_points(tmp_path / "big.npy")  # (it blamed NaN or inf, with numpy's overflow warning)


def test_paths_the_system_refuses_are_named_errors(tmp_path):
    with pytest.raises(InputError, match="`path` must name a file; got an empty path"):
        read_points("")
    with pytest.raises(InputError, match="cannot be read"):
        read_points(tmp_path / ("a" * 300 + ".csv"))  # (a bare OSError: File name too long)
    (tmp_path / "folder.csv").mkdir()
    with pytest.raises(InputError, match=r"folder\.csv: is a folder; `path` must name the file to write"):
        write_points(tmp_path / "folder.csv", [[0.0, 1.0]])
    (tmp_path / "file.txt").write_text("")
    under_a_file = r"file\.txt/x\.csv: cannot be written \(.*file\.txt is a file, not a folder\)"
    with pytest.raises(InputError, match=under_a_file):
        write_points(tmp_path / "file.txt" / "x.csv", [[0.0, 1.0]])
    with pytest.raises(InputError, match="cannot be written"):
        write_points(tmp_path / ("a" * 300 + ".csv"), [[0.0, 1.0]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("x,y\n1,2\n3\n4,5\n", "line 3 has 1 value, the header 2"),  # (it blamed line 2: '1,2' is not a number)
        ("1;2\n3;4\n5\n6;7\n", "line 3 has 1 value, the rows before it 2"),
        ("1,2\n3\n", "line 2 has 1 value, the rows before it 2"),  # (audit 24: '1,2' was taken for a header)
    ],
)
def test_a_ragged_delimited_file_names_its_short_line(tmp_path, text, message):
    (tmp_path / "ragged.csv").write_text(text)
    with pytest.raises(InputError, match=message):
        read_points(tmp_path / "ragged.csv")


@pytest.mark.parametrize("text", ["1,5 2,5\n3 4\n5 6\n", "1,5 2,5\n3 4\n5 6\n7,5 8\n9 10\n"])
def test_a_first_line_of_numbers_written_otherwise_is_not_dropped_as_a_header(tmp_path, text):
    # audit round 24: decimal commas in a file split by spaces made the first line a header
    # (cells '1,5' and '2,5'), and the point (1.5, 2.5) was dropped without a word
    (tmp_path / "points.txt").write_text(text)
    with pytest.raises(InputError, match=r"line 1, column 1: '1,5' is not a number \(decimal commas are read only"):
        read_points(tmp_path / "points.txt")


@pytest.mark.parametrize("header", ["x y", ",x,y", "X;Y", "lat lon"])
def test_a_first_line_that_names_columns_is_still_a_header(tmp_path, header):
    index = header.startswith(",")
    delimiter = ";" if ";" in header else "," if index else " "
    rows = [[0, 1.5, 2.0], [1, 3.0, 4.0]] if index else [[1.5, 2.0], [3.0, 4.0]]
    body = "\n".join(delimiter.join(str(v) for v in row) for row in rows)
    (tmp_path / "points.csv").write_text(f"{header}\n{body}\n")
    np.testing.assert_array_equal(read_points(tmp_path / "points.csv"), [[1.5, 2.0], [3.0, 4.0]])


def test_write_points_refuses_a_mask_as_every_reader_does(tmp_path):
    with pytest.raises(TypeError, match=r"`points` must hold coordinates .*dtype bool \(a mask\?"):
        write_points(tmp_path / "mask.csv", np.eye(2, dtype=bool))
    assert not (tmp_path / "mask.csv").exists()


def test_mixed_tabs_and_spaces_still_split_as_whitespace(tmp_path):
    (tmp_path / "mixed.txt").write_text("1\t2\n3 4\n5\t6\n")
    np.testing.assert_array_equal(read_points(tmp_path / "mixed.txt"), [[1, 2], [3, 4], [5, 6]])


def test_too_few_columns_get_no_advice_to_choose_columns(tmp_path):
    # (it said "pick the coordinates with `columns`" for a file of 2 columns read as 3D)
    (tmp_path / "p.csv").write_text("x,y\n0,1\n2,3\n")
    with pytest.raises(InputError, match=r"must have 3 coordinates; got 2 columns") as info:
        read_points(tmp_path / "p.csv", n_dims=(3,))
    assert "`columns`" not in str(info.value)
    (tmp_path / "q.csv").write_text("a,b,c,d\n0,1,2,3\n")
    with pytest.raises(InputError, match="pick the coordinates with `columns`"):
        read_points(tmp_path / "q.csv", n_dims=(3,))


def test_too_many_columns_picked_are_named_as_picked(tmp_path):
    # audit 26 L8: "got 4 columns ('x', 'y', 'z', 'nx', 'ny', 'nz', 'red')" named all the file's columns
    (tmp_path / "p.csv").write_text("x,y,z,nx,ny,nz,red\n0,1,2,0,0,1,9\n1,2,3,0,1,0,9\n")
    with pytest.raises(InputError, match=r"got 4 columns \('x', 'y', 'z', 'nx'\)\.$"):
        read_points(tmp_path / "p.csv", columns=["x", "y", "z", "nx"])
    (tmp_path / "one.csv").write_text("a\n0\n1\n")
    with pytest.raises(InputError, match=r"got 1 column \('a'\)"):
        read_points(tmp_path / "one.csv")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("id,x,y,label\n0,1.5,2,p0\n1,2.5,3,p1\n", [[1.5, 2.0], [2.5, 3.0]]),  # a label column beside x, y
        ("a,0,0\nb,1,0\nc,0,1\n", [[0, 0], [1, 0], [0, 1]]),  # a leading name column, no header
        ("x,y,note\n0,0,\n1,0,\n0,1,hi\n", [[0, 0], [1, 0], [0, 1]]),  # an optional note, mostly empty
        ("1,2,\n3,4,\n", [[1, 2], [3, 4]]),  # a delimiter closing every line
        ("u;v;class\n0,5;1;cat\n1;2,5;dog\n", [[0.5, 1.0], [1.0, 2.5]]),  # decimal commas, no x/y names
    ],
)
def test_label_and_empty_columns_are_not_coordinates(tmp_path, text, expected):
    """A cell that is not a number made the whole file unreadable, even with `columns`
    picking other columns (audit 26): a column of labels or empty cells is now no
    coordinate, and a cell that is not a number counts only in a picked column."""
    path = tmp_path / "points.csv"
    path.write_text(text)
    np.testing.assert_array_equal(read_points(path), expected)


@pytest.mark.parametrize(
    ("text", "columns", "message"),
    [
        ("id,x,y,label\n0,1.5,2,p0\n1,2.5,3,p1\n", ["x", "label"], r"line 2, column 4: 'p0' is not a number\.$"),
        ("1,2,\n3,,\n", None, r"line 2, column 2: an empty cell \(a ',' too many\?\); pick the coordinates"),
        ("1_000 2.5 3.0\n4 5 6\n", None, "line 1, column 1: '1_000' is not a number"),  # a number, wrongly written
        ("1 2,5 3\n4 5 6\n7 8 9\n", [0, 1], r"column 2: '2,5' is not a number \(decimal commas are read only"),
    ],
)
def test_a_cell_that_is_not_a_number_in_a_picked_column_is_named(tmp_path, text, columns, message):
    path = tmp_path / "points.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_points(path, columns=columns)


@pytest.mark.parametrize("start", [0, 1])
def test_a_first_column_of_row_numbers_without_a_header_is_read_with_a_warning(tmp_path, start):
    """pandas' to_csv(header=False) writes the row numbers first: 2D data was read as 3D
    with the row number as x, silently (audit 26). It stays a coordinate (the file says
    nothing else; a curve sampled at 0, 1, 2, ... is data) but the reader says so."""
    rows = np.c_[np.arange(start, start + 4), RNG.random((4, 2))]
    path = tmp_path / "indexed.csv"
    path.write_text("\n".join(",".join(repr(float(v)) for v in row) for row in rows) + "\n")
    with pytest.warns(UserWarning, match=r"column 1 holds the row numbers .* pick the coordinates with `columns` "):
        assert read_points(path).shape == (4, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(read_points(path, columns=[1, 2]), rows[:, 1:])
        # no warning where the rest is no point (a curve y(i)) or the numbers do not count rows
        (tmp_path / "curve.csv").write_text("0,1.5\n1,2.5\n2,0.5\n")
        assert read_points(tmp_path / "curve.csv").shape == (3, 2)
        shifted = rows.copy()
        shifted[:, 0] += 0.5
        path.write_text("\n".join(",".join(repr(float(v)) for v in row) for row in shifted) + "\n")
        assert read_points(path).shape == (4, 3)
