"""Reading and writing the files users have: point sets and binary shapes.

- :func:`read_points` reads a point set from delimited text (``.csv``, ``.txt``,
  ``.tsv``, ``.xyz``; header, delimiter and decimal comma found by themselves), NumPy
  (``.npy``), MATLAB (``.mat``), PLY, PCD (ASCII or binary) and OBJ files, picking the
  coordinate columns by name or index.
- :func:`write_points` writes a point set in any of those formats but ``.tsv``
  (:data:`WRITE_SUFFIXES`; PLY, PCD and OBJ for 3D points only); :func:`read_points`
  reads every file it writes back exactly.
- :func:`read_shape` reads a binary shape (a silhouette) from any image file imageio
  decodes (PNG, BMP, GIF, TIFF, JPEG, ...); :func:`read_image` gives the grey image.

Every problem with a file is an :class:`~centrality_vision.exceptions.InputError` (a
``ValueError``) whose one-line message starts with the file's path.
"""

from ._images import IMAGE_SUFFIXES, read_image, read_shape
from ._points import POINT_SUFFIXES, WRITE_SUFFIXES, read_points, write_points

__all__ = [
    "IMAGE_SUFFIXES",
    "POINT_SUFFIXES",
    "WRITE_SUFFIXES",
    "read_image",
    "read_points",
    "read_shape",
    "write_points",
]
