"""Binary shapes from image files (PNG, BMP, GIF, TIFF, JPEG, PGM/PPM, WebP)."""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from .._validation import as_binary_image, is_real_dtype
from ..exceptions import InputError
from ._points import _existing_file, _first_line

__all__ = ["IMAGE_SUFFIXES", "read_image", "read_shape"]

#: Suffixes :func:`read_shape` reads (case-insensitive), all decoded by imageio.
IMAGE_SUFFIXES = (".png", ".bmp", ".gif", ".tif", ".tiff", ".jpg", ".jpeg", ".pgm", ".ppm", ".pbm", ".pnm", ".webp")
# The first bytes every file of a format starts with: a file that does not decode and lacks
# them is named as not of its suffix's format (the decoders' own words were their internals:
# "Could not find a backend to open <_io.BytesIO object at 0x...>").
_JPEG, _TIFF = (b"\xff\xd8\xff",), (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
_SIGNATURES = {
    ".png": (b"\x89PNG\r\n\x1a\n",),
    ".gif": (b"GIF87a", b"GIF89a"),
    ".bmp": (b"BM",),
    ".jpg": _JPEG,
    ".jpeg": _JPEG,
    ".tif": _TIFF,
    ".tiff": _TIFF,
}


def read_image(path, /) -> np.ndarray:
    """Read an image file as a 2D float64 grey image (colour averaged, alpha handled).

    The pixels are decoded by :func:`imageio.v3.imread` (TIFF files by :mod:`tifffile`):
    the first frame of an animated GIF, the first page of a multi-page TIFF (with a warning
    that says how many the file holds). Colour images become the mean of their red, green
    and blue channels. An alpha channel is ignored
    unless the colour is the same everywhere and only the alpha varies (a silhouette stored
    as transparency): then the alpha is the image.

    Parameters
    ----------
    path : str or os.PathLike
        An image file; see :data:`IMAGE_SUFFIXES`.

    Returns
    -------
    image : ndarray of shape (n_rows, n_cols), float64
        Row 0 is the top of the picture.

    Raises
    ------
    InputError
        Missing file, a suffix that is not an image's, a file that does not decode, or
        a decoded array that is not a 2D grey or colour image; the message starts with
        the path.

    Examples
    --------
    >>> import tempfile, pathlib, imageio.v3 as iio
    >>> pixels = np.array([[0, 255], [255, 255]], dtype=np.uint8)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     iio.imwrite(pathlib.Path(folder) / "a.bmp", pixels)
    ...     read_image(pathlib.Path(folder) / "a.bmp").tolist()
    [[0.0, 255.0], [255.0, 255.0]]
    """
    path = _existing_file(path)
    if path.suffix.lower() not in IMAGE_SUFFIXES:
        raise InputError(f"{path}: an image must be a {', '.join(IMAGE_SUFFIXES)} file; got suffix {path.suffix!r}.")
    import imageio.v3 as iio

    data = path.read_bytes()
    if not data:
        raise InputError(f"{path}: the file is empty.")
    kind = path.suffix.lower().lstrip(".").upper()
    try:  # decode from memory: a decoder failing on a damaged file then leaves no file open
        if kind in ("TIF", "TIFF"):
            pixels = _first_tiff_page(data, path)
        else:
            pixels = np.asarray(iio.imread(io.BytesIO(data), index=0, extension=path.suffix.lower()))
    except InputError:
        raise
    except Exception as exc:  # imageio and its plugins raise OSError, ValueError, SyntaxError, ...
        # (a file of another format under this suffix decodes: only a failure is explained so)
        signatures = _SIGNATURES.get(path.suffix.lower(), ())
        why = (
            f"it does not start as a {kind} file: {data[:8]!r}"
            if signatures and not data.startswith(signatures)
            else f"{type(exc).__name__}: {_first_line(exc)}"
        )
        raise InputError(f"{path}: not a readable {kind} image ({why}).") from None
    frames = _frame_count(data)
    if frames > 1:  # (a command-line user with a TIFF stack got a 2D result without a word)
        warnings.warn(
            f"{path}: holds {frames} frames (pages); the first is read, as a 2D image.", UserWarning, stacklevel=2
        )
    if np.iscomplexobj(pixels):  # a grey value has no imaginary part to drop silently
        raise InputError(f"{path}: the image has complex pixels ({pixels.dtype}); expected real grey or colour values.")
    if not is_real_dtype(pixels.dtype):
        raise InputError(f"{path}: not a readable {kind} image (pixel type {pixels.dtype}).")
    if pixels.size == 0:
        raise InputError(f"{path}: not a readable {kind} image (it decodes to no pixels, shape {pixels.shape}).")
    if pixels.ndim == 3 and pixels.shape[2] in (2, 4):
        colour, alpha = pixels[..., :-1], pixels[..., -1]
        flat = colour.reshape(-1, colour.shape[2])
        uniform_colour = bool(np.all(flat == flat[0])) if flat.size else True
        pixels = alpha if uniform_colour and np.ptp(alpha) > 0 else colour
    if pixels.ndim == 3 and pixels.shape[2] in (1, 3):
        pixels = pixels.astype(np.float64)
        if pixels.size and np.nanmax(np.abs(pixels)) > 1e300:  # (their sum overflowed): each channel's share
            pixels = (pixels / pixels.shape[2]).sum(axis=2)
        else:
            pixels = pixels.mean(axis=2)
    if pixels.ndim != 2:
        raise InputError(f"{path}: must be a 2D grey or colour image; got an array of shape {pixels.shape}.")
    pixels = pixels.astype(np.float64)
    if not np.all(np.isfinite(pixels)):
        raise InputError(f"{path}: the image holds NaN or inf values.")
    return pixels


def _frame_count(data: bytes) -> int:
    """How many frames (GIF, WebP, PNG animations) or pages (TIFF) the decoded file holds; 1
    where Pillow cannot tell."""
    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as image:
            return int(getattr(image, "n_frames", 1))
    except Exception:  # (a format Pillow does not open was decoded by another plugin)
        return 1


def _first_tiff_page(data: bytes, path) -> np.ndarray:
    """The first page of a TIFF file, as (rows, cols) or (rows, cols, samples).

    Read by page and laid out by the page's own axes: a whole series (what imageio's
    ``index=0`` gives) stacks every page, and pages 1 to 4 pixels wide then looked like the
    colour channels of one picture; a planar colour page stores its samples first.
    """
    import tifffile

    try:
        with tifffile.TiffFile(io.BytesIO(data)) as tif:
            page = tif.pages[0]
            pixels, axes = np.asarray(page.asarray()), str(page.axes)
    except Exception as exc:
        # tifffile decodes LZW and JPEG only with the optional imagecodecs; Pillow decodes
        # them itself (its first frame is the first page). The file's own error otherwise.
        import imageio.v3 as iio

        try:
            return np.asarray(iio.imread(io.BytesIO(data), index=0, plugin="pillow"))
        except Exception:
            raise exc from None
    if set(axes) - {"Y", "X", "S"} or len(axes) != pixels.ndim:
        raise InputError(
            f"{path}: must be a 2D grey or colour image; got a TIFF page of axes {axes} and shape {pixels.shape}."
        )
    if "S" in axes:
        pixels = np.moveaxis(pixels, axes.index("S"), -1)
    return pixels


def read_shape(path, /, *, foreground: str = "auto", threshold: float | None = None) -> np.ndarray:
    """Read an image file as a 2D boolean shape mask (True on the shape).

    The grey image from :func:`read_image` goes to
    :func:`centrality_vision._validation.as_binary_image`, the one rule of the package:
    it is split at ``threshold``, by default half its range (``(min + max) / 2``), and
    ``foreground`` says which side is the shape: ``"dark"`` (below the threshold, e.g.
    black silhouettes on white as in Kimia-99), ``"light"`` (above it), or ``"auto"``:
    the side that touches less of the image border, so both dark-on-white and
    white-on-black files work. A file is always read as grey levels: a 1-bit image
    (black and white, decoded as 0 and 1) is split the same way, so black on white is
    a black shape, not a mask whose white pixels are the shape. A shape that covers
    most of the border with an explicit ``foreground`` gives a :class:`UserWarning`
    (it looks inverted).

    Parameters
    ----------
    path : str or os.PathLike
        An image file (PNG, BMP, GIF, TIFF, JPEG, PGM/PPM, WebP).
    foreground : {"auto", "dark", "light"}, default="auto"
        Which side of the threshold is the shape.
    threshold : float, optional
        Grey level separating the two sides (pixels equal to it are dark); by default
        half the image's range.

    Returns
    -------
    mask : ndarray of bool, shape (n_rows, n_cols)

    Raises
    ------
    InputError
        Everything :func:`read_image` raises, a uniform image (no shape in it), a
        ``threshold`` that is NaN or infinite or leaves no shape, or a bad
        ``foreground``; the message starts with the path.
    TypeError
        A ``threshold`` that is not a real number.

    Examples
    --------
    >>> import tempfile, pathlib, imageio.v3 as iio
    >>> pixels = np.full((4, 5), 255, dtype=np.uint8)
    >>> pixels[1:3, 1:4] = 0  # a dark 2 x 3 rectangle on white
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     iio.imwrite(pathlib.Path(folder) / "shape.png", pixels)
    ...     mask = read_shape(pathlib.Path(folder) / "shape.png")
    >>> mask.astype(int)
    array([[0, 0, 0, 0, 0],
           [0, 1, 1, 1, 0],
           [0, 1, 1, 1, 0],
           [0, 0, 0, 0, 0]])
    """
    pixels = read_image(path)
    if threshold is None and pixels.min() == pixels.max():  # (0.5, set below, would be blamed for it)
        raise InputError(
            f"{Path(path)}: the image is uniform (every pixel is {pixels.flat[0]:g}): there is no shape in it."
        )
    if threshold is None and np.all((pixels == 0) | (pixels == 1)):
        # 0/1 pixels from a file are black and white, not a mask: split them at half their
        # range like any grey image, so ``foreground="auto"`` still finds the shape
        threshold = 0.5
    try:
        return as_binary_image(pixels, name="image", foreground=foreground, threshold=threshold, check_inverted=True)
    except InputError as exc:
        raise InputError(f"{Path(path)}: {exc}") from None
