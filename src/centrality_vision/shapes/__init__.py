"""Centrality-based shape description and classification (thesis ch. 4).

- :class:`CentralityHistogram`: normalised histograms of pixel-graph centralities, a
  scikit-learn transformer from a list of binary images to feature rows.
- :class:`CentralityComparisons` and :class:`CentralityComparisonForest`: random binary
  comparisons of centrality values at shape-relative positions, and a random forest
  over them (thesis 4.3.3).
- :func:`shape_centralities` and :data:`default_cache`: centralities per image, computed
  once and cached.
"""

from ._cache import SHAPE_CENTRALITIES, CentralityCache, as_shape_images, default_cache, shape_centralities
from ._comparisons import CentralityComparisonForest, CentralityComparisons, centrality_map
from ._histogram import CentralityHistogram

__all__ = [
    "SHAPE_CENTRALITIES",
    "CentralityCache",
    "CentralityComparisonForest",
    "CentralityComparisons",
    "CentralityHistogram",
    "as_shape_images",
    "centrality_map",
    "default_cache",
    "shape_centralities",
]
