"""Loaders for the data bundled in ``centrality_vision/datasets/data/``.

The files are read with :mod:`importlib.resources`, so the loaders work from a source
tree, an installed wheel or a zipped package alike. Every call returns new arrays that
the caller owns and may modify.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass
from fnmatch import fnmatch
from functools import cache, lru_cache
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..exceptions import InputError

__all__ = ["DATA_ENV", "PointSetPair", "Kimia99", "MPEG7", "load_fish", "load_face", "load_kimia99", "load_mpeg7"]

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

    Examples
    --------
    >>> moving, fixed = load_fish()
    >>> moving.shape, fixed.shape
    ((91, 2), (91, 2))
    >>> pair = load_fish()
    >>> pair.moving.shape == pair[0].shape, pair._fields
    (True, ('moving', 'fixed'))
    """

    moving: np.ndarray
    fixed: np.ndarray


@cache
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


#: Environment variable naming a folder laid out like the project's shared data
#: (``cpd/face_*.txt``, ``mpeg7/*.gif``): where :func:`load_face` and :func:`load_mpeg7`
#: look when given no path.
DATA_ENV = "CENTRALITY_VISION_DATA"


def _data_root(path, what: str, sub: str, needed: str, hint: str) -> Path:
    """The folder holding a file matching ``needed`` (a lower-case glob, matched case-insensitively):
    ``path``, ``path/sub``, ``$DATA_ENV/sub``, or the ``shared/data/sub`` folder beside a source
    checkout; an error naming them otherwise."""
    tried = []
    if path is not None:
        if not isinstance(path, (str, os.PathLike)):
            raise TypeError(f"`path` must be a folder path (str or os.PathLike) or None; got {type(path).__name__}.")
        if not os.fspath(path):  # (Path("") is the current folder)
            raise InputError(f"`path` must be a folder holding {needed}; got an empty path.")
        if Path(path).is_file():
            raise InputError(f"`path` must be a folder holding {needed}; got the file {str(path)!r}.")
        candidates = [Path(path), Path(path) / sub]
    else:
        candidates = []
        env = os.environ.get(DATA_ENV)
        if env:
            candidates += [Path(env) / sub, Path(env)]
        checkout = Path(__file__).resolve().parents[3]  # <checkout>/src/centrality_vision/datasets
        if (checkout / "pyproject.toml").is_file():
            candidates.append(checkout.parent / "shared" / "data" / sub)
    for folder in candidates:
        tried.append(str(folder))
        # (case-insensitive: a folder of .GIF files is read, as the loaders read them)
        if folder.is_dir() and any(
            entry.is_file() and fnmatch(entry.name.lower(), needed) for entry in folder.iterdir()
        ):
            return folder
    where = ", ".join(tried) if tried else f"nowhere (no `path` given and ${DATA_ENV} is not set)"
    raise FileNotFoundError(
        f"{what} is not bundled with centrality-vision ({hint}). Pass `path=` a folder holding {needed}, "
        f"or set ${DATA_ENV} to a folder with a {sub}/ subfolder. Looked in: {where}."
    )


def load_face(path=None) -> PointSetPair:
    """The 3D face of the Coherent Point Drift package: two sets of 392 points.

    ``moving`` (CPD's Y) and ``fixed`` (CPD's X) are two versions of a face surface
    (thesis fig. 5.5). The data come from Myronenko's CPD MATLAB package, distributed
    under the GNU GPL v2, so they are not shipped with this BSD-3 package: the loader
    reads ``face_source.txt`` (Y) and ``face_target.txt`` (X), one point per line,
    from a folder you give. Each call reads the files afresh.

    Parameters
    ----------
    path : str or os.PathLike, optional
        A folder holding the two files (or a ``cpd/`` subfolder holding them). By
        default ``$CENTRALITY_VISION_DATA/cpd``, then, in a source checkout, the
        ``shared/data/cpd`` folder beside it.

    Returns
    -------
    data : PointSetPair
        ``moving`` and ``fixed``, float64 arrays of shape (392, 3).

    Raises
    ------
    FileNotFoundError
        When no folder holds the files; the message lists where it looked.
    InputError
        ``path`` is a file or empty, or a file is not 3 coordinates per line (read by
        :func:`centrality_vision.io.read_points`: a header line, commas or a byte-order
        mark are fine; the error names the line).

    References
    ----------
    .. [1] A. Myronenko and X. Song, "Point Set Registration: Coherent Point Drift",
       IEEE Trans. Pattern Anal. Mach. Intell. 32(12), 2262-2275, 2010.

    Examples
    --------
    >>> try:
    ...     data = load_face()
    ... except FileNotFoundError:  # the data is not installed with the package
    ...     data = None
    >>> data is None or (data.moving.shape, data.fixed.shape) == ((392, 3), (392, 3))
    True
    """
    folder = _data_root(
        path, "The CPD face", "cpd", "face_source.txt", "it is GPL-2; copy face_*.txt of the CPD package to a folder"
    )
    from ..io import read_points

    pair = []
    for name in ("face_source.txt", "face_target.txt"):
        if not (folder / name).is_file():
            raise FileNotFoundError(f"{folder} holds face_source.txt but not {name}, which the CPD face needs.")
        # (the package's reader: a header, a byte-order mark or commas are read, errors name the line)
        pair.append(read_points(folder / name, n_dims=(3,)))
    return PointSetPair(moving=pair[0], fixed=pair[1])


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
        for name in ("images", "labels", "names"):
            if not hasattr(getattr(self, name), "__len__"):
                raise TypeError(f"`{name}` must be a sequence; got {getattr(self, name)!r}.")
        n = len(self.images)
        if len(self.labels) != n or len(self.names) != n:
            raise InputError(
                f"`images`, `labels` and `names` must have the same length; got {n}, "
                f"{len(self.labels)} and {len(self.names)}."
            )
        # arrays of str, as documented: ``image`` compares names element-wise (a list of names
        # compared equal to no name at all)
        for name in ("labels", "names"):
            if not all(isinstance(item, (str, np.str_)) for item in getattr(self, name)):
                raise TypeError(f"`{name}` must hold strings; got {getattr(self, name)!r}.")
            object.__setattr__(self, name, np.array(list(getattr(self, name)), dtype=str))
        for i, image in enumerate(self.images):
            if not isinstance(image, np.ndarray) or image.ndim != 2 or image.dtype != bool:
                what = (
                    f"an array of shape {image.shape} and dtype {image.dtype}"
                    if isinstance(image, np.ndarray)
                    else (f"{type(image).__name__}")
                )
                raise TypeError(f"`images` must hold 2D bool masks; got {what} at index {i}.")
        object.__setattr__(self, "images", list(self.images))

    def __len__(self) -> int:
        return len(self.images)

    def __repr__(self) -> str:
        classes = np.unique(self.labels)
        return f"Kimia99(n_images={len(self)}, classes={classes.tolist()})"

    def image(self, name: str) -> np.ndarray:
        """Return the silhouette called ``name`` (a file stem such as ``'cow1'``).

        The array returned is the one held in :attr:`images` (not a copy).

        Parameters
        ----------
        name : str
            One of :attr:`names`.

        Returns
        -------
        ndarray of bool
            The 2D mask ``images[i]`` of the first ``i`` with ``names[i] == name``.

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
        if not isinstance(name, str):  # (an index or bytes: a wrong type, not an unknown name)
            raise TypeError(f"`name` must be an image name (str), e.g. 'dog1'; got {name!r}.")
        hits = np.flatnonzero(self.names == name)
        if len(hits) == 0:
            shown = ", ".join(repr(str(s)) for s in self.names[:5])
            raise InputError(f"`name` must be one of the {len(self)} image names (e.g. {shown}, ...); got {name!r}.")
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


class MPEG7(Kimia99):
    """MPEG-7 CE-Shape-1 part B: 1,400 silhouettes in 70 classes of 20.

    Returned by :func:`load_mpeg7`; the same fields as :class:`Kimia99` (``images``,
    ``labels``, ``names``, ``image(name)``), sorted by file name. Labels are the file
    names' class part (``'apple'``, ``'Bone'``, ...); names are file stems
    (``'apple-1'``).

    Examples
    --------
    The data set is not shipped with the package; :func:`load_mpeg7` reads it from a
    folder of GIFs (``$CENTRALITY_VISION_DATA/mpeg7`` by default):

    >>> data = load_mpeg7(classes=["apple", "bat"])  # doctest: +SKIP
    >>> data, data.names[:2].tolist()  # doctest: +SKIP
    (MPEG7(n_images=40, n_classes=2), ['apple-1', 'apple-10'])

    It holds the fields of :class:`Kimia99`; a small one built by hand:

    >>> import numpy as np
    >>> square = np.zeros((5, 5), dtype=bool); square[1:4, 1:4] = True
    >>> small = MPEG7(images=[square, square.T], labels=["apple", "apple"], names=["apple-1", "apple-2"])
    >>> small, len(small), int(small.image("apple-2").sum())
    (MPEG7(n_images=2, n_classes=1), 2, 9)
    """

    def __repr__(self) -> str:
        return f"MPEG7(n_images={len(self)}, n_classes={np.unique(self.labels).size})"


def _read_gif_mask(path: Path) -> np.ndarray:
    """The light shape of one GIF; the package's image reader names the file when it is empty,
    damaged, not an image or too large to decode (imageio's OSError and PIL's errors before)."""
    from .._validation import as_binary_image
    from ..io import read_image

    return as_binary_image(read_image(path), name=str(path), foreground="light")


def load_mpeg7(path=None, *, classes=None) -> MPEG7:
    """MPEG-7 CE-Shape-1 part B, read from a folder of ``<class>-<i>.gif`` files.

    The standard shape-retrieval set (Latecki, Lakaemper and Eckhardt, CVPR 2000):
    1,400 binary silhouettes, white on black, 70 classes of 20. It is not shipped with
    the package (no licence text comes with it); give the folder. A pixel is shape
    when it is lighter than half the image's range.

    Parameters
    ----------
    path : str or os.PathLike, optional
        The folder holding the GIFs (or an ``mpeg7/`` subfolder holding them). By
        default ``$CENTRALITY_VISION_DATA/mpeg7``, then, in a source checkout, the
        ``shared/data/mpeg7`` folder beside it.
    classes : sequence of str, optional
        Read only these classes (all by default).

    Returns
    -------
    data : MPEG7
        ``images`` (2D bool arrays), ``labels`` and ``names`` (str arrays), sorted by
        file name.

    Raises
    ------
    FileNotFoundError
        When no folder holds the GIFs; the message lists where it looked.
    InputError
        A file name without ``-<number>``, or an unknown class in ``classes``.

    References
    ----------
    .. [1] L. J. Latecki, R. Lakaemper and U. Eckhardt, "Shape descriptors for non-rigid
       shapes with a single closed contour", CVPR 2000.

    Examples
    --------
    >>> try:
    ...     data = load_mpeg7(classes=["apple"])
    ... except FileNotFoundError:  # the data is not installed with the package
    ...     data = None
    >>> data is None or (len(data), set(data.labels.tolist())) == (20, {"apple"})
    True
    """
    folder = _data_root(path, "MPEG-7", "mpeg7", "*.gif", "download CE-Shape-1 part B")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".gif" and p.is_file())
    labels = []
    for file in files:
        label, sep, number = file.stem.rpartition("-")
        if not sep or not number.isdigit():
            raise InputError(f"{file}: MPEG-7 file names must look like <class>-<number>.gif.")
        labels.append(label)
    if classes is not None:
        if isinstance(classes, str):
            classes = [classes]
        given = classes
        # (bytes iterate as ints: b"apple" was shown as [97, 112, ...])
        if not hasattr(classes, "__iter__") or isinstance(classes, (bytes, bytearray)):
            raise TypeError(f"`classes` must be a class name or a sequence of them; got {given!r}.")
        classes = list(classes)  # once: a generator is used up by the check below
        if not all(isinstance(c, str) for c in classes):
            raise TypeError(f"`classes` must be a class name or a sequence of them; got {classes!r}.")
        if not classes:
            raise InputError("`classes` must name at least one class (None loads them all); got an empty list.")
        unknown = sorted(set(classes) - set(labels))
        if unknown:
            raise InputError(f"`classes` must be MPEG-7 classes found in {folder}; got unknown {unknown}.")
        keep = [i for i, label in enumerate(labels) if label in set(classes)]
        files, labels = [files[i] for i in keep], [labels[i] for i in keep]
    return MPEG7(
        images=[_read_gif_mask(file) for file in files],
        labels=np.array(labels, dtype=str),
        names=np.array([file.stem for file in files], dtype=str),
    )
