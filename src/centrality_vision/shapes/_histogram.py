"""Centrality histograms of binary shapes (thesis 4.3.2)."""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validation import check_bool, check_choice, check_int
from ..exceptions import InputError
from ._cache import (
    _effective_jobs,
    as_shape_images,
    is_connectivity,
    resolve_cache,
    resolve_centralities,
    shape_centralities,
)

__all__ = ["CentralityHistogram", "ShapeInputMixin", "resolve_centralities"]


def _same(a, b) -> bool:
    """Whether a parameter kept its value (a generator or a cache: the same object)."""
    if a is b:
        return True
    try:
        return type(a) is type(b) and bool(a == b)
    except (TypeError, ValueError):  # (an array's ambiguous truth value)
        return False


class ShapeInputMixin:
    """How the shape estimators read images and get their centralities.

    Uses the parameters ``connectivity``, ``weights``, ``foreground``, ``threshold``,
    ``cache``, ``n_jobs`` and ``progress`` of the estimator (see
    :func:`~centrality_vision.shapes.shape_centralities`). After ``fit``, only ``cache``,
    ``n_jobs`` and ``progress`` (how the work runs) may change: ``transform`` and
    ``predict`` refuse any other parameter changed since fit, whose features would not be
    the fitted ones.
    """

    #: parameters of how the work runs, not of what it gives: they may change after fit
    _RUN_PARAMETERS = frozenset({"progress", "cache", "n_jobs"})

    def _result_parameters(self) -> dict:
        return {
            name: tuple(value) if isinstance(value, list) else value
            for name, value in self.get_params(deep=False).items()
            if name not in self._RUN_PARAMETERS
        }

    def _remember_parameters(self) -> None:
        """At the end of fit: the parameters the fitted state was made with."""
        self._fitted_parameters = self._result_parameters()

    def _check_unchanged(self) -> None:
        """After fit, every parameter but how the work runs must be the fit's: features (or a
        forest's votes) of other settings would be mixed silently with the fitted ones."""
        fitted, now = self._fitted_parameters, self._result_parameters()
        changed = [name for name in now if not _same(now[name], fitted.get(name))]
        if changed:
            raise InputError(
                "changed since fit: "
                + ", ".join(f"`{name}` ({fitted.get(name)!r} at fit, now {now[name]!r})" for name in changed)
                + "; call fit again."
            )

    def _check_shared_parameters(self) -> None:
        """The parameters every shape estimator shares, checked where ``fit`` runs (before, a
        bad ``weights`` or ``connectivity`` passed ``fit`` and failed in ``transform``)."""
        if not is_connectivity(self.connectivity):
            raise InputError(
                f"`connectivity`: the 'connectivity' parameter of {type(self).__name__} must be 4 or 8. "
                f"Got {self.connectivity!r} instead."
            )
        check_bool(self.weights, name="weights")
        check_bool(self.progress, name="progress")
        resolve_cache(self.cache)
        _effective_jobs(self.n_jobs)

    def _masks(self, X):
        self._check_shared_parameters()
        fill = getattr(self, "fill_holes", False)
        check_bool(fill, name="fill_holes")
        masks = as_shape_images(X, foreground=self.foreground, threshold=self.threshold)
        if fill:
            from scipy.ndimage import binary_fill_holes

            masks = [binary_fill_holes(mask) for mask in masks]
        return masks

    def _centralities(self, masks, names):
        return shape_centralities(
            masks,
            names,
            connectivity=self.connectivity,
            weights=self.weights,
            progress=self.progress,
            cache=self.cache,
            n_jobs=self.n_jobs,
        )


#: The most histogram bins a shape feature takes: far more than any shape has pixel values
#: to tell apart, and 100,000 float64 per image and centrality is still small.
MAX_BINS = 100_000


def _histogram(values: np.ndarray, bins: int, scaling: str) -> np.ndarray:
    if scaling == "minmax":
        lo, hi = values.min(), values.max()
    else:  # "max"
        lo, hi = 0.0, values.max()
    # values equal but for rounding (a few ulp apart on symmetric shapes) count as equal:
    # min-max scaling would stretch their rounding over the whole range
    spread = hi - lo > 1e-9 * max(abs(hi), abs(lo))
    scaled = (values - lo) / (hi - lo) if spread else np.zeros_like(values)
    position = scaled * bins
    # a value on a bin edge (0.5 of the largest, say: common in symmetric shapes) computed a
    # few ulp below it on one graph and above it on its transpose or mirror image would fall
    # in different bins; snap positions within 1e-9 of an edge onto it
    edge = np.rint(position)
    position = np.where(np.abs(position - edge) <= 1e-9, edge, position)
    counts = np.bincount(np.minimum(position.astype(np.int64), bins - 1), minlength=bins)
    return counts / values.size


class CentralityHistogram(ShapeInputMixin, TransformerMixin, BaseEstimator):
    """Normalised histograms of pixel-graph centralities, one row per shape.

    Each shape's 8-neighbour pixel graph gets the chosen centrality (thesis Algorithm 4.1);
    its values are divided by their largest and counted in ``bins`` equal bins of [0, 1],
    and the counts are divided by the number of pixels, so the feature sums to 1 and does
    not depend on the shape's size. ``centrality="all"`` concatenates betweenness,
    closeness, eigenvector and degree (4 x ``bins`` features).

    Centralities are computed once per image and kept in ``cache``, so the same images
    under another centrality, bin count or estimator are not recomputed.

    Parameters
    ----------
    centrality : str or list of str, default="closeness"
        A name from :data:`centrality_vision.centrality.CENTRALITIES`, ``"all"``, or a list.
    bins : int, default=40
        Bins per centrality (the thesis uses 40), from 2 to 100,000.
    connectivity : {8, 4}, default=8
        Pixel neighbourhood.
    scaling : {"max", "minmax"}, default="max"
        ``"max"`` divides each shape's values by their largest, the normalisation of
        thesis eq. 2.9 (``d / max d``), so a value means the same in every shape;
        ``"minmax"`` maps the smallest value to 0 and the largest to 1 (the range
        MATLAB's ``hist(v, 40)`` bins over). On Kimia-99 "max" is closer to the thesis'
        Table 4.1 (all 0.98, degree 0.83 noiseless; "minmax": 0.94 and 0.57). A shape
        whose values are all equal falls in the last bin under "max" (each value is the
        largest) and in the first under "minmax"; values that are all zero fall in the
        first bin under both.
    progress : bool, default=False
        Show a progress bar on stderr while centralities are computed.
    weights : bool, default=False
        True gives pixel edges their Euclidean lengths (1 and sqrt 2) for the
        shortest-path centralities (betweenness, closeness, eccentricity, harmonic), so
        that a rotated shape gets nearly the same features; False counts hops (the
        thesis). Degree and eigenvector do not change.
    foreground : {"auto", "dark", "light"}, default="auto"
        Which side of a grey image is the shape; ``"auto"``: the side that touches
        less of the image border. Boolean and 0/1 images are masks (True/1 = shape).
    threshold : float, optional
        Grey level splitting grey images; default half their range, ``(min + max) / 2``.
    cache : None, CentralityCache or path, default=None
        Where centralities are kept: None is the process-wide in-memory
        :data:`~centrality_vision.shapes.default_cache`; a directory gives an on-disk
        cache, keyed by the pixels, that worker processes share (so parallel
        cross-validation computes every image once).
    n_jobs : int, optional
        Images computed in parallel through joblib (``joblib.parallel_backend("dask")``
        runs them on a Dask cluster); the kernel threads are divided among the jobs.
        Results do not depend on it.
    fill_holes : bool, default=False
        Fill background regions enclosed by the shape before building its graph. Salt
        noise punches such holes; the leading eigenvector of the adjacency then
        localises on the largest hole-free patch (its participation ratio on Kimia-99
        falls from 0.31 to 0.19 at 1% noise and 0.04 at 10%), and an eigenvector
        histogram learned on clean shapes reads every noisy shape alike. With the holes
        filled it keeps 0.89 held-in accuracy at 1% noise instead of 0.12 (see
        ``results/benchmarks/shapes_eigenvector.txt``). Real holes of a shape are
        filled too.

    Attributes
    ----------
    centralities_ : tuple of str
        The centralities, in the order their histograms are concatenated.
    n_features_out_ : int

    Notes
    -----
    With ``weights=True`` turning a shape changes its closeness histogram little: on
    Kimia-99, turned by 15, 37 or 60 degrees (bilinear resampling), by 0.03 to 0.05 in
    L1 (median), where shapes of one class are 0.10 apart and of different classes
    0.27; resampling alone (37 degrees and back) accounts for 0.025, and each shape's
    mean inner distance changes by at most 3%. Naive Bayes with scikit-learn's default
    ``GaussianNB(var_smoothing=1e-9)`` magnifies that: a bin that is empty in a class's
    few training shapes gets a near-zero variance, and held-out accuracy falls from 0.90
    to 0.80 at 15 degrees. With ``var_smoothing`` chosen by cross-validation on the
    training shapes (1e-2 in every fold) it is 0.94 upright and 0.92 to 0.95 turned
    (``benchmarks/shapes.py --rotation``).

    Examples
    --------
    >>> import numpy as np
    >>> disk = np.add.outer((np.arange(21) - 10) ** 2, (np.arange(21) - 10) ** 2) < 64
    >>> features = CentralityHistogram(centrality="all", bins=10).fit_transform([disk, disk[:, :12]])
    >>> features.shape, np.allclose(features.reshape(2, 4, 10).sum(axis=2), 1)
    ((2, 40), True)
    """

    def __init__(
        self,
        centrality="closeness",
        bins: int = 40,
        connectivity: int = 8,
        scaling: str = "max",
        progress: bool = False,
        *,
        weights: bool = False,
        foreground: str = "auto",
        threshold=None,
        cache=None,
        n_jobs=None,
        fill_holes: bool = False,
    ):
        self.centrality = centrality
        self.bins = bins
        self.connectivity = connectivity
        self.scaling = scaling
        self.progress = progress
        self.weights = weights
        self.foreground = foreground
        self.threshold = threshold
        self.cache = cache
        self.n_jobs = n_jobs
        self.fill_holes = fill_holes

    def _validate_params(self) -> tuple[str, ...]:
        names = resolve_centralities(self.centrality)
        # (one bin holds every pixel: the feature is the constant 1, and a classifier fed only
        # constant features divides by their zero variance)
        check_int(self.bins, name="bins", low=2, high=MAX_BINS)
        check_choice(self.scaling, ("minmax", "max"), name="scaling")
        self._check_shared_parameters()
        return names

    def fit(self, X, y=None):
        """Check the parameters and the images; nothing is learned from the data.

        Parameters
        ----------
        X : sequence of 2D binary arrays
        y : ignored

        Examples
        --------
        >>> import numpy as np
        >>> square = np.zeros((6, 6), dtype=bool); square[1:5, 1:5] = True
        >>> hist = CentralityHistogram(centrality=["degree", "closeness"], bins=5).fit([square])
        >>> hist.centralities_, hist.n_features_out_
        (('degree', 'closeness'), 10)
        """
        names = self._validate_params()
        self._masks(X)
        self.centralities_ = names
        self.n_features_out_ = len(names) * self.bins
        self._remember_parameters()
        return self

    def transform(self, X) -> np.ndarray:
        """Histogram features of the shapes in ``X``, shape (n_images, ``n_features_out_``)."""
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "centralities_")
        self._validate_params()
        self._check_unchanged()
        records = self._centralities(self._masks(X), self.centralities_)
        out = np.empty((len(records), self.n_features_out_))
        for i, record in enumerate(records):
            out[i] = np.concatenate([_histogram(record[name], self.bins, self.scaling) for name in self.centralities_])
        return out

    @property
    def _fitted_bins(self) -> int:
        """The bins per centrality of the fit (``bins`` may have changed since)."""
        return self.n_features_out_ // len(self.centralities_)

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """Names ``"<centrality>_bin<k>"`` of the output features.

        Parameters
        ----------
        input_features : ignored
            Present for scikit-learn's API (the inputs are images, not named columns).

        Returns
        -------
        ndarray of str objects, shape (``n_features_out_``,)
            ``k`` runs over the bins of the fit for each centrality of ``centralities_``, in
            order (the fitted bins: changing ``bins`` after ``fit`` does not change them).

        Examples
        --------
        >>> import numpy as np
        >>> square = np.zeros((6, 6), dtype=bool); square[1:5, 1:5] = True
        >>> hist = CentralityHistogram(centrality=["degree", "closeness"], bins=2).fit([square])
        >>> hist.get_feature_names_out().tolist()
        ['degree_bin0', 'degree_bin1', 'closeness_bin0', 'closeness_bin1']
        """
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "centralities_")
        return np.array(
            [f"{name}_bin{k}" for name in self.centralities_ for k in range(self._fitted_bins)], dtype=object
        )

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False
        tags.requires_fit = True
        return tags
