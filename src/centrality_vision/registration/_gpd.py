"""Graph-based Point Drift (thesis ch. 5): CPD with a centrality prior in the shared E-step."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.utils.validation import check_is_fitted

from .. import graphs as _graphs
from .._deprecation import FORMER, former_parameter, renamed_parameters
from .._validation import ANY_DIMS, as_graph, as_points, as_real_array, check_bool, check_choice, check_float, check_int
from ..centrality import CENTRALITIES, PATH_CENTRALITIES, compute
from ..exceptions import InputError
from ..graphs._pointsets import _affine_rank
from ..transforms import centred, power_of_two_scale
from ._cpd import _CPD, RigidCPD
from ._estep import CentralityPrior

__all__ = ["GPD", "GRAPHS", "centrality_prior", "normalize_centrality"]

GRAPHS = ("delaunay", "gabriel", "emst", "knn", "complete", "edgeless")


def _edgeless(points):
    from scipy import sparse

    n = points.shape[0]
    return sparse.csr_array((n, n))


def _unit_radius(points: np.ndarray) -> np.ndarray:
    """``points`` centred and scaled to unit RMS radius (the graphs below are similarity invariant)."""
    _, c = centred(points)
    unit = power_of_two_scale(c)
    radius = unit * float(np.sqrt(np.mean(np.sum((c / unit) ** 2, axis=1))))
    return c / radius if radius > 0 else c


def _graph_points(points: np.ndarray) -> np.ndarray:
    """The coordinates the graphs are built on: ``points`` of unit RMS radius (see
    :func:`_unit_radius`), and for a set that spans fewer dimensions than it has (a flat
    scan in 3D, an outline lifted into a plane of 10D, a line) its coordinates in the space
    it spans, whose graphs are the set's own (they depend on distances only); a line's with
    a second coordinate of 0 (the graphs are built in 2D at least).

    The span is read off the caller's points, to within the rounding of their coordinates
    (as the graphs read it: ``graphs._pointsets._affine_rank``): centring takes the offset away,
    and with it the knowledge that a turned plane 1e4 from the origin, 6e-12 of its extent
    thick, is a plane. Built as 3D, its Delaunay graph passed or failed Qhull's check by
    chance, and the default graph of any flat 3D set was refused. A turned line 1e6 from the
    origin got a "Delaunay graph" of its rounding (137 edges where the path has 29)."""
    rank = _affine_rank(points)
    unit = _unit_radius(points)
    if 1 <= rank < points.shape[1]:  # (unit is centred)
        spanned = unit @ np.linalg.svd(unit, full_matrices=False)[2][:rank].T
        return spanned if rank >= 2 else np.c_[spanned, np.zeros(len(spanned))]
    return unit


def _build_graph(points: np.ndarray, graph, k: int):
    if callable(graph):
        built = as_graph(graph(points), name="graph(points)")
        if built.shape[0] != points.shape[0]:
            raise InputError(
                f"`graph(points)` must return a graph with one node per point ({points.shape[0]}); "
                f"got {built.shape[0]} nodes."
            )
        return built
    points = _graph_points(points)
    if points.shape[0] < 3 and graph in ("delaunay", "gabriel"):
        return _graphs.complete_graph(points) if points.shape[0] > 1 else _edgeless(points)
    if graph == "delaunay":
        return _graphs.delaunay_graph(points)
    if graph == "gabriel":
        return _graphs.gabriel_graph(points)
    if graph == "emst":
        return _graphs.emst_graph(points) if points.shape[0] > 1 else _edgeless(points)
    if graph == "knn":
        n = points.shape[0]
        return _graphs.knn_graph(points, n_neighbors=min(k, n - 1)) if n > 1 else _edgeless(points)
    if graph == "complete":
        return _graphs.complete_graph(points) if points.shape[0] > 1 else _edgeless(points)
    return _edgeless(points)


def normalize_centrality(values, *, name: str = "values") -> np.ndarray:
    """Min-max scale centrality values to [0, 1]; a constant vector (to 1e-9) becomes zeros.

    Parameters
    ----------
    values : array_like of shape (n,)
        Finite real values, at least one.
    name : str, default="values"
        The parameter name error messages give.

    Returns
    -------
    ndarray of float, shape (n,)
        ``(values - min) / (max - min)``: 0 at the smallest value, 1 at the largest; all zeros
        when the span is at most 1e-9 times the largest absolute value.

    Examples
    --------
    >>> normalize_centrality([2.0, 4.0, 3.0])
    array([0. , 1. , 0.5])
    >>> normalize_centrality([1.0, 1.0 + 1e-15])
    array([0., 0.])
    """
    v = as_real_array(values, name=name, shape="a 1D array of centrality values").astype(float)
    if v.ndim != 1 or v.size == 0:
        raise InputError(f"`{name}` must be a non-empty 1D array of centrality values; got shape {v.shape}.")
    if not np.all(np.isfinite(v)):
        raise InputError(f"`{name}` must be finite; got NaN or inf.")
    lo, hi = float(v.min()), float(v.max())
    if hi / 2 - lo / 2 <= 0.5e-9 * max(abs(hi), abs(lo), 1e-300):
        return np.zeros_like(v)
    if math.isfinite(hi - lo):
        return (v - lo) / (hi - lo)
    return (v / 2 - lo / 2) / (hi / 2 - lo / 2)  # values near the float64 limit: the span overflows


# numpy's histogram rules; those that follow the spread of the values ("fd", "scott" and
# "auto" through "fd") make 1 / width bins, unbounded as the spread shrinks
_BIN_RULES = ("auto", "fd", "doane", "scott", "stone", "rice", "sturges", "sqrt")
_MAX_RULE_BINS = 100_000
#: ``phi`` is refused outside [_MIN_PHI, 1 / _MIN_PHI], ``kappa`` below _MIN_KAPPA (a prior
#: weighted 1e12 times the spatial term leaves the geometry no say at all)
_MIN_PHI = 1e-100
_MIN_KAPPA = 1e-12


def _check_prior_options(bins, phi, kappa) -> None:
    """The checks of ``bins``, ``phi`` and ``kappa`` (GPD runs them before building graphs)."""
    if isinstance(bins, str):
        check_choice(bins, _BIN_RULES, name="bins")
    else:
        check_int(bins, name="bins", low=1, high=_MAX_RULE_BINS)
    # centralities lie in [0, 1]: beyond these bounds the Gaussian term is 0 or a hard cut,
    # and 1 / (2 phi^2) would overflow
    if phi is not None:
        check_float(phi, name="phi", low=_MIN_PHI, high=1.0 / _MIN_PHI)
    if kappa is not None:
        check_float(kappa, name="kappa", low=_MIN_KAPPA, high=1.0)


def _rule_width(values, rule):
    """The bin width of numpy's spread-based rules (0 where the rule does not follow the spread
    or the spread is 0, which numpy turns into one bin)."""
    n = values.size
    if rule in ("fd", "auto"):
        iqr = float(np.subtract(*np.percentile(values, [75, 25])))
        fd = 2.0 * iqr * n ** (-1.0 / 3.0)
        if rule == "fd" or fd == 0.0:
            return fd
        return min(fd, (float(np.ptp(values)) / (np.log2(n) + 1.0)) if n > 0 else 0.0)
    if rule == "scott":
        return (24.0 * np.pi**0.5 / n) ** (1.0 / 3.0) * float(np.std(values))
    return 0.0


@renamed_parameters(v_moving="moving_centrality", v_fixed="fixed_centrality")
def centrality_prior(moving_centrality, fixed_centrality, *, bins=10, phi=None, kappa=None) -> CentralityPrior:
    """GPD's prior from normalised centralities of the moving and fixed sets (thesis eq. 5.10).

    ``h(m)`` is the share of moving points whose centrality falls in the histogram bin of
    ``v(y_m)`` (``bins`` equal bins on [0, 1], or any ``numpy.histogram`` rule name). It is
    the thesis' bin count divided by M: a constant factor that cancels when ``w = 0`` and
    otherwise keeps the outlier constant ``c`` on CPD's scale, so that a constant centrality
    gives exactly CPD (Theorem 1). ``phi2`` defaults to the variance of the fixed set's
    centralities; when that is 0 the Gaussian term carries no information and is dropped.
    ``kappa`` weighs geometry against topology as ``kappa A + (1 - kappa) B``, with the
    overall factor absorbed in sigma2 (which CPD re-estimates): the prior is multiplied by
    ``(1 - kappa) / kappa``, so 0.5 (or None) is the thesis' equal weighting and 1 is plain CPD.

    Parameters
    ----------
    moving_centrality : array_like of shape (n_moving,)
        The moving points' centralities, normalised to [0, 1]
        (:func:`normalize_centrality`).
    fixed_centrality : array_like of shape (n_fixed,)
        The fixed points' centralities, normalised to [0, 1].
    bins : int >= 1 or str, default=10
        Equal bins on [0, 1] for ``h``, or a :func:`numpy.histogram_bin_edges` rule name
        (``"fd"``, ``"auto"``, ...) applied to the moving centralities.
    phi : float > 0, optional
        Width of the Gaussian term in centrality; default: the standard deviation of the
        fixed centralities.
    kappa : float in (0, 1], optional
        Weight of geometry against topology; None is 0.5, the thesis' equal weighting.

    Returns
    -------
    CentralityPrior
        The per-point log weights and the centralities, as CPD's shared E-step takes them
        (``prior=`` of the posterior functions).

    Notes
    -----
    .. versionchanged:: 0.1.0
       ``v_moving`` and ``v_fixed`` are now ``moving_centrality`` and ``fixed_centrality``,
       as in :meth:`GPD.fit`; the former names still work, with a FutureWarning.

    Examples
    --------
    >>> p = centrality_prior([0.0, 0.0, 1.0], [0.0, 1.0], bins=2)
    >>> p.log_weight.round(4)  # two of three moving values share the first bin
    array([-0.4055, -0.4055, -1.0986])
    >>> round(p.inv2phi2, 6)  # phi2 = var([0, 1]) = 0.25
    2.0
    """
    vy = as_real_array(moving_centrality, name="moving_centrality", shape="a 1D array").astype(float)
    vx = as_real_array(fixed_centrality, name="fixed_centrality", shape="a 1D array").astype(float)
    for name, v in (("moving_centrality", vy), ("fixed_centrality", vx)):
        if v.ndim != 1 or v.size == 0:
            raise InputError(f"`{name}` must be a non-empty 1D array; got shape {v.shape}.")
        if not np.all(np.isfinite(v)):
            raise InputError(f"`{name}` must be finite; got {int(np.count_nonzero(~np.isfinite(v)))} NaN or inf.")
        if v.min() < -1e-12 or v.max() > 1 + 1e-12:
            raise InputError(f"`{name}` must be normalised to [0, 1]; got range [{v.min():.6g}, {v.max():.6g}].")
    _check_prior_options(bins, phi, kappa)
    if isinstance(bins, str):
        width = _rule_width(vy, bins)
        if 0.0 < width < 1.0 / _MAX_RULE_BINS:
            # (a spread of centralities near zero: numpy would allocate 1 / width bins)
            raise InputError(
                f"`bins` rule {bins!r} gives bins of width {width:.3g} for these centralities, "
                f"more than {_MAX_RULE_BINS:,} on [0, 1]; pass a number of bins instead."
            )
        with warnings.catch_warnings():
            # 'stone' searches up to 100 bins and warns when its best is the last; the rule's
            # choice stands (it is what the caller asked for)
            warnings.filterwarnings("ignore", message="The number of bins estimated may be suboptimal")
            edges = np.histogram_bin_edges(vy, bins=bins, range=(0.0, 1.0))
    else:
        edges = np.linspace(0.0, 1.0, int(bins) + 1)
    counts, _ = np.histogram(vy, bins=edges)
    which = np.clip(np.searchsorted(edges, vy, side="right") - 1, 0, counts.size - 1)
    log_weight = np.log(counts[which] / vy.size)
    if phi is None:
        phi2 = float(np.var(vx))
    else:
        phi2 = float(phi) ** 2
    inv2phi2 = 0.0 if phi2 <= 0 else 1.0 / (2.0 * phi2)
    # (1 - kappa) / kappa: the prior's weight over the spatial term's, at most 1 / _MIN_KAPPA
    kappa = 0.5 if kappa is None else float(kappa)
    return CentralityPrior(log_weight, vy.copy(), vx.copy(), inv2phi2, (1.0 - kappa) / kappa)


_SCHEDULES = ("anneal",)


class _Schedule:
    """A prior that changes with sigma2 (picklable, so a fitted GPD can be copied)."""

    def __init__(self, prior: CentralityPrior, schedule):
        self.prior = prior
        self.schedule = schedule

    def __call__(self, sigma2_ratio: float):
        if self.schedule == "anneal":
            return replace(self.prior, strength=self.prior.strength * min(1.0, sigma2_ratio))
        return self.prior if sigma2_ratio >= self.schedule else None


class GPD(BaseEstimator):
    """Graph-based Point Drift: any CPD whose E-step is weighted by a centrality prior.

    Builds a data-graph on each set, computes a centrality on each, normalises it to [0, 1]
    and fits a clone of ``base_cpd`` with the posterior of thesis eq. 5.10:
    ``P_g(m | x_n) = h(m) exp(psi(x_n, m)) / (sum_k h(k) exp(psi(x_n, k)) + c)``,
    ``psi = -(|x_n - T(y_m)|^2 / (2 sigma2) + (v(x_n) - v(y_m))^2 / (2 phi^2))``
    (``h`` the share of moving points in the histogram bin of ``v(y_m)``, ``c`` CPD's outlier
    constant). The M-steps are the base CPD's, unchanged, and so are its ``normalize``,
    ``init`` and ``landmarks``. The graphs and centralities are computed once, on the sets
    as given (topology does not move with the transform); named graphs are built on each set
    centred and scaled to unit RMS radius, which leaves them unchanged but well conditioned.
    With a complete or edgeless graph every centrality is constant and GPD is CPD exactly
    (Theorem 1).

    Parameters
    ----------
    base_cpd : RigidCPD, AffineCPD or NonRigidCPD, optional
        The CPD whose loop, M-step and stopping rule are used (default ``RigidCPD()``).
        It is cloned (``sklearn.base.clone``), never fitted itself; its ``callback`` is
        shared with the clone, not copied.
    centrality : str or callable, default='closeness'
        One of :data:`centrality_vision.centrality.CENTRALITIES`, or ``f(graph) -> values``.
    graph : str or callable, default='delaunay'
        One of :data:`GRAPHS` or ``f(points) -> sparse graph`` with one node per point. A
        named graph of a set that spans fewer dimensions than it has (a flat scan in 3D, a
        line) is built in the space the set spans (a line's in 2D, with a second coordinate
        of 0), to within the rounding of its coordinates; a callable gets the caller's
        points.
    bins : int in [1, 100,000] or str, default=10
        Histogram bins for ``h(m)`` (see :func:`centrality_prior`).
    phi : float in [1e-100, 1e100], optional
        Width of the Gaussian on centrality differences; default: the standard deviation of
        the fixed set's centralities.
    kappa : float in [1e-12, 1], optional
        Geometry-vs-topology balance ``kappa A + (1 - kappa) B`` (thesis 5.4.5); None or 0.5
        is the thesis' equal weighting, 1 is plain CPD.
    prior_schedule : None, 'anneal' or float in (0, 1), default=None
        How the prior's weight follows sigma2: None keeps it (the thesis); 'anneal' scales
        it by ``sigma2 / sigma2_0`` (the prior guides the coarse start and fades as the
        sets close in); a float ``f`` keeps it while ``sigma2 >= f sigma2_0`` and then runs
        plain CPD.
    weights : bool, default=False
        Use edge lengths in the centrality (shortest paths by length) instead of hop counts;
        path centralities only (betweenness, closeness, harmonic, eccentricity).
    graph_neighbors : int, default=6
        Neighbours per point for ``graph='knn'`` (``n_neighbors`` of
        :func:`~centrality_vision.graphs.knn_graph`; the base CPD's ``n_neighbors`` is its
        E-step's); on a set of ``n <= graph_neighbors`` points, ``n - 1`` (the complete
        graph).
    k : deprecated
        The former name of ``graph_neighbors``; it still works, with a FutureWarning, and
        will be removed.

    Attributes
    ----------
    estimator_ : RigidCPD, AffineCPD or NonRigidCPD
        The fitted clone of ``base_cpd``. Its fitted attributes (``transform_``,
        ``moving_transformed_``, ``sigma2_``, ``n_iter_``, ``converged_``, ``history_``,
        ``fixed_to_moving_``, ``posteriors_``, ...) are readable on the GPD itself.
    moving_centrality_, fixed_centrality_ : ndarray
        The normalised centralities.
    moving_graph_, fixed_graph_ : sparse array or None
        The graphs (None where centralities were given).
    prior_ : CentralityPrior
        The prior at full weight.

    Notes
    -----
    Measured on the Chui-Rangarajan families (``benchmarks/registration_suite.py``, 100
    pairs per level, fish and Kimia ``dog1`` outlines). Over
    ``NonRigidCPD(n_neighbors=10, w="auto")`` the closeness prior with
    ``prior_schedule="anneal"`` succeeds as often as that CPD in every family (averaged over
    levels) and more often with occlusion (fish 66.8% against 65.3%, dog1 68.8% against
    63.7%; one level less often: fish 50% occluded, 13% against 16%); the constant prior
    gains more with occlusion (70-76%) but loses with noise (fish, noise 0.05: error 0.035
    against 0.029). The occlusion gain comes from the histogram weights ``h(m)``, not from
    the topology: ``bins=1`` removes it, ``phi=1e6`` (no centrality term) keeps it, and so
    do centralities randomly permuted within each set (``--explain``). Over the dense CPD
    the constant prior succeeds more often than CPD with clutter (fish, outliers: 79%
    against 40%) and less often with noise. Under ``w="auto"`` the constant prior can read
    most of a cluttered fixed set as outliers (the CPD fish pair with 60 uniform clutter
    points: ``w_`` 0.83 and mean error 0.17, where ``prior_schedule="anneal"`` gives 0.0083,
    a fixed ``w=0.4`` 0.0085 and CPD alone 0.0083): EM's likelihood prefers that fit, so
    ``w="auto"`` keeps it. Use ``"anneal"`` or a fixed ``w`` there.

    Examples
    --------
    >>> import numpy as np
    >>> from centrality_vision.registration import GPD, RigidCPD
    >>> y = np.random.default_rng(0).random((60, 2))
    >>> r = np.array([[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    >>> x = y @ r.T + 0.5
    >>> gpd = GPD(RigidCPD(scale=False, tol=1e-10), centrality="closeness").fit(y, x)
    >>> bool(np.allclose(gpd.moving_transformed_, x, atol=1e-6))
    True
    """

    def __init__(
        self,
        base_cpd=None,
        *,
        centrality="closeness",
        graph="delaunay",
        bins=10,
        phi=None,
        kappa=None,
        prior_schedule=None,
        weights=False,
        graph_neighbors=6,
        k=FORMER,
    ):
        self.base_cpd = base_cpd
        self.centrality = centrality
        self.graph = graph
        self.bins = bins
        self.phi = phi
        self.kappa = kappa
        self.prior_schedule = prior_schedule
        self.weights = weights
        self.graph_neighbors = graph_neighbors
        self.k = k

    def set_params(self, **params):
        """Set parameters, nested ones too (``base_cpd__w=0.2``, as in a grid search): on a GPD
        whose ``base_cpd`` is None they apply to its default, ``RigidCPD()``.

        Examples
        --------
        >>> GPD().set_params(base_cpd__w=0.2).base_cpd
        RigidCPD(w=0.2)
        """
        if self.base_cpd is None and "base_cpd" not in params and any(key.startswith("base_cpd__") for key in params):
            self.base_cpd = RigidCPD()  # (sklearn's own would call None.set_params: an AttributeError)
        return super().set_params(**params)

    def __getattr__(self, name):
        # the base estimator's fitted attributes, read through estimator_ (no copies kept)
        if name.endswith("_") and not name.startswith("_"):
            estimator = self.__dict__.get("estimator_")
            if estimator is not None:
                return getattr(estimator, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def _check_params(self):
        if self.base_cpd is not None and not isinstance(self.base_cpd, _CPD):
            raise TypeError(f"`base_cpd` must be a RigidCPD, AffineCPD or NonRigidCPD; got {self.base_cpd!r}.")
        if not callable(self.centrality):
            check_choice(self.centrality, CENTRALITIES, name="centrality")
        if not callable(self.graph):
            check_choice(self.graph, GRAPHS, name="graph")
        check_bool(self.weights, name="weights")
        if self.weights and isinstance(self.centrality, str) and self.centrality not in PATH_CENTRALITIES:
            # (degree, eigenvector, PageRank and Katz read stored values as strengths, not
            # lengths: GPD passed them weights=True, deprecated or unknown there)
            raise InputError(
                f"`weights=True` (shortest paths by edge length) applies to {', '.join(PATH_CENTRALITIES)}; "
                f"got centrality={self.centrality!r}."
            )
        neighbors, name = former_parameter(self, "k", "graph_neighbors")
        neighbors = check_int(neighbors, name=name, low=1)
        _check_prior_options(self.bins, self.phi, self.kappa)
        schedule = self.prior_schedule
        if isinstance(schedule, str):
            check_choice(schedule, _SCHEDULES, name="prior_schedule")
        elif schedule is not None:
            check_float(schedule, name="prior_schedule", low=0.0, high=1.0, low_open=True, high_open=True)
        return neighbors

    def _centrality(self, points, graph, given, name, neighbors):
        if given is not None:
            values = as_real_array(given, name=f"{name}_centrality", shape="a 1D array").astype(float)
            if values.shape != (points.shape[0],):
                raise InputError(f"`{name}_centrality` must have shape ({points.shape[0]},); got {values.shape}.")
            return normalize_centrality(values, name=f"{name}_centrality"), None
        if graph is None:
            if not callable(self.graph):  # every graph GPD builds joins distinct points
                try:
                    as_points(points, name=name, n_dims=ANY_DIMS, allow_duplicates=False)
                except InputError as exc:
                    raise InputError(
                        f"{exc} GPD's {self.graph!r} graph needs distinct points: remove the duplicates. "
                        f"From Python, you can also pass your own `{name}_graph` or `{name}_centrality`."
                    ) from None
            try:
                graph = _build_graph(points, self.graph, neighbors)
            except InputError as exc:
                kind = getattr(self.graph, "__name__", self.graph)
                # the Delaunay-based graphs take 2D and 3D points only
                offered = ("knn", "emst") if points.shape[1] in (2, 3) else ("knn", "complete")
                others = " or ".join(repr(g) for g in offered if g != kind)
                raise InputError(
                    f"`{name}`: GPD could not build its {kind!r} graph: {exc} Choose another `graph` "
                    f"(e.g. {others}). From Python, you can also pass your own "
                    f"`{name}_graph` or `{name}_centrality`."
                ) from None
        else:
            graph = as_graph(graph, name=f"{name}_graph")
            if graph.shape[0] != points.shape[0]:
                raise InputError(
                    f"`{name}_graph` must have {points.shape[0]} nodes, one per point; got {graph.shape[0]}."
                )
        if callable(self.centrality):
            values = as_real_array(self.centrality(graph), name="centrality(graph)", shape="a 1D array").astype(float)
            if values.shape != (points.shape[0],):
                raise InputError(f"`centrality(graph)` must return shape ({points.shape[0]},); got {values.shape}.")
        else:
            values = compute(graph, self.centrality, weights=True) if self.weights else compute(graph, self.centrality)
        return normalize_centrality(values, name=f"{name} centrality"), graph

    def fit(
        self,
        moving,
        fixed,
        *,
        true_moving=None,
        landmarks=None,
        moving_graph=None,
        fixed_graph=None,
        moving_centrality=None,
        fixed_centrality=None,
    ):
        """Register ``moving`` onto ``fixed``; returns ``self``.

        ``moving_graph``/``fixed_graph`` (sparse adjacency, one node per point) or
        ``moving_centrality``/``fixed_centrality`` (raw values, normalised here) replace the
        ones GPD would build. ``true_moving`` and ``landmarks`` as in :meth:`RigidCPD.fit`.

        Parameters
        ----------
        moving : array_like of shape (M, D)
            The set to transform. Not modified. D from 1 to 64, but 2 or 3 where GPD builds a
            ``"delaunay"``, ``"gabriel"`` or ``"emst"`` graph.
        fixed : array_like of shape (N, D)
            The set it is brought onto, of the same D. Not modified.
        true_moving : array_like of shape (M, D), optional
            Where each moving point truly belongs; ``history_["error"]`` then holds
            ``|true_moving - T(Y)|`` per iteration.
        landmarks : sequence of (i, j) pairs, optional
            Moving point ``i`` corresponds to fixed point ``j`` (see :meth:`RigidCPD.fit`).
        moving_graph, fixed_graph : sparse array or matrix of shape (n, n), or a networkx or igraph graph, optional
            Undirected graph with one node per point of that set, used instead of the ``graph``
            GPD would build; ignored where the set's centrality is given.
        moving_centrality, fixed_centrality : array_like of shape (M,) and (N,), optional
            Finite centrality values, one per point, used instead of computing ``centrality``;
            they are min-max normalised (:func:`normalize_centrality`).

        Returns
        -------
        self : GPD

        Examples
        --------
        >>> import numpy as np
        >>> from centrality_vision.registration import GPD, RigidCPD
        >>> y = np.random.default_rng(0).random((20, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> x = y @ r.T + 0.5
        >>> gpd = GPD(RigidCPD(scale=False, tol=1e-10), graph="delaunay").fit(y, x)
        >>> gpd.moving_graph_.shape, gpd.moving_centrality_.shape  # one node, one value per point
        ((20, 20), (20,))
        >>> float(gpd.moving_centrality_.min()), float(gpd.moving_centrality_.max())  # normalised
        (0.0, 1.0)
        >>> gpd.converged_, bool(np.allclose(gpd.transform_.rotation, r))
        (True, True)

        Centralities of your own replace the graphs (they are min-max normalised):

        >>> own = GPD(RigidCPD(scale=False, tol=1e-10)).fit(
        ...     y, x, moving_centrality=np.arange(20.0), fixed_centrality=np.arange(20.0)
        ... )
        >>> own.moving_graph_ is None, own.moving_centrality_[:3].round(3).tolist()
        (True, [0.0, 0.053, 0.105])
        """
        neighbors = self._check_params()
        base = RigidCPD() if self.base_cpd is None else self.base_cpd
        moving_arr = as_points(moving, name="moving", n_dims=ANY_DIMS)
        # the dimensions first: a graph of the wrong ones fails with a message about the graph
        fixed_arr = as_points(fixed, name="fixed", n_dims=(moving_arr.shape[1],))
        vy, gy = self._centrality(moving_arr, moving_graph, moving_centrality, "moving", neighbors)
        vx, gx = self._centrality(fixed_arr, fixed_graph, fixed_centrality, "fixed", neighbors)
        prior = centrality_prior(vy, vx, bins=self.bins, phi=self.phi, kappa=self.kappa)
        hook = prior if self.prior_schedule is None else _Schedule(prior, self.prior_schedule)
        # clone deep-copies parameters; the callback is a hook the caller watches, so it is shared
        estimator = clone(base).set_params(callback=base.callback)
        self.estimator_ = estimator.fit(moving_arr, fixed_arr, true_moving=true_moving, landmarks=landmarks, prior=hook)
        self.moving_centrality_ = vy
        self.fixed_centrality_ = vx
        self.moving_graph_ = gy
        self.fixed_graph_ = gx
        self.prior_ = prior
        return self

    def transform(self, points) -> np.ndarray:
        """Apply the fitted transform to new points.

        Parameters
        ----------
        points : array_like of shape (n_points, D)
            Points in the moving set's frame, D as in :meth:`fit`.

        Returns
        -------
        ndarray of shape (n_points, D)
            ``transform_(points)``.

        Examples
        --------
        >>> import numpy as np
        >>> from centrality_vision.registration import GPD, RigidCPD
        >>> y = np.random.default_rng(0).random((20, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> x = y @ r.T + 0.5
        >>> gpd = GPD(RigidCPD(scale=False, tol=1e-10)).fit(y, x)
        >>> gpd.transform([[0.0, 0.0], [1.0, 0.0]]).round(3)  # r @ p + 0.5
        array([[0.5  , 0.5  ],
               [1.455, 0.796]])
        """
        check_is_fitted(self, "estimator_")
        return self.estimator_.transform(points)

    def score(self, moving, fixed) -> float:
        """The fitted base estimator's :meth:`RigidCPD.score`.

        Parameters
        ----------
        moving : array_like of shape (M, D)
            Points to transform with the fitted transform.
        fixed : array_like of shape (N, D)
            Points to compare them with.

        Returns
        -------
        float
            Minus the mean distance from each fixed point to its nearest transformed moving point
            (at most 0; larger is better), in the caller's units.

        Examples
        --------
        >>> import numpy as np
        >>> from centrality_vision.registration import GPD, RigidCPD
        >>> y = np.random.default_rng(0).random((20, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> x = y @ r.T + 0.5
        >>> gpd = GPD(RigidCPD(scale=False, tol=1e-10)).fit(y, x)
        >>> bool(abs(gpd.score(y, x)) < 1e-9), round(gpd.score(y, x + [0.1, 0.0]), 3)
        (True, -0.086)
        """
        check_is_fitted(self, "estimator_")
        return self.estimator_.score(moving, fixed)

    def posterior(self) -> np.ndarray:
        """The full GPD posterior matrix (M x N) of the final state; see :meth:`RigidCPD.posterior`.

        Examples
        --------
        >>> import numpy as np
        >>> from centrality_vision.registration import GPD, RigidCPD
        >>> y = np.random.default_rng(0).random((20, 2))
        >>> r = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
        >>> x = y @ r.T + 0.5
        >>> P = GPD(RigidCPD(scale=False, tol=1e-10)).fit(y, x).posterior()
        >>> P.shape, bool(np.allclose(P.sum(axis=0), 1))  # w=0: each fixed point's column sums to 1
        ((20, 20), True)
        >>> bool(np.array_equal(P.argmax(axis=0), np.arange(20)))  # y[m] went to x[m]
        True
        """
        check_is_fitted(self, "estimator_")
        return self.estimator_.posterior()
