"""Random binary comparisons of centrality values (thesis 4.3.3) and their forest."""

from __future__ import annotations

import numbers

import numpy as np
from scipy import ndimage
from sklearn.base import BaseEstimator, ClassifierMixin, TransformerMixin

from .._deprecation import both_names_error
from .._neighbours import query_with_ties
from .._seeding import as_generator
from .._validation import check_choice, check_float, check_int, is_real_dtype
from .._warnings import warn
from ..exceptions import InputError
from ._histogram import ShapeInputMixin, _same, resolve_centralities

__all__ = ["CentralityComparisons", "CentralityComparisonForest", "centrality_map"]


def _check_map_inputs(mask, values, nodes):
    from .._validation import as_binary_image

    mask = as_binary_image(mask, name="mask")
    values = np.asarray(values)
    nodes = np.asarray(nodes)
    n = int(np.count_nonzero(mask))
    if not is_real_dtype(values.dtype, bool_ok=False):
        raise TypeError(f"`values` must hold real numbers; got dtype {values.dtype}.")
    if values.shape != (n,):
        raise InputError(
            f"`values` must hold one value per foreground pixel of `mask` ({n}); got shape {values.shape}."
        )
    if not np.all(np.isfinite(values)):
        raise InputError("`values` must be finite; got NaN or inf.")
    if not np.issubdtype(nodes.dtype, np.integer) or nodes.shape != (n,):
        raise InputError(
            f"`nodes` must be the {n} flat indices of the foreground pixels of `mask`; got shape {nodes.shape} "
            f"and dtype {nodes.dtype}."
        )
    if not np.array_equal(np.sort(nodes), np.flatnonzero(mask)):
        raise InputError("`nodes` must list each foreground pixel of `mask` once (flat row-major indices).")
    return mask, values.astype(np.float64), nodes


def centrality_map(mask, values, nodes, *, reference: str = "centroid"):
    """Dense centrality image of a shape, its reference point and its size.

    Every pixel takes the value of its nearest foreground pixel, so that a location that
    falls into a hole made by noise, or just off the outline, still reads the shape.

    Parameters
    ----------
    mask : 2D binary array
        The shape (see :func:`as_shape_images`).
    values : ndarray of shape (n_foreground,)
        One value per foreground pixel, aligned with ``nodes``.
    nodes : ndarray of shape (n_foreground,)
        Flat (row-major) pixel index of each value, each foreground pixel once (the
        ``nodes`` of :func:`centrality_vision.graphs.pixel_graph`).
    reference : {"centroid", "graph-centre"}, default="centroid"
        The reference point: the centre of mass of the foreground, or the mean position
        of the pixels of smallest value (the graph centre when ``values`` are
        eccentricities).

    Returns
    -------
    dense : ndarray, same shape as ``mask``
    centre : ndarray of shape (2,)
        (row, col) of the reference point.
    size : float
        Root-mean-square distance of the foreground pixels from the centre of mass (at
        least 1); it is unchanged in expectation when pixels are removed at random.

    Examples
    --------
    >>> import numpy as np
    >>> mask = np.zeros((3, 4), dtype=bool); mask[1, 1:4] = True
    >>> dense, centre, size = centrality_map(mask, [1.0, 0.5, 2.0], [5, 6, 7], reference="graph-centre")
    >>> dense
    array([[1. , 1. , 0.5, 2. ],
           [1. , 1. , 0.5, 2. ],
           [1. , 1. , 0.5, 2. ]])
    >>> centre.tolist(), round(size, 3)
    ([1.0, 2.0], 1.0)
    """
    check_choice(reference, ("centroid", "graph-centre"), name="reference")
    mask, values, nodes = _check_map_inputs(mask, values, nodes)
    image = np.zeros(mask.shape)
    image.flat[nodes] = values
    _, (rows, cols) = ndimage.distance_transform_edt(~mask, return_indices=True)
    dense = image[rows, cols]
    coords = np.argwhere(mask).astype(float)
    centroid = coords.mean(axis=0)
    size = float(np.sqrt(np.mean(np.sum((coords - centroid) ** 2, axis=1))))
    if reference == "graph-centre":
        centre = np.stack(np.unravel_index(nodes[values == values.min()], mask.shape), axis=1).mean(axis=0)
    else:
        centre = centroid
    return dense, centre, max(size, 1.0)


def _principal_axes(mask: np.ndarray) -> np.ndarray:
    """(2, 2) matrix whose columns are the shape's major and minor axes, in (row, col).

    The axes are the eigenvectors of the pixels' second moments about their centre of
    mass; each points the way the pixels are skewed (positive third moment along it), so
    the frame turns with the shape (and flips with a mirror image). Axes are only
    defined up to those choices: a shape as wide as it is long, or symmetric along an
    axis, has no preferred direction there, and the frame follows pixel noise.
    """
    coords = np.argwhere(mask).astype(float)
    coords -= coords.mean(axis=0)
    _, vectors = np.linalg.eigh(coords.T @ coords / max(len(coords), 1))
    axes = vectors[:, ::-1]  # major axis first
    skew = np.mean((coords @ axes) ** 3, axis=0)
    return axes * np.where(skew < 0, -1.0, 1.0)


def _nearest_pixels(mask: np.ndarray, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of the foreground pixel nearest to each of ``pixels`` (..., 2).

    A pixel of the shape is itself; any other, inside the image or beyond its border,
    goes to the nearest foreground pixel (a k-d tree query, ties to the first in
    row-major order), so the result does not depend on the background around the shape.
    """
    rows, cols = pixels[..., 0].copy(), pixels[..., 1].copy()
    inside = (rows >= 0) & (rows < mask.shape[0]) & (cols >= 0) & (cols < mask.shape[1])
    off = ~inside
    off[inside] = ~mask[rows[inside], cols[inside]]
    if off.any():
        from scipy.spatial import cKDTree

        foreground = np.argwhere(mask)  # row-major order
        # the tree returns one of the tied pixels, not the first: take them all (integer
        # coordinates: equal distances are equal exactly)
        _, index, tied = query_with_ties(cKDTree(foreground), pixels[off], 0)
        nearest = np.where(tied, index, foreground.shape[0]).min(axis=1)
        rows[off], cols[off] = foreground[nearest, 0], foreground[nearest, 1]
    return rows, cols


def _random_state(estimator) -> np.random.Generator:
    """The generator of ``random_state``, or of the deprecated ``seed`` when it was given
    (with a FutureWarning); a bad value's error names the parameter it came from."""
    if estimator.seed is None:
        return as_generator(estimator.random_state, name="random_state")
    import inspect

    default = inspect.signature(type(estimator).__init__).parameters["random_state"].default
    if not _same(estimator.random_state, default):  # as renamed_parameters does with both names
        given = f" (seed={estimator.seed!r}, random_state={estimator.random_state!r})"
        raise both_names_error("seed", "random_state", given)

    warn(
        f"`seed` of {type(estimator).__name__} is deprecated and will be removed; use `random_state`.",
        FutureWarning,
    )
    return as_generator(estimator.seed)


# The most comparisons (features) a shape estimator draws.
_MAX_COMPARISONS = 10**7


class CentralityComparisons(ShapeInputMixin, TransformerMixin, BaseEstimator):
    """Random binary comparisons of centrality values at positions relative to the shape.

    Comparison ``k`` is a pair of offsets ``(a_k, b_k)`` drawn uniformly from
    ``[-extent, extent]^2`` and an optional centrality; for a shape with reference point
    ``c`` (centre of mass, or the graph centre) and size ``s`` (RMS radius), it reads the
    centrality ``v`` at ``x = c + s a_k`` and ``y = c + s b_k`` and outputs
    ``1.0 if v(x) >= v(y) else 0.0`` (thesis fig. 4.7). A position off the shape reads
    the foreground pixel nearest to it. Offsets scale with the shape, so the features do
    not depend on its size or position; with ``orientation="principal"`` they are taken
    along the shape's principal axes, so that they turn with it too.

    Parameters
    ----------
    centrality : str or list of str, default="closeness"
        Centralities to compare (``"all"``: the four of the thesis); each comparison
        uses one of them, drawn at random.
    n_comparisons : int in [1, 10^7], default=2000
    extent : float in (0, 1e6], default=2.0
        Largest offset, in units of the shape's RMS radius.
    reference : {"centroid", "graph-centre"}, default="centroid"
    orientation : {"image", "principal"}, default="image"
        The frame of the offsets. ``"image"`` (the thesis): the image's rows and
        columns, and a position beyond the image border is clipped to the border, so
        the features depend on the margin around the shape too. ``"principal"``: the
        shape's major and minor axes (eigenvectors of its second moments, each pointing
        the way the shape is skewed), and a position beyond the border reads the
        foreground pixel nearest to it, so the features turn with the shape and do not
        depend on the margin. Near-round or symmetric shapes have no stable axes. On
        Kimia-99 turned by 15, 37 and 60 degrees, the forest with ``weights=True`` keeps
        its held-out accuracy (0.85) with ``"principal"`` and loses up to 0.74 of its
        0.90 with ``"image"`` (``benchmarks/shapes.py --rotation``).
    connectivity : {8, 4}, default=8
    random_state : int, Generator or None, default=0
        Seed of the random comparisons.
    progress : bool, default=False
    weights, foreground, threshold, cache, n_jobs, fill_holes :
        As in :class:`CentralityHistogram` (``n_jobs`` also grows the trees in
        parallel in the forest).
    seed : deprecated
        The former name of ``random_state``; giving it warns (FutureWarning).

    Attributes
    ----------
    offsets_ : ndarray of shape (n_comparisons, 2, 2)
        ``offsets_[k, 0]`` and ``offsets_[k, 1]`` are the (row, col) offsets of x and y.
    which_ : ndarray of shape (n_comparisons,)
        Index into ``centralities_`` of each comparison.
    centralities_ : tuple of str

    Examples
    --------
    >>> import numpy as np
    >>> yy, xx = np.mgrid[:20, :20]
    >>> disk = (yy - 10) ** 2 + (xx - 10) ** 2 < 49
    >>> bar = (abs(yy - 10) < 3) & (abs(xx - 10) < 8)
    >>> comparisons = CentralityComparisons(n_comparisons=8, extent=1.0).fit([disk, bar])
    >>> comparisons.offsets_.shape, comparisons.centralities_
    ((8, 2, 2), ('closeness',))
    >>> features = comparisons.transform([disk, bar])
    >>> features.shape, set(features.ravel().tolist())
    ((2, 8), {0.0, 1.0})

    The offsets are relative to the shape's centre and size: the same disk elsewhere in a
    larger image gives the same features.

    >>> moved = np.zeros((30, 40), dtype=bool); moved[6:26, 15:35] = disk
    >>> bool(np.array_equal(comparisons.transform([moved])[0], features[0]))
    True
    """

    def __init__(
        self,
        centrality="closeness",
        n_comparisons: int = 2000,
        extent: float = 2.0,
        reference: str = "centroid",
        connectivity: int = 8,
        random_state=0,
        progress: bool = False,
        *,
        orientation: str = "image",
        weights: bool = False,
        foreground: str = "auto",
        threshold=None,
        cache=None,
        n_jobs=None,
        fill_holes: bool = False,
        seed=None,
    ):
        self.centrality = centrality
        self.n_comparisons = n_comparisons
        self.extent = extent
        self.reference = reference
        self.orientation = orientation
        self.connectivity = connectivity
        self.random_state = random_state
        self.progress = progress
        self.weights = weights
        self.foreground = foreground
        self.threshold = threshold
        self.cache = cache
        self.n_jobs = n_jobs
        self.fill_holes = fill_holes
        self.seed = seed

    def _drawn_with(self) -> tuple:
        """The checked parameters that the drawn comparisons depend on."""
        names = resolve_centralities(self.centrality)
        # (each comparison is a feature per image: 10^7 are 80 MB per image; 10^11 asked for
        # 2.9 TiB and raised a MemoryError)
        n = check_int(self.n_comparisons, name="n_comparisons", low=1, high=_MAX_COMPARISONS)
        # (at most 1e6 radii: beyond, pixel positions leave int64)
        extent = check_float(self.extent, name="extent", low=0.0, low_open=True, high=1e6)
        check_choice(self.reference, ("centroid", "graph-centre"), name="reference")
        check_choice(self.orientation, ("image", "principal"), name="orientation")
        return names, n, extent

    def fit(self, X, y=None):
        """Draw the comparisons (the images are only checked).

        Parameters
        ----------
        X : sequence of images of shape (rows, cols)
            Masks or grey images (see :func:`as_shape_images`); sizes may differ.
        y : ignored

        Returns
        -------
        self : CentralityComparisons

        Examples
        --------
        The draw depends on ``random_state`` and the parameters only, not on the images:

        >>> import numpy as np
        >>> disk = np.add.outer((np.arange(15) - 7) ** 2, (np.arange(15) - 7) ** 2) < 25
        >>> square = np.zeros((8, 8), dtype=bool); square[2:6, 2:6] = True
        >>> a = CentralityComparisons(["closeness", "degree"], n_comparisons=5, random_state=1).fit([disk])
        >>> b = CentralityComparisons(["closeness", "degree"], n_comparisons=5, random_state=1).fit([square])
        >>> bool(np.array_equal(a.offsets_, b.offsets_)), a.centralities_
        (True, ('closeness', 'degree'))
        >>> bool(np.abs(a.offsets_).max() <= a.extent), a.which_.shape
        (True, (5,))
        """
        names, n, extent = self._drawn_with()
        self._masks(X)
        rng = _random_state(self)
        self.centralities_ = names
        self.offsets_ = rng.uniform(-extent, extent, size=(n, 2, 2))
        self.which_ = rng.integers(0, len(names), size=n)
        self._remember_parameters()
        return self

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """Names ``"<centrality>_cmp<k>"`` of the output features, one per drawn comparison.

        Parameters
        ----------
        input_features : ignored
            Present for scikit-learn's API (the inputs are images, not named columns).

        Returns
        -------
        ndarray of str objects, shape (``n_comparisons``,)
            Comparison ``k`` of the fit, named by the centrality it compares (``which_``).

        Examples
        --------
        >>> import numpy as np
        >>> square = np.zeros((6, 6), dtype=bool); square[1:5, 1:5] = True
        >>> comparisons = CentralityComparisons("degree", n_comparisons=3).fit([square])
        >>> comparisons.get_feature_names_out().tolist()
        ['degree_cmp0', 'degree_cmp1', 'degree_cmp2']
        """
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "offsets_")
        return np.array([f"{self.centralities_[c]}_cmp{k}" for k, c in enumerate(self.which_)], dtype=object)

    def transform(self, X) -> np.ndarray:
        """Binary comparison features, shape (n_images, n_comparisons), values 0.0 or 1.0."""
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "offsets_")
        # parameters set after fit are checked, and must be the fitted ones (a new centrality
        # was ignored, a bad orientation ran as "image", a new reference mixed with the draw)
        self._drawn_with()
        self._check_unchanged()
        masks = self._masks(X)
        names = list(self.centralities_)
        if self.reference == "graph-centre" and "eccentricity" not in names:
            names.append("eccentricity")
        records = self._centralities(masks, names)
        out = np.empty((len(masks), self.offsets_.shape[0]))
        for i, (mask, record) in enumerate(zip(masks, records)):
            nodes = record["nodes"]
            stack = np.stack([centrality_map(mask, record[name], nodes)[0] for name in self.centralities_])
            values = record["eccentricity"] if self.reference == "graph-centre" else record[self.centralities_[0]]
            _, centre, size = centrality_map(mask, values, nodes, reference=self.reference)
            if self.orientation == "principal":
                offsets = self.offsets_ @ _principal_axes(mask).T  # along the axes, in (row, col)
                pixels = np.rint(centre + size * offsets).astype(np.int64)  # (n, 2, 2)
                rows, cols = _nearest_pixels(mask, pixels)
            else:  # the thesis: image axes, positions beyond the border clipped to it
                pixels = np.rint(centre + size * self.offsets_).astype(np.int64)
                rows = np.clip(pixels[..., 0], 0, mask.shape[0] - 1)
                cols = np.clip(pixels[..., 1], 0, mask.shape[1] - 1)
            vx = stack[self.which_, rows[:, 0], cols[:, 0]]
            vy = stack[self.which_, rows[:, 1], cols[:, 1]]
            out[i] = vx >= vy
        return out

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False
        tags.requires_fit = True
        return tags


class CentralityComparisonForest(ShapeInputMixin, ClassifierMixin, BaseEstimator):
    """Shape classifier: a random forest over random binary comparisons of centralities.

    The proposal of thesis 4.3.3: features are random comparisons
    :math:`[v(x) \\ge v(y)]` at positions relative to the shape
    (:class:`CentralityComparisons`); each tree node chooses, among a random subset of
    them, the one with the largest information gain (entropy criterion), as in Lepetit
    and Fua's randomised trees. The trees are scikit-learn's.

    Parameters
    ----------
    centrality : str or list of str, default="closeness"
    n_estimators : int, default=300
    n_comparisons : int in [1, 10^7], default=2000
    max_features : int, float or "sqrt", default="sqrt"
        Comparisons examined per tree node.
    max_depth : int or None, default=None
    extent, reference, connectivity, orientation :
        As in :class:`CentralityComparisons`.
    random_state : int or None, default=0
        Seeds the comparisons and the trees.
    progress : bool, default=False
    weights, foreground, threshold, cache, n_jobs, fill_holes :
        As in :class:`CentralityHistogram` (``n_jobs`` also grows the trees in
        parallel in the forest).
    seed : deprecated
        The former name of ``random_state``; giving it warns (FutureWarning).

    Attributes
    ----------
    classes_ : ndarray
    comparisons_ : CentralityComparisons
    forest_ : sklearn.ensemble.RandomForestClassifier

    References
    ----------
    .. [1] V. Lepetit and P. Fua, "Keypoint recognition using randomized trees", IEEE
       PAMI 28(9), 1465-1479, 2006.

    Examples
    --------
    >>> import numpy as np
    >>> yy, xx = np.mgrid[:30, :30]
    >>> disk = (yy - 15) ** 2 + (xx - 15) ** 2 < 100
    >>> bar = (abs(yy - 15) < 3) & (abs(xx - 15) < 12)
    >>> clf = CentralityComparisonForest(n_estimators=20, n_comparisons=50).fit([disk, bar] * 3, [0, 1] * 3)
    >>> clf.predict([disk, bar]).tolist()
    [0, 1]
    >>> proba = clf.predict_proba([disk, bar])  # columns in the order of classes_
    >>> clf.classes_.tolist(), proba.shape, bool(np.allclose(proba.sum(axis=1), 1))
    ([0, 1], (2, 2), True)
    >>> proba.argmax(axis=1).tolist(), clf.comparisons_.offsets_.shape, len(clf.forest_.estimators_)
    ([0, 1], (50, 2, 2), 20)
    """

    def __init__(
        self,
        centrality="closeness",
        n_estimators: int = 300,
        n_comparisons: int = 2000,
        max_features="sqrt",
        max_depth=None,
        extent: float = 2.0,
        reference: str = "centroid",
        connectivity: int = 8,
        random_state=0,
        progress: bool = False,
        *,
        orientation: str = "image",
        weights: bool = False,
        foreground: str = "auto",
        threshold=None,
        cache=None,
        n_jobs=None,
        fill_holes: bool = False,
        seed=None,
    ):
        self.centrality = centrality
        self.n_estimators = n_estimators
        self.n_comparisons = n_comparisons
        self.max_features = max_features
        self.max_depth = max_depth
        self.extent = extent
        self.reference = reference
        self.orientation = orientation
        self.connectivity = connectivity
        self.random_state = random_state
        self.progress = progress
        self.weights = weights
        self.foreground = foreground
        self.threshold = threshold
        self.cache = cache
        self.n_jobs = n_jobs
        self.fill_holes = fill_holes
        self.seed = seed

    def _seeds(self) -> tuple[int, int]:
        rng = _random_state(self)
        a, b = rng.integers(0, 2**31 - 1, size=2)
        return int(a), int(b)

    def fit(self, X, y):
        """Draw the comparisons and grow the forest on the shapes ``X`` with labels ``y``.

        Parameters
        ----------
        X : sequence of images of shape (rows, cols)
            Masks or grey images (see :func:`as_shape_images`); sizes may differ.
        y : array_like of shape (n_samples,)
            Class label of each image of ``X`` (required).

        Returns
        -------
        self : CentralityComparisonForest
        """
        from sklearn.ensemble import RandomForestClassifier
        from sklearn.utils import check_array
        from sklearn.utils.multiclass import check_classification_targets

        if y is None:
            raise InputError(
                "`y` is required: CentralityComparisonForest requires y to be passed, but the target y is None."
            )
        from ._retrieval import _check_labels

        # the retrieval scores' check: [0, "bar"] became the strings '0' and 'bar', NaN a class
        y = _check_labels(y, None, name="y", what="image")
        try:
            y = check_array(y, ensure_2d=False, dtype=None, input_name="y")
            check_classification_targets(y)
        except ValueError as exc:  # (continuous labels: scikit-learn's words, named here)
            raise InputError(f"`y` must hold class labels: {exc}") from None
        masks = self._masks(X)
        if y.shape[0] != len(masks):
            raise InputError(f"`y` must hold one label per image ({len(masks)}); got shape {y.shape}.")
        check_int(self.n_estimators, name="n_estimators", low=1)
        # (scikit-learn checks the rest, but passes ints beyond C's range to an OverflowError)
        if self.max_depth is not None:
            check_int(self.max_depth, name="max_depth", low=1)
        if isinstance(self.max_features, (bool, np.bool_)):  # (scikit-learn reads True as 1 feature)
            raise TypeError(
                f"`max_features` must be an int, a float, 'sqrt', 'log2' or None; got {self.max_features!r}."
            )
        if isinstance(self.max_features, numbers.Integral):
            check_int(self.max_features, name="max_features", low=1)
        elif isinstance(self.max_features, numbers.Real):  # a share of the comparisons
            check_float(self.max_features, name="max_features", low=0.0, low_open=True, high=1.0)
        elif self.max_features is not None:
            check_choice(self.max_features, ("sqrt", "log2"), name="max_features")
        comparison_seed, forest_seed = self._seeds()
        self.comparisons_ = CentralityComparisons(
            centrality=self.centrality,
            n_comparisons=self.n_comparisons,
            extent=self.extent,
            reference=self.reference,
            orientation=self.orientation,
            connectivity=self.connectivity,
            random_state=comparison_seed,
            progress=self.progress,
            weights=self.weights,
            cache=self.cache,
            n_jobs=self.n_jobs,
        ).fit(masks)
        self.forest_ = RandomForestClassifier(
            n_estimators=self.n_estimators,
            criterion="entropy",
            max_features=self.max_features,
            max_depth=self.max_depth,
            random_state=forest_seed,
            n_jobs=self.n_jobs,
        ).fit(self.comparisons_.transform(masks), y)
        self.classes_ = self.forest_.classes_
        self._remember_parameters()
        return self

    def predict_proba(self, X) -> np.ndarray:
        """Class probabilities (mean of the trees' leaf distributions), shape (n_images, n_classes).

        Parameters
        ----------
        X : sequence of images of shape (rows, cols)
            Masks or grey images, read as in :meth:`fit`.

        Returns
        -------
        ndarray of shape (n_images, n_classes)
            Columns in the order of ``classes_``; each row sums to 1.
        """
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "forest_")
        self._check_unchanged()  # the forest was grown on the features of the fitted parameters
        # how the work runs may change after fit (documented): the parts take the values now set
        self.comparisons_.set_params(cache=self.cache, n_jobs=self.n_jobs, progress=self.progress)
        self.forest_.set_params(n_jobs=self.n_jobs)
        return self.forest_.predict_proba(self.comparisons_.transform(self._masks(X)))

    def predict(self, X) -> np.ndarray:
        """Most probable class of each shape.

        Parameters
        ----------
        X : sequence of images of shape (rows, cols)
            Masks or grey images, read as in :meth:`fit`.

        Returns
        -------
        ndarray of shape (n_images,)
            Labels from ``classes_`` (on equal probabilities, the first in ``classes_``).
        """
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False
        return tags
