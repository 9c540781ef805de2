"""Point-set matching without iterative registration (thesis ch. 6).

- :func:`mwme_match`: correspondences from the degrees of the minimum-weight
  maximum-entropy graphs of the two sets, and the similarity transform they give.
"""

from ._mwme import mwme_match

__all__ = ["mwme_match"]
