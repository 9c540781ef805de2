"""Centrality-based shape description and classification (thesis ch. 4).

- :class:`CentralityHistogram`: normalised histograms of pixel-graph centralities, a
  scikit-learn transformer from a list of binary images to feature rows.
- :class:`CentralityComparisons` and :class:`CentralityComparisonForest`: random binary
  comparisons of centrality values at shape-relative positions, and a random forest
  over them (thesis 4.3.3).
- :func:`shape_centralities` and :class:`CentralityCache`: centralities per image,
  computed once and cached (in memory, or on disk shared by worker processes), in
  parallel with ``n_jobs``.
"""

from ._cache import (
    PATH_CENTRALITIES,
    SHAPE_CENTRALITIES,
    CentralityCache,
    as_shape_images,
    default_cache,
    resolve_cache,
    shape_centralities,
)
from ._comparisons import CentralityComparisonForest, CentralityComparisons, centrality_map
from ._histogram import CentralityHistogram

__all__ = [
    "PATH_CENTRALITIES",
    "SHAPE_CENTRALITIES",
    "CentralityCache",
    "CentralityComparisonForest",
    "CentralityComparisons",
    "CentralityHistogram",
    "as_shape_images",
    "centrality_map",
    "default_cache",
    "resolve_cache",
    "shape_centralities",
]
