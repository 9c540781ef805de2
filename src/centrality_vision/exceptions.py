"""Exceptions and warnings raised by centrality-vision."""

__all__ = [
    "CentralityVisionError",
    "InputError",
    "CodeChangedError",
    "ConvergenceWarning",
    "CollapseWarning",
    "MatchingWarning",
]


class CentralityVisionError(Exception):
    """Base class of every exception raised on purpose by centrality-vision.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.transforms import RigidTransform
    >>> mirror = np.array([[1.0, 0.0], [0.0, -1.0]])  # not a proper rotation
    >>> try:
    ...     RigidTransform(mirror, [0.0, 0.0])
    ... except CentralityVisionError as exc:
    ...     print(type(exc).__name__, isinstance(exc, CentralityVisionError))
    InputError True
    """


class InputError(CentralityVisionError, ValueError):
    """An argument has the right type but an invalid value (shape, NaN, range, ...).

    It is a :class:`ValueError`, so ``except ValueError`` catches it.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.transforms import AffineTransform
    >>> AffineTransform(np.eye(2), [0.0, float("nan")])
    Traceback (most recent call last):
    ...
    centrality_vision.exceptions.InputError: `linear` and `translation` must be finite; got NaN or inf.
    >>> try:
    ...     AffineTransform(np.eye(2), [0.0, float("nan")])
    ... except ValueError as exc:
    ...     print(type(exc).__name__)
    InputError
    """


class CodeChangedError(CentralityVisionError, RuntimeError):
    """The package's files changed while a long run went on (a development install edited).

    A result computed then may come from code other than the one its stored key names, so
    it is not stored: the run stops, keeping the results stored before, and a new run
    computes the rest with the code as it is. It is a :class:`RuntimeError`.

    Examples
    --------
    >>> issubclass(CodeChangedError, RuntimeError), issubclass(CodeChangedError, CentralityVisionError)
    (True, True)
    """


class ConvergenceWarning(UserWarning):
    """An iterative method stopped at ``max_iter`` before meeting ``tol``.

    Examples
    --------
    >>> import warnings
    >>> import numpy as np
    >>> from centrality_vision.registration import RigidCPD
    >>> y = np.random.default_rng(0).random((20, 2))
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     reg = RigidCPD(max_iter=2).fit(y, y + 0.1)
    >>> [w.category.__name__ for w in caught], reg.converged_
    (['ConvergenceWarning'], False)

    Turned into an error, it can be caught as an exception:

    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", ConvergenceWarning)
    ...     try:
    ...         RigidCPD(max_iter=2).fit(y, y + 0.1)
    ...     except ConvergenceWarning as exc:
    ...         print(str(exc).split(" before")[0])
    RigidCPD stopped at `max_iter=2`
    """


class CollapseWarning(ConvergenceWarning):
    """A registration ended degenerate: the moving set shrank to a blob, the fitted Gaussians
    ended much wider than the transformed moving set (one blob explains the fixed set), or
    sigma2 reached zero while too few points were matched. The estimator's ``converged_`` is
    then False.

    Examples
    --------
    A similarity fit onto a dense blob with four far points shrinks the moving set onto
    the blob:

    >>> import warnings
    >>> import numpy as np
    >>> from centrality_vision.registration import RigidCPD
    >>> rng = np.random.default_rng(1)
    >>> y = rng.random((20, 2))
    >>> x = np.vstack([rng.normal(0.0, 1e-3, (20, 2)), [[50.0, 0.0], [-50.0, 0.0], [0.0, 50.0], [0.0, -50.0]]])
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     reg = RigidCPD(w=0.1, tol=1e-8).fit(y, x)
    >>> [w.category.__name__ for w in caught], reg.converged_, bool(reg.transform_.scale < 1e-6)
    (['CollapseWarning'], False, True)
    >>> issubclass(CollapseWarning, ConvergenceWarning)  # a filter on ConvergenceWarning covers it
    True
    """


class MatchingWarning(UserWarning):
    """A matching disagrees with its own fitted transform: some matched pairs are not nearest
    neighbours once the transform is applied, so the correspondences are not trustworthy.

    Examples
    --------
    The MWME matching pairs points by their degrees, which noise changes:

    >>> import warnings
    >>> import numpy as np
    >>> from centrality_vision.matching import match
    >>> rng = np.random.default_rng(0)
    >>> fixed = rng.random((12, 2))
    >>> noisy = fixed + rng.normal(0.0, 0.05, fixed.shape)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     result = match(noisy, fixed, method="mwme")
    >>> [w.category.__name__ for w in caught]
    ['MatchingWarning']
    >>> "not nearest neighbours" in str(caught[0].message)
    True
    """
