"""Exceptions and warnings raised by centrality-vision."""

__all__ = ["CentralityVisionError", "InputError", "ConvergenceWarning"]


class CentralityVisionError(Exception):
    """Base class of every exception raised on purpose by centrality-vision."""


class InputError(CentralityVisionError, ValueError):
    """An argument has the right type but an invalid value (shape, NaN, range, ...).

    It is a :class:`ValueError`, so ``except ValueError`` catches it.
    """


class ConvergenceWarning(UserWarning):
    """An iterative method stopped at ``max_iter`` before meeting ``tol``."""
