"""Centralities of binary shapes, computed once per image and kept in a bounded cache."""

from __future__ import annotations

import hashlib
import os
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np

from .._validation import as_binary_image, check_choice
from ..centrality import compute
from ..exceptions import InputError
from ..graphs import pixel_graph

__all__ = ["SHAPE_CENTRALITIES", "CentralityCache", "default_cache", "as_shape_images", "shape_centralities"]

#: The four centralities of the thesis' shape experiments, in the order "all" concatenates them.
SHAPE_CENTRALITIES = ("betweenness", "closeness", "eigenvector", "degree")


def as_shape_images(images, *, name: str = "X") -> list[np.ndarray]:
    """Validate a sequence of 2D binary shapes (sizes may differ); return boolean masks.

    A shape must have background too: an all-foreground image has no outline, which
    usually means the image was passed inverted (light shape expected on dark).
    """
    if isinstance(images, np.ndarray) and images.ndim == 2:
        raise InputError(
            f"`{name}` must be a sequence of 2D images (a list, or an array of shape (n_images, rows, cols)); "
            f"got a single 2D array of shape {images.shape}. Wrap one image in a list."
        )
    if isinstance(images, (str, bytes)) or not hasattr(images, "__len__"):
        raise TypeError(f"`{name}` must be a sequence of 2D binary images; got {type(images).__name__}.")
    if len(images) == 0:
        raise InputError(f"`{name}` must hold at least one image; got an empty sequence.")
    masks = []
    for i, image in enumerate(images):
        mask = as_binary_image(image, name=f"{name}[{i}]")
        if mask.all():
            raise InputError(
                f"`{name}[{i}]` must have background pixels; got an all-foreground image of shape {mask.shape} "
                "(is it inverted? foreground must be True/1)."
            )
        masks.append(mask)
    return masks


def _key(mask: np.ndarray, connectivity: int) -> tuple:
    digest = hashlib.blake2b(np.packbits(mask).tobytes(), digest_size=16).hexdigest()
    return (mask.shape, connectivity, digest)


class CentralityCache:
    """A bounded, thread-safe cache of pixel-graph centralities keyed by image content.

    The same image (the same pixels) under another feature or estimator is never
    recomputed while it stays in the cache; the least recently used images are dropped
    beyond ``max_images``.

    Parameters
    ----------
    max_images : int, default=4096
        How many images to keep in memory (each holds one float64 value per pixel and
        centrality).
    directory : path, optional
        Also keep every computed centrality on disk, one ``.npy`` file per image and
        centrality, written atomically. A later process (or a run that was stopped and
        started again) reads them instead of recomputing.
    """

    def __init__(self, max_images: int = 4096, directory=None):
        self.max_images = int(max_images)
        self.directory = None if directory is None else Path(directory)
        self._store: OrderedDict[tuple, dict] = OrderedDict()
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def _path(self, key: tuple, name: str) -> Path:
        (rows, cols), connectivity, digest = key
        return self.directory / f"{digest}-{rows}x{cols}-c{connectivity}-{name}.npy"

    def _load(self, key: tuple, name: str):
        if self.directory is None:
            return None
        path = self._path(key, name)
        return np.load(path) if path.exists() else None

    def _save(self, key: tuple, name: str, values: np.ndarray) -> None:
        if self.directory is None:
            return
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self._path(key, name)
        tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
        with open(tmp, "wb") as handle:
            np.save(handle, values)
        os.replace(tmp, path)

    def __len__(self) -> int:
        return len(self._store)

    def clear(self) -> None:
        """Drop every entry and reset the hit and miss counts."""
        with self._lock:
            self._store.clear()
            self.hits = self.misses = 0

    def get(self, mask: np.ndarray, name: str, *, connectivity: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Centrality ``name`` of the pixel graph of ``mask`` and the pixel index of each node."""
        key = _key(mask, connectivity)
        with self._lock:
            entry = self._store.get(key)
            if entry is not None:
                self._store.move_to_end(key)
                if name in entry:
                    self.hits += 1
                    values = entry[name]
                    if self.directory is not None and not self._path(key, name).exists():
                        self._save(key, name, values)  # computed before a directory was set
                    return values, entry["nodes"]
        if entry is None:
            entry = {"nodes": np.flatnonzero(mask)}  # pixel_graph's node order: row-major
        values = self._load(key, name)
        if values is not None:
            self.hits += 1
        else:
            self.misses += 1
            if "graph" not in entry:
                entry["graph"], _ = pixel_graph(mask, connectivity=connectivity)
            values = compute(entry["graph"], name)
            self._save(key, name, values)
        values.setflags(write=False)
        entry["nodes"].setflags(write=False)
        with self._lock:
            entry = self._store.setdefault(key, entry)
            entry[name] = values
            self._store.move_to_end(key)
            while len(self._store) > self.max_images:
                self._store.popitem(last=False)
        return values, entry["nodes"]


#: The cache that every shape feature uses unless it is given another.
default_cache = CentralityCache()


def shape_centralities(
    images, names=SHAPE_CENTRALITIES, *, connectivity: int = 8, progress: bool = False, cache: CentralityCache | None = None
) -> list[dict[str, np.ndarray]]:
    """Centralities of the 8- (or 4-) neighbour pixel graph of each shape.

    Parameters
    ----------
    images : sequence of 2D binary arrays
        Shapes, True/1 on the shape; sizes may differ.
    names : sequence of str
        Centralities to compute (see :data:`centrality_vision.centrality.CENTRALITIES`).
    connectivity : {8, 4}
    progress : bool
        Show a progress bar on stderr.
    cache : CentralityCache, optional
        Defaults to :data:`default_cache`.

    Returns
    -------
    list of dict
        One dict per image: each name maps to the values (one per foreground pixel, in
        row-major order), and ``"nodes"`` to the flat pixel index of each value.

    Examples
    --------
    >>> import numpy as np
    >>> square = np.zeros((5, 5), dtype=bool); square[1:4, 1:4] = True
    >>> out = shape_centralities([square], ["degree"])
    >>> out[0]["degree"].reshape(3, 3)
    array([[3., 5., 3.],
           [5., 8., 5.],
           [3., 5., 3.]])
    """
    from ..centrality import CENTRALITIES

    masks = as_shape_images(images)
    names = [check_choice(n, CENTRALITIES, name="centrality") for n in names]
    if connectivity not in (4, 8) or isinstance(connectivity, bool):
        raise InputError(f"`connectivity` must be 4 or 8; got {connectivity!r}.")
    cache = default_cache if cache is None else cache
    items = masks
    if progress:
        from tqdm.auto import tqdm

        items = tqdm(masks, desc="centralities", unit="image", leave=False)
    out = []
    for mask in items:
        record = {}
        for name in names:
            record[name], record["nodes"] = cache.get(mask, name, connectivity=connectivity)
        out.append(record)
    return out
