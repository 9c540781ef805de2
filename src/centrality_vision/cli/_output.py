"""The one output writer of the command line, and the parameters block every output carries.

``write_output(path, record, ...)`` picks the layout from the suffix of ``--out``:

``.json``
    ``record``: every result and a ``"parameters"`` block (every option, the seed, null
    where nothing is random, and the package version).
``.npz``
    ``arrays``, plus a ``parameters`` entry holding the block as a JSON string.
``.csv``, ``.npy`` with a table
    The table only: a plain CSV with one header line (``pandas.read_csv`` reads it with
    default arguments) or a float array;
    ``record`` without the table goes to the *sidecar* ``<name>.json`` beside it, with
    the column names.
A point-set suffix (``.csv``, ``.txt``, ``.xyz``, ``.npy``, ``.mat``, ``.ply``, ``.pcd``, ``.obj``) with points
    The points, written by :func:`centrality_vision.io.write_points` (so they are read
    back by ``read_points`` and by the format's usual tools); ``record`` goes to the
    sidecar ``<name>.json``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

__all__ = ["parameters_block", "to_jsonable", "write_json", "write_npz", "sidecar_path", "write_output"]


def parameters_block(options: Mapping) -> dict:
    """The ``"parameters"`` block: every option that applied (``--seed`` among them where the
    run drew at random) and the package version."""
    from .. import __version__

    block = {key: to_jsonable(value) for key, value in options.items() if not callable(value)}
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
    with open(path, "wb") as handle:  # by name, numpy would write NAME.NPZ.npz
        np.savez_compressed(handle, **entries)
    return path


def sidecar_path(path) -> Path:
    """Where the record of a table or point-set output goes: ``name.csv`` -> ``name.json``."""
    path = Path(path)
    return path.with_suffix(".json")


def _write_table(path: Path, columns: Mapping[str, np.ndarray]) -> None:
    import csv

    names = list(columns)
    arrays = [np.asarray(columns[name]) for name in names]
    if path.suffix.lower() == ".npy":
        with open(path, "wb") as handle:  # by name, numpy would write NAME.NPY.npy
            np.save(handle, np.column_stack([a.astype(np.float64) for a in arrays]))
        return

    def cell(value, kind: str) -> str:
        if kind in "iub":
            return str(int(value))
        if kind == "f":
            return repr(float(value))
        return str(value)

    kinds = [a.dtype.kind for a in arrays]
    with path.open("w", encoding="utf-8", newline="") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(names)
        writer.writerows([cell(v, kind) for v, kind in zip(row, kinds)] for row in zip(*arrays))


def write_output(
    path, record: Mapping, *, arrays: Mapping | None = None, table: Mapping | None = None, points=None
) -> list[Path]:
    """Write a command's result to ``path`` in the layout its suffix asks for; return the files written.

    ``record`` is the whole result (with its ``"parameters"``); ``arrays`` what goes into
    an ``.npz``; ``table`` (equal-length named columns) what goes into ``.csv``/
    ``.npy`` when the command writes tables; ``points`` what goes into a point-set file
    when it writes points. Keys of ``record`` that the table or point file already holds
    are named by ``"columns"`` in the sidecar instead of repeated.
    """
    path = _prepare(path)
    kind = path.suffix.lower()
    if kind == ".json":
        return [write_json(path, record)]
    if kind == ".npz":
        return [write_npz(path, arrays if arrays is not None else {}, record["parameters"])]
    if table is not None:
        _write_table(path, table)
        side = {"file": path.name, "columns": list(table), **record}
    elif points is not None:
        from ..io import write_points

        write_points(path, points)
        side = {"file": path.name, **record}
    else:  # pragma: no cover - the parsers only offer the suffixes a command writes
        raise RuntimeError(f"internal error: no table or points to write to {path}")  # a bug: exit status 1
    return [path, write_json(sidecar_path(path), side)]
