"""The one E-step shared by every CPD variant and by GPD.

``_e_step(moving_t, fixed, sigma2, w, log_prior=None)`` returns the sufficient statistics of the
posterior matrix ``P`` (M x N) of CPD [1]_ (or of GPD's: CPD's posterior with the centrality
prior added to every log-term before the rows are normalised) without ever forming it:
``P1 = P 1``, ``Pt1 = P^T 1``, ``PX = P X``, ``Np = 1^T P 1``, the negative log-likelihood and, for each
fixed point, its most probable moving point. Everything is computed in log space (each row is
shifted by its largest exponent before ``exp``), so a tiny ``sigma2`` neither underflows to 0/0
nor overflows.

References
----------
.. [1] A. Myronenko and X. Song, "Point set registration: coherent point drift",
   IEEE TPAMI 32(12), 2262-2275, 2010.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

import numpy as np

from .._deprecation import renamed_parameters
from .._parallel import _pool, get_num_threads, run_chunks
from .._validation import check_choice
from .._warnings import warn
from ..exceptions import InputError
from . import _kernels as K

__all__ = [
    "Posteriors",
    "CentralityPrior",
    "E_STEP_METHODS",
    "PRECISIONS",
    "EStepPlanner",
    "_e_step",
    "dense_posterior",
    "knn_posterior",
    "knn_posterior_matrix",
]

E_STEP_METHODS = ("auto", "dense", "truncated", "fgt")
PRECISIONS = ("float64", "float32")
"""The dense E-step's precisions. 'float32' takes each term ``exp(t)``, ``t = s - r <= 0``, in
float32 from the float64 ``t`` rounded to float32 (``t`` below -87 clamped at -87, as float64
clamps at -700); scores, row maxima and every sum stay in float64. The rounding of ``t`` (at
most ``87 * 2^-24``) and the float32 exponential (relative error below 2e-7) give each term a
relative error below 5.5e-6, and a clamped term an absolute error below
``exp(-87) < 1.7e-38`` (a row's largest term is 1 or its outlier term is, so its denominator
is at least 1). Hence, against float64: each posterior ``P[m, n]`` within
``1.1e-5 P[m, n] + 3.4e-38 (M + 1)``; ``P1`` and ``P^T 1`` within 1.1e-5 times their values
plus ``3.4e-38 (M + 1) N``; ``P X`` within ``1.1e-5 P |X|`` plus ``3.4e-38 (M + 1) N max |X|``;
the negative log-likelihood within ``N (5.5e-6 + 1.7e-38 M)``. Measured on random sets:
about 2e-8 relative on ``P1`` and ``P X``."""

# The FGT path recomputes its too-small rows exactly: densely up to this many pairs.
_DENSE_PAIRS = 4_000_000
# Grid cells per truncation radius r: a row visits the cells overlapping its box of side 2r,
# about (2r + 2 cell)^2, of which the disc pi r^2 is 35% with cells of side r and 55% with r/4
# (measured: 1.7x faster on 100,000 points).
_CELLS_PER_REACH = 4
# Truncated path: values buffered per call of its scores kernel (1 MiB, in a core's L2 cache).
_BLOCK = 1 << 17
# Chunks of fixed points whose partial sums are added in order (see _reduce_rows): enough
# to balance 16 threads, few enough that the partials cost nothing to add.
_CHUNKS = 16
# Below this many pairs an E-step runs on the calling thread: handing chunks of a
# sub-millisecond job to the pool costs more than it saves, badly so on a busy machine
# (measured: 500 points, load 20 on 2 cores, 1.7 s per fit with 2 threads, 1.0 s with 1).
_SERIAL_PAIRS = 1 << 20
# From this many pairs up to _SERIAL_PAIRS the rows are two halves: the calling thread runs
# one, a pool thread the other if it starts in time (measured at 1,000 points: an E-step
# 1.28 ms on one thread, see benchmarks/registration.py); the halves are added in order, so
# results do not depend on the thread count.
_PAIR_PAIRS = 1 << 19
# The calling thread's share of the two halves' rows. It starts at once; the pool thread
# wakes 20-50 us later and its end takes another wake-up to reach the caller, so even
# halves leave the caller waiting. Measured over whole accelerated fits at 800 and 1,000
# points (interleaved, medians of 25): shares 0.54-0.58 were 2-13% faster than 0.5, 0.62
# slower again. The split depends on the number of rows alone, so results stay
# bit-identical for any thread count.
_CALLER_SHARE = 0.54
# From this many moving points the dense path takes each row's exponentials over a band of
# the sorted moving points (see _dense); below it sorting costs more than the band saves.
_BAND_POINTS = 256
# With the band, each row's scores too are taken only over the run that its nearest moving
# point bounds (see _kernels.dense_rows) when the narrowest band leaves at least this many
# moving points out: finding the nearest point costs about what scoring ~900 points does
# (one thread, per E-step: 0.91-1.02x at 1,000 points where 400-900 are left out; 1.07x at
# 3,000 with 1,230, 1.2-1.57x with 2,000-2,750; 1.13-1.32x at 2,000 with 1,360-1,840).
_SCORE_BAND_SAVED = 1000


@dataclass(frozen=True)
class CentralityPrior:
    """GPD's log prior ``strength * (log_weight[m] - (v_x[n] - v_y[m])^2 / (2 phi2))``,
    ``v_y`` the moving points' centralities and ``v_x`` the fixed points'.

    Kept in this separable form so that no M x N array is ever built.

    Parameters
    ----------
    log_weight : ndarray of shape (M,)
        ``log h(m)``, the log share of the moving points in ``m``'s centrality bin.
    moving_centrality : ndarray of shape (M,)
        ``v_y``, normalised to [0, 1] by :func:`centrality_prior`.
    fixed_centrality : ndarray of shape (N,)
        ``v_x``, normalised likewise.
    inv2phi2 : float
        ``1 / (2 phi2)``; 0 drops the Gaussian term.
    strength : float, default=1
        How much the prior counts against the spatial term: 1 is the thesis' eq. 5.10,
        0 is CPD. (``scale``, ``v_moving`` and ``v_fixed`` are the former names of
        ``strength`` and the centralities; they still work, with a FutureWarning.)

    Examples
    --------
    :func:`~centrality_vision.registration.centrality_prior` builds it from centralities;
    by hand, two moving points of equal weight and three fixed points:

    >>> import numpy as np
    >>> prior = CentralityPrior(np.zeros(2), np.array([0.0, 1.0]), np.array([0.0, 0.5, 1.0]), inv2phi2=2.0)
    >>> prior.matrix()  # pairs of equal centrality are the most likely
    array([[ 0. , -0.5, -2. ],
           [-2. , -0.5,  0. ]])
    >>> prior.bounds()
    (-2.0, 0.0)
    """

    log_weight: np.ndarray
    moving_centrality: np.ndarray
    fixed_centrality: np.ndarray
    inv2phi2: float
    strength: float = 1.0

    # the former field names, read-only
    v_moving = property(lambda self: _former_field(self, "v_moving", "moving_centrality"))
    v_fixed = property(lambda self: _former_field(self, "v_fixed", "fixed_centrality"))
    scale = property(lambda self: _former_field(self, "scale", "strength"))

    def bounds(self) -> tuple[float, float]:
        """Lower and upper bound of the prior over all pairs (for the truncated search).

        Examples
        --------
        >>> import numpy as np
        >>> prior = CentralityPrior(np.log([0.5, 0.25]), np.array([0.0, 1.0]), np.array([0.5]), inv2phi2=2.0)
        >>> low, high = prior.bounds()
        >>> round(low, 3), round(high, 3)  # log 0.25 - 1 * 2, log 0.5
        (-3.386, -0.693)
        >>> bool(low <= prior.matrix().min() and prior.matrix().max() <= high)
        True
        """
        if self.strength == 0 or self.log_weight.size == 0:
            return 0.0, 0.0
        both = (self.fixed_centrality, self.moving_centrality)
        span = (max(v.max() for v in both) - min(v.min() for v in both)) ** 2
        low = self.strength * (self.log_weight.min() - span * self.inv2phi2)
        return float(low), float(self.strength * self.log_weight.max())

    def matrix(self) -> np.ndarray:
        """The dense (M, N) prior, for tests and small problems.

        Examples
        --------
        >>> import numpy as np
        >>> prior = CentralityPrior(np.log([0.5, 0.25]), np.array([0.0, 1.0]), np.array([0.5]), inv2phi2=2.0)
        >>> prior.matrix().round(3)  # log_weight[m] - (0.5 - moving_centrality[m])^2 * 2
        array([[-1.193],
               [-1.886]])
        """
        dv = self.fixed_centrality[None, :] - self.moving_centrality[:, None]
        return self.strength * (self.log_weight[:, None] - dv * dv * self.inv2phi2)


CentralityPrior.__init__ = renamed_parameters(
    v_moving="moving_centrality", v_fixed="fixed_centrality", scale="strength"
)(CentralityPrior.__init__)


def _former_field(prior, old, new):
    warn(f"`CentralityPrior.{old}` is renamed `{new}`; the old name will be removed.", FutureWarning)
    return getattr(prior, new)


@dataclass(frozen=True)
class Posteriors:
    """Sufficient statistics of one E-step.

    Attributes
    ----------
    p1 : ndarray of shape (M,)
        ``P 1``: the expected number of fixed points each moving point explains.
    pt1 : ndarray of shape (N,)
        ``P^T 1``: the probability that each fixed point is not an outlier.
    px : ndarray of shape (M, D)
        ``P X``.
    n_p : float
        ``1^T P 1``.
    neg_log_likelihood : float
        ``-sum_n log(sum_m exp(s_mn) + c) + N D/2 log sigma2`` (constants dropped), CPD's
        objective up to a constant.
    best : ndarray of shape (N,) or None
        For each fixed point, the moving point of largest posterior, or -1 where the outlier
        component is more probable than any moving point; None from a dense E-step asked
        not to compute it (``want_best=False``).

    Examples
    --------
    A fitted CPD keeps those of its final E-step in ``posteriors_``:

    >>> import numpy as np
    >>> from centrality_vision.registration import RigidCPD
    >>> y = np.random.default_rng(0).random((15, 2))
    >>> fixed = np.vstack([y + 0.1, [[5.0, 5.0]]])  # a copy and one far outlier
    >>> post = RigidCPD(w=0.2, tol=1e-8).fit(y, fixed).posteriors_
    >>> post.p1.shape, post.pt1.shape, post.px.shape, round(post.n_p, 3)
    ((15,), (16,), (15, 2), 15.0)
    >>> post.best.tolist()  # each copy's moving point; -1: the outlier
    [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, -1]
    """

    p1: np.ndarray
    pt1: np.ndarray
    px: np.ndarray
    n_p: float
    neg_log_likelihood: float
    best: np.ndarray | None
    method: str = "dense"


def _single(precision) -> bool:
    """Whether ``precision`` (one of :data:`PRECISIONS`) asks for float32 terms."""
    return check_choice(precision, PRECISIONS, name="precision") == "float32"


def log_outlier_constant(sigma2: float, w: float, n_dims: int, n_moving: int, n_fixed: int) -> float:
    """``log c`` with ``c = (2 pi sigma2)^(D/2) w/(1-w) M/N``; ``-inf`` for ``w = 0``."""
    if w == 0:
        return -math.inf
    return 0.5 * n_dims * math.log(2 * math.pi * sigma2) + math.log(w / (1 - w)) + math.log(n_moving / n_fixed)


def _prior_arrays(prior: CentralityPrior | None):
    if prior is None or prior.strength == 0:
        empty = np.empty(0)
        return empty, empty, empty, 0.0, 0.0
    centralities = prior.moving_centrality, prior.fixed_centrality
    return prior.log_weight, *centralities, float(prior.strength), float(prior.inv2phi2)


def _reduce_rows(work, n_rows, n_moving, n_dims):
    """Run ``work(lo, hi, p1, pxt)`` over chunks of rows on the thread pool and return the
    summed ``p1`` (M,) and ``pxt`` (D, M).

    The chunks depend only on ``n_rows`` (:data:`_CHUNKS` of them), each fills its own zeroed
    partial sums, and the partials are added in chunk order as soon as their predecessors are
    in: the same additions in the same order whatever the number of threads, so results are
    bit-identical for any thread count; only a few partials are alive at a time. Below
    :data:`_SERIAL_PAIRS` pairs the pool's 16 chunks cost more than they save (6% of an
    E-step at 1,000 points, 33% at 300, measured): from :data:`_PAIR_PAIRS` the rows are
    two parts (:func:`_two_halves`: the calling thread takes :data:`_CALLER_SHARE` of them,
    one pool thread the rest), below it one chunk on the calling thread.
    """
    serial = n_rows * n_moving < _SERIAL_PAIRS
    pair = serial and n_rows >= 2 and n_rows * n_moving >= _PAIR_PAIRS
    n_chunks = (2 if pair else 1) if serial else min(n_rows, _CHUNKS)
    edges = [i * n_rows // n_chunks for i in range(n_chunks + 1)]
    if pair:
        edges[1] = int(n_rows * _CALLER_SHARE)
    total_p1 = np.zeros(n_moving)
    total_pxt = np.zeros((n_dims, n_moving))
    done = {}
    state = {"next": 0}
    lock = threading.Lock()

    def task(lo, hi):
        for c in range(lo, hi):
            part_p1 = np.zeros(n_moving)
            part_pxt = np.zeros((n_dims, n_moving))
            work(edges[c], edges[c + 1], part_p1, part_pxt)
            with lock:
                done[c] = (part_p1, part_pxt)
                while state["next"] in done:
                    a, b = done.pop(state["next"])
                    np.add(total_p1, a, out=total_p1)
                    np.add(total_pxt, b, out=total_pxt)
                    state["next"] += 1

    if pair and get_num_threads() > 1:
        _two_halves(task)
    elif serial:
        task(0, n_chunks)
    else:
        run_chunks(task, n_chunks)
    return total_p1, total_pxt


def _two_halves(task):
    """``task(0, 1)`` on the calling thread and ``task(1, 2)`` on a pool thread, or on the
    calling thread too when the pool has not started it by then (a busy machine), so that
    the caller never waits for a thread the system has not scheduled."""
    claimed = [False]
    lock = threading.Lock()

    def second():
        with lock:
            if claimed[0]:
                return False
            claimed[0] = True
        task(1, 2)
        return True

    future = _pool(get_num_threads()).submit(second)
    task(0, 1)
    if not second():  # the pool thread took the second half: wait for it
        future.result()


def _band_axis(extent, n_moving, inv2s2, tau) -> int | None:
    """The axis along which the dense path's rows take their exponentials over a band of the
    sorted moving points (:func:`_kernels.dense_rows`), or None when no band would be
    narrower than the set: the band of a row is at least ``2 sqrt(tau / inv2s2)`` wide.
    ``extent``: the moving set's along each axis."""
    if tau is None or n_moving < _BAND_POINTS:
        return None
    axis = int(np.argmax(extent))
    return axis if 2.0 * math.sqrt(tau / inv2s2) < extent[axis] else None


def _score_band(extent, n_moving, inv2s2, tau) -> bool:
    """Whether the band also restricts each row's scores (see :data:`_SCORE_BAND_SAVED`):
    the narrowest band, ``2 sqrt(tau / inv2s2)`` wide, leaves enough points out."""
    narrowest = min(1.0, 2.0 * math.sqrt(tau / inv2s2) / max(extent, 1e-300))
    return (1.0 - narrowest) * n_moving >= _SCORE_BAND_SAVED


def _dense_cost(moving_t, n_fixed, tau, prior, d2_nearest):
    """The dense path's modelled cost (ns) as a function of sigma2: every pair's score and
    exponential, or, with the band (see :func:`_dense`), each row's exponentials (and, when
    restricted, scores) over the share of the moving points within ``sqrt(2 sigma2 tau + d^2)``
    along the band's axis (``d`` the median distance to the nearest moving point), plus a
    row's search. (A function, so that a planner can follow it to another sigma2.)"""
    n_moving = moving_t.shape[0]
    pairs = float(n_moving) * n_fixed
    extent = np.ptp(moving_t, axis=0)
    has_prior = prior is not None and prior.strength != 0
    d2 = float(np.median(d2_nearest))

    def cost(sigma2):
        inv2s2 = 1.0 / (2.0 * sigma2)
        axis = None if has_prior else _band_axis(extent, n_moving, inv2s2, tau)
        if axis is None:
            return _COST_DENSE * pairs
        share = min(1.0, 2.0 * math.sqrt(tau / inv2s2 + d2) / max(extent[axis], 1e-300))
        scored = share if _score_band(extent[axis], n_moving, inv2s2, tau) else 1.0
        exps = (_COST_DENSE - _COST_DENSE_SCORE) * share
        return pairs * (_COST_DENSE_SCORE * scored + exps) + _COST_DENSE_ROW * n_fixed

    return cost


def _dense(moving_t, fixed, inv2s2, log_c, prior, single=False, tau=None, want_best=True, memo=None):
    """Every pair (see :func:`_kernels.dense_rows`); ``single``: the exponentials in float32;
    ``want_best=False`` returns None for ``best`` (see :func:`fixed_to_moving`); ``memo``:
    a dict kept over the E-steps of one ``fixed`` set (see :func:`_sorted_rows`).

    With ``tau`` (and no prior, from :data:`_BAND_POINTS` moving points) each row takes its
    exponentials only over the band of the moving points, sorted along their widest axis,
    that can hold a term above ``exp(-tau)`` of the row's largest (:func:`_band_axis`); the
    fixed points are sorted the same way, so that four consecutive rows share most of their
    bands. Measured on 1,000 points of a Kimia outline in unit RMS radius, one thread:
    0.96x the time of every exponential at sigma2 >= 0.1, 1.1x faster at 1e-2, 1.3x at
    3e-3, 1.6-1.8x at 1e-3 and below.
    """
    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    lw, vy, vx, scale, inv2phi2 = _prior_arrays(prior)
    # (the preparation and the scatter back are compiled: in numpy they took ~100 us of a
    # 1,000-point E-step of ~800)
    yt, extent = K.transpose_extent(moving_t)
    axis = None if lw.size else _band_axis(extent, n_moving, inv2s2, tau)
    unsorted = np.empty(0, dtype=np.int64)
    if axis is None:
        order = np.arange(n_moving) if want_best else unsorted  # (best holds the caller's index)
        key = np.empty(0)
        x = fixed
        row_order = unsorted
    else:
        order = _moving_order(yt[axis], axis, memo)
        yt = K.gather_columns(yt, order)
        key = yt[axis]
        row_order, x = _sorted_rows(fixed, axis, memo)
    pt1 = np.empty(n_fixed)
    log_den = np.empty(n_fixed)
    best = np.empty(n_fixed if want_best else 0, dtype=np.int64)
    dtype = np.float32 if single else np.float64
    band_tau = math.inf if tau is None else float(tau)
    score_band = axis is not None and _score_band(extent[axis], n_moving, inv2s2, band_tau)

    def work(lo, hi, p1, pxt):
        scores = np.empty(n_moving)
        rows = np.zeros((K._GROUP, n_moving), dtype=dtype)
        coef = np.empty((n_dims + 1, K._GROUP))
        K.dense_rows(
            x,
            yt,
            lo,
            hi,
            inv2s2,
            log_c,
            lw,
            vy,
            vx,
            scale,
            inv2phi2,
            single,
            key,
            0 if axis is None else axis,
            band_tau,
            score_band,
            order,
            scores,
            rows,
            coef,
            p1,
            pxt,
            pt1,
            log_den,
            best,
        )

    p1, pxt = _reduce_rows(work, n_fixed, n_moving, n_dims)
    p1, px, pt1, log_den = K.scatter_statistics(p1, pxt, unsorted if axis is None else order, pt1, log_den, row_order)
    if not want_best:
        return p1, px, pt1, log_den, None
    if axis is not None:
        best_out = np.empty_like(best)
        best_out[row_order] = best
        best = best_out
    return p1, px, pt1, log_den, best


def _moving_order(values, axis, memo):
    """The stable argsort of ``values`` (the moving points along ``axis``): the last E-step's
    order, kept in ``memo``, refined by insertion (the points move little between E-steps:
    ~4 against ~30 us at 1,000 points), else from scratch. Both give the same permutation."""
    n = values.shape[0]
    hints = None if memo is None else memo.setdefault("moving", {})
    hint = None if hints is None else hints.get(axis)
    if hint is not None and hint.shape[0] == n:
        order = hint.copy()
        if K.refine_order(values, order, 8 * n):
            hints[axis] = order
            return order
    order = np.argsort(values, kind="stable")
    if hints is not None:
        hints[axis] = order
    return order


def _sorted_rows(fixed, axis, memo):
    """``(order, fixed[order])`` with ``order`` the stable argsort of ``fixed[:, axis]``; a
    fit's E-steps share one ``memo`` dict, which keeps them per axis for the ``fixed`` array
    it first saw (the same array object, never modified during a fit; 26 us an E-step at
    1,000 points)."""
    if memo is not None and memo.get("fixed") is fixed and axis in memo["rows"]:
        return memo["rows"][axis]
    order = np.argsort(fixed[:, axis], kind="stable")
    out = order, np.ascontiguousarray(fixed[order])
    if memo is not None:
        if memo.get("fixed") is not fixed:
            memo.clear()
            memo.update(fixed=fixed, rows={})
        memo["rows"][axis] = out
    return out


def fixed_to_moving(
    moving_t, fixed, sigma2, w, prior: CentralityPrior | None = None, *, model_dims: int | None = None
) -> np.ndarray:
    """For each fixed point the moving point of largest posterior (the first, in the moving
    set's order, of equal ones), or -1 where the outlier component is more probable: the
    ``best`` of a dense E-step at this state, which a fit's E-steps skip (``want_best=False``)
    and compute once for their last state (a third of an E-step's work).

    From :data:`_PLAN_PAIRS` pairs without a prior, the most probable moving point is the
    nearest one, found by a grid (or a k-d tree) instead of every pair (at 100,000 points a
    dense pass takes seconds): the same point, but among points at exactly equal distance
    a k-d tree may name another than the first. ``model_dims``: see :func:`_e_step`.
    """
    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    inv2s2 = 1.0 / (2.0 * sigma2)
    log_c = log_outlier_constant(sigma2, w, model_dims or n_dims, n_moving, n_fixed)
    lw, vy, vx, scale, inv2phi2 = _prior_arrays(prior)
    if not lw.size and n_fixed * n_moving > _PLAN_PAIRS:
        d2, index = _nearest(moving_t, fixed)
        return np.where(-d2 * inv2s2 >= log_c, index, -1).astype(np.int64)
    yt = np.ascontiguousarray(moving_t.T)
    order = np.arange(n_moving)
    best = np.empty(n_fixed, dtype=np.int64)

    def task(lo, hi):
        K.dense_best(fixed, yt, lo, hi, inv2s2, log_c, lw, vy, vx, scale, inv2phi2, order, best)

    pairs = n_fixed * n_moving
    if pairs >= _SERIAL_PAIRS:
        run_chunks(task, n_fixed)
    elif pairs >= _PAIR_PAIRS and get_num_threads() > 1:
        edges = [0, int(n_fixed * _CALLER_SHARE), n_fixed]
        _two_halves(lambda a, b: task(edges[a], edges[b]))
    else:
        task(0, n_fixed)
    return best


def _cells(extent: np.ndarray, cell: float) -> tuple[float, np.ndarray]:
    """``(cell, cells per axis)`` of a grid over ``extent`` with cells of side ``cell``, at
    most 2**20 per axis (keeping 3D keys far from int64 overflow)."""
    cell = max(cell, float(extent.max()) / 2**20, 1e-300)
    return cell, np.floor(extent / cell).astype(np.int64) + 1


class _Grid:
    """Moving points sorted into cubic cells of side ``cell`` (for the truncated path)."""

    def __init__(self, points: np.ndarray, cell: float):
        lo = points.min(axis=0)
        extent = points.max(axis=0) - lo
        self.origin = lo
        self.cell, self.dims = _cells(extent, cell)
        keys = K.grid_keys(points, lo, self.cell, self.dims)
        self.order = np.argsort(keys, kind="stable")
        self.keys = keys[self.order]
        self.points = np.ascontiguousarray(points[self.order])


def _grid_for(moving_t, d2_min, extra):
    """The truncated path's grid: cells of a quarter of a typical row's reach.

    A row's reach is ``sqrt(d_min^2 + extra)``. Sizing cells by ``extra`` alone (the sigma2
    term) makes them far smaller than the reach once the nearest distances dominate (tiny
    sigma2): every row then walks ~(2 d_min / cell)^D empty cells (measured at 3,000
    points, sigma2 = 1e-12: 120 ms against 19 ms for the dense path). The median squared
    nearest distance stands for the typical row; with ``extra`` above it the cells are
    those of ``extra`` alone.
    """
    typical = max(extra, float(np.median(d2_min)) if d2_min.size else 0.0)
    return _Grid(moving_t, math.sqrt(typical) / _CELLS_PER_REACH)


def _nearest(moving_t, fixed):
    """Squared distance from each fixed point to its nearest moving point, and that point.

    In 1 to 3 dimensions by rings of cells of a grid with about two moving points per cell
    (:func:`_kernels.grid_nearest`; ties to the smaller index). Measured at 3,000 uniform
    2D points: 0.7 ms against 1.9 ms for building and querying a ``scipy.spatial.cKDTree``
    (20,000: 4.5 against 14 ms on 2 threads). The tree stays the way for more dimensions
    and for sets too clustered for a grid (a cell with more than :data:`_CROWDED` points).
    """
    n_fixed = fixed.shape[0]
    work = n_fixed * max(1, int(math.log2(max(moving_t.shape[0], 2))))
    found = _nearest_grid(moving_t)
    if found is None:
        from scipy.spatial import cKDTree

        workers = get_num_threads() if work > _SERIAL_PAIRS else 1
        dist, index = cKDTree(moving_t).query(fixed, k=1, workers=workers)
        return dist * dist, index
    origin, cell, dims, order, points, starts = found
    d2 = np.empty(n_fixed)
    index = np.empty(n_fixed, dtype=np.int64)

    def task(lo, hi):
        K.grid_nearest(fixed, points, order, starts, origin, cell, dims, lo, hi, d2, index)

    if work > _SERIAL_PAIRS and get_num_threads() > 1:
        run_chunks(task, n_fixed)
    else:
        task(0, n_fixed)
    return d2, index


_CROWDED = 64  # more points than this in one cell: the nearest-point grid gives way to a k-d tree


def _nearest_grid(points):
    """``(origin, cell, dims, order, sorted points, starts)`` of a grid of cells holding
    about two of ``points`` each (:func:`_kernels.bucket_points`); None in more than 3
    dimensions or when a cell holds more than :data:`_CROWDED` points."""
    n_points, n_dims = points.shape
    if n_dims > 3:
        return None
    origin = points.min(axis=0)
    with np.errstate(over="ignore"):
        extent = points.max(axis=0) - origin
    largest = float(extent.max())
    if not math.isfinite(largest):  # coordinates spanning more than float64's range
        return None
    spread = extent[extent > 1e-12 * largest]
    # cell^D' = 2 / M of the volume spanned on the D' axes with any extent
    cell = 1.0
    if spread.size:
        cell = (float(np.prod(spread / largest)) * 2.0 / n_points) ** (1.0 / spread.size) * largest
    cell, dims = _cells(extent, cell)
    while int(np.prod(dims)) > 4 * n_points + 64:  # a long thin set: fewer, larger cells
        cell, dims = _cells(extent, 2.0 * cell)
    order, sorted_points, starts = K.bucket_points(points, origin, cell, dims)
    if n_points > _CROWDED and int(np.max(np.diff(starts))) > _CROWDED:
        return None
    return origin, cell, dims, order, sorted_points, starts


def _reach_d2(d2_nearest):
    """Squared nearest distances with slack, so that rounding (the tree's sqrt against our
    squared sum) never drops the nearest point from the truncated search."""
    return d2_nearest * (1.0 + 1e-9) + 1e-300


def _truncation_extra(sigma2, tau, prior):
    low, high = (0.0, 0.0) if prior is None else prior.bounds()
    return 2.0 * sigma2 * (tau + (high - low))


def _truncated(moving_t, fixed, sigma2, inv2s2, log_c, prior, tau, grid=None, nearest=None):
    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    d2_min = _reach_d2((nearest if nearest is not None else _nearest(moving_t, fixed))[0])
    extra = _truncation_extra(sigma2, tau, prior)
    if grid is None:
        grid = _grid_for(moving_t, d2_min, extra)
    lw, vy, vx, scale, inv2phi2 = _prior_arrays(prior)
    if lw.size:  # the prior follows the moving points into grid order
        lw, vy = lw[grid.order], vy[grid.order]
    pt1 = np.empty(n_fixed)
    log_den = np.empty(n_fixed)
    best = np.empty(n_fixed, dtype=np.int64)
    capacity = max(n_moving, _BLOCK)

    def work(lo, hi, p1, pxt):
        index = np.empty(capacity, dtype=np.int64)
        value = np.empty(capacity)
        row_ptr = np.empty(capacity + 1, dtype=np.int64)
        ref = np.empty(capacity)
        a = lo
        while a < hi:
            b = K.truncated_scores(
                fixed,
                grid.points,
                grid.keys,
                grid.origin,
                grid.cell,
                grid.dims,
                a,
                hi,
                d2_min,
                extra,
                inv2s2,
                log_c,
                lw,
                vy,
                vx,
                scale,
                inv2phi2,
                index,
                value,
                row_ptr,
                ref,
                best,
            )
            if b <= a:  # pragma: no cover - capacity >= M makes this impossible
                raise RuntimeError("truncated E-step: a row did not fit its buffer")
            K.sparse_accumulate(index, value, row_ptr, fixed, a, b, ref, log_c, p1, pxt, pt1, log_den)
            a = b

    p1_sorted, pxt_sorted = _reduce_rows(work, n_fixed, n_moving, n_dims)
    p1 = np.empty(n_moving)
    p1[grid.order] = p1_sorted
    px = np.empty((n_moving, n_dims))
    px[grid.order] = pxt_sorted.T
    best = np.where(best >= 0, grid.order[np.maximum(best, 0)], -1)
    return p1, px, pt1, log_den, best


def _fgt_order(eps: float) -> int:
    """Smallest expansion order p whose per-dimension tail bound (Cramer's inequality,
    boxes of side h so |u| <= 1/2) is below ``eps``: 1.09 (sqrt(2)/2)^p / sqrt(p!) <= eps."""
    p = 1
    while 1.09 * (math.sqrt(2) / 2) ** p / math.sqrt(math.factorial(p)) > eps and p < 60:
        p += 1
    return p


class FGTGridTooLarge(MemoryError):
    """The fast Gauss transform's box grid cannot be indexed (h far below the sets' extent)."""


def gauss_transform(sources, weights, targets, h, *, eps=1e-10, translate=None):
    """``out[t, r] = sum_j weights[j, r] exp(-|targets_t - sources_j|^2 / h^2)`` by a fast Gauss transform.

    Hermite expansions of order ``p`` about boxes of side ``h`` [1]_; each target sums the
    boxes within ``sqrt(log(1/eps)) + 1/2`` box widths, either directly (cost per target: boxes
    x p^D) or, with ``translate=True``, through one Taylor series per target box (cost per box
    pair: D p^(D+1), then p^D per target), which wins when boxes hold many points; ``None``
    picks by that count. The absolute error is at most about ``eps * sum_j |weights[j]|``.

    References
    ----------
    .. [1] L. Greengard and J. Strain, "The fast Gauss transform", SIAM J. Sci. Stat.
       Comput. 12(1), 79-94, 1991.
    """
    sources = np.ascontiguousarray(sources, dtype=float)
    targets = np.ascontiguousarray(targets, dtype=float)
    weights = np.ascontiguousarray(weights, dtype=float).reshape(sources.shape[0], -1)
    n_dims = sources.shape[1]
    p = _fgt_order(eps / n_dims)
    reach = int(math.ceil(math.sqrt(math.log(1.0 / eps)) + 0.5))
    side = h
    origin = np.minimum(sources.min(axis=0), targets.min(axis=0))
    extent = np.maximum(sources.max(axis=0), targets.max(axis=0)) - origin
    dims_f = np.floor(extent / side) + 1
    if float(np.prod(dims_f)) > 2.0**62:
        raise FGTGridTooLarge(
            f"The fast Gauss transform's grid of boxes of side h = {h:.3g} would have {float(np.prod(dims_f)):.3g} "
            "cells, too many to index; use method='truncated' or 'dense'."
        )
    dims = dims_f.astype(np.int64)
    keys = K.grid_keys(sources, origin, side, dims)
    box_keys, box_of = np.unique(keys, return_inverse=True)
    size = box_keys.size * weights.shape[1] * p**n_dims * 8
    if size > _FGT_MAX_BYTES:
        raise MemoryError(
            f"The fast Gauss transform would need {size / 2**30:.1f} GiB of expansion coefficients "
            f"({box_keys.size} boxes x {p}^{n_dims} terms); use method='truncated' or 'dense'."
        )
    coords = np.stack(np.unravel_index(box_keys, tuple(dims)), axis=1).astype(np.int64)
    centers = origin + (coords + 0.5) * side
    coeffs = np.zeros((box_keys.size, weights.shape[1], p**n_dims))
    K.fgt_coefficients(sources, weights, box_of.astype(np.int64), centers, 1.0 / h, p, coeffs)
    out = np.empty((targets.shape[0], weights.shape[1]))
    t_keys = K.grid_keys(targets, origin, side, dims)
    t_box_keys, t_box_of = np.unique(t_keys, return_inverse=True)
    if translate is None:
        # direct: every target meets each source box; translated: every target box does (D p terms each)
        translate = targets.shape[0] > 2 * n_dims * p * t_box_keys.size
    if not translate:

        def task(lo, hi):
            K.fgt_evaluate(targets, lo, hi, box_keys, centers, coeffs, origin, side, dims, 1.0 / h, p, reach, out)

        run_chunks(task, targets.shape[0])
        return out
    t_order = np.argsort(t_box_of, kind="stable")
    t_start = np.searchsorted(t_box_of[t_order], np.arange(t_box_keys.size + 1))
    t_coords = np.stack(np.unravel_index(t_box_keys, tuple(dims)), axis=1).astype(np.int64)
    trans = K.hermite_translation_matrices(reach, p)

    def task_boxes(lo, hi):
        K.fgt_translate_evaluate(
            targets,
            t_start,
            t_order,
            t_coords,
            box_keys,
            coords,
            coeffs,
            origin,
            side,
            dims,
            1.0 / h,
            p,
            reach,
            trans,
            lo,
            hi,
            out,
        )

    run_chunks(task_boxes, t_box_keys.size)
    return out


def _fgt(moving_t, fixed, sigma2, log_c, eps, nearest=None):
    """E-step by two fast Gauss transforms (no prior); rows whose sum is too small for the
    transform's error bound are computed exactly (dense or truncated)."""
    n_moving, n_dims = moving_t.shape
    h = math.sqrt(2.0 * sigma2)
    d2_nearest, index = nearest if nearest is not None else _nearest(moving_t, fixed)
    raw = gauss_transform(moving_t, np.ones((n_moving, 1)), fixed, h, eps=eps)[:, 0]
    c = math.exp(min(log_c, 709.0)) if log_c > -math.inf else 0.0  # (709: exp's float64 limit)
    # the transform's absolute error is ~eps * M: rows whose sum is not far above it are redone exactly
    exact = raw < 1e4 * eps * n_moving
    raw = np.maximum(raw, 0.0)
    den = raw + c
    with np.errstate(divide="ignore"):
        inv = np.where(exact, 0.0, 1.0 / den)
    q = np.concatenate([inv[:, None], fixed * inv[:, None]], axis=1)
    out = gauss_transform(fixed, q, moving_t, h, eps=eps)
    p1, px = out[:, 0].copy(), out[:, 1:].copy()
    pt1 = raw * inv
    log_den = np.log(np.where(exact, 1.0, den))
    best = np.where(-d2_nearest / (2 * sigma2) >= log_c, index, -1)
    rows = np.flatnonzero(exact)
    if rows.size:
        sub = np.ascontiguousarray(fixed[rows])
        inv2s2 = 1.0 / (2.0 * sigma2)
        if rows.size * n_moving <= _DENSE_PAIRS:
            d_p1, d_px, d_pt1, d_log_den, d_best = _dense(moving_t, sub, inv2s2, log_c, None)
        else:  # many rows: visit only their neighbourhoods (exact to rounding as well)
            tau = 36.8 + math.log(n_moving)
            sub_nearest = (d2_nearest[rows], index[rows])
            d_p1, d_px, d_pt1, d_log_den, d_best = _truncated(
                moving_t, sub, sigma2, inv2s2, log_c, None, tau, nearest=sub_nearest
            )
        p1 += d_p1
        px += d_px
        pt1[rows] = d_pt1
        log_den[rows] = d_log_den
        best[rows] = d_best
    return p1, px, pt1, log_den, best


# The FGT's expansion coefficients may not take more memory than this.
_FGT_MAX_BYTES = 2**32

# Costs per unit of work (nanoseconds, 2 cores): a dense pair, a pair the truncated path
# visits, one FGT term for one right-hand side (or one step of a box lookup). They only order
# the paths before a planner has timed them (and choose when there is no planner); every
# path is correct. Their ratios matter more than their size: a probe predicts a path it has
# not timed from the first path it timed. Measured (uniform 2D points, 3,000 and 20,000,
# sigma2 1..1e-12, load 5 on 2 cores), seconds per modelled second: dense 3.2-4.2,
# truncated 3.4-8, FGT 2.5-5 where it is the fastest path (sigma2 >= 1e-2) and 2.3-10 below.
_COST_DENSE, _COST_TRUNCATED, _COST_FGT = 0.6, 4.5, 0.4
# The dense pair's score and maximum (a quarter of its one-thread time: 0.29 of 1.1 ns; the
# rest is the exponential, its sum and the accumulation), and a banded row's own search
# (its nearest moving point and four binary searches: about 250 pairs' work).
_COST_DENSE_SCORE = 0.16
_COST_DENSE_ROW = 150.0
# The truncated path's fixed cost per row and per log2(M): its walk over the ~(2 x 4 + 2)^D
# cells of its search box (two binary searches over the M moving points per row of cells;
# measured 1.5-3 us per row in 2D at 3,000 and 20,000 points, load 5 on 2 cores), paid
# however few candidates the cells hold.
_COST_TRUNCATED_ROW = 50.0
# How each path's work scales with sigma2, as a power of sigma2^(D/2), where no better model
# is at hand: the dense path not at all (its band's cost model, _dense_cost, takes over when
# the probe made one), the truncated path's neighbourhoods with their volume, the FGT's
# boxes inversely.
_SIGMA2_POWER = {"dense": 0.0, "truncated": 1.0, "fgt": -1.0}
# Below this many pairs the dense path takes under a millisecond: nothing else is considered
# by the planner (its probe would cost more than it could save over a whole fit).
_PLAN_PAIRS = 1 << 20
# Under EStepPlanner.hold, the dense path runs instead of the winner only if predicted this
# many times faster (predictions of paths a probe skipped come from the cost model alone).
_HOLD_SWITCH = 2.0


def _fgt_cost(moving_t, fixed, sigma2, eps):
    """Estimated FGT cost (ns) of both transforms, each by its cheaper evaluation."""
    h = math.sqrt(2.0 * sigma2)
    n_dims = moving_t.shape[1]
    reach = int(math.ceil(math.sqrt(math.log(1.0 / eps)) + 0.5))
    p = _fgt_order(eps / n_dims)

    def count_boxes(points):
        lo = points.min(axis=0)
        dims = np.floor((points.max(axis=0) - lo) / h).astype(np.int64) + 1
        if float(np.prod(dims.astype(float))) > 2.0**62:
            return math.inf, math.inf  # box keys would overflow: the transform refuses such a grid
        keys = K.grid_keys(points, lo, h, dims)
        return np.unique(keys).size, float(np.prod(dims.astype(float)))

    counted = {"moving": count_boxes(moving_t), "fixed": count_boxes(fixed)}

    def transform_cost(src, tgt, n_rhs):
        n_src_boxes, bbox = counted[src]
        n_tgt_boxes, tgt_bbox = counted[tgt]
        src, tgt = (moving_t, fixed) if src == "moving" else (fixed, moving_t)
        if not math.isfinite(bbox) or not math.isfinite(tgt_bbox):
            return math.inf
        if n_src_boxes * n_rhs * p**n_dims * 8 > _FGT_MAX_BYTES / 4:
            return math.inf  # the coefficients alone would take too much memory
        in_reach = min(n_src_boxes, (2 * reach + 1) ** n_dims * n_src_boxes / bbox)
        # every target (box) looks up each cell within reach, empty or not, by binary search
        lookup = (2 * reach + 1) ** n_dims * math.log2(n_src_boxes + 1)
        direct = tgt.shape[0] * (in_reach * p**n_dims * n_rhs + lookup)
        translated = (
            n_tgt_boxes * (in_reach * n_dims * p ** (n_dims + 1) * n_rhs + lookup) + tgt.shape[0] * p**n_dims * n_rhs
        )
        # the sources' expansion coefficients, and sorting both sets into boxes
        fixed_part = src.shape[0] * p**n_dims * n_rhs + (src.shape[0] + tgt.shape[0]) * math.log2(src.shape[0] + 2)
        return min(direct, translated) + fixed_part

    return _COST_FGT * (transform_cost("moving", "fixed", 1) + transform_cost("fixed", "moving", 1 + n_dims))


def _model_costs(moving_t, fixed, sigma2, prior, tau, eps):
    """Estimated cost (ns) of each candidate path (the truncated one from 256 sampled rows),
    and what the paths can reuse: the nearest moving points and the truncated path's grid."""
    n_moving, n_fixed = moving_t.shape[0], fixed.shape[0]
    start = time.perf_counter()
    nearest = _nearest(moving_t, fixed)
    t_nearest = time.perf_counter() - start
    dense_cost = _dense_cost(moving_t, n_fixed, tau, prior, nearest[0])
    costs = {"dense": dense_cost(sigma2)}
    d2_min = _reach_d2(nearest[0])
    extra = _truncation_extra(sigma2, tau, prior)
    start = time.perf_counter()
    grid = _grid_for(moving_t, d2_min, extra)
    t_grid = time.perf_counter() - start
    rows = np.linspace(0, n_fixed - 1, min(256, n_fixed)).astype(np.int64)
    visited = K.count_candidates(fixed, rows, grid.keys, grid.origin, grid.cell, grid.dims, d2_min, extra)
    candidates = max(float(visited.mean()), 1.0)
    row_floor = _COST_TRUNCATED_ROW * math.log2(n_moving + 1)
    costs["truncated"] = (_COST_TRUNCATED * candidates + row_floor) * n_fixed
    if prior is None or prior.strength == 0:
        # rows whose transformed sum falls below the transform's error bound, 1e4 eps M, are
        # redone exactly (see _fgt); the sum is at most M times its largest term
        # exp(-d_min^2 / (2 sigma2)), so rows with that term below 1e4 eps surely are
        redone = int(np.count_nonzero(-nearest[0] / (2.0 * sigma2) < math.log(1e4 * eps)))
        if redone * n_moving <= _DENSE_PAIRS:
            exact = _COST_DENSE * redone * n_moving
        else:
            exact = costs["truncated"] * redone / n_fixed
        costs["fgt"] = _fgt_cost(moving_t, fixed, sigma2, eps) + exact
    # what the paths reuse was built here: a probe adds its time to theirs, as their own
    # calls outside a probe build it themselves
    setup = {"dense": 0.0, "truncated": t_nearest + t_grid, "fgt": t_nearest}
    # what the truncated path's cost at another sigma2 follows (see EStepPlanner.predicted)
    work = (candidates, float(np.median(d2_min)), extra, row_floor)
    return costs, {"nearest": nearest, "grid": grid, "setup": setup, "truncated_work": work, "dense_cost": dense_cost}


def _choose(moving_t, fixed, sigma2, prior, tau, eps):
    """The cheapest path by the cost model alone (``method='auto'`` without a planner)."""
    if moving_t.shape[0] * fixed.shape[0] <= _PLAN_PAIRS:
        return "dense", {}
    costs, cached = _model_costs(moving_t, fixed, sigma2, prior, tau, eps)
    return min(costs, key=costs.get), cached


def _run(
    method,
    moving_t,
    fixed,
    sigma2,
    w,
    prior,
    tau,
    eps,
    cached,
    single=False,
    want_best=True,
    memo=None,
    model_dims=None,
):
    """One E-step by the given path; ``cached`` holds what :func:`_model_costs` computed;
    ``single``: the dense path's exponentials in float32 (the other paths ignore it);
    ``want_best=False`` lets the dense path leave ``best`` None; ``memo``: see :func:`_dense`;
    ``model_dims``: see :func:`_e_step`."""
    n_moving = moving_t.shape[0]
    n_dims = model_dims or moving_t.shape[1]
    n_fixed = fixed.shape[0]
    inv2s2 = 1.0 / (2.0 * sigma2)
    log_c = log_outlier_constant(sigma2, w, n_dims, n_moving, n_fixed)
    if method == "dense":
        p1, px, pt1, log_den, best = _dense(moving_t, fixed, inv2s2, log_c, prior, single, tau, want_best, memo)
    elif method == "fgt":
        try:
            p1, px, pt1, log_den, best = _fgt(moving_t, fixed, sigma2, log_c, eps, cached.get("nearest"))
        except FGTGridTooLarge:
            # method='fgt' asked for at a sigma2 far below the sets' extent: the exact truncated
            # path instead (its grid is sized by the points, not by h); the posterior's
            # ``method`` (a fit's ``history_["method"]``) says so
            method = "truncated"
    if method == "truncated":
        p1, px, pt1, log_den, best = _truncated(
            moving_t, fixed, sigma2, inv2s2, log_c, prior, tau, cached.get("grid"), cached.get("nearest")
        )
    nll = float(-np.sum(log_den) + 0.5 * n_fixed * n_dims * math.log(sigma2))
    return Posteriors(p1=p1, pt1=pt1, px=px, n_p=float(np.sum(pt1)), neg_log_likelihood=nll, best=best, method=method)


class EStepPlanner:
    """Chooses the E-step path of one fit by timing the candidates (``method='auto'``).

    A probe runs the candidate paths ('dense', 'truncated' and, without a prior, 'fgt') on
    the current state, in the order of a cost model, each timed; it keeps the fastest as the
    winner and returns the winner's statistics. Later calls run the winner alone and probe
    again as soon as another path is predicted faster at the current sigma2 (each path's probe
    time, measured or predicted, extrapolated by how its work scales with sigma2: the dense
    path's with its band, about as sigma2^(1/2) once narrow, the truncated path's
    neighbourhoods as sigma2^(D/2), the FGT's box count as sigma2^(-D/2); see
    :meth:`predicted`), or sigma2 has moved more than
    ``reprobe_factor`` times away from the sigma2 of the last probe, or ``reprobe_calls``
    calls have passed. (Without the prediction, a fit whose sigma2 shrinks 10x between
    probes kept the FGT where dense had become 6x faster, or dense where the truncated path
    had become 2.8x faster; measured at 3,000 and 20,000 points.) When sigma2 swings back
    and forth over decades (a fit near its end can), one of the last probes within
    ``sqrt(reprobe_factor)`` of the current sigma2 and fewer than ``reprobe_calls`` calls
    ago decides instead, if it still would.

    A probe skips a path predicted slower than ``skip_factor`` times the fastest time
    measured in it: the prediction is the cost model scaled by that path's last measured
    time over its modelled cost (by the first path's of this probe for a path never
    measured), so a path measured slow once is not retried while the model says so. Below
    2^20 pairs only 'dense' is run (under a millisecond there).

    A path's probe time includes what it builds for itself outside a probe (the nearest
    moving points, the truncated path's grid), which the probe builds once for all. The
    dense path's time only falls as sigma2 shrinks (its band of exponentials narrows): a
    time it took in this fit at a sigma2 up to ``reprobe_factor`` above the probe's bounds
    it, so the probe takes that bound instead of running it again, and runs it only when it
    wins (at 3,000 points a probe that re-ran it cost a fit 12-20 ms of its 0.3 s). When
    the two fastest are within ``retime_factor`` of each other, the runner-up runs once more
    and keeps the least of its two times: on a busy machine one timing can be off by more
    than such a gap, and load only adds time. A winner is kept until another path is
    predicted ``switch_factor`` times faster (no probe for a gain within it), and a fit sets
    ``hold`` around the E-step of an extrapolated jump it may reject (the winner runs
    unprobed); both halved what probing cost a 3,000-point accelerated fit (from 20-50% over
    the dense path alone to 10-15%).

    Timings decide, so two runs of one fit may take different paths; every path equals the
    dense one to its bound ('truncated' to rounding, 'fgt' to about ``eps`` of the total
    weight). Pass a fixed ``method`` for results bit-identical across runs and for any
    number of this library's threads.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> planner = EStepPlanner()
    >>> post = planner(rng.random((400, 2)), rng.random((300, 2)), 0.01, 0.0)
    >>> post.method in ("dense", "truncated", "fgt"), planner.winner == post.method
    (True, True)
    """

    def __init__(self, *, reprobe_factor=10.0, reprobe_calls=50, skip_factor=2.0, retime_factor=1.5, switch_factor=1.2):
        self.switch_factor = switch_factor
        # set by a fit around a speculative E-step (an extrapolated jump it may reject): the
        # winner runs and nothing is probed (probes at jumps cost 20-30% of a 3,000-point fit)
        self.hold = False
        self.reprobe_factor = reprobe_factor
        self.reprobe_calls = reprobe_calls
        self.skip_factor = skip_factor
        self.retime_factor = retime_factor
        self.winner = None
        self.probes = 0
        self.timings = {}  # path -> seconds at the last probe that ran it
        self._dense_time = {}  # with a prior or not -> the dense path's last (sigma2, seconds)
        self._scale = {}  # path -> measured seconds per modelled ns
        self._sigma2 = None
        self._calls = 0
        self._at_probe = {}  # path -> seconds at the last probe (measured, or predicted if skipped)
        # what the truncated and dense paths' costs at another sigma2 follow: (candidates per
        # row, median d_min^2, extra, row floor) and the dense cost as a function of sigma2
        self._truncated_work = None
        self._dense_cost = None
        self._recent = []  # the last probes' states, to take up again when sigma2 swings back
        self._total = 0  # calls so far
        self.reused = 0  # calls that took up an earlier probe's choice instead of probing

    def predicted(self, sigma2, n_dims):
        """Each path's time at ``sigma2`` extrapolated from the last probe by how its work
        scales with sigma2: the dense path's by its cost model (the band's share of the moving
        points, about sigma2^(1/2) once narrow; constant without a band); the FGT's box count
        as sigma2^(-D/2); the truncated path's candidates per row with the volume of its reach,
        ``(d_min^2 + extra)^(D/2)`` (``extra`` proportional to sigma2, ``d_min^2`` the probe's
        median), at least one, plus its fixed cost per row, so a path whose rows hold only
        their nearest point is not predicted to keep getting faster."""
        ratio = sigma2 / self._sigma2
        out = {}
        for path, t in self._at_probe.items():
            if path == "truncated" and self._truncated_work is not None:
                candidates, d2, extra, floor = self._truncated_work
                reach = ((d2 + extra * ratio) / max(d2 + extra, 1e-300)) ** (n_dims / 2)
                before = _COST_TRUNCATED * candidates + floor
                out[path] = t * (_COST_TRUNCATED * max(candidates * reach, 1.0) + floor) / before
            elif path == "dense" and self._dense_cost is not None:
                out[path] = t * self._dense_cost(sigma2) / max(self._dense_cost(self._sigma2), 1e-300)
            else:
                out[path] = t * ratio ** (_SIGMA2_POWER[path] * n_dims / 2)
        return out

    def _fits(self, sigma2, n_dims, factor):
        """Whether the last probe still decides at ``sigma2``: within ``factor`` of its sigma2
        and no other path predicted to have become the faster one."""
        if abs(math.log(sigma2 / self._sigma2)) > math.log(factor):
            return False
        guess = self.predicted(sigma2, n_dims)
        return self.switch_factor * min(guess.values()) >= guess[self.winner]

    def _due(self, sigma2, n_dims):
        if self.winner is None or self._calls >= self.reprobe_calls:
            return True
        if self._fits(sigma2, n_dims, self.reprobe_factor):
            return False
        # sigma2 may swing back and forth over decades (a fit near its end): a recent probe
        # near this sigma2 is taken up again rather than probing anew
        for state in reversed(self._recent):
            if self._total - state[-1] >= self.reprobe_calls:
                break
            self._restore(state)
            if self._fits(sigma2, n_dims, math.sqrt(self.reprobe_factor)):
                self.reused += 1
                return False
        return True

    def _dense_times(self, prior):
        """The dense path's last (sigma2, seconds) in this fit, with a prior or without (the
        eight latest: older entries are dropped here, before the caller appends one)."""
        times = self._dense_time.setdefault(prior is not None and prior.strength != 0, [])
        del times[:-8]
        return times

    def _restore(self, state):
        self._sigma2, self.winner, self._at_probe, self._truncated_work, self._dense_cost, _ = state

    def __call__(
        self,
        moving_t,
        fixed,
        sigma2,
        w,
        prior=None,
        *,
        tau=None,
        eps=1e-8,
        precision="float64",
        want_best=True,
        memo=None,
        model_dims=None,
    ):
        """One E-step (see :func:`_e_step` for the arguments) by the path the planner picks."""
        tau = _default_tau(moving_t.shape[0]) if tau is None else tau
        single = _single(precision)
        if moving_t.shape[0] * fixed.shape[0] <= _PLAN_PAIRS:
            self.winner = "dense"
            return _run("dense", moving_t, fixed, sigma2, w, prior, tau, eps, {}, single, want_best, memo, model_dims)
        self._total += 1
        if self.hold and self.winner is not None:
            # a jump's E-step, unprobed: the winner, unless the dense path is predicted far
            # faster at this sigma2 (a jump can move sigma2 4x at once: at 100,000 points
            # the FGT kept there took 4.2 s where the band's dense path took 1.4). Only the
            # dense path: its band's model predicted well; a switch to the truncated path by
            # its predicted neighbourhoods cost a 10,000-point fit 0.5 s of its 0.9
            self._calls += 1
            guess = self.predicted(sigma2, moving_t.shape[1])
            path = self.winner
            if "dense" in guess and guess["dense"] * _HOLD_SWITCH < guess[self.winner]:
                path = "dense"
            start = time.perf_counter()
            post = _run(path, moving_t, fixed, sigma2, w, prior, tau, eps, {}, single, want_best, memo, model_dims)
            if path == "dense":  # a time the next probe can take as the dense path's bound
                self._dense_times(prior).append((sigma2, time.perf_counter() - start))
            return post
        if not self._due(sigma2, moving_t.shape[1]):
            self._calls += 1
            return _run(
                self.winner, moving_t, fixed, sigma2, w, prior, tau, eps, {}, single, want_best, memo, model_dims
            )
        costs, cached = _model_costs(moving_t, fixed, sigma2, prior, tau, eps)
        setup = cached["setup"]
        order = sorted((c, m) for m, c in costs.items() if math.isfinite(c))
        results = {}
        measured = {}

        # the dense path's time only falls as sigma2 shrinks (its band narrows): a time
        # measured in this fit (per kind of prior) at a sigma2 up to reprobe_factor above
        # this one bounds it, stands for it in the probe, and it runs again only to win
        dense_times = self._dense_times(prior)
        bounds = [t for s2, t in dense_times if sigma2 <= s2 <= self.reprobe_factor * sigma2]
        dense_bound = min(bounds) if bounds else None
        if dense_bound is not None:  # known already: first, so that it bounds the others' skips
            order = [o for o in order if o[1] == "dense"] + [o for o in order if o[1] != "dense"]

        def timed(path):
            start = time.perf_counter()
            results[path] = _run(
                path, moving_t, fixed, sigma2, w, prior, tau, eps, cached, single, want_best, memo, model_dims
            )
            # the nearest points and the grid were built once for the probe; outside it
            # the path builds them itself, so their time counts as its own
            seconds = time.perf_counter() - start + setup[path]
            if path == "dense":
                dense_times.append((sigma2, seconds))
                seconds = min(seconds, dense_bound if dense_bound is not None else math.inf)
            return seconds

        best_time = math.inf
        first_scale = None
        at_probe = {}
        for cost, path in order:
            # a path not measured before is predicted at the seconds per modelled ns of the
            # first path measured in this probe (the machine's speed and load of the moment)
            if measured:
                at_probe[path] = cost * self._scale.get(path, first_scale)
                if at_probe[path] > self.skip_factor * best_time:
                    continue
            known = path == "dense" and dense_bound is not None
            measured[path] = dense_bound if known else timed(path)
            self._scale[path] = measured[path] / max(cost, 1e-300)
            first_scale = self._scale[path] if first_scale is None else first_scale
            best_time = min(best_time, measured[path])
        ranked = sorted(measured, key=measured.get)
        if (
            len(ranked) > 1
            and measured[ranked[1]] < self.retime_factor * measured[ranked[0]]
            and ranked[1] in results  # (a dense time taken at a nearby larger sigma2 is a bound already)
        ):
            # a close call: one timing on a busy machine can be off by more than the gap, and
            # load only ever adds time, so the runner-up keeps the least of two
            measured[ranked[1]] = min(measured[ranked[1]], timed(ranked[1]))
        self.winner = min(measured, key=measured.get)
        if self.winner not in results:  # the dense path, not run in this probe
            timed(self.winner)
        self.timings.update(measured)
        self._at_probe = {**at_probe, **measured}
        self._truncated_work = cached.get("truncated_work")
        self._dense_cost = cached.get("dense_cost")
        self.probes += 1
        self._sigma2 = sigma2
        self._calls = 1
        state = (sigma2, self.winner, self._at_probe, self._truncated_work, self._dense_cost, self._total)
        self._recent = [*self._recent[-7:], state]
        return results[self.winner]


def _default_tau(n_moving):
    # keep every term above 1e-16 of its row's largest, summed over all M of them
    return 36.8 + math.log(n_moving)


def _e_step(
    moving_t,
    fixed,
    sigma2,
    w,
    log_prior: CentralityPrior | None = None,
    *,
    method="auto",
    tau=None,
    eps=1e-8,
    planner: EStepPlanner | None = None,
    precision="float64",
    want_best=True,
    memo=None,
    fgt_fallback=False,
    model_dims=None,
):
    """The shared E-step; see the module docstring.

    ``method``: 'dense' (every pair's score; from :data:`_BAND_POINTS` moving points without
    a prior, the exponentials over the band of sorted moving points that can hold a term
    within ``tau`` of the row's largest: see :func:`_dense`), 'truncated' (pairs within
    ``tau`` of each row's largest exponent, by a cell grid); both exact to rounding with the
    default ``tau = 36.8 + log M``, 'fgt' (fast Gauss
    transform, absolute error about ``eps`` times the total weight; CPD only) or 'auto': the
    fastest by timing when a ``planner`` (one :class:`EStepPlanner` per fit) is given, else
    the cheapest by a cost model (dense below 2^20 pairs).

    ``precision``: 'float64', or 'float32' for the dense path's exponentials in float32 (see
    :data:`PRECISIONS`); the truncated and FGT paths ignore it.

    ``want_best=False``: the dense path may leave ``Posteriors.best`` None (a fit computes it
    once, for its last state, by :func:`fixed_to_moving`). ``memo``: a dict a fit keeps over
    its E-steps on one ``fixed`` set (the dense path's sorted fixed points).
    ``fgt_fallback`` (a fit's): 'fgt' on over 2^20 pairs where its expansion is predicted
    to cost over 10 times the dense path takes the exact truncated path instead.
    ``model_dims``: the dimension of the mixture, when the sets span fewer dimensions than
    their coordinates (None: the coordinates'): the outlier constant ``c`` and the
    objective are those of a density within ``model_dims`` dimensions.
    """
    if tau is None:
        tau = _default_tau(moving_t.shape[0])
    if method == "auto":
        if planner is not None:
            return planner(
                moving_t,
                fixed,
                sigma2,
                w,
                log_prior,
                tau=tau,
                eps=eps,
                precision=precision,
                want_best=want_best,
                memo=memo,
                model_dims=model_dims,
            )
        method, cached = _choose(moving_t, fixed, sigma2, log_prior, tau, eps)
    else:
        cached = {}
        # a fit's method='fgt' where its expansion would cost over 10 times every pair's
        # exponential on over 2^20 pairs (3D at a small sigma2: 4,500 points took 8 s per
        # E-step, growing, where the dense fit took 0.6 s in all): the exact truncated path,
        # as for a grid too large
        pairs = moving_t.shape[0] * fixed.shape[0]
        if (
            method == "fgt"
            and fgt_fallback
            and pairs > _PLAN_PAIRS
            and _fgt_cost(moving_t, fixed, sigma2, eps) > 10.0 * _COST_DENSE * pairs
        ):
            method = "truncated"
    if method == "fgt" and log_prior is not None and log_prior.strength != 0:
        raise InputError("`method` 'fgt' computes CPD's posterior only; GPD's prior needs 'dense' or 'truncated'.")
    if method == "fgt" and moving_t.shape[1] > 3:  # (its work grows as p^D: 300 4D points ran for minutes)
        raise InputError(
            f"`method` 'fgt' is for 2D and 3D sets; got {moving_t.shape[1]}D points (use 'dense' or 'truncated')."
        )
    return _run(
        method, moving_t, fixed, sigma2, w, log_prior, tau, eps, cached, _single(precision), want_best, memo, model_dims
    )


def dense_posterior(
    moving_t, fixed, sigma2, w, log_prior: CentralityPrior | None = None, *, model_dims: int | None = None
) -> np.ndarray:
    """The full posterior matrix ``P`` of shape (M, N), computed in log space (small sets only);
    ``model_dims``: see :func:`_e_step`."""
    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    d2 = np.sum((moving_t[:, None, :] - fixed[None, :, :]) ** 2, axis=2)
    s = -d2 / (2.0 * sigma2)
    if log_prior is not None and log_prior.strength != 0:
        s = s + log_prior.matrix()
    log_c = log_outlier_constant(sigma2, w, model_dims or n_dims, n_moving, n_fixed)
    ref = np.maximum(s.max(axis=0), log_c)
    e = np.exp(s - ref)
    den = e.sum(axis=0) + np.exp(log_c - ref)
    return e / den


def _knn_scores(moving_t, fixed, sigma2, prior, k, tree):
    """Rows, columns and log-terms of the k-NN model: each moving point's k nearest fixed points."""
    n_moving = moving_t.shape[0]
    k = min(int(k), fixed.shape[0])
    dist, cols = tree.query(moving_t, k=k)
    dist = np.asarray(dist, dtype=float).ravel()
    cols = np.asarray(cols, dtype=np.int64).ravel()
    rows = np.repeat(np.arange(n_moving), k)
    found = cols < fixed.shape[0]  # the tree marks a neighbour it could not place (inf distance) by N
    if not found.all():
        rows, cols, dist = rows[found], cols[found], dist[found]
    s = -(dist**2) / (2.0 * sigma2)
    if prior is not None and prior.strength != 0:
        dv = prior.fixed_centrality[cols] - prior.moving_centrality[rows]
        s = s + prior.strength * (prior.log_weight[rows] - dv * dv * prior.inv2phi2)
    return rows, cols, s


def knn_posterior(
    moving_t, fixed, sigma2, w, prior: CentralityPrior | None = None, *, k, tree=None, model_dims: int | None = None
) -> Posteriors:
    """E-step of the k-nearest-neighbour CPD model (``n_neighbors=k`` on the estimators).

    The dense model lets every moving point explain every fixed point. Here a moving point
    ``m`` may explain only its ``k`` nearest fixed points ``K(m)`` (found afresh at every
    E-step), so the posterior of fixed point ``n`` is spread over ``S_n = {m : n in K(m)}``:
    ``P(m | x_n) = exp(s_mn) / (sum_{m' in S_n} exp(s_m'n) + c)`` for ``m`` in ``S_n``, else
    0, with CPD's ``s_mn = -|x_n - T(y_m)|^2 / (2 sigma2)`` (plus GPD's prior) and outlier
    constant ``c``. A fixed point that is no moving point's neighbour (far clutter) gets no
    posterior mass at all: it is an outlier whatever ``w``. With ``k >= N`` this is exactly
    the dense E-step. The objective takes, for such an unclaimed fixed point, the term of its
    nearest transformed moving point, so it stays finite and continuous.

    ``tree``: a ``scipy.spatial.cKDTree`` of ``fixed`` (built here when None); ``model_dims``:
    see :func:`_e_step`.

    Examples
    --------
    >>> import numpy as np
    >>> moving = np.array([[0.0, 0.0], [10.0, 0.0]])
    >>> fixed = np.array([[0.0, 1.0], [10.0, 1.0], [50.0, 50.0]])
    >>> post = knn_posterior(moving, fixed, 1.0, 0.0, k=1)
    >>> post.pt1.tolist(), post.best.tolist()  # the far point is claimed by no moving point
    ([1.0, 1.0, 0.0], [0, 1, -1])
    """
    from scipy.spatial import cKDTree

    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    if tree is None:
        tree = cKDTree(fixed)
    rows, cols, s = _knn_scores(moving_t, fixed, sigma2, prior, k, tree)
    log_c = log_outlier_constant(sigma2, w, model_dims or n_dims, n_moving, n_fixed)
    col_max = np.full(n_fixed, -np.inf)
    np.maximum.at(col_max, cols, s)
    claimed = np.isfinite(col_max)
    ref = np.where(claimed, np.maximum(col_max, log_c), 0.0)
    e = np.exp(s - ref[cols])
    col_sum = np.bincount(cols, weights=e, minlength=n_fixed)
    outlier = np.exp(log_c - ref) if math.isfinite(log_c) else np.zeros(n_fixed)
    den = col_sum + outlier
    p = np.divide(e, den[cols], out=np.zeros_like(e), where=den[cols] > 0)
    p1 = np.bincount(rows, weights=p, minlength=n_moving)
    pt1 = np.bincount(cols, weights=p, minlength=n_fixed)
    px = np.empty((n_moving, n_dims))
    for d in range(n_dims):
        px[:, d] = np.bincount(rows, weights=p * fixed[cols, d], minlength=n_moving)
    log_den = np.empty(n_fixed)
    log_den[claimed] = ref[claimed] + np.log(den[claimed])
    if not claimed.all():
        # an unclaimed fixed point: the term of its nearest transformed moving point (and c)
        d_near = cKDTree(moving_t).query(fixed[~claimed], k=1)[0]
        log_den[~claimed] = np.logaddexp(-(d_near**2) / (2.0 * sigma2), log_c)
    # the most probable moving point of each fixed point (-1: the outlier term wins or none claims it)
    order = np.lexsort((rows, -p, cols))
    first = np.ones(order.size, dtype=bool)
    first[1:] = cols[order][1:] != cols[order][:-1]
    best = np.full(n_fixed, -1, dtype=np.int64)
    top = order[first]
    wins = p[top] * den[cols[top]] > outlier[cols[top]]
    best[cols[top][wins]] = rows[top][wins]
    nll = float(-np.sum(log_den) + 0.5 * n_fixed * (model_dims or n_dims) * math.log(sigma2))
    return Posteriors(p1=p1, pt1=pt1, px=px, n_p=float(np.sum(pt1)), neg_log_likelihood=nll, best=best, method="knn")


def knn_posterior_matrix(
    moving_t, fixed, sigma2, w, prior: CentralityPrior | None = None, *, k, model_dims: int | None = None
) -> np.ndarray:
    """The full (M, N) posterior of the k-NN model (see :func:`knn_posterior`; small sets only)."""
    from scipy.spatial import cKDTree

    n_moving, n_dims = moving_t.shape
    n_fixed = fixed.shape[0]
    rows, cols, s = _knn_scores(moving_t, fixed, sigma2, prior, k, cKDTree(fixed))
    log_c = log_outlier_constant(sigma2, w, model_dims or n_dims, n_moving, n_fixed)
    full = np.full((n_moving, n_fixed), -np.inf)
    full[rows, cols] = s
    ref = np.maximum(full.max(axis=0), log_c)
    ref = np.where(np.isfinite(ref), ref, 0.0)
    e = np.exp(full - ref)
    den = e.sum(axis=0) + (np.exp(log_c - ref) if math.isfinite(log_c) else 0.0)
    return np.divide(e, den, out=np.zeros_like(e), where=den > 0)
