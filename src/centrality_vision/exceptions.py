"""Exceptions and warnings raised by centrality-vision."""

__all__ = ["CentralityVisionError", "InputError", "ConvergenceWarning", "CollapseWarning", "MatchingWarning"]


class CentralityVisionError(Exception):
    """Base class of every exception raised on purpose by centrality-vision."""


class InputError(CentralityVisionError, ValueError):
    """An argument has the right type but an invalid value (shape, NaN, range, ...).

    It is a :class:`ValueError`, so ``except ValueError`` catches it.
    """


class ConvergenceWarning(UserWarning):
    """An iterative method stopped at ``max_iter`` before meeting ``tol``."""


class CollapseWarning(ConvergenceWarning):
    """A registration ended degenerate: the moving set shrank to a blob, or sigma2 reached
    zero while too few points were matched. The estimator's ``converged_`` is then False."""


class MatchingWarning(UserWarning):
    """A matching disagrees with its own fitted transform: some matched pairs are not nearest
    neighbours once the transform is applied, so the correspondences are not trustworthy."""
