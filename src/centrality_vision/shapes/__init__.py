"""Centrality-based shape description and classification (thesis ch. 4).

- :class:`CentralityHistogram`: normalised histograms of pixel-graph centralities, a
  scikit-learn transformer from a list of binary images to feature rows.
- :class:`CentralityComparisons` and :class:`CentralityComparisonForest`: random binary
  comparisons of centrality values at shape-relative positions, and a random forest
  over them (thesis 4.3.3).
- :func:`pairwise_shape_distances`: shape retrieval from outline profiles of reach and
  inner distances on the pixel graph, or from centrality histograms (chi-square, earth
  mover's), with :func:`diffusion_rerank` and the field's scores
  (:func:`bullseye_score`, :func:`retrieval_counts`, :func:`nearest_neighbor_accuracy`).
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
from ._retrieval import (
    ANGLE_QUANTILES,
    ANGLE_REACH,
    DISTANCE_QUANTILES,
    FEATURE_SCALES,
    REACH_RADII,
    VISIBILITY_QUANTILES,
    bullseye_score,
    diffusion_rerank,
    nearest_neighbor_accuracy,
    nearest_neighbour_accuracy,  # noqa: F401 (the former name, not in __all__)
    normalize_shape,
    outline_profiles,
    pairwise_shape_distances,
    retrieval_counts,
    shape_distance,
)

__all__ = [
    "ANGLE_QUANTILES",
    "ANGLE_REACH",
    "DISTANCE_QUANTILES",
    "FEATURE_SCALES",
    "REACH_RADII",
    "VISIBILITY_QUANTILES",
    "PATH_CENTRALITIES",
    "SHAPE_CENTRALITIES",
    "CentralityCache",
    "CentralityComparisonForest",
    "CentralityComparisons",
    "CentralityHistogram",
    "as_shape_images",
    "bullseye_score",
    "diffusion_rerank",
    "nearest_neighbor_accuracy",
    "normalize_shape",
    "outline_profiles",
    "pairwise_shape_distances",
    "retrieval_counts",
    "shape_distance",
    "centrality_map",
    "default_cache",
    "resolve_cache",
    "shape_centralities",
]
