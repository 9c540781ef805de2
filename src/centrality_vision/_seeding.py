"""Seeding: one convention for every random choice in the package."""

from __future__ import annotations

import numbers

import numpy as np

__all__ = ["as_generator"]


def as_generator(seed, *, name: str = "seed") -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` from ``seed``.

    ``seed`` may be ``None`` (fresh entropy), a non-negative int, or a Generator (used as it
    is, so a caller can thread one generator through several calls). ``name`` is the
    parameter an error names.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        return np.random.default_rng()
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise TypeError(f"`{name}` must be None, a non-negative int or a numpy.random.Generator; got {seed!r}.")
    return np.random.default_rng(int(seed))
