"""Data bundled with centrality-vision, loaded without network access.

- :func:`load_kimia99`: Kimia's 99 shapes, binary silhouettes in 9 classes of 11, from
  the LEMS vision group at Brown University (Sebastian, Klein and Kimia, IEEE PAMI 26(5),
  2004); used for the thesis' shape experiments (chapters 4 and 5).
- :func:`load_fish`: the 2D fish point-set pair of Coherent Point Drift (Myronenko and
  Song, IEEE PAMI 32(12), 2010), from pycpd (MIT licence).

Not bundled (their terms do not allow it in a BSD-3 wheel, or none are stated); the
loaders read them from a folder you give, ``$CENTRALITY_VISION_DATA``, or the
``shared/data`` folder beside a source checkout:

- :func:`load_face`: the 3D face pair of CPD, from Myronenko's CPD MATLAB package
  (GNU GPL v2).
- :func:`load_mpeg7`: MPEG-7 CE-Shape-1 part B, 1,400 silhouettes in 70 classes, the
  standard shape-retrieval benchmark.

:func:`contour_points` samples point sets from the outlines of binary shapes.

The files live in ``centrality_vision/datasets/data/``; its ``README.md`` gives the
provenance and licence notice of each.
"""

from ._contours import contour_points
from ._loaders import DATA_ENV, MPEG7, Kimia99, PointSetPair, load_face, load_fish, load_kimia99, load_mpeg7

__all__ = [
    "DATA_ENV",
    "MPEG7",
    "Kimia99",
    "PointSetPair",
    "contour_points",
    "load_face",
    "load_fish",
    "load_kimia99",
    "load_mpeg7",
]
