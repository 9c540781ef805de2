"""Loaders for the data bundled in ``centrality_vision/datasets/data/``.

The files are read with :mod:`importlib.resources`, so the loaders work from a source
tree, an installed wheel or a zipped package alike. Every call returns new arrays that
the caller owns and may modify.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import NamedTuple

import numpy as np

from ..exceptions import InputError

__all__ = ["PointSetPair", "Kimia99", "load_fish", "load_face", "load_kimia99"]

_PACKAGE = "centrality_vision.datasets"
_KIMIA_THRESHOLD = 128  # foreground (shape) = pixel value < 128 in the dark-on-white PNGs


def _data_dir():
    return resources.files(_PACKAGE).joinpath("data")


class PointSetPair(NamedTuple):
    """A pair of point sets to register: ``moving`` is brought onto ``fixed``.

    A :class:`typing.NamedTuple`, so it unpacks as ``moving, fixed = load_fish()``.

    Attributes
    ----------
    moving : ndarray of shape (n_points, n_dims)
        The set that a registration transforms (CPD's Y, the ``*_source.txt`` file).
    fixed : ndarray of shape (n_points, n_dims)
        The set it is brought onto (CPD's X, the ``*_target.txt`` file).
    """

    moving: np.ndarray
    fixed: np.ndarray


@lru_cache(maxsize=None)
def _read_point_text(name: str) -> str:
    return _data_dir().joinpath("cpd", name).read_text(encoding="ascii")


def _load_points(name: str, n_dims: int) -> np.ndarray:
    points = np.loadtxt(io.StringIO(_read_point_text(name)), dtype=np.float64, ndmin=2)
    if points.shape[1] != n_dims:  # pragma: no cover - guards against a damaged install
        raise RuntimeError(f"Bundled file cpd/{name} should have {n_dims} columns; it has shape {points.shape}.")
    return points


def load_fish() -> PointSetPair:
    """The 2D fish of the Coherent Point Drift papers: two sets of 91 points.

    ``moving`` (CPD's Y) is a non-rigid deformation of ``fixed`` (CPD's X). The sets
    are used in the thesis' registration figures (figs. 5.4 and 5.7). Each call reads
    the data afresh, so the arrays may be modified freely.

    Returns
    -------
    data : PointSetPair
        ``moving`` and ``fixed``, float64 arrays of shape (91, 2); row i of one set is
        not assumed to correspond to row i of the other.

    References
    ----------
    .. [1] A. Myronenko and X. Song, "Point Set Registration: Coherent Point Drift",
       IEEE Trans. Pattern Anal. Mach. Intell. 32(12), 2262-2275, 2010.

    Examples
    --------
    >>> moving, fixed = load_fish()
    >>> moving.shape, fixed.shape, moving.dtype
    ((91, 2), (91, 2), dtype('float64'))
    """
    return PointSetPair(moving=_load_points("fish_source.txt", 2), fixed=_load_points("fish_target.txt", 2))


def load_face() -> PointSetPair:
    """The 3D face of the Coherent Point Drift package: two sets of 392 points.

    ``moving`` (CPD's Y) and ``fixed`` (CPD's X) are two versions of a face surface
    (thesis fig. 5.5). The data come from Myronenko's CPD MATLAB package, distributed
    under the GNU GPL v2; see ``data/README.md``. Each call reads the data afresh.

    Returns
    -------
    data : PointSetPair
        ``moving`` and ``fixed``, float64 arrays of shape (392, 3).

    References
    ----------
    .. [1] A. Myronenko and X. Song, "Point Set Registration: Coherent Point Drift",
       IEEE Trans. Pattern Anal. Mach. Intell. 32(12), 2262-2275, 2010.

    Examples
    --------
    >>> data = load_face()
    >>> data.moving.shape, data.fixed.shape
    ((392, 3), (392, 3))
    """
    return PointSetPair(moving=_load_points("face_source.txt", 3), fixed=_load_points("face_target.txt", 3))


@dataclass(frozen=True, eq=False, repr=False)
class Kimia99:
    """Kimia's 99 shapes: binary silhouettes in 9 classes of 11.

    Returned by :func:`load_kimia99`; entries are sorted by file name and aligned:
    ``images[i]`` is the silhouette named ``names[i]`` of class ``labels[i]``.

    Attributes
    ----------
    images : list of ndarray
        2D boolean masks, True on the shape. Sizes vary from image to image.
    labels : ndarray of str, shape (n_images,)
        Class of each image: ``'airplane'``, ``'dude'``, ``'fish'``, ``'greeble'``,
        ``'hand'``, ``'quadruped'``, ``'rabbit'``, ``'ray'`` or ``'tool'``.
    names : ndarray of str, shape (n_images,)
        File name of each image without ``.png``, e.g. ``'cow1'``.

    Examples
    --------
    >>> data = load_kimia99()
    >>> len(data), data.names[:2].tolist(), data.labels[:2].tolist()
    (99, ['bonefishes', 'bonefishesocc1'], ['fish', 'fish'])
    >>> data.image("cow1").shape
    (106, 120)
    """

    images: list[np.ndarray]
    labels: np.ndarray
    names: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.images)
        if len(self.labels) != n or len(self.names) != n:
            raise InputError(
                f"`images`, `labels` and `names` must have the same length; got {n}, "
                f"{len(self.labels)} and {len(self.names)}."
            )

    def __len__(self) -> int:
        return len(self.images)

    def __repr__(self) -> str:
        classes = np.unique(self.labels)
        return f"Kimia99(n_images={len(self)}, classes={classes.tolist()})"

    def image(self, name: str) -> np.ndarray:
        """Return the silhouette called ``name`` (a file stem such as ``'cow1'``).

        The array returned is the one held in :attr:`images` (not a copy).

        Raises
        ------
        InputError
            If no image has that name (an :class:`~centrality_vision.InputError`,
            which is a ``ValueError``).

        Examples
        --------
        >>> mask = load_kimia99().image("dog1")
        >>> mask.dtype, bool(mask.any() and not mask.all())
        (dtype('bool'), True)
        """
        hits = np.flatnonzero(self.names == name) if isinstance(name, str) else []
        if len(hits) == 0:
            shown = ", ".join(repr(str(s)) for s in self.names[:5])
            raise InputError(
                f"`name` must be one of the {len(self)} image names (e.g. {shown}, ...); got {name!r}."
            )
        return self.images[int(hits[0])]


@lru_cache(maxsize=1)
def _read_kimia99() -> tuple[tuple[np.ndarray, ...], tuple[str, ...], tuple[str, ...]]:
    """Decode the bundled PNGs once; the masks cached here are read-only."""
    from skimage.io import imread

    folder = _data_dir().joinpath("kimia99")
    with folder.joinpath("labels.csv").open("r", encoding="utf-8", newline="") as handle:
        label_of = {row["file"]: row["label"] for row in csv.DictReader(handle)}
    files = sorted(entry.name for entry in folder.iterdir() if entry.name.endswith(".png"))
    if sorted(label_of) != files:  # pragma: no cover - guards against a damaged install
        raise RuntimeError("Bundled kimia99/labels.csv does not list exactly the bundled PNG files.")
    masks = []
    for file in files:
        pixels = imread(io.BytesIO(folder.joinpath(file).read_bytes()))
        if pixels.ndim != 2:  # pragma: no cover - the bundled PNGs are grayscale
            raise RuntimeError(f"Bundled kimia99/{file} should be grayscale; it has shape {pixels.shape}.")
        mask = pixels < _KIMIA_THRESHOLD
        mask.setflags(write=False)
        masks.append(mask)
    names = tuple(file.removesuffix(".png") for file in files)
    labels = tuple(label_of[file] for file in files)
    return tuple(masks), labels, names


def load_kimia99() -> Kimia99:
    """Kimia's 99 shapes: 99 binary silhouettes, 9 classes of 11 (thesis ch. 4 and 5).

    The PNGs are dark shapes on a white background, a few with grey anti-aliasing
    pixels; a pixel is foreground (True) when its 8-bit value is below 128. The images
    are decoded once per process; each call returns new, writable copies, so changing
    one result does not affect another.

    Returns
    -------
    data : Kimia99
        ``images`` (list of 2D bool arrays), ``labels`` and ``names`` (str arrays of
        shape (99,)), sorted by file name; ``data.image("cow1")`` fetches one by name.

    References
    ----------
    .. [1] T. B. Sebastian, P. N. Klein and B. B. Kimia, "Recognition of shapes by
       editing their shock graphs", IEEE Trans. Pattern Anal. Mach. Intell. 26(5),
       550-571, 2004.

    Examples
    --------
    >>> data = load_kimia99()
    >>> len(data), np.unique(data.labels).tolist()  # doctest: +NORMALIZE_WHITESPACE
    (99, ['airplane', 'dude', 'fish', 'greeble', 'hand', 'quadruped', 'rabbit', 'ray',
          'tool'])
    >>> int(data.image("cow1").sum()) > 0
    True
    """
    masks, labels, names = _read_kimia99()
    return Kimia99(
        images=[mask.copy() for mask in masks],
        labels=np.array(labels, dtype=str),
        names=np.array(names, dtype=str),
    )
