"""Former parameter names that still work for a while, with a FutureWarning."""

from __future__ import annotations

import functools
import inspect
import warnings

__all__ = ["renamed_parameters", "both_names_error"]


def both_names_error(old: str, new: str, detail: str = "") -> TypeError:
    """The error for a former parameter name given together with its new one (also for an
    estimator's former parameter, which stays in its signature for ``get_params``)."""
    return TypeError(f"`{old}` is the former name of `{new}`; give `{new}` only; got both{detail}.")


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
                warnings.warn(
                    f"{olds} of {function.__name__}() {'is' if len(given) == 1 else 'are'} renamed {news}; "
                    f"the old name{'s' if len(given) > 1 else ''} will be removed.",
                    FutureWarning,
                    stacklevel=2,
                )
            return function(*args, **kwargs)

        return wrapper

    return decorate
