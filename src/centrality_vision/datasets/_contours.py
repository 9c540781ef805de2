"""Point sets sampled from binary shapes."""

from __future__ import annotations

import numpy as np

from .._validation import as_binary_image, check_int

__all__ = ["contour_points"]


#: The most points :func:`contour_points` returns (160 MB; 10**12 asked numpy for 7 TiB).
_MAX_POINTS = 10_000_000


def contour_points(image, n_points: int, /) -> np.ndarray:
    """Points equally spaced by arc length along the outer contour of a binary shape.

    The iso-contour at level 0.5 of the (zero-padded) mask that encloses the largest area
    (the outer boundary of the largest component, never a hole's) is resampled by linear
    interpolation at ``n_points`` equally spaced arc lengths, starting at the contour's
    first point. Coordinates are (row, col) in pixels.

    Parameters
    ----------
    image : array_like of shape (n_rows, n_cols)
        Binary shape (see :func:`centrality_vision.graphs.pixel_graph`).
    n_points : int, 3 to 10,000,000

    Returns
    -------
    ndarray of shape (n_points, 2)

    Examples
    --------
    >>> import numpy as np
    >>> square = np.zeros((12, 12), dtype=bool); square[2:10, 2:10] = True
    >>> pts = contour_points(square, 16)
    >>> pts.shape, bool(np.all((pts >= 1) & (pts <= 10)))
    ((16, 2), True)
    """
    from skimage.measure import find_contours

    mask = as_binary_image(image, name="image")
    n_points = check_int(n_points, name="n_points", low=3, high=_MAX_POINTS)
    padded = np.pad(mask, 1).astype(float)
    # the outer contour is the one enclosing the largest area (a hole's outline can be the
    # longest: a comb-shaped hole in a square, found by a fuzz run, took all the points)
    contour = max(find_contours(padded, 0.5), key=lambda c: abs(signed_area(c))) - 1.0
    if not np.allclose(contour[0], contour[-1]):
        contour = np.vstack([contour, contour[:1]])
    steps = np.linalg.norm(np.diff(contour, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    targets = np.linspace(0.0, arc[-1], n_points, endpoint=False)
    return np.stack([np.interp(targets, arc, contour[:, 0]), np.interp(targets, arc, contour[:, 1])], axis=1)


def signed_area(contour: np.ndarray) -> float:
    """Signed area of a closed (row, col) polygon by the shoelace formula (positive
    counter-clockwise in (col, row) axes)."""
    rows, cols = contour[:, 0], contour[:, 1]
    return 0.5 * float(np.sum(cols * np.roll(rows, -1) - np.roll(cols, -1) * rows))
