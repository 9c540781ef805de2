"""Data bundled with centrality-vision, loaded without network access.

- :func:`load_kimia99`: Kimia's 99 shapes, binary silhouettes in 9 classes of 11, from
  the LEMS vision group at Brown University (Sebastian, Klein and Kimia, IEEE PAMI 26(5),
  2004); used for the thesis' shape experiments (chapters 4 and 5).
- :func:`load_fish` and :func:`load_face`: the 2D fish and 3D face point-set pairs of
  Coherent Point Drift (Myronenko and Song, IEEE PAMI 32(12), 2010). The fish comes
  from pycpd (MIT licence); the face from Myronenko's CPD MATLAB package, distributed
  under the GNU GPL v2.

:func:`contour_points` samples point sets from the outlines of binary shapes.

The files live in ``centrality_vision/datasets/data/``; its ``README.md`` gives the
provenance and licence notice of each.
"""

from ._contours import contour_points
from ._loaders import Kimia99, PointSetPair, load_face, load_fish, load_kimia99

__all__ = ["Kimia99", "PointSetPair", "contour_points", "load_face", "load_fish", "load_kimia99"]
