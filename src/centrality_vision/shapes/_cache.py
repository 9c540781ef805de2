"""Centralities of binary shapes, computed once per image and kept in a bounded cache.

A :class:`CentralityCache` keys every result by the image's pixels (a hash of the
mask), the neighbourhood and the edge lengths, so the same shape is never computed twice
in a process; with a ``directory`` it also keeps the results on disk, where other
processes (joblib or Dask workers, later runs) find them. Processes that share a
directory also share the work: an image another process is computing is skipped and
read when it is ready, so parallel cross-validation folds never compute the same image.
"""

from __future__ import annotations

import hashlib
import numbers
import os
import threading
import time
import zipfile
from collections import OrderedDict
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .._deprecation import renamed_parameters
from .._provenance import code_digest, current_code_digest
from .._validation import as_binary_image, as_real_array, check_bool, check_choice, check_int, nearest_existing
from ..centrality import CENTRALITIES, PATH_CENTRALITIES, compute
from ..exceptions import InputError
from ..graphs import pixel_graph

__all__ = [
    "SHAPE_CENTRALITIES",
    "PATH_CENTRALITIES",
    "CentralityCache",
    "default_cache",
    "resolve_cache",
    "as_shape_images",
    "shape_centralities",
]

#: The four centralities of the thesis' shape experiments, in the order "all" concatenates them.
SHAPE_CENTRALITIES = ("betweenness", "closeness", "eigenvector", "degree")

_STALE_LOCK_SECONDS = 600.0  # a lock this old (or whose process is gone) is taken over
_POLL_SECONDS = 0.05


def as_shape_images(
    images, *, name: str = "X", foreground: str = "auto", threshold: float | None = None
) -> list[np.ndarray]:
    """Validate a sequence of 2D shapes (sizes may differ); return boolean masks.

    Each image goes through :func:`centrality_vision._validation.as_binary_image`:
    boolean and 0/1 images are masks (True/1 = shape); grey images (e.g. 0/255) are
    split at ``threshold`` (default: half their range) and ``foreground="auto"`` takes
    the side that touches less of the image border as the shape. A mask whose shape
    touches most of the border gets a warning (it looks inverted). A shape must have
    background too: an all-foreground image has no outline.

    Parameters
    ----------
    images : sequence of 2D array_like, or array_like of shape (n_images, rows, cols)
        At least one image; a single 2D array is refused (wrap it in a list).
    name : str, default="X"
        The parameter name error messages give (``X[i]`` for image ``i``).
    foreground : {"auto", "dark", "light"}, default="auto"
        Which side of a grey image is the shape; ``"dark"`` also takes the 0s of a mask.
    threshold : float, optional
        Grey level splitting grey images; default half each image's range, ``(min + max) / 2``.

    Returns
    -------
    list of ndarray of bool
        One 2D mask per image (True = the shape), each with foreground and background pixels.

    Examples
    --------
    >>> image = np.zeros((5, 5), dtype=np.uint8)
    >>> image[1:4, 1:4] = 255
    >>> (mask,) = as_shape_images([image])
    >>> mask.dtype, int(mask.sum())
    (dtype('bool'), 9)
    """
    if isinstance(images, np.ndarray) and images.ndim == 2:
        raise InputError(
            f"`{name}` must be a sequence of 2D images (a list, or an array of shape (n_images, rows, cols)); "
            f"got a single 2D array of shape {images.shape}. Wrap one image in a list."
        )
    if isinstance(images, (str, bytes)) or not hasattr(images, "__len__") or getattr(images, "ndim", 1) == 0:
        raise TypeError(f"`{name}` must be a sequence of 2D binary images; got {type(images).__name__}.")
    if len(images) == 0:
        raise InputError(f"`{name}` must hold at least one image; got an empty sequence.")
    masks = []
    for i, image in enumerate(images):
        mask = as_binary_image(
            image, name=f"{name}[{i}]", foreground=foreground, threshold=threshold, check_inverted=True
        )
        if mask.all():
            raise InputError(
                f"`{name}[{i}]` must have background pixels; got an all-foreground image of shape {mask.shape} "
                "(is it inverted? foreground must be True/1)."
            )
        masks.append(mask)
    return masks


def is_connectivity(value) -> bool:
    """Whether ``value`` is a pixel neighbourhood of the shape layer: the int 4 or 8 (not a
    bool, not 8.0, which would also name cache files ``c8.0``)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool) and value in (4, 8)


def _as_mask(mask) -> np.ndarray:
    """The boolean mask :func:`~centrality_vision.graphs.pixel_graph` reads from ``mask``.

    The cache's key and node indices must be those of the pixels the values are computed
    from: a grey image's nonzero pixels are not its shape (pixel_graph thresholds it)."""
    if isinstance(mask, np.ndarray) and mask.dtype == bool and mask.ndim == 2 and mask.any():
        return mask
    return as_binary_image(mask, name="mask")


def _key(mask: np.ndarray, connectivity: int, weights: bool = False) -> tuple:
    """The cache key of a mask's values; ``connectivity`` and ``weights`` are checked here, once for
    every entry point (``lookup``, ``get``, ``put``), so that each accepts exactly what the others do."""
    if not is_connectivity(connectivity):
        raise InputError(f"`connectivity` must be 4 or 8; got {connectivity!r}.")
    weights = check_bool(weights, name="weights")
    digest = hashlib.blake2b(np.packbits(mask).tobytes(), digest_size=16).hexdigest()
    return (mask.shape, int(connectivity), weights, digest)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):  # (a number beyond the C long of a pid is no process)
        return False
    except (PermissionError, OSError):
        return True
    return True


def _compute(mask: np.ndarray, name: str, connectivity: int, weights: bool, graph=None) -> np.ndarray:
    if graph is None:
        graph, _ = pixel_graph(mask, connectivity=connectivity)
    options = {"weights": True} if weights and name in PATH_CENTRALITIES else {}
    return compute(graph, name, **options)


class CentralityCache:
    """A bounded, thread-safe cache of pixel-graph centralities keyed by image content.

    The same image (the same pixels) under another feature or estimator is never
    recomputed while it stays in the cache; the least recently used images are dropped
    beyond ``max_images``.

    Parameters
    ----------
    max_images : int >= 0, default=4096
        How many images to keep in memory (each holds one float64 value per pixel and
        centrality); 0 keeps none (with ``directory``, the disk alone).
    directory : path, optional
        Also keep every computed centrality on disk, one ``.npz`` file per image and
        centrality, named by a hash of the pixels and a digest of the package's code (values
        computed by another version are not read back), written atomically, and holding a
        checksum of its name and values (a damaged or edited file is recomputed). Another
        process (a joblib or Dask worker, or a later run) with a cache on the same
        directory reads them instead of recomputing; while one process computes an
        image it holds a ``.lock`` file there, and the others compute other images
        first and then wait for it. A folder that refuses new files (mounted read-only,
        say, after it was filled) still serves the files it holds; what is computed then
        stays in memory, and a :class:`UserWarning` says so once.

    Notes
    -----
    A cache is a shared resource: copying it (``copy.deepcopy``, as
    :func:`sklearn.base.clone` does with parameters) returns the same cache, and
    pickling it (to send an estimator to a worker process) keeps only ``max_images``
    and ``directory``, so the worker starts with an empty memory and the shared disk.

    Examples
    --------
    >>> import numpy as np
    >>> cache = CentralityCache()
    >>> square = np.zeros((5, 5), dtype=bool); square[1:4, 1:4] = True
    >>> values, nodes = cache.get(square, "degree")
    >>> values.reshape(3, 3)[1], (cache.hits, cache.misses)
    (array([5., 8., 5.]), (0, 1))
    >>> _ = cache.get(square, "degree")  # now served from memory
    >>> (cache.hits, cache.misses), cache.lookup(square, "closeness") is None  # lookup never computes
    ((1, 1), True)
    >>> entry = cache.put(square, "closeness", np.ones(9))  # values computed elsewhere
    >>> sorted(entry), len(cache)
    (['closeness', 'degree', 'nodes'], 1)
    >>> cache.clear(); len(cache), (cache.hits, cache.misses)
    (0, (0, 0))

    With a ``directory``, another cache on the same folder (another process, a later run)
    reads the values back instead of computing them:

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = CentralityCache(directory=folder).get(square, "degree")
    ...     other = CentralityCache(directory=folder)
    ...     found, _ = other.lookup(square, "degree")
    ...     print(found.tolist() == values.tolist(), other.hits, other.misses)
    True 1 0
    """

    def __init__(self, max_images: int = 4096, directory=None):
        self.max_images = check_int(max_images, name="max_images", low=0)
        if directory is not None and not isinstance(directory, (str, os.PathLike)):
            raise TypeError(f"`directory` must be a path (str or os.PathLike) or None; got {type(directory).__name__}.")
        if directory is not None and not str(directory).strip():
            raise InputError("`directory` must name a folder; got an empty path (for the current folder, pass '.').")
        self.directory = None if directory is None else Path(directory)
        if self.directory is not None:
            # the folder, or the nearest part of its path that exists, must be a folder
            existing = nearest_existing(self.directory)
            if not existing.is_dir():
                where = "a file" if existing == self.directory else f"below a file ({str(existing)!r} is a file)"
                raise InputError(
                    f"`directory` must be a folder (created when missing); got {str(directory)!r}, {where}."
                )
        self._store: OrderedDict[tuple, dict] = OrderedDict()
        self._lock = threading.Lock()
        self._unwritable_said = False
        self.hits = 0
        self.misses = 0

    def __repr__(self) -> str:
        directory = None if self.directory is None else str(self.directory)
        return f"CentralityCache(max_images={self.max_images}, directory={directory!r})"

    def __deepcopy__(self, memo):
        return self

    def __getstate__(self):
        return {"max_images": self.max_images, "directory": self.directory}

    def __setstate__(self, state):
        self.__init__(state["max_images"], state["directory"])

    def _path(self, key: tuple, name: str) -> Path:
        (rows, cols), connectivity, weights, digest = key
        suffix = "-w" if weights else ""
        # the package's code digest: values computed by other code are never read back
        return self.directory / f"{digest}-{rows}x{cols}-c{connectivity}{suffix}-{code_digest()}-{name}.npz"

    @staticmethod
    def _checksum(path: Path, values: np.ndarray) -> np.ndarray:
        """SHA-256 of the file's name and its values' bytes, as 32 uint8."""
        digest = hashlib.sha256(path.name.encode())
        digest.update(np.ascontiguousarray(values).tobytes())
        return np.frombuffer(digest.digest(), dtype=np.uint8)

    def _load(self, key: tuple, name: str, n_nodes: int):
        """The stored values, or None when absent or not this image's: a file of another
        length or type (float64 is stored), with NaN or inf values, or whose checksum does not
        match its name and values (a foreign, stale, damaged or edited file under the same
        name) is recomputed, never used."""
        if self.directory is None:
            return None
        path = self._path(key, name)
        try:
            with np.load(path) as stored:
                values, check = stored["values"], stored["check"]
        except (EOFError, ValueError, OSError, KeyError, IndexError, TypeError, AttributeError, zipfile.BadZipFile):
            return None  # absent, or not one of our files (a partial one, an .npy, another archive)
        if values.shape != (n_nodes,) or values.dtype != np.float64 or not np.isfinite(values).all():
            return None
        if not np.array_equal(check, self._checksum(path, values)):
            return None
        return values

    def _unwritable(self, path: Path, error: OSError) -> None:
        """Say once per cache that ``directory`` refuses a file: the values computed from
        then on are kept in memory only (a read-only cache filled beforehand still serves
        what it holds)."""
        with self._lock:
            if self._unwritable_said:
                return
            self._unwritable_said = True
        from .._warnings import warn

        reason = error.strerror or type(error).__name__
        warn(
            f"the cache folder {str(self.directory)!r} could not take {path.name} ({reason}): centralities "
            "computed now are kept in memory only.",
            UserWarning,
        )

    def _save(self, key: tuple, name: str, values: np.ndarray) -> None:
        # (values computed after the package's files changed may come from other code than
        # the digest in the file's name: kept in memory only)
        if self.directory is None or current_code_digest() != code_digest():
            return
        path = self._path(key, name)
        tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            with open(tmp, "wb") as handle:
                np.savez(handle, values=values, check=self._checksum(path, values))
            os.replace(tmp, path)
        except OSError as error:  # a read-only folder, a folder in the file's place, a full disk
            if tmp.is_file():
                tmp.unlink(missing_ok=True)
            self._unwritable(path, error)

    @contextmanager
    def _claim(self, key: tuple, name: str):
        """Yield True while this process holds the lock on (key, name); False if another does."""
        if self.directory is None:
            yield True
            return
        lock = self._path(key, name).with_suffix(".lock")
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            if not self._stale(lock):
                yield False
                return
            lock.unlink(missing_ok=True)
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                yield False
                return
        except OSError as error:  # a folder that refuses new files: compute here, unlocked
            self._unwritable(lock, error)
            yield True
            return
        try:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            yield True
        finally:
            lock.unlink(missing_ok=True)

    @staticmethod
    def _stale(lock: Path) -> bool:
        try:
            age = time.time() - lock.stat().st_mtime
            pid = int(lock.read_text() or "0")
        except (FileNotFoundError, ValueError):
            return True
        return age > _STALE_LOCK_SECONDS or (pid > 0 and not _pid_alive(pid))

    def __len__(self) -> int:
        return len(self._store)

    def clear(self) -> None:
        """Drop every entry kept in memory and reset the hit and miss counts (the disk is kept)."""
        with self._lock:
            self._store.clear()
            self.hits = self.misses = 0

    def _remember(self, key: tuple, entry: dict, name: str, values: np.ndarray) -> dict:
        values.setflags(write=False)
        entry["nodes"].setflags(write=False)
        with self._lock:
            entry = self._store.setdefault(key, entry)
            entry[name] = values
            self._store.move_to_end(key)
            while len(self._store) > self.max_images:
                self._store.popitem(last=False)
            return dict(entry)  # a copy: the caller cannot change what the cache holds

    @renamed_parameters(name="centrality")
    def lookup(self, mask: np.ndarray, centrality: str, *, connectivity: int = 8, weights: bool = False):
        """The cached values (memory, then disk) or None; never computes.

        Parameters
        ----------
        mask : 2D array_like
            The shape: a boolean mask (True = shape), or a 0/1 or grey image split as
            :func:`as_shape_images` splits it with its defaults.
        centrality : str
            A centrality from :data:`centrality_vision.centrality.CENTRALITIES` (formerly
            ``name``).
        connectivity : {8, 4}, default=8
            Pixel neighbourhood.
        weights : bool, default=False
            As in :meth:`get`.

        Returns
        -------
        (values, nodes) or None
            As :meth:`get` returns them, or None when neither memory nor disk holds them.
        """
        name = check_choice(centrality, CENTRALITIES, name="centrality")
        mask = _as_mask(mask)
        key = _key(mask, connectivity, weights)
        with self._lock:
            entry = self._store.get(key)
            if entry is not None:
                self._store.move_to_end(key)
                if name in entry:
                    self.hits += 1
                    if self.directory is not None and not self._path(key, name).exists():
                        self._save(key, name, entry[name])  # computed before a directory was set
                    return entry[name], entry["nodes"]
        values = self._load(key, name, int(np.count_nonzero(mask)))
        if values is None:
            return None
        with self._lock:
            self.hits += 1
        entry = self._remember(key, entry or {"nodes": np.flatnonzero(mask)}, name, values)
        return values, entry["nodes"]

    @renamed_parameters(name="centrality")
    def get(
        self, mask: np.ndarray, centrality: str, *, connectivity: int = 8, weights: bool = False, wait: bool = True
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Centrality ``centrality`` of the pixel graph of ``mask`` and the pixel index of each node.

        ``weights=True`` gives the shortest-path centralities (betweenness, closeness,
        harmonic, eccentricity) Euclidean edge lengths 1 and sqrt 2; degree and
        eigenvector are the same either way. With ``wait=False``, returns None instead
        of waiting when another process holds the lock on this image.

        Parameters
        ----------
        mask : 2D array_like
            The shape: a boolean mask (True = shape), or a 0/1 or grey image split as
            :func:`as_shape_images` splits it with its defaults.
        centrality : str
            A centrality from :data:`centrality_vision.centrality.CENTRALITIES` (formerly
            ``name``).
        connectivity : {8, 4}, default=8
            Pixel neighbourhood.
        weights : bool, default=False
            Euclidean edge lengths (True) or hop counts (False) for the shortest-path centralities.
        wait : bool, default=True
            Only matters with a ``directory``, where a ``.lock`` file marks an image that another
            process (or thread) is computing. True: poll every 0.05 s until its values are on
            disk, or until the lock is gone and this call computes them itself (a lock older than
            600 s, or whose process has ended, is taken over). False: return None at once.

        Returns
        -------
        (values, nodes) or None
            ``values``: float64, one per foreground pixel in row-major order; ``nodes``: the flat
            (row-major) pixel index of each; both of shape (n_foreground,) and read-only. None
            with ``wait=False`` while another process holds the lock.
        """
        mask = _as_mask(mask)
        found = self.lookup(mask, centrality, connectivity=connectivity, weights=weights)
        if found is not None:
            return found
        name = centrality  # (checked by lookup)
        key = _key(mask, connectivity, weights)
        while True:
            with self._claim(key, name) as mine:
                if mine:
                    values = self._load(key, name, int(np.count_nonzero(mask)))  # written while we were looking
                    if values is None:
                        with self._lock:
                            self.misses += 1
                        values = _compute(mask, name, connectivity, weights)
                        self._save(key, name, values)
                    entry = self._remember(key, {"nodes": np.flatnonzero(mask)}, name, values)
                    return values, entry["nodes"]
            if not wait:
                return None
            time.sleep(_POLL_SECONDS)
            found = self.lookup(mask, name, connectivity=connectivity, weights=weights)
            if found is not None:
                return found

    @renamed_parameters(name="centrality")
    def put(
        self, mask: np.ndarray, centrality: str, values: np.ndarray, *, connectivity: int = 8, weights: bool = False
    ):
        """Store values computed elsewhere (e.g. by a worker) under ``mask``'s key.

        They are checked as :meth:`get` would compute them: a known centrality, a pixel
        connectivity, one finite value per foreground pixel (a NaN stored here was served
        to every later lookup).

        Parameters
        ----------
        mask : 2D array_like
            The shape: a boolean mask (True = shape), or a 0/1 or grey image split as
            :func:`as_shape_images` splits it with its defaults.
        centrality : str
            A centrality from :data:`centrality_vision.centrality.CENTRALITIES` (formerly
            ``name``).
        values : array_like of shape (n_foreground,)
            Finite real values, one per foreground pixel in row-major order.
        connectivity : {8, 4}, default=8
            Pixel neighbourhood the values were computed with.
        weights : bool, default=False
            Whether they were computed with Euclidean edge lengths (see :meth:`get`).

        Returns
        -------
        dict
            A copy of the image's entry in memory: ``"nodes"`` (flat pixel indices) and each
            centrality kept for it, ``centrality`` included, as read-only arrays. The values are also written to
            the ``directory``, unless a file for them is already there.
        """
        mask = _as_mask(mask)
        name = check_choice(centrality, CENTRALITIES, name="centrality")
        key = _key(mask, connectivity, weights)
        # (complex values lost their imaginary part, and a Python int beyond float64 raised OverflowError)
        values = as_real_array(values, name="values", shape="one value per foreground pixel")
        values = np.array(values, dtype=np.float64)
        if values.shape != (int(np.count_nonzero(mask)),):
            raise InputError(
                f"`values` must hold one value per foreground pixel ({int(np.count_nonzero(mask))}); "
                f"got shape {values.shape}."
            )
        if not np.all(np.isfinite(values)):
            raise InputError(f"`values` must be finite; got {int(np.count_nonzero(~np.isfinite(values)))} NaN or inf.")
        if self.directory is not None and not self._path(key, name).exists():
            self._save(key, name, values)
        with self._lock:
            entry = self._store.get(key)
        return self._remember(key, entry or {"nodes": np.flatnonzero(mask)}, name, values)


#: The process-wide in-memory cache that shape features use when given ``cache=None``.
default_cache = CentralityCache()
_directory_caches: dict[str, CentralityCache] = {}
_registry_lock = threading.Lock()


def resolve_cache(cache, *, name: str = "cache") -> CentralityCache:
    """``None`` -> :data:`default_cache`; a :class:`CentralityCache` -> itself; a path ->
    the process's cache on that directory (one per directory, so its memory is reused).

    Parameters
    ----------
    cache : None, CentralityCache, str or os.PathLike
        A path names a folder (created when first written to); ``~`` is expanded.
    name : str, default="cache"
        The parameter name error messages give.

    Returns
    -------
    CentralityCache

    Examples
    --------
    >>> resolve_cache(None) is default_cache
    True
    >>> own = CentralityCache()
    >>> resolve_cache(own) is own
    True
    """
    if cache is None:
        return default_cache
    if isinstance(cache, CentralityCache):
        return cache
    if isinstance(cache, (str, os.PathLike)):
        if not str(cache).strip():
            raise InputError(f"`{name}` must name a folder; got an empty path (for the current folder, pass '.').")
        directory = str(Path(cache).expanduser().resolve())
        with _registry_lock:
            if directory not in _directory_caches:
                _directory_caches[directory] = CentralityCache(directory=directory)
            return _directory_caches[directory]
    raise TypeError(f"`{name}` must be None, a CentralityCache or a directory path; got {type(cache).__name__}.")


def _kernel_threads(n_jobs: int) -> int:
    """Kernel threads per job: the cores divided among the jobs.

    Inside a joblib worker (which sets ``OMP_NUM_THREADS`` to its share of the cores)
    that share is honoured too, so nested parallelism does not oversubscribe.
    """
    from .._parallel import available_cores, get_num_threads

    threads = max(1, min(get_num_threads(), available_cores()) // max(1, n_jobs))
    env = os.environ.get("OMP_NUM_THREADS", "")
    if env.isdigit() and int(env) > 0:
        threads = min(threads, int(env))
    return threads


@contextmanager
def kernel_threads(n: int | None):
    """Run the centrality kernels on ``n`` threads inside the block (None: leave as is).

    Results do not depend on the thread count; only the speed does.
    """
    from .._parallel import _state, get_num_threads, set_num_threads

    if n is None or n == get_num_threads():
        yield
        return
    previous = _state["threads"]
    set_num_threads(n)
    try:
        yield
    finally:
        set_num_threads(previous)


def _worker(masks, names, connectivity, weights, cache, threads, parent):
    """One joblib task: the centralities of some images, through the (pickled) cache.

    In a worker process the kernels get the job's share of the cores; in a thread of
    the parent (joblib's threading backend) the thread count, a process-wide setting,
    is left alone.
    """
    with kernel_threads(threads if os.getpid() != parent else None):
        out = []
        for mask in masks:
            record = {}
            for name in names:
                record[name], _ = cache.get(mask, name, connectivity=connectivity, weights=weights)
            out.append(record)
    return out


def _effective_jobs(n_jobs) -> int:
    from joblib import effective_n_jobs

    if n_jobs is not None and (
        isinstance(n_jobs, bool) or not isinstance(n_jobs, (int, np.integer)) or n_jobs == 0 or abs(n_jobs) > 2**31 - 1
    ):  # (joblib passes it to C: beyond a C int, an OverflowError)
        raise InputError(
            f"`n_jobs` must be None, a positive int or a negative int (-1: all cores), at most 2^31 - 1 in size; "
            f"got {n_jobs!r}."
        )
    return effective_n_jobs(n_jobs)


def resolve_centralities(centrality, *, name: str = "centrality") -> tuple[str, ...]:
    """``"all"`` -> the four shape centralities; a name -> itself; a list -> checked tuple."""
    if isinstance(centrality, str):
        if centrality == "all":
            return SHAPE_CENTRALITIES
        return (check_choice(centrality, CENTRALITIES + ("all",), name=name),)
    if isinstance(centrality, (bytes, bytearray)):  # (iterated, its letters read as ints: "got 100")
        raise TypeError(f"`{name}` must be a centrality name (str), 'all' or a list of names; got {centrality!r}.")
    try:
        names = tuple(centrality)
    except TypeError:
        raise TypeError(f"`{name}` must be a centrality name, 'all' or a list of names; got {centrality!r}.") from None
    if not names:
        raise InputError(f"`{name}` must name at least one centrality; got an empty list.")
    names = tuple(check_choice(n, CENTRALITIES, name=name) for n in names)
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        twice = ", ".join(map(repr, repeated))
        raise InputError(f"`{name}` must name each centrality once; got {twice} more than once.")
    return names


@renamed_parameters(names="centrality")
def shape_centralities(
    images,
    centrality=SHAPE_CENTRALITIES,
    *,
    connectivity: int = 8,
    weights: bool = False,
    progress: bool = False,
    cache=None,
    n_jobs=None,
    foreground: str = "auto",
    threshold: float | None = None,
) -> list[dict[str, np.ndarray]]:
    """Centralities of the 8- (or 4-) neighbour pixel graph of each shape.

    Parameters
    ----------
    images : sequence of 2D arrays
        Shapes; sizes may differ. Masks (True/1 = shape) or grey images (see
        :func:`as_shape_images` for ``foreground`` and ``threshold``).
    centrality : str or sequence of str, default=SHAPE_CENTRALITIES
        Centralities to compute, each once (see :data:`centrality_vision.centrality.CENTRALITIES`;
        ``'all'``: the four of ``SHAPE_CENTRALITIES``, as elsewhere in this module; formerly
        ``names``).
    connectivity : {8, 4}
    weights : bool, default=False
        False counts hops (the thesis). True gives pixel edges their Euclidean lengths,
        1 and sqrt 2, for the shortest-path centralities (betweenness, closeness,
        harmonic, eccentricity), which makes them nearly invariant to rotation; degree
        and eigenvector do not change.
    progress : bool
        Show a progress bar on stderr.
    cache : None, CentralityCache or path
        Where results are kept: None is the process-wide in-memory
        :data:`default_cache`; a directory path gives a cache on disk that processes
        share (see :class:`CentralityCache`).
    n_jobs : int, optional
        Images computed at the same time, through :class:`joblib.Parallel` (so
        ``joblib.parallel_backend("dask")`` sends them to a Dask cluster); the kernel
        threads are divided among the jobs. None: one job (or the number set by an
        enclosing ``joblib.parallel_config``). Results do not depend on it.
    foreground, threshold :
        How grey images become masks (see :func:`as_shape_images`).

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
    masks = as_shape_images(images, foreground=foreground, threshold=threshold)
    names = resolve_centralities(centrality)
    if not is_connectivity(connectivity):
        raise InputError(f"`connectivity` must be 4 or 8; got {connectivity!r}.")
    connectivity = int(connectivity)
    check_bool(progress, name="progress")
    weights = check_bool(weights, name="weights")
    cache = resolve_cache(cache)
    jobs = _effective_jobs(n_jobs)
    options = {"connectivity": connectivity, "weights": weights}

    records: list[dict | None] = [None] * len(masks)
    missing = []
    for i, mask in enumerate(masks):
        record = {}
        for name in names:
            found = cache.lookup(mask, name, **options)
            if found is None:
                missing.append(i)
                break
            record[name], record["nodes"] = found
        else:
            records[i] = record
    if missing and jobs > 1 and len(missing) > 1:
        from joblib import Parallel, delayed

        chunks = [missing[k::jobs] for k in range(min(jobs, len(missing)))]
        parts = Parallel(n_jobs=len(chunks))(
            delayed(_worker)(
                [masks[i] for i in chunk],
                names,
                connectivity,
                weights,
                cache,
                _kernel_threads(len(chunks)),
                os.getpid(),
            )
            for chunk in chunks
        )
        for chunk, part in zip(chunks, parts):
            for i, record in zip(chunk, part):
                stored = {}
                for name in names:
                    # (each put's own entry: with max_images=0 the last put's entry holds only
                    # its own centrality, the earlier ones evicted)
                    entry = cache.put(masks[i], name, record[name], **options)
                    stored[name] = entry[name]
                records[i] = stored | {"nodes": entry["nodes"]}
        missing = []
    bar = None
    if progress and missing:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(missing), desc="centralities", unit="image", leave=False)
    try:
        with kernel_threads(_kernel_threads(1)):
            # First pass: images no other process is computing; second: wait for the rest.
            for wait in (False, True):
                left = []
                for i in missing:
                    record = {}
                    for name in names:
                        found = cache.get(masks[i], name, wait=wait, **options)
                        if found is None:
                            break
                        record[name], record["nodes"] = found
                    else:
                        records[i] = record
                        if bar is not None:
                            bar.update(1)
                        continue
                    left.append(i)
                missing = left
    finally:
        if bar is not None:
            bar.close()
    return records
