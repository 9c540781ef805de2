"""Damaged files: every reader answers with an InputError, never a crash, an exit or a huge allocation."""

import io
import random
import warnings

import imageio.v3 as iio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from centrality_vision.exceptions import InputError
from centrality_vision.io import read_points, read_shape

# A 238-byte MAT file (a fuzzed copy of a savemat output) on which scipy's loadmat crashed
# the interpreter (segmentation fault) while reading its data past the end of the file.
CRASHING_MAT = bytes.fromhex(
    "4d41544c414220352e30204d41542d66696c6520506c6174666f726d3a20706f7369782c2043726561746564206f6e3a"
    "2053756e204e6f762032322031323a32363a313320323032360000000000000000000000000000000000000000000000"
    "000000000000000000000000000000000000000000000000000000000001494d0e000000600000000600000008000000"
    "060000000000000005000000080000000300000002000000010001006100000009e9000030000000000000000000006e"
    "616e0000000000000000400000000000001040000000000000f03f000000000000084000000000006e616e001440"
)


def test_a_mat_file_that_crashed_scipy_is_an_input_error(tmp_path):
    path = tmp_path / "crash.mat"
    path.write_bytes(CRASHING_MAT)
    with pytest.raises(InputError, match="not a readable .mat file"):
        read_points(path)


def _savemat_bytes(contents, **kwargs) -> bytes:
    from scipy.io import savemat

    buffer = io.BytesIO()
    savemat(buffer, contents, **kwargs)
    return buffer.getvalue()


def _edit(data: bytes, offset: int, new: bytes) -> bytes:
    return data[:offset] + new + data[offset + len(new) :]


# Byte edits of a one-array savemat file ("a", 3 x 2 doubles; the array starts at byte 128,
# its flags at 144, its data tag at 176). Each crashed scipy's loadmat (segmentation fault)
# in a replay of the mutation test below.
_MAT_EDITS = {
    "complex flag, no imaginary part": (145, b"\xb9"),
    "data of an unknown type (75)": (176, b"\x4b"),
    "data of type 0": (176, b"\x00"),
    "data of a reserved type (8)": (176, b"\x08"),
    "array longer than the file": (132, b"\x00\x01"),
    "data longer than the array": (180, b"\x40"),
    "data shorter than its shape": (180, b"\x28"),
    "flags of the wrong type": (136, b"\x05"),
    "small element holding 9 bytes": (168, b"\x01\x00\x09\x00"),
}


@pytest.mark.parametrize("edit", sorted(_MAT_EDITS))
def test_a_mat_file_with_a_damaged_array_is_an_input_error(tmp_path, edit):
    seed = _savemat_bytes({"a": np.arange(6.0).reshape(3, 2)})
    assert seed[176:178] == b"\x09\x00" and seed[180] == 48  # the layout the edits assume
    path = tmp_path / "damaged.mat"
    path.write_bytes(_edit(seed, *_MAT_EDITS[edit]))
    with pytest.raises(InputError, match=r"damaged.mat: not a readable .mat file \(byte 1\d\d"):
        read_points(path)


def test_a_mat_file_whose_compressed_array_is_damaged_is_an_input_error(tmp_path):
    import zlib

    plain = _savemat_bytes({"a": np.arange(6.0).reshape(3, 2)})
    inner = _edit(plain[128:], 17, b"\xb9")  # the complex flag again, inside the compressed block
    packed = zlib.compress(inner)
    path = tmp_path / "z.mat"
    path.write_bytes(plain[:128] + np.array([15, len(packed)], "<u4").tobytes() + packed)
    with pytest.raises(InputError, match="z.mat: not a readable .mat file .*compressed byte"):
        read_points(path)
    path.write_bytes(plain[:128] + np.array([15, len(packed)], "<u4").tobytes() + packed[:-5] + b"\x00" * 5)
    with pytest.raises(InputError, match="z.mat: not a readable .mat file .*compressed data"):
        read_points(path)


@pytest.mark.parametrize("line", [b"property", b"property list"])
def test_a_ply_property_line_without_its_type_is_an_input_error(tmp_path, line):
    # found by the mutation test below: the header check indexed the missing words
    path = tmp_path / "cut.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 1\n" + line + b"\nend_header\n1 2 3\n")
    with pytest.raises(InputError, match="cut.ply"):
        read_points(path)


def test_a_damaged_ply_header_is_an_input_error_not_an_exit(tmp_path):
    path = tmp_path / "bad.ply"  # meshio.read prints and calls sys.exit(1) on this one
    path.write_bytes(b"plyX\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n")
    with pytest.raises(InputError, match="not a readable PLY file"):
        read_points(path)


def _seeds() -> dict:

    seeds = {
        ".csv": b"x,y,z\n1,2,3\n4,5,6\n",
        ".txt": b"1 2\n3 4\n",
        ".ply": b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
        b"end_header\n1 2 3\n4 5 6\n",
        ".pcd": b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
        b"1 2 3\n4 5 6\n",
        ".obj": b"v 1 2 3\nv 4 5 6\nf 1 2 1\n",
    }
    buffer = io.BytesIO()
    np.save(buffer, np.arange(6.0).reshape(3, 2))
    seeds[".npy"] = buffer.getvalue()
    seeds[".mat"] = _savemat_bytes({"a": np.arange(6.0).reshape(3, 2)})
    image = np.full((8, 8), 255, np.uint8)
    image[2:5, 2:6] = 0
    for suffix in (".png", ".bmp", ".gif"):
        seeds[suffix] = iio.imwrite("<bytes>", image, extension=suffix)
    return seeds


SEEDS = _seeds()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(suffix=st.sampled_from(sorted(SEEDS)), seed=st.integers(0, 2**32 - 1))
def test_mutated_files_give_points_or_an_input_error(tmp_path, suffix, seed):
    rng = random.Random(seed)
    data = bytearray(SEEDS[suffix])
    for _ in range(rng.randint(1, 6)):
        i = rng.randrange(len(data) + 1)
        op = rng.random()
        if op < 0.4 and data:
            data[min(i, len(data) - 1)] = rng.randrange(256)
        elif op < 0.7:
            data[i:i] = bytes([rng.randrange(256)]) * rng.randint(1, 3)
        elif op < 0.85:
            del data[i : i + rng.randint(1, 10)]
        else:
            data[i:i] = rng.choice([b"nan", b"1e400", b"-", b",", b";", b"\n", b"999999999999", b"\xef\xbb\xbf"])
    path = tmp_path / f"f{suffix}"
    path.write_bytes(bytes(data))
    reader = read_shape if suffix in (".png", ".bmp", ".gif") else read_points
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an inverted-looking shape may warn
            out = reader(path)
    except InputError:
        return
    assert out.dtype == bool or np.isfinite(out).all()


@pytest.mark.parametrize(("line", "value"), [(b"POINTS", b""), (b"WIDTH", b""), (b"POINTS", b"two")])
def test_a_pcd_count_line_without_an_integer_is_an_input_error(tmp_path, line, value):
    # found by the mutation test above: a POINTS or WIDTH line with no value raised IndexError
    path = tmp_path / "count.pcd"
    header = {b"WIDTH": b"2", b"HEIGHT": b"1", b"POINTS": b"2"}
    header[line] = value
    if line == b"WIDTH":
        del header[b"POINTS"]  # WIDTH x HEIGHT counts only without POINTS
    body = b"".join(key + (b" " + v if v else b"") + b"\n" for key, v in header.items())
    path.write_bytes(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n" + body + b"DATA ascii\n1 2 3\n4 5 6\n")
    with pytest.raises(InputError, match="POINTS, WIDTH or HEIGHT line without an integer"):
        read_points(path)


def test_a_pcd_count_beyond_the_file_is_an_input_error_not_an_out_of_memory_kill(tmp_path):
    # found by the mutation test above in a CI run: COUNT 9999999999991 built that many column
    # names and the kernel killed the test process (24 GB)
    path = tmp_path / "count.pcd"
    path.write_bytes(
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 9999999999991 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
        b"DATA ascii\n1 2 3\n4 5 6\n"
    )
    declared = r"COUNT line declares 9999999999993 values per point, more than the file's 108 bytes"
    with pytest.raises(InputError, match=declared):
        read_points(path)


def test_a_cell_beyond_the_csv_modules_limit_is_an_input_error(tmp_path):
    # the csv module's own error (not a ValueError, no path) came through
    path = tmp_path / "long.csv"
    path.write_bytes(b"1," + b"2" + b" " * 200_000 + b"\n3,4\n")
    with pytest.raises(InputError, match=r"long\.csv: a line could not be split into cells: field larger"):
        read_points(path)


@pytest.mark.parametrize(
    ("counts", "got"),
    [("POINTS -1", "POINTS -1"), ("WIDTH -2\nHEIGHT -1", "WIDTH -2, HEIGHT -1")],
)
@pytest.mark.parametrize("n_values", [6, 7])
def test_a_pcd_with_a_negative_point_count_is_an_input_error(tmp_path, counts, got, n_values):
    # numpy reads count -1 as "all": the records were read whole, or its bare error came out
    path = tmp_path / "cloud.pcd"
    header = f"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n{counts}\nDATA binary\n".encode()
    path.write_bytes(header + np.arange(n_values, dtype="<f4").tobytes())
    with pytest.raises(InputError, match=f"cloud.pcd: the PCD header's point counts must not be negative; got {got}"):
        read_points(path)


def test_a_signalling_nan_is_refused_without_a_warning(tmp_path):
    snan = np.array([0x7FA00000, 0x3F800000, 0x40000000], "<u4").view("<f4").reshape(1, 3)
    np.save(tmp_path / "p.npy", np.vstack([snan, np.ones((3, 3), np.float32)]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match="NaN"):
            read_points(tmp_path / "p.npy")
