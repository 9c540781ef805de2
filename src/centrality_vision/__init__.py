"""centrality-vision: graph centrality for computer vision.

Subpackages, in the one direction data flows:

- :mod:`centrality_vision.graphs`: pixel graphs and data-graphs of point sets.
- :mod:`centrality_vision.centrality`: degree, betweenness, closeness, harmonic,
  eigenvector and eccentricity centralities, and the degree entropy.
- :mod:`centrality_vision.datasets`: the bundled Kimia-99 silhouettes and CPD point sets.
- :mod:`centrality_vision.plotting`: figures (matplotlib is imported lazily).

The package's exceptions and warnings (:mod:`centrality_vision.exceptions`) are exported
here too: bad input raises :class:`InputError` (a ``ValueError``); a registration that
stops early warns :class:`ConvergenceWarning`, one whose scale or variance collapses
:class:`CollapseWarning`, and an unreliable matching :class:`MatchingWarning`; a long run
whose package files are edited while it goes on stops with :class:`CodeChangedError`.
"""

from importlib.metadata import PackageNotFoundError, version

from ._parallel import get_num_threads, set_num_threads
from .exceptions import (
    CentralityVisionError,
    CodeChangedError,
    CollapseWarning,
    ConvergenceWarning,
    InputError,
    MatchingWarning,
)

try:
    __version__ = version("centrality-vision")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0"

__all__ = [
    "CentralityVisionError",
    "CodeChangedError",
    "CollapseWarning",
    "ConvergenceWarning",
    "InputError",
    "MatchingWarning",
    "get_num_threads",
    "set_num_threads",
    "__version__",
]
