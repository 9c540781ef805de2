"""Former parameter and function names that still work for a while, with a FutureWarning."""

from __future__ import annotations

import functools
import inspect

from ._warnings import warn

__all__ = ["renamed_parameters", "renamed_function", "both_names_error", "FORMER", "former_parameter"]

#: The default of an estimator's former parameter name: "not given".
FORMER = "deprecated"


def both_names_error(old: str, new: str, detail: str = "") -> TypeError:
    """The error for a former parameter name given together with its new one (also for an
    estimator's former parameter, which stays in its signature for ``get_params``)."""
    return TypeError(f"`{old}` is the former name of `{new}`; give `{new}` only; got both{detail}.")


def former_parameter(estimator, old: str, new: str):
    """The value to use of an estimator parameter renamed ``old`` -> ``new``, and the name
    to check it under (``"Class.old"`` or ``"Class.new"``).

    An estimator keeps its former parameter in its signature, with the default
    :data:`FORMER`, because ``get_params`` and ``clone`` read every parameter. When it was
    given, its value is used with a :class:`FutureWarning`; given together with a new
    value other than the new parameter's default, it is a :class:`TypeError`.

    Examples
    --------
    >>> import warnings
    >>> class Fit:
    ...     def __init__(self, max_iter=10, iters=FORMER):
    ...         self.max_iter, self.iters = max_iter, iters
    >>> former_parameter(Fit(max_iter=5), "iters", "max_iter")
    (5, 'Fit.max_iter')
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     former_parameter(Fit(iters=3), "iters", "max_iter")
    (3, 'Fit.iters')
    >>> print(caught[0].message)
    `iters` of Fit is renamed `max_iter`; the old name will be removed.
    """
    kind = type(estimator).__name__
    value = getattr(estimator, old)
    if isinstance(value, str) and value == FORMER:
        return getattr(estimator, new), f"{kind}.{new}"
    current = getattr(estimator, new)
    default = inspect.signature(type(estimator).__init__).parameters[new].default
    if not (current is default or (type(current) is type(default) and current == default)):
        raise both_names_error(f"{kind}.{old}", new)
    warn(f"`{old}` of {kind} is renamed `{new}`; the old name will be removed.", FutureWarning)
    return value, f"{kind}.{old}"


def renamed_parameters(**new_names: str):
    """Decorate a function whose parameters were renamed (``old="new"``).

    A call that passes a former name as a keyword runs as if it had passed the new name,
    with a :class:`FutureWarning` saying so; passing both names is a :class:`TypeError`.
    The signature (and the documentation) shows the new names only.

    Examples
    --------
    >>> import warnings
    >>> @renamed_parameters(source="moving")
    ... def shift(moving, by=1):
    ...     return moving + by
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     shift(source=1)
    2
    >>> print(caught[0].message)
    `source` of shift() is renamed `moving`; the old name will be removed.
    """

    def decorate(function):
        # a class is called by its name, not by its __init__
        label = function.__qualname__.rsplit(".", 1)[0] if function.__name__ == "__init__" else function.__name__

        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            given = [old for old in new_names if old in kwargs]
            # the new names the positional arguments fill (Python's "multiple values" error
            # named only the new name)
            positional = list(inspect.signature(function).parameters)[: len(args)] if given else []
            for old in given:
                if new_names[old] in kwargs or new_names[old] in positional:
                    raise both_names_error(old, new_names[old])
                kwargs[new_names[old]] = kwargs.pop(old)
            if given:  # one warning per call
                olds = " and ".join(f"`{old}`" for old in given)
                news = " and ".join(f"`{new_names[old]}`" for old in given)
                warn(
                    f"{olds} of {label}() {'is' if len(given) == 1 else 'are'} renamed {news}; "
                    f"the old name{'s' if len(given) > 1 else ''} will be removed.",
                    FutureWarning,
                )
            return function(*args, **kwargs)

        return wrapper

    return decorate


def renamed_function(function, old: str):
    """``function`` under its former name ``old``: the same call, with a :class:`FutureWarning`.

    Examples
    --------
    >>> import warnings
    >>> def shift(moving, by=1):
    ...     return moving + by
    >>> old_shift = renamed_function(shift, "move")
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     old_shift(1, by=2)
    3
    >>> print(caught[0].message)
    `move()` is renamed `shift()`; the old name will be removed.
    """

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        warn(f"`{old}()` is renamed `{function.__name__}()`; the old name will be removed.", FutureWarning)
        return function(*args, **kwargs)

    wrapper.__name__ = wrapper.__qualname__ = old
    wrapper.__doc__ = f"Former name of :func:`{function.__name__}` (renamed; the old name will be removed)."
    return wrapper
