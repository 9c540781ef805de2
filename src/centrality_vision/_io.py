"""Files in and out for the ``centrality-vision`` command.

One reader for point sets (``.txt``, ``.csv``, ``.npy``), one for binary images
(``.png``), and writers for ``.json``, ``.npz``, ``.csv`` and ``.npy`` that all carry
the run's parameters. Every problem with an input file is raised as an
:class:`~centrality_vision.exceptions.InputError` whose one-line message starts with
the file's path, so the command line can print it as it is.

Point files
    ``.txt`` / ``.csv``: one point per line, coordinates separated by commas or by
    whitespace; blank lines and lines starting with ``#`` are skipped; the first
    remaining line may be a header (e.g. ``x,y``) when it is not numeric. Every row must
    have the same number of columns (2 or 3 for point sets). ``.npy``: a 2D numeric
    array saved with :func:`numpy.save` (no pickles).
Images
    ``.png`` (anything :func:`skimage.io.imread` decodes). Colour is turned into grey,
    the alpha channel is ignored, and the image is thresholded at half its range
    (``(min + max) / 2``). ``foreground="auto"`` takes as the shape the side (dark or
    light) that covers less of the image border, so dark shapes on white (Kimia) and
    white shapes on black both work.
Outputs
    ``.json``: a record whose ``"parameters"`` block lists every option, the seed (null
    where nothing is random) and the package version. ``.npz``: arrays plus a
    ``parameters`` entry holding that block as a JSON string. ``.csv``: a table with a
    header line, preceded by ``# parameters: {...}`` (read it back with
    ``numpy.loadtxt(path, delimiter=",", skiprows=2)`` or ``pandas.read_csv(path,
    comment="#")``). ``.npy``: the same table as a float array; its column names and
    the parameters go to ``<name>.parameters.json`` beside it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .exceptions import InputError

__all__ = [
    "POINT_SUFFIXES",
    "IMAGE_SUFFIXES",
    "read_points",
    "read_image",
    "parameters_block",
    "to_jsonable",
    "write_json",
    "write_npz",
    "write_table",
    "sidecar_path",
]

POINT_SUFFIXES = (".txt", ".csv", ".npy")
IMAGE_SUFFIXES = (".png",)
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _existing_file(path) -> Path:
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file.")
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a file.")
    return path


def read_points(path, *, n_dims: Sequence[int] = (2, 3)) -> np.ndarray:
    """Read a point set, one point per row, as a float64 array of shape (n_points, n_dims).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.txt``, ``.csv`` or ``.npy`` file (see the module docstring for the layout).
    n_dims : sequence of int, default=(2, 3)
        Allowed numbers of columns.

    Raises
    ------
    InputError
        Missing file, unknown suffix, unparsable or ragged rows, a wrong number of
        columns, NaN or inf values, or no points; the message names the file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "p.csv"
    ...     _ = path.write_text("x,y\\n0,0\\n1,0.5\\n")
    ...     read_points(path).tolist()
    [[0.0, 0.0], [1.0, 0.5]]
    """
    path = _existing_file(path)
    suffix = path.suffix.lower()
    if suffix not in POINT_SUFFIXES:
        raise InputError(f"{path}: a point set must be a {', '.join(POINT_SUFFIXES)} file; got suffix {path.suffix!r}.")
    if suffix == ".npy":
        try:
            array = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise InputError(f"{path}: not a readable .npy array ({_first_line(exc)}).") from None
        if not isinstance(array, np.ndarray) or array.dtype == object or not (
            np.issubdtype(array.dtype, np.number) or array.dtype == bool
        ):
            raise InputError(f"{path}: must hold a numeric array; got dtype {getattr(array, 'dtype', type(array))}.")
        if np.iscomplexobj(array):
            raise InputError(f"{path}: must hold real numbers; got dtype {array.dtype}.")
        if array.ndim != 2:
            raise InputError(f"{path}: must hold a 2D array (one point per row); got shape {array.shape}.")
        array = array.astype(np.float64)
        lines = None
    else:
        array, lines = _parse_text(path)
    if array.shape[0] == 0:
        raise InputError(f"{path}: holds no points.")
    if array.shape[1] not in n_dims:
        wanted = " or ".join(str(d) for d in n_dims)
        raise InputError(f"{path}: points must have {wanted} columns (coordinates); got {array.shape[1]}.")
    bad = ~np.isfinite(array).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        where = f"line {lines[row]}" if lines is not None else f"row {row}"
        raise InputError(f"{path}: {int(bad.sum())} point(s) with NaN or inf, the first at {where}.")
    return np.ascontiguousarray(array)


def _parse_text(path: Path) -> tuple[np.ndarray, list[int]]:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file of numbers (it is not UTF-8 text).") from None
    rows: list[list[float]] = []
    lines: list[int] = []
    width = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        cells = [cell.strip() for cell in stripped.split(",")] if "," in stripped else stripped.split()
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            if not rows and width is None:  # a header line: remember its width, skip it
                width = len(cells)
                continue
            raise InputError(f"{path}: line {number} is not a row of numbers: {_clip(stripped)!r}.") from None
        if rows and len(values) != len(rows[0]):
            raise InputError(
                f"{path}: line {number} has {len(values)} values, the rows before it {len(rows[0])}."
            )
        rows.append(values)
        lines.append(number)
    if not rows:
        raise InputError(f"{path}: holds no points.")
    if width is not None and width != len(rows[0]):
        raise InputError(f"{path}: the header has {width} names but the rows {len(rows[0])} values.")
    return np.array(rows, dtype=np.float64), lines


def read_image(path, *, foreground: str = "auto") -> np.ndarray:
    """Read an image file as a 2D boolean mask (True = shape).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.png`` file.
    foreground : {"auto", "dark", "light"}, default="auto"
        Which side of the threshold is the shape; ``"auto"`` picks the side that covers
        less of the image border.

    Raises
    ------
    InputError
        Missing file, not an image, an empty or uniform image; the message names the file.
    """
    if foreground not in ("auto", "dark", "light"):
        raise InputError(f"`foreground` must be 'auto', 'dark' or 'light'; got {foreground!r}.")
    path = _existing_file(path)
    if path.suffix.lower() not in IMAGE_SUFFIXES:
        raise InputError(f"{path}: an image must be a {', '.join(IMAGE_SUFFIXES)} file; got suffix {path.suffix!r}.")
    import io

    from skimage.io import imread

    data = path.read_bytes()
    if not data:
        raise InputError(f"{path}: the file is empty.")
    if not data.startswith(_PNG_SIGNATURE):
        raise InputError(f"{path}: not a readable image (it does not start like a PNG file).")
    try:  # decode from memory: a decoder failing on a damaged file then leaves no file open
        pixels = np.asarray(imread(io.BytesIO(data)))
    except Exception as exc:  # imageio/PIL raise OSError, ValueError, SyntaxError, ...
        raise InputError(f"{path}: not a readable image ({type(exc).__name__}: {_first_line(exc)}).") from None
    if pixels.dtype == object or not (np.issubdtype(pixels.dtype, np.number) or pixels.dtype == bool):
        raise InputError(f"{path}: not a readable image (pixel type {pixels.dtype}).")
    if pixels.ndim == 3 and pixels.shape[2] in (2, 3, 4):
        channels = pixels[..., :3] if pixels.shape[2] >= 3 else pixels[..., :1]
        pixels = channels.astype(np.float64).mean(axis=2)
    if pixels.ndim != 2:
        raise InputError(f"{path}: must be a 2D grey or colour image; got an array of shape {pixels.shape}.")
    if pixels.size == 0:
        raise InputError(f"{path}: the image is empty (shape {pixels.shape}).")
    pixels = pixels.astype(np.float64)
    low, high = float(pixels.min()), float(pixels.max())
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InputError(f"{path}: the image holds NaN or inf values.")
    if low == high:
        raise InputError(f"{path}: the image is uniform (every pixel is {low:g}): there is no shape in it.")
    light = pixels > (low + high) / 2
    if foreground == "auto":
        border = np.concatenate([light[0], light[-1], light[1:-1, 0], light[1:-1, -1]])
        foreground = "dark" if border.mean() > 0.5 else "light"
    return ~light if foreground == "dark" else light


def parameters_block(options: Mapping, *, seed=None) -> dict:
    """The ``"parameters"`` block: every option, the seed and the package version."""
    from . import __version__

    block = {key: to_jsonable(value) for key, value in options.items() if not callable(value)}
    block["seed"] = to_jsonable(seed)
    block["version"] = __version__
    return block


def to_jsonable(value):
    """``value`` with numpy scalars and arrays as Python numbers and lists; NaN and inf as None."""
    if isinstance(value, Mapping):
        return {str(key): to_jsonable(item) for key, item in value.items()}
    if isinstance(value, (str, bool)) or value is None:
        return value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (list, tuple)):
        return [to_jsonable(item) for item in value]
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, int):
        return value
    return str(value)


def _prepare(path) -> Path:
    path = Path(path)
    if path.parent != Path("."):
        path.parent.mkdir(parents=True, exist_ok=True)
    return path


def write_json(path, record: Mapping) -> Path:
    """Write ``record`` (numpy values allowed) as indented JSON."""
    path = _prepare(path)
    path.write_text(json.dumps(to_jsonable(record), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


def write_npz(path, arrays: Mapping, parameters: Mapping) -> Path:
    """Write ``arrays`` to a compressed ``.npz`` with the parameters as a JSON string entry."""
    path = _prepare(path)
    entries = {key: np.asarray(value) for key, value in arrays.items() if value is not None}
    entries["parameters"] = np.array(json.dumps(to_jsonable(parameters)))
    np.savez_compressed(path, **entries)
    return path


def sidecar_path(path) -> Path:
    """Where the parameters of a ``.npy`` output go: ``name.npy`` -> ``name.parameters.json``."""
    path = Path(path)
    return path.with_name(path.stem + ".parameters.json")


def write_table(path, columns: Mapping[str, np.ndarray], parameters: Mapping) -> Path:
    """Write equal-length columns as ``.csv`` (header, parameters comment) or ``.npy`` (plus sidecar)."""
    path = _prepare(path)
    names = list(columns)
    table = np.column_stack([np.asarray(columns[name], dtype=np.float64) for name in names])
    if path.suffix.lower() == ".npy":
        np.save(path, table)
        write_json(sidecar_path(path), {"columns": names, "parameters": parameters})
        return path
    integer = [np.issubdtype(np.asarray(columns[name]).dtype, np.integer) for name in names]
    with path.open("w", encoding="utf-8", newline="") as handle:
        handle.write("# parameters: " + json.dumps(to_jsonable(parameters)) + "\n")
        handle.write(",".join(names) + "\n")
        for row in table:
            handle.write(",".join(str(int(v)) if is_int else repr(float(v)) for v, is_int in zip(row, integer)) + "\n")
    return path


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return _clip(text[0]) if text else type(exc).__name__


def _clip(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."
