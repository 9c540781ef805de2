"""Point-set matching without iterative registration (thesis ch. 6 and its future work).

- :func:`match`: one entry point, ``match(moving, fixed, method=...)`` returning a
  :class:`MatchResult` (correspondence moving -> fixed with -1 for unmatched points, and
  the fitted similarity transform). Methods: ``"robust"`` (local MWME signatures,
  consensus over similarity hypotheses, refinement), ``"mwme"`` (the thesis' global
  matching) and ``"shape-context"`` (shape contexts with Hungarian assignment, the
  baseline).
- :func:`mwme_match`: correspondences from the degrees of the minimum-weight
  maximum-entropy graphs of the two sets, and the similarity transform they give.
"""

from ._api import METHODS, match
from ._common import MatchResult
from ._mwme import mwme_match

__all__ = ["match", "MatchResult", "METHODS", "mwme_match"]
