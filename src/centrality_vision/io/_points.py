"""Point sets in and out: delimited text, XYZ, NumPy, MATLAB, PLY, PCD and OBJ files.

Every reader turns a file into a *table*: a float64 array with one row per point and,
where the format names them, the names of its columns (a CSV header, the PLY vertex
properties, the PCD fields). One rule then picks the coordinates from the table (see
:func:`read_points`), so ``columns=`` works the same for every format.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
import re
import struct
import warnings
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validation import _describe, check_bool, counted, is_real_dtype, nearest_existing
from ..exceptions import InputError

__all__ = ["POINT_SUFFIXES", "WRITE_SUFFIXES", "read_points", "write_points"]

#: Suffixes :func:`read_points` reads (case-insensitive).
POINT_SUFFIXES = (".txt", ".csv", ".tsv", ".xyz", ".npy", ".mat", ".ply", ".pcd", ".obj")
#: Suffixes :func:`write_points` writes.
WRITE_SUFFIXES = (".txt", ".csv", ".xyz", ".npy", ".mat", ".ply", ".pcd", ".obj")
_TEXT_SUFFIXES = (".txt", ".csv", ".tsv", ".xyz")
_THREE_D_ONLY = (".ply", ".pcd", ".obj")
# (the command line shows a backticked parameter as its option: `columns` as --columns)
_COLUMNS_HINT = "; pick the coordinates with `columns`"
_INDEX_NAMES = ("", "index", "idx", "id", "i", "node", "unnamed: 0", "point", "point_id")


@dataclass
class _Table:
    """What a reader found: values (n_rows, n_columns), column names or None, and where rows came from."""

    values: np.ndarray
    names: list[str] | None = None
    lines: np.ndarray | None = None  # line number of each row in a text file
    # text files: a column -> the message naming its first cell that is not a number (the
    # cell is NaN in ``values``), and the columns of labels: every cell empty or with a letter
    not_numbers: dict[int, str] = dataclasses.field(default_factory=dict)
    text_columns: frozenset[int] = frozenset()

    def where(self, row: int) -> str:
        return f"line {int(self.lines[row])}" if self.lines is not None else f"row {row}"


def _existing_file(path) -> Path:
    if not isinstance(path, (str, Path)) and not hasattr(path, "__fspath__"):
        raise TypeError(f"`path` must be a str or os.PathLike; got {_describe(path)}.")
    if os.fspath(path) == "":
        raise InputError("`path` must name a file; got an empty path.")
    path = Path(path)
    try:
        exists = path.exists()
    except OSError as exc:  # a name longer than the file system allows, ...
        raise InputError(f"{_clip(str(path), 200)}: cannot be read ({exc.strerror or exc}).") from None
    if not exists:
        raise InputError(f"{path}: no such file.")
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a file.")
    return path


def read_points(
    path,
    /,
    *,
    columns: Sequence[str | int] | str | None = None,
    variable: str | None = None,
    n_dims: Sequence[int] = (2, 3),
    nan_rows: bool = False,
) -> np.ndarray:
    """Read a point set as a float64 array of shape (n_points, n_dims), one point per row.

    The format follows the suffix (case-insensitive):

    ``.csv``, ``.txt``, ``.tsv``, ``.xyz``
        Delimited text. The delimiter is the first of semicolon, tab and comma found on
        every line, else runs of spaces; a semicolon file may use decimal commas
        (``0,5;1,5``).
        Blank lines and lines starting with ``#`` are skipped, a UTF-8 byte-order mark is
        ignored. The first line is a header when *none* of its cells is a number and one
        holds a letter (e.g. ``x,y,z,intensity`` or pandas' ``,x,y`` with an index
        column); a first line with some numbers and some words is data, and a first line
        with cells that are neither (``1,5 2,5`` in a file split by spaces) is an error,
        never silently dropped. A cell that is not a number (a label, an empty note) is
        an error only in a column picked as a coordinate.
    ``.npy``
        A 2D numeric array saved with :func:`numpy.save` (no pickles). The header's shape
        is checked against the file size before anything is loaded.
    ``.mat``
        A MATLAB file up to v7 (v7.3 is HDF5 and refused). Level-5 files (MATLAB 5 to
        7) are parsed here, every byte count checked, because :func:`scipy.io.loadmat`
        can crash the interpreter on a damaged one; level-4 files are read by
        :func:`scipy.io.loadmat`. Real numeric 2D arrays are candidates (logical ones,
        masks, are not coordinates);
        ``variable`` names the array, needed only when the file holds more than one.
    ``.ply``
        The vertex element of an ASCII or binary PLY file (both parsed here); its scalar
        properties (``x``, ``y``, ``z``, ``intensity``, ...) are the columns, in the
        file's order, and list properties are skipped.
    ``.pcd``
        A Point Cloud Library file, ``DATA ascii`` or ``binary`` (``binary_compressed``
        is refused); its ``FIELDS`` are the columns.
    ``.obj``
        The ``v`` (vertex) lines of a Wavefront OBJ file; faces, normals and texture
        coordinates are ignored, and so are a vertex's optional weight or colour.

    The coordinates are then picked from the file's columns: ``columns`` if given; else
    the columns named ``x``, ``y`` (and ``z`` if present), whatever their case, when the
    file names its columns; else every column, after dropping a leading index column
    (named ``""``, ``index``, ``id``, ``node``, ``Unnamed: 0``, ...) where the columns
    left are a point of ``n_dims`` coordinates (so ``i,j`` is read as two); a column in
    which every cell is empty or holds a letter (a label) is left out first. Other
    columns, such as an intensity, are ignored unless ``columns`` selects them. A file
    without a header whose first column holds the row numbers (0, 1, 2, ... or 1, 2, 3,
    ...) and whose other columns would make a point is read with that column as a
    coordinate, with a warning.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    columns : sequence of str or int, or str, optional
        The coordinate columns, by name (needs names in the file) or by 0-based index,
        e.g. ``["x", "y", "z"]``, ``[1, 2]`` or the string ``"x,y,z"``.
    variable : str, optional
        ``.mat`` only: the name of the array to read.
    n_dims : int or sequence of int, default=(2, 3)
        Allowed numbers of coordinates (each >= 1).
    nan_rows : bool, default=False
        Allow rows that are entirely NaN (e.g. to mark outliers that have no true
        position); a row with some but not all values NaN is still an error.

    Returns
    -------
    points : ndarray of shape (n_points, n_dims), float64

    Raises
    ------
    InputError
        Missing file, unknown suffix, unparsable values, ragged rows, a wrong number of
        columns, unknown ``columns``, NaN or inf values, or no points. The message is one
        line starting with the file's path.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "scan.csv"
    ...     _ = path.write_text("x;y;intensity\\n0;0,5;7\\n1;1,5;9\\n")
    ...     read_points(path).tolist()
    [[0.0, 0.5], [1.0, 1.5]]
    """
    columns = _check_columns(columns)
    if variable is not None and not isinstance(variable, str):
        raise TypeError(f"`variable` must be a str or None; got {_describe(variable)}.")
    n_dims = _check_n_dims(n_dims)
    check_bool(nan_rows, name="nan_rows")
    path = _existing_file(path)
    suffix = path.suffix.lower()
    if suffix not in POINT_SUFFIXES:
        raise InputError(f"{path}: a point set must be a {', '.join(POINT_SUFFIXES)} file; got suffix {path.suffix!r}.")
    if variable is not None and suffix != ".mat":
        raise InputError(f"{path}: `variable` applies to .mat files only; got a {suffix} file.")
    reader = {".npy": _read_npy, ".mat": _read_mat, ".ply": _read_ply, ".pcd": _read_pcd, ".obj": _read_obj}
    with np.errstate(invalid="ignore"):  # a signalling NaN cast to float64 warns; it is refused below as NaN
        table = reader[suffix](path, variable) if suffix == ".mat" else reader.get(suffix, _read_text)(path)
    if table.values.shape[0] == 0:
        raise InputError(f"{path}: holds no points.")
    picked = _pick_columns(path, table, columns, n_dims)
    points = np.ascontiguousarray(table.values[:, picked], dtype=np.float64)
    finite = np.isfinite(points)
    bad = ~finite.all(axis=1)
    if nan_rows:
        bad &= ~np.isnan(points).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        allowed = " (rows that are entirely NaN are allowed)" if nan_rows else ""
        raise InputError(
            f"{path}: {int(bad.sum())} point(s) with NaN or inf, the first at {table.where(row)}{allowed}."
        )
    return points


def _check_n_dims(n_dims) -> tuple[int, ...]:
    """``n_dims`` as a tuple of positive ints (an int alone is one allowed count)."""
    if isinstance(n_dims, (int, np.integer)) and not isinstance(n_dims, (bool, np.bool_)):
        n_dims = (n_dims,)
    if isinstance(n_dims, (str, bytes)) or not hasattr(n_dims, "__iter__"):
        raise TypeError(
            f"`n_dims` must be a sequence of ints (the allowed numbers of coordinates); got {_describe(n_dims)}."
        )
    values = tuple(n_dims)
    if any(isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) for v in values):
        raise TypeError(f"`n_dims` must be a sequence of ints; got {values!r}.")
    if not values or min(values) < 1:
        raise InputError(f"`n_dims` must hold at least one number of coordinates, each >= 1; got {values!r}.")
    return tuple(int(v) for v in values)


def _check_columns(columns):
    if columns is None:
        return None
    if isinstance(columns, str):
        columns = [part.strip() for part in columns.split(",")]
    try:
        items = list(columns)
    except TypeError:
        raise TypeError(
            f"`columns` must be a sequence of names or indices, or None; got {_describe(columns)}."
        ) from None
    out = []
    for item in items:
        if isinstance(item, (int, np.integer)) and not isinstance(item, bool):
            out.append(int(item))
        elif isinstance(item, str) and item:
            # (a header names no column "-1": a cell that is a number makes its line data)
            out.append(int(item) if re.fullmatch(r"-?\d+", item) else item)
        elif isinstance(item, str):
            raise InputError(f"`columns` must not hold an empty name; got {columns!r}.")
        else:
            raise TypeError(f"`columns` must hold column names or 0-based indices; got {item!r} in {columns!r}.")
    if not out:
        raise InputError("`columns` must name at least one column; got none.")
    if len(set(out)) != len(out):
        raise InputError(f"`columns` must not repeat a column; got {columns!r}.")
    return out


def _named_column(path: Path, lower: list[str], name: str, shown: str) -> int:
    """The index of the one column called ``name`` (case-insensitive); an error when the header repeats it."""
    found = [index for index, other in enumerate(lower) if other == name.lower()]
    if len(found) > 1:
        raise InputError(
            f"{path}: the header names {len(found)} columns {name!r} (indices {', '.join(map(str, found))}){shown}; "
            "pick the coordinates by 0-based index with `columns`."
        )
    return found[0]


def _pick_columns(path: Path, table: _Table, columns, n_dims) -> list[int]:
    n_columns = table.values.shape[1]
    names = table.names
    shown = f" ({', '.join(repr(name) for name in names)})" if names else ""
    if columns is not None:
        picked = []
        lower = [name.lower() for name in names] if names else None
        for item in columns:
            if isinstance(item, int):
                if not 0 <= item < n_columns:
                    raise InputError(
                        f"{path}: `columns` index {item} is out of range; the file has {n_columns} columns{shown}."
                    )
                picked.append(item)
            elif lower is None:
                raise InputError(
                    f"{path}: `columns` names {item!r} but the file names no columns; use 0-based indices."
                )
            elif item.lower() not in lower:
                raise InputError(f"{path}: `columns` names {item!r}, which is not a column of the file{shown}.")
            else:
                picked.append(_named_column(path, lower, item, shown))
    else:
        lower = [name.lower() for name in names] if names else []
        if "x" in lower and "y" in lower:
            picked = [_named_column(path, lower, axis, shown) for axis in ("x", "y", "z") if axis in lower]
        else:
            # (a column of labels or of empty cells is no coordinate)
            picked = [j for j in range(n_columns) if j not in table.text_columns]
            if names and len(picked) > 1 and lower[picked[0]] in _INDEX_NAMES and len(picked) - 1 in n_dims:
                picked = picked[1:]
    for j in picked:
        if j in table.not_numbers:
            # (choosing columns helps only where the file has other columns to choose)
            hint = _COLUMNS_HINT if columns is None and n_columns > min(n_dims) else ""
            raise InputError(f"{table.not_numbers[j]}{hint}.")
    if columns is None and not names and len(picked) - 1 in n_dims and len(picked) in n_dims:
        _warn_row_numbers(path, table, picked)
    wanted = " or ".join(str(d) for d in n_dims)
    if len(picked) not in n_dims:
        # (choosing columns helps only where the file has more of them than wanted)
        hint = "" if columns is not None or len(picked) < min(n_dims) else _COLUMNS_HINT
        if columns is not None and names:  # the picked columns, not all the file's
            shown = f" ({', '.join(repr(names[j]) for j in picked)})"
        raise InputError(
            f"{path}: points must have {wanted} coordinates; got {counted(len(picked), 'column')}{shown}{hint}."
        )
    return picked


def _warn_row_numbers(path: Path, table: _Table, picked: list[int]) -> None:
    """Warn where a file without a header starts with the row numbers (0, 1, 2, ... or 1, 2,
    3, ...; pandas' ``to_csv(header=False)`` writes them): they are read as a coordinate, as
    the file says nothing else, but a set whose first coordinate counts its rows is rare."""
    first = table.values[:, picked[0]]
    n_rows = first.shape[0]
    if n_rows < 3:
        return
    steps = np.arange(n_rows, dtype=np.float64)
    if np.array_equal(first, steps) or np.array_equal(first, steps + 1):
        rest = ", ".join(str(j) for j in picked[1:])
        warnings.warn(
            f"{path}: column {picked[0] + 1} holds the row numbers {first[0]:.0f}, {first[1]:.0f}, ..., "
            f"{first[-1]:.0f}, read as a coordinate; if it is an index, pick the coordinates with `columns` "
            f"(0-based: {rest}).",
            UserWarning,
            stacklevel=4,  # read_points' caller
        )


# ------------------------------------------------------------------------------- text


# ASCII digits only: Python's float() also reads "1_000" and other scripts' digits, which a
# point file never means
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*([eE][+-]?\d+)?|\.\d+([eE][+-]?\d+)?|nan|inf|infinity)", re.IGNORECASE | re.ASCII)


def _ragged(path: Path, rows, split, names, width: int):
    """Raise the error of rows of unequal length, naming the first line that differs from the
    header, or without one from most rows (the first line may be the odd one out; a row with
    a '#' cell, a comment after the values, counts only where every row has one)."""
    cells = [split(line) for _, line in rows]
    widths = [len(row) for row in cells]
    commented = [any(cell.strip().startswith("#") for cell in row) for row in cells]
    if names is None:
        counts = {}
        for length, comment in zip(widths, commented):
            if not comment or all(commented):
                counts[length] = counts.get(length, 0) + 1
        width = max(counts, key=lambda length: (counts[length], length == widths[0]))
    k = next(k for k, length in enumerate(widths) if length != width)
    number = rows[k][0]
    before = "the header" if names is not None else "the other rows" if k == 0 else "the rows before it"
    hint = " (a '#' after the values starts no comment: a comment takes a line of its own)" if commented[k] else ""
    raise InputError(f"{path}: line {number} has {counted(widths[k], 'value')}, {before} {width}{hint}.")


def _read_text(path: Path) -> _Table:
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file of numbers (it is not UTF-8 text).") from None
    if "\x00" in text:
        raise InputError(f"{path}: not a text file of numbers (it holds NUL bytes).")
    rows = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise InputError(f"{path}: holds no points.")
    split, decimal_comma, delimiter = _sniff([line for _, line in rows[:64]], path)
    first_number, first = rows[0]
    cells = split(first)
    numeric = [_is_number(cell, decimal_comma) for cell in cells]
    names = None
    if not any(numeric):
        if not any(_LETTER.search(cell) for cell in cells):
            # no cell is a number and none is a name: numbers written some other way (a
            # decimal comma in a file split by spaces), not a header to drop
            raise InputError(
                f"{path}: line {first_number}, column 1: {_clip(cells[0].strip())!r} is not a number"
                f"{_comma_hint(cells[0])}."
            )
        names = [cell.strip().strip('"') for cell in cells]
        rows = rows[1:]
        if not rows:
            raise InputError(f"{path}: holds no points (only the header line {first_number}).")
    width = len(names) if names is not None else len(cells)
    lines = np.array([number for number, _ in rows])
    if not decimal_comma:  # the fast path; on any doubt the loop below finds and names the bad cell
        try:
            values = np.loadtxt(
                [line for _, line in rows], delimiter=delimiter, dtype=np.float64, ndmin=2, comments=None, quotechar='"'
            )
        except ValueError:
            values = None
        if values is not None and values.shape == (len(rows), width):
            return _Table(values, names, lines)
    # a cell that is not a number is an error only in a column picked as a coordinate (a
    # label or an empty note column beside the coordinates is ignored, as a numeric one is)
    values = np.empty((len(rows), width), dtype=np.float64)
    not_numbers: dict[int, str] = {}
    counts = np.zeros(width, dtype=np.int64)
    for k, (number, line) in enumerate(rows):
        cells = split(line)
        if len(cells) != width:
            _ragged(path, rows, split, names, width)
        for j, cell in enumerate(cells):
            try:
                values[k, j] = _to_float(cell, decimal_comma)
            except (_NotANumber, ValueError):
                values[k, j] = np.nan
                # (a label holds a letter; "1_000" or "1,5" is a number written wrongly)
                counts[j] += bool(_LETTER.search(cell)) or not cell.strip()
                if j not in not_numbers:
                    if not cell.strip() and delimiter:
                        why = f"an empty cell (a '{delimiter}' too many?)"
                    else:
                        first_line = k == 0 and names is None
                        header_hint = " (a header line must name every column)" if first_line else ""
                        why = f"{_clip(cell.strip())!r} is not a number" + (_comma_hint(cell) or header_hint)
                    not_numbers[j] = f"{path}: line {number}, column {j + 1}: {why}"
    text_columns = frozenset(int(j) for j in np.flatnonzero(counts == len(rows)))
    return _Table(values, names, lines, not_numbers, text_columns)


# a header cell names something: it holds a letter ('x', 'intensity'; nan and inf are numbers)
_LETTER = re.compile(r"[^\W\d_]")
_DECIMAL_COMMA = re.compile(r"\s*[+-]?\d*,\d+([eE][+-]?\d+)?\s*")


def _comma_hint(cell: str) -> str:
    """Why a cell such as '1,5' was not read as 1.5, or ''."""
    if _DECIMAL_COMMA.fullmatch(cell):
        return " (decimal commas are read only in files whose cells are separated by ';' on every line)"
    return ""


def _sniff(sample: list[str], path: Path):
    """The cell splitter of a text file and whether it writes decimal commas.

    The delimiter is the first of semicolon, tab and comma that occurs on every sampled
    line, else runs of whitespace. (:class:`csv.Sniffer` was tried first: on a few short
    lines, such as a header and a row with an empty cell, it picks a wrong delimiter.)
    """
    delimiter = next((d for d in (";", "\t", ",") if all(d in line for line in sample)), " ")
    if delimiter == " ":
        # a semicolon or comma on half the lines or more but not all: a ragged file, whose
        # short line the row check names (split by whitespace, a good line was blamed: '1,2'
        # is not a number, or taken for a header)
        delimiter = next((d for d in (";", ",") if 2 * sum(d in line for line in sample) >= len(sample) >= 2), " ")
    if delimiter == " ":
        return (lambda line: line.split()), False, None
    decimal_comma = delimiter == ";" and any("," in line for line in sample)

    def split(line: str) -> list[str]:
        try:
            return next(csv.reader([line], delimiter=delimiter, skipinitialspace=True))
        except csv.Error as exc:  # e.g. a cell longer than the csv module's limit
            raise InputError(f"{path}: a line could not be split into cells: {exc}.") from None

    return split, decimal_comma, delimiter


class _NotANumber(ValueError):
    """Internal: a text cell is not a number; the readers turn it into an InputError naming the cell."""


def _to_float(cell: str, decimal_comma: bool) -> float:
    cell = cell.strip().strip('"')
    if decimal_comma:
        cell = cell.replace(",", ".")
    return _number_word(cell)


def _number_word(word: str) -> float:
    """A word of a point file as a float; _NotANumber (a ValueError) if it is not a number."""
    if not _NUMBER.fullmatch(word):
        raise _NotANumber(word)
    return float(word)


def _numpy_rows(lines: list[str]) -> np.ndarray:
    """Lines of whitespace-separated numbers as a float array, at numpy's speed; ValueError
    on any doubt (ragged rows, a word that is not a number, or a "_", which numpy reads as
    Python does: "1_000" is 1000)."""
    if any("_" in line for line in lines):
        raise _NotANumber("_")
    return np.array([line.split() for line in lines], dtype=np.float64)


def _is_number(cell: str, decimal_comma: bool) -> bool:
    try:
        _to_float(cell, decimal_comma)
    except _NotANumber:
        return False
    return True


# ------------------------------------------------------------------------------- .npy


def _read_npy(path: Path) -> _Table:
    """Check the header (dtype, shape against the file size) before loading anything."""
    with path.open("rb") as handle:
        try:
            version = np.lib.format.read_magic(handle)
            reader = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
            if version not in reader:
                raise InputError(f"format version {version}")  # re-raised below with the file's name
            shape, fortran_order, dtype = reader[version](handle, max_header_size=10_000)
        except Exception as exc:  # ValueError, EOFError, SyntaxError, tokenize.TokenError, ...
            raise InputError(f"{path}: not a readable .npy array ({_first_line(exc)}).") from None
        offset = handle.tell()
    if dtype.kind == "b":  # as the API refuses boolean coordinates
        raise InputError(f"{path}: must hold coordinates (real numbers); got dtype bool (a mask?).")
    if np.issubdtype(dtype, np.complexfloating):
        raise InputError(f"{path}: must hold real numbers; got dtype {dtype}.")
    if not is_real_dtype(dtype):
        raise InputError(f"{path}: must hold a numeric array; got dtype {dtype}.")
    if len(shape) != 2:
        raise InputError(f"{path}: must hold a 2D array (one point per row); got shape {shape}.")
    if min(shape) < 0:
        raise InputError(f"{path}: not a readable .npy array (its header gives the negative shape {shape}).")
    needed = math.prod(shape) * dtype.itemsize
    available = path.stat().st_size - offset
    if needed != available:
        raise InputError(
            f"{path}: the header announces shape {shape} of {dtype} ({needed} bytes) "
            f"but the file holds {available} bytes of data."
        )
    array = np.load(path, allow_pickle=False, mmap_mode="r")
    with np.errstate(over="ignore"):  # long doubles beyond float64: named below
        values = np.array(array, dtype=np.float64)
    if dtype.kind == "f" and dtype.itemsize > 8 and np.any(np.isinf(values) & np.isfinite(array)):
        raise InputError(f"{path}: holds {dtype} values beyond the float64 range (|x| > 1.8e308).")
    return _Table(values)


# ------------------------------------------------------------------------------- .mat


# Level-5 MAT files (MATLAB 5 to 7.0) are read here rather than by scipy's loadmat: its
# compiled reader trusts the byte counts and flags of a file, so a damaged one (a complex
# flag with no imaginary part, an unknown data type, a count past the end) crashes the
# interpreter; about one in 300 random byte edits of a small file did. This reader takes
# what read_points needs (real numeric arrays), names every other variable,
# and checks every count against the bytes there are. Level 4 files go to loadmat, whose
# level-4 reader is plain Python.

# data types (MAT-File Format, table 1-1) -> numpy type codes; 14 is miMATRIX, 15 miCOMPRESSED
_MI_NUMERIC = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 9: "f8", 12: "i8", 13: "u8"}
_MI_TYPES = frozenset(_MI_NUMERIC) | {14, 15, 16, 17, 18}
_MI_MATRIX, _MI_COMPRESSED = 14, 15
# array classes (table 1-3); 6 to 15 are numeric
_MX_CLASSES = {
    1: "cell array",
    2: "struct",
    3: "object",
    4: "char array",
    5: "sparse matrix",
    **{
        k: f"{name} array"
        for k, name in enumerate(
            ("double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"), start=6
        )
    },
    16: "function handle",
    17: "opaque object",
}
_MX_LOGICAL, _MX_COMPLEX = 0x200, 0x800


@dataclass
class _MatVariable:
    name: str
    what: str  # "a MATLAB double array of shape (3, 2)"
    values: np.ndarray | None  # set for 2D real numeric and logical arrays only


class _Mat5:
    """One pass over a level-5 MAT file's variables; InputError on any damage."""

    def __init__(self, path: Path, data: bytes):
        self.path = path
        if data[126:128] not in (b"IM", b"MI"):
            raise self.error(126, f"the byte-order mark is {data[126:128]!r}, not b'IM' or b'MI'")
        self.order = "<" if data[126:128] == b"IM" else ">"
        self.data = data

    def error(self, at, what: str) -> InputError:
        return InputError(f"{self.path}: not a readable .mat file (byte {at}: {what}).")

    def elements(self, buffer: bytes, start: int, end: int, where: str):
        """(type, body start, body length, where) of each data element in buffer[start:end]."""
        offset = start
        while offset < end:
            at = f"{where}{offset}"
            if offset + 8 > end:
                raise self.error(at, f"a data element needs 8 bytes, {end - offset} left")
            kind, nbytes = struct.unpack_from(self.order + "II", buffer, offset)
            if kind >> 16:  # small data element: type and count share the first 4 bytes
                kind, nbytes = kind & 0xFFFF, kind >> 16
                if nbytes > 4 or kind not in _MI_TYPES or kind in (_MI_MATRIX, _MI_COMPRESSED):
                    raise self.error(at, f"a small data element of type {kind} holding {nbytes} bytes")
                yield kind, offset + 4, nbytes, at
                offset += 8
                continue
            if kind not in _MI_TYPES:
                raise self.error(at, f"unknown data type {kind}")
            if nbytes > end - offset - 8:
                raise self.error(at, f"{nbytes} bytes declared, {end - offset - 8} left")
            yield kind, offset + 8, nbytes, at
            offset += 8 + nbytes + (0 if kind == _MI_COMPRESSED else -nbytes % 8)

    def variables(self):
        for kind, body, nbytes, at in self.elements(self.data, 128, len(self.data), ""):
            if kind == _MI_COMPRESSED:
                inflater = zlib.decompressobj()
                try:
                    # zlib compresses at most ~1032:1; a stream that expands more is damaged
                    inner = inflater.decompress(self.data[body : body + nbytes], 1032 * nbytes + 1024)
                except zlib.error as exc:
                    raise self.error(at, f"compressed data: {exc}") from None
                if inflater.unconsumed_tail:
                    raise self.error(at, f"{nbytes} compressed bytes expand more than zlib can")
                for inner_kind, inner_body, inner_nbytes, inner_at in self.elements(
                    inner, 0, len(inner), f"{at}, compressed byte "
                ):
                    if inner_kind == _MI_MATRIX:
                        yield self.variable(inner, inner_body, inner_nbytes, inner_at)
            elif kind == _MI_MATRIX:
                yield self.variable(self.data, body, nbytes, at)

    def variable(self, buffer: bytes, body: int, nbytes: int, at: str) -> _MatVariable:
        parts = iter(self.elements(buffer, body, body + nbytes, at + ", array byte "))

        def next_part(what: str):
            part = next(parts, None)
            if part is None:
                raise self.error(at, f"the array ends before its {what}")
            return part

        kind, start, size, where = next_part("flags")
        if kind != 6 or size != 8:
            raise self.error(where, "an array must start with 8 bytes of miUINT32 flags")
        flags = int(np.frombuffer(buffer, self.order + "u4", 1, start)[0])
        mx_class = flags & 0xFF
        if mx_class not in _MX_CLASSES:
            raise self.error(where, f"unknown array class {mx_class}")
        what = "a MATLAB " + _MX_CLASSES[mx_class]
        if mx_class == 17:  # no dimensions in an opaque object
            return _MatVariable(self.name(buffer, *next_part("name")), what, None)
        kind, start, size, where = next_part("dimensions")
        if kind not in (5, 6) or size < 8 or size % 4:  # some writers use miUINT32
            raise self.error(where, "an array's dimensions must be two or more 32-bit integers")
        shape = tuple(int(d) for d in np.frombuffer(buffer, self.order + "i4", size // 4, start))
        if min(shape) < 0:
            raise self.error(where, f"negative dimensions {shape}")
        name = self.name(buffer, *next_part("name"))
        if mx_class in (5, 16) or mx_class < 4:
            return _MatVariable(name, f"{what} of shape {shape}", None)
        complex_ = bool(flags & _MX_COMPLEX)
        logical = bool(flags & _MX_LOGICAL)
        if complex_ or logical:
            what = "a MATLAB complex " + _MX_CLASSES[mx_class] if complex_ else "a MATLAB logical array"
        what += f" of shape {shape}"
        if mx_class == 4:
            return _MatVariable(name, what, None)
        n_values = math.prod(shape)
        for part in ("real part", "imaginary part") if complex_ else ("data",):
            kind, start, size, where = next_part(part)
            if kind not in _MI_NUMERIC:
                raise self.error(where, f"the {part} of an array in data type {kind}")
            if size != n_values * int(_MI_NUMERIC[kind][1]):
                raise self.error(
                    where, f"{what} needs {n_values} values; its {part} holds {size} bytes of {_MI_NUMERIC[kind]}"
                )
            if part == "data" and len(shape) == 2:
                values = np.frombuffer(buffer, self.order + _MI_NUMERIC[kind], n_values, start).reshape(
                    shape, order="F"
                )
                return _MatVariable(name, what, None if logical else values.astype(np.float64))
        return _MatVariable(name, what, None)

    def name(self, buffer: bytes, kind: int, start: int, size: int, where: str) -> str:
        if kind not in (1, 2, 16):
            raise self.error(where, f"an array name of data type {kind}")
        try:
            return bytes(buffer[start : start + size]).decode("utf-8")
        except UnicodeDecodeError:
            raise self.error(where, "an array name that is not text") from None


def _read_mat(path: Path, variable: str | None) -> _Table:
    from scipy.io import loadmat
    from scipy.io.matlab import matfile_version

    try:
        major, _ = matfile_version(path)
    except Exception as exc:  # scipy raises MatReadError, ValueError, ...
        raise InputError(f"{path}: not a readable .mat file ({type(exc).__name__}: {_first_line(exc)}).") from None
    if major == 2:
        raise InputError(f"{path}: MATLAB v7.3 (HDF5) files are not supported; save with -v7 (or read it with h5py).")
    if major == 1:
        found = {v.name: v for v in _Mat5(path, path.read_bytes()).variables() if v.name}
    else:  # level 4
        try:
            contents = loadmat(path)
        except Exception as exc:  # scipy raises ValueError, TypeError, MatReadError, ...
            raise InputError(f"{path}: not a readable .mat file ({type(exc).__name__}: {_first_line(exc)}).") from None
        found = {}
        for key, value in contents.items():
            if not key.startswith("__"):
                readable = isinstance(value, np.ndarray) and value.ndim == 2
                readable = readable and is_real_dtype(value.dtype, bool_ok=False)
                found[key] = _MatVariable(key, _describe(value), value if readable else None)
    arrays = {name: v.values for name, v in found.items() if v.values is not None}
    if variable is not None:
        if variable not in found:
            names = ", ".join(sorted(found)) or "none"
            raise InputError(f"{path}: no variable {variable!r} (variables: {names}).")
        if variable not in arrays:
            raise InputError(
                f"{path}: variable {variable!r} must be a 2D real numeric array; got {found[variable].what}."
            )
        return _Table(arrays[variable].astype(np.float64))
    if not arrays:
        listed = "; ".join(f"{name!r}: {found[name].what}" for name in sorted(found)) or "none"
        raise InputError(f"{path}: holds no 2D real numeric array to read as points (variables: {listed}).")
    if len(arrays) != 1:
        names = ", ".join(sorted(arrays))
        raise InputError(f"{path}: name the variable to read with `variable`; 2D numeric arrays in the file: {names}.")
    return _Table(next(iter(arrays.values())).astype(np.float64))


# ------------------------------------------------------------------------------- .ply


# numpy's codes of the PLY scalar types
_PLY_CODES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
_PLY_SIZES = {kind: np.dtype(code).itemsize for kind, code in _PLY_CODES.items()}


def _ply_header(path: Path, data: bytes):
    """The format, the elements ``[name, count, [(property, count_type, type), ...]]`` and the
    body offset (``count_type``: a list's count type, None for a scalar; ``type``: a scalar's,
    or a list's item type).

    The vertex count is checked against the bytes that follow the header (a binary
    element takes at least its scalar sizes, a list at least its count's bytes).
    """
    # the line that is "end_header" (a comment may hold the words)
    found = re.search(rb"^end_header[ \t]*\r?$", data, flags=re.MULTILINE)
    end = found.start() if found else -1
    if not data.startswith(b"ply") or end < 0:
        raise InputError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header).")
    header = data[:end].decode("ascii", errors="replace").splitlines()
    if header[0].strip() != "ply":
        raise InputError(f"{path}: not a readable PLY file (its first line is not 'ply').")
    newline = data.find(b"\n", end)
    body_offset = newline + 1 if newline >= 0 else len(data)
    body = len(data) - body_offset
    fmt, elements, sizes = "", [], []
    for line in header:
        words = line.split()
        if words[:1] == ["format"] and len(words) > 1:
            fmt = words[1]
        elif words[:1] == ["element"]:
            # a damaged count would drop the element and give its properties to the one
            # before: a binary body then read with the wrong record size
            if len(words) != 3 or not (words[2].isascii() and words[2].isdigit()):
                raise InputError(
                    f"{path}: not a readable PLY file (a damaged element line: {_clip(line)!r}; "
                    "expected 'element NAME COUNT' with COUNT a whole number)."
                )
            elements.append([words[1], int(words[2]), []])
            sizes.append(0)
        elif words[:1] == ["property"]:
            if not elements:
                raise InputError(
                    f"{path}: not a readable PLY file (a property line before any element: {_clip(line)!r})."
                )
            # a list property takes at least its count's bytes, a scalar its size
            is_list = words[1:2] == ["list"]
            types = words[2:4] if is_list else words[1:2]
            if (
                len(words) != (5 if is_list else 3)
                or not all(kind in _PLY_SIZES for kind in types)
                or (is_list and _PLY_CODES[types[0]][0] == "f")  # a list's count is an integer
            ):
                raise InputError(f"{path}: not a readable PLY file (a damaged property line: {_clip(line)!r}).")
            sizes[-1] += _PLY_SIZES[types[0]]
            elements[-1][2].append((words[-1], types[0] if is_list else None, types[-1]))
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise InputError(f"{path}: not a readable PLY file (unknown format {fmt!r}).")
    vertex = [element for element in elements if element[0] == "vertex"]
    if len(vertex) != 1:
        raise InputError(f"{path}: the PLY file must have one vertex element; got {len(vertex)}.")
    at_least = (
        sum(element[1] * size for element, size in zip(elements, sizes)) if fmt.startswith("binary") else vertex[0][1]
    )
    if at_least > body:
        raise InputError(
            f"{path}: the header declares {vertex[0][1]} vertices but the file holds only {body} bytes after it."
        )
    return fmt, elements, body_offset


def _read_ply(path: Path) -> _Table:
    """The vertex element, one column per scalar property in the file's order.

    Both encodings are parsed here: meshio's ASCII reader assumes the properties start
    with x, y, z and reads other orders wrongly, and its binary reader needs x, y and z
    and fails on a list property inside the vertex element.
    """
    data = path.read_bytes()
    fmt, elements, body_offset = _ply_header(path, data)
    vertex = next(element for element in elements if element[0] == "vertex")
    names = [name for name, count_type, _ in vertex[2] if count_type is None]
    if fmt == "ascii":
        return _read_ply_ascii(path, data[body_offset:], elements, names)
    order = "<" if fmt == "binary_little_endian" else ">"
    offset = body_offset
    for name, count, properties in elements:
        if name == "vertex":
            return _read_ply_binary(path, data, offset, order, count, properties)
        if all(count_type is None for _, count_type, _ in properties):
            offset += count * sum(_PLY_SIZES[kind] for _, _, kind in properties)
        else:
            for _ in range(count):
                offset = _ply_instance(path, data, offset, order, properties, None)
    raise AssertionError("unreachable: _ply_header checked the vertex element")  # pragma: no cover


def _ply_instance(path: Path, data: bytes, offset: int, order: str, properties, out: list | None) -> int:
    """Step over one binary element instance with list properties, appending its scalar
    values to ``out`` unless it is None; the offset after the instance."""
    for _, count_type, kind in properties:
        if count_type is None:
            value = _ply_scalar(path, data, offset, order, kind)
            if out is not None:
                out.append(float(value))
            offset += _PLY_SIZES[kind]
        else:
            length = int(_ply_scalar(path, data, offset, order, count_type))
            if length < 0:
                raise InputError(f"{path}: not a readable PLY file (a list property of length {length}).")
            offset += _PLY_SIZES[count_type] + length * _PLY_SIZES[kind]
            if offset > len(data):  # (a last list that runs past the end was read as whole)
                raise InputError(f"{path}: the file ends inside its elements (at byte {len(data)}).")
    return offset


def _ply_scalar(path: Path, data: bytes, offset: int, order: str, kind: str):
    if offset + _PLY_SIZES[kind] > len(data):
        raise InputError(f"{path}: the file ends inside its elements (at byte {len(data)}).")
    return np.frombuffer(data, dtype=order + _PLY_CODES[kind], count=1, offset=offset)[0]


def _read_ply_binary(path: Path, data: bytes, offset: int, order: str, count: int, properties) -> _Table:
    """A binary vertex element starting at ``offset``, its scalar properties in the file's order."""
    names = [name for name, count_type, _ in properties if count_type is None]
    if any(count_type is not None for _, count_type, _ in properties):  # rare: one instance at a time
        values = []
        for _ in range(count):
            offset = _ply_instance(path, data, offset, order, properties, values)
        return _Table(np.array(values, dtype=np.float64).reshape(count, len(names)), names)
    dtype = np.dtype([(f"p{k}", order + _PLY_CODES[kind]) for k, (_, _, kind) in enumerate(properties)])
    if offset + count * dtype.itemsize > len(data):
        raise InputError(
            f"{path}: the header declares {count} vertices of {dtype.itemsize} bytes but the file holds only "
            f"{max(0, len(data) - offset)} bytes for them."
        )
    records = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
    values = np.empty((count, len(properties)))
    for k in range(len(properties)):
        values[:, k] = records[f"p{k}"]
    return _Table(values, names)


def _read_ply_ascii(path: Path, body: bytes, elements, names: list[str]) -> _Table:
    """An ASCII PLY body: one line per element instance, elements in header order; a body of
    more lines than the header declares is refused (the header's count may be the wrong one)."""
    lines = [line for line in body.decode("ascii", errors="replace").splitlines() if line.strip()]
    declared = sum(count for _, count, _ in elements)
    if len(lines) > declared:
        counts = ", ".join(f"{count} {name}" for name, count, _ in elements)
        raise InputError(
            f"{path}: the header declares {declared} lines ({counts}) but the body holds {len(lines)}: "
            "is the header's count wrong?"
        )
    first = 0
    for name, count, properties in elements:
        if name != "vertex":
            first += count
            continue
        rows = lines[first : first + count]
        if len(rows) != count:
            raise InputError(f"{path}: the header declares {count} vertices but the file holds {len(rows)}.")
        if all(count_type is None for _, count_type, _ in properties):  # the usual case, at numpy's speed
            try:
                values = _numpy_rows(rows).reshape(count, -1)
            except ValueError:  # ragged or not numbers: the row-by-row reading below names the row
                values = None
            if values is not None and values.shape[1] == len(names):
                return _Table(values, names)
        values = np.empty((count, len(names)))
        for row, line in enumerate(rows):
            words, at, out = line.split(), 0, []
            try:
                for _, count_type, _ in properties:
                    if count_type is not None:  # a count, then that many items; a negative count: the row cannot match
                        length = int(words[at])
                        at = at + length + 1 if length >= 0 else len(words) + 1
                    else:
                        out.append(_number_word(words[at]))
                        at += 1
            except (IndexError, ValueError):
                at = -1
            if at != len(words):
                raise InputError(
                    f"{path}: vertex {row} is not a row of the header's {len(properties)} vertex properties: "
                    f"{_clip(line.strip())!r}."
                )
            values[row] = out
        return _Table(values, names)
    raise AssertionError("unreachable: _ply_header checked the vertex element")  # pragma: no cover


def _meshio():
    try:
        import meshio
        import meshio.ply
    except ImportError:  # pragma: no cover - meshio is a dependency
        raise ImportError("writing PLY files needs the meshio package: pip install meshio") from None
    return meshio


# ------------------------------------------------------------------------------- .pcd


_PCD_TYPES = {
    ("F", 4): "f4",
    ("F", 8): "f8",
    ("I", 1): "i1",
    ("I", 2): "i2",
    ("I", 4): "i4",
    ("I", 8): "i8",
    ("U", 1): "u1",
    ("U", 2): "u2",
    ("U", 4): "u4",
    ("U", 8): "u8",
}


def _read_pcd(path: Path) -> _Table:
    """PCD v0.7 (and v0.6/v0.5 headers): ASCII or binary data; the header fields name the columns.

    No maintained Python package reads PCD without pulling in a whole point-cloud
    library (Open3D, python-pcl), and the format is a short text header followed by
    rows or a packed array, so it is parsed here.
    """
    data = path.read_bytes()
    header: dict[str, list[str]] = {}
    offset = 0
    while True:
        end = data.find(b"\n", offset)
        if end < 0:
            raise InputError(f"{path}: not a PCD file (no DATA line in its header).")
        line = data[offset:end].decode("ascii", errors="replace").strip()
        offset = end + 1
        if not line or line.startswith("#"):
            continue
        key, *words = line.split()
        header[key.upper()] = words
        if key.upper() == "DATA":
            break
    fields = header.get("FIELDS") or header.get("COLUMNS")
    if not fields:
        raise InputError(f"{path}: not a PCD file (no FIELDS line in its header).")
    n = len(fields)
    sizes = header.get("SIZE", ["4"] * n)
    types = header.get("TYPE", ["F"] * n)
    counts = header.get("COUNT", ["1"] * n)
    try:
        sizes, counts = [int(s) for s in sizes], [int(c) for c in counts]
        counted = {key: int(header[key][0]) for key in ("POINTS", "WIDTH", "HEIGHT") if key in header}
        # (older headers: an organised cloud holds WIDTH x HEIGHT points)
        n_points = counted.get("POINTS", counted.get("WIDTH", 0) * counted.get("HEIGHT", 1))
    except (ValueError, IndexError):  # not a number, or a POINTS/WIDTH/HEIGHT line with none
        raise InputError(
            f"{path}: the PCD header has a SIZE, COUNT, POINTS, WIDTH or HEIGHT line without an integer."
        ) from None
    negative = [f"{key} {value}" for key, value in counted.items() if value < 0]
    if negative:
        raise InputError(f"{path}: the PCD header's point counts must not be negative; got {', '.join(negative)}.")
    if not (len(sizes) == len(types) == len(counts) == n) or min(counts) < 1:
        raise InputError(f"{path}: the PCD header's FIELDS, SIZE, TYPE and COUNT lines do not match.")
    if n_points == 0:
        raise InputError(f"{path}: holds no points (its header declares 0).")
    if sum(counts) > len(data):
        # (a point's values take a byte each at least, and their header a byte per count: a
        # damaged COUNT of 1e13 built that many names and ran the machine out of memory)
        raise InputError(
            f"{path}: the PCD header's COUNT line declares {sum(counts)} values per point, more than the "
            f"file's {len(data)} bytes."
        )
    names = []
    for field, count in zip(fields, counts):
        names += [field] if count == 1 else [f"{field}_{k}" for k in range(count)]
    mode = header["DATA"][0].lower() if header["DATA"] else ""
    if mode == "ascii":
        text = data[offset:].decode("ascii", errors="replace")
        lines = [line for line in text.splitlines() if line.strip()]
        if len(lines) != n_points:
            raise InputError(f"{path}: the header declares {n_points} points but the file holds {len(lines)} rows.")
        try:
            values = _numpy_rows(lines)
        except ValueError:
            raise InputError(f"{path}: the ASCII data are not rows of {len(names)} numbers.") from None
        if values.ndim != 2 or values.shape[1] != len(names):
            raise InputError(f"{path}: the ASCII data are not rows of {len(names)} numbers.")
        return _Table(values, names)
    if mode == "binary":
        try:
            dtype = np.dtype(
                [
                    (f"f{k}", "<" + _PCD_TYPES[(t.upper(), s)], (c,))
                    for k, (t, s, c) in enumerate(zip(types, sizes, counts))
                ]
            )
        except KeyError:
            raise InputError(f"{path}: unknown PCD TYPE/SIZE pair in {list(zip(types, sizes))}.") from None
        if n_points * dtype.itemsize > len(data) - offset:
            raise InputError(
                f"{path}: the header declares {n_points} points ({n_points * dtype.itemsize} bytes) "
                f"but the file holds {len(data) - offset} bytes of data."
            )
        records = np.frombuffer(data, dtype=dtype, count=n_points, offset=offset)
        values = (
            np.column_stack([records[f"f{k}"].astype(np.float64) for k in range(n)])
            if n_points
            else np.empty((0, len(names)))
        )
        return _Table(values, names)
    if mode == "binary_compressed":
        raise InputError(f"{path}: compressed PCD data are not supported; save it as DATA ascii or binary.")
    raise InputError(f"{path}: unknown PCD DATA kind {mode!r} (expected ascii or binary).")


# ------------------------------------------------------------------------------- .obj


def _read_obj(path: Path) -> _Table:
    """The ``v x y z [w | r g b]`` lines; everything else (faces, normals, groups) is skipped."""
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not an OBJ file (it is not UTF-8 text).") from None
    rows, lines = [], []
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split()
        if words[:1] != ["v"]:
            continue
        try:
            rows.append([_number_word(word) for word in words[1:4]])
        except ValueError:
            raise InputError(f"{path}: line {number} is not a vertex 'v x y z': {_clip(line.strip())!r}.") from None
        if len(rows[-1]) != 3:
            raise InputError(f"{path}: line {number} is not a vertex 'v x y z': {_clip(line.strip())!r}.")
        lines.append(number)
    values = np.array(rows, dtype=np.float64).reshape(-1, 3)
    return _Table(values, ["x", "y", "z"], np.array(lines, dtype=np.int64))


# ------------------------------------------------------------------------------- writing


def write_points(path, points, /) -> Path:
    """Write a point set in the format of ``path``'s suffix; :func:`read_points` reads it back.

    ``.csv``: a header ``x,y[,z]`` and comma-separated rows (``pandas.read_csv`` reads it
    with default arguments). ``.txt`` and ``.xyz``: space-separated rows, no header.
    ``.npy``: :func:`numpy.save`. ``.mat``: the variable ``points``
    (:func:`scipy.io.savemat`). ``.ply`` (binary, via meshio), ``.pcd`` (``DATA ascii``)
    and ``.obj`` (``v`` lines) hold 3D points only. Numbers are written as the shortest
    decimal that reads back as the same float64 (at most 17 significant digits), so text
    formats round-trip exactly; missing parent folders are created.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    points : array_like of shape (n_points, n_dims)
        Finite coordinates, or rows that are entirely NaN (in the text, ``.npy`` and
        ``.mat`` formats).

    Returns
    -------
    path : pathlib.Path

    Raises
    ------
    InputError
        Points the format cannot hold, a suffix that is not one of :data:`WRITE_SUFFIXES`,
        or a path the system refuses (a folder, a file where a folder goes, no permission,
        a name too long); the message names the path.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_points(pathlib.Path(folder) / "p.csv", [[0, 0.5], [1, 1.5]])
    ...     print(path.read_text(), end="")
    x,y
    0.0,0.5
    1.0,1.5
    """
    if not isinstance(path, (str, Path)) and not hasattr(path, "__fspath__"):
        raise TypeError(f"`path` must be a str or os.PathLike; got {_describe(path)}.")
    path = Path(path)
    if "\x00" in str(path):
        raise InputError(f"`path` must be a file name without NUL characters; got {_clip(str(path), 200)!r}.")
    suffix = path.suffix.lower()
    if suffix not in WRITE_SUFFIXES:
        raise InputError(f"`path` must end in one of {', '.join(WRITE_SUFFIXES)}; got {str(path)!r}.")
    try:
        arr = np.asarray(points)
    except ValueError:  # (rows of unequal length)
        raise InputError(
            "`points` must be rows of equal length (an array of shape (n_points, n_dims)); got rows of "
            "different lengths."
        ) from None
    if not is_real_dtype(arr.dtype):
        raise TypeError(f"`points` must be a real numeric array; got {_describe(arr)}.")
    if arr.dtype == bool:  # (as every reader and estimator refuses one)
        raise TypeError(
            f"`points` must hold coordinates (real numbers); got an {_describe(arr)} "
            "(a mask? convert with .astype(float) if 0/1 coordinates are meant)."
        )
    if arr.ndim != 2 or arr.shape[1] < 1:
        raise InputError(f"`points` must have shape (n_points, n_dims); got shape {arr.shape}.")
    if arr.shape[0] == 0:  # read_points refuses a file without points: none is written
        raise InputError(f"`points` must hold at least one point; got shape {arr.shape}.")
    arr = arr.astype(np.float64)
    partial = ~np.isfinite(arr).all(axis=1) & ~np.isnan(arr).all(axis=1)
    if partial.any():
        raise InputError(
            f"`points` must be finite, or NaN in every coordinate of a row; row {int(np.argmax(partial))} is not."
        )
    if suffix in _THREE_D_ONLY:
        if arr.shape[1] != 3:
            raise InputError(
                f"`points` must be 3D for {path} ({suffix} files hold 3D points); got {arr.shape[1]}D points "
                "(write .csv, .txt, .npy or .mat)."
            )
        if np.isnan(arr).any():
            raise InputError(
                f"`points` must not have NaN rows for {path} ({suffix} files cannot mark missing points); "
                "write .csv, .txt, .npy or .mat."
            )
    try:
        if path.is_dir():
            raise InputError(f"{path}: is a folder; `path` must name the file to write.")
        ancestor = nearest_existing(path.parent)  # (mkdir's own error under a file is "File exists")
        if not ancestor.is_dir():
            raise InputError(f"{path}: cannot be written ({ancestor} is a file, not a folder).")
        if path.parent != Path("."):
            path.parent.mkdir(parents=True, exist_ok=True)
        _write_points(path, arr, suffix)
    except OSError as exc:  # a file where a folder goes, no permission, a name too long, ...
        raise InputError(f"{_clip(str(path), 200)}: cannot be written ({exc.strerror or exc}).") from None
    return path


def _write_points(path: Path, arr: np.ndarray, suffix: str) -> None:
    names = ["x", "y", "z"][: arr.shape[1]] if arr.shape[1] <= 3 else [f"x{k}" for k in range(arr.shape[1])]
    # numpy and scipy append a lower-case suffix to a name that lacks it (points.NPY became
    # points.NPY.npy): write through an open file, under exactly the name given
    if suffix == ".npy":
        with open(path, "wb") as handle:
            np.save(handle, arr)
    elif suffix == ".mat":
        from scipy.io import savemat

        with open(path, "wb") as handle:
            savemat(handle, {"points": arr})
    elif suffix == ".ply":
        _meshio().write_points_cells(path, arr, [], file_format="ply", binary=True)
    elif suffix == ".obj":
        path.write_text("".join(f"v {_fmt(x)} {_fmt(y)} {_fmt(z)}\n" for x, y, z in arr), encoding="utf-8")
    elif suffix == ".pcd":
        header = (
            f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\n"
            f"COUNT 1 1 1\nWIDTH {arr.shape[0]}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {arr.shape[0]}\nDATA ascii\n"
        )
        path.write_text(header + _rows(arr, " "), encoding="ascii")
    elif suffix == ".csv":
        path.write_text(",".join(names) + "\n" + _rows(arr, ","), encoding="utf-8")
    else:
        path.write_text(_rows(arr, " "), encoding="utf-8")


def _fmt(value: float) -> str:
    return repr(float(value)) if math.isfinite(value) else "nan"


def _rows(arr: np.ndarray, delimiter: str) -> str:
    return "".join(delimiter.join(_fmt(v) for v in row) + "\n" for row in arr)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return _clip(text[0]) if text else type(exc).__name__


def _clip(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."
