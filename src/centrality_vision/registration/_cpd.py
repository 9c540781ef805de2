"""Coherent Point Drift: rigid/similarity, affine and non-rigid, on one shared EM loop."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .._validation import ANY_DIMS, as_points, check_choice, check_float, check_int
from ..exceptions import ConvergenceWarning, InputError
from ..transforms import AffineTransform, NonRigidTransform, RigidTransform, SimilarityTransform
from ._estep import E_STEP_METHODS, CentralityPrior, _e_step, dense_posterior
from ._mstep import LowRankKernel, affine_m_step, gaussian_kernel, nonrigid_m_step, rigid_m_step

__all__ = ["RigidCPD", "AffineCPD", "NonRigidCPD", "IterationInfo", "Snapshots", "initial_sigma2", "alignment_error"]

# sigma2 below this fraction of the data's spread means the sets coincide: stop, converged.
_SIGMA2_FLOOR = 1e-14


@dataclass(frozen=True)
class IterationInfo:
    """What a ``callback`` receives after each E-step (iteration 0 is the initial state)."""

    iteration: int
    transform: object
    moving_transformed: np.ndarray
    sigma2: float
    objective: float
    error: float | None


class Snapshots:
    """A ``callback`` that keeps the moving set at chosen iterations (for thesis figs. 5.4, 5.5, 5.7).

    ``frames`` maps each recorded iteration to a copy of the moving points; the final state is
    always kept too, so a method that converged early still has a last frame.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((30, 2))
    >>> snaps = Snapshots([0, 2])
    >>> reg = RigidCPD(tol=1e-3, callback=snaps).fit(y, y + 0.1)
    >>> sorted(snaps.frames)[:2]
    [0, 2]
    """

    def __init__(self, iterations):
        self.iterations = {check_int(i, name="iterations[i]", low=0) for i in iterations}
        self.frames = {}
        self._last = None

    def __call__(self, info: IterationInfo):
        if self._last is not None and self._last not in self.iterations:
            self.frames.pop(self._last, None)  # an earlier "last" frame that was not asked for
        self.frames[info.iteration] = info.moving_transformed
        self._last = info.iteration


def initial_sigma2(moving, fixed) -> float:
    """CPD's starting variance ``sum_mn |x_n - y_m|^2 / (D M N)``, in O((M + N) D).

    Examples
    --------
    >>> initial_sigma2([[0.0, 0.0]], [[3.0, 4.0]])
    12.5
    """
    moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
    fixed = as_points(fixed, name="fixed", n_dims=(moving.shape[1],))
    centre = fixed.mean(axis=0)
    x, y = fixed - centre, moving - centre
    n_fixed, n_moving, n_dims = x.shape[0], y.shape[0], x.shape[1]
    total = n_moving * np.sum(x * x) + n_fixed * np.sum(y * y) - 2.0 * x.sum(axis=0) @ y.sum(axis=0)
    return float(total / (n_dims * n_moving * n_fixed))


def alignment_error(true_moving, moving_transformed) -> float:
    """``|X - T(Y)|``: the Frobenius norm over known correspondences (thesis figs. 5.3, 5.6, 5.8).

    Examples
    --------
    >>> alignment_error([[0.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 2.0]])
    1.0
    """
    a = as_points(true_moving, name="true_moving", n_dims=ANY_DIMS)
    b = as_points(moving_transformed, name="moving_transformed", n_dims=(a.shape[1],))
    if a.shape != b.shape:
        raise InputError(f"`true_moving` must have the shape of the moving set {b.shape}; got {a.shape}.")
    return float(np.linalg.norm(a - b))


class _CPD:
    """The EM loop shared by every CPD variant (and by GPD, which adds a prior)."""

    def __init__(self, *, w=0.0, max_iter=150, tol=1e-5, sigma2=None, method="auto", callback=None, progress=False):
        self.w = w
        self.max_iter = max_iter
        self.tol = tol
        self.sigma2 = sigma2
        self.method = method
        self.callback = callback
        self.progress = progress

    # ----------------------------------------------------------------- parameters
    def get_params(self) -> dict:
        import inspect

        classes = [c for c in type(self).__mro__ if issubclass(c, _CPD) and "__init__" in c.__dict__]
        names = [p for c in classes for p in inspect.signature(c.__init__).parameters if p != "self"]
        return {name: getattr(self, name) for name in dict.fromkeys(names)}

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({params})"

    def _check_common(self):
        name = type(self).__name__
        check_float(self.w, name=f"{name}.w", low=0.0, high=1.0, high_open=True)
        check_int(self.max_iter, name=f"{name}.max_iter", low=0)
        check_float(self.tol, name=f"{name}.tol", low=0.0)
        if self.sigma2 is not None:
            check_float(self.sigma2, name=f"{name}.sigma2", low=0.0, low_open=True)
        check_choice(self.method, E_STEP_METHODS, name=f"{name}.method")
        if self.callback is not None and not callable(self.callback):
            raise TypeError(f"`{name}.callback` must be callable or None; got {self.callback!r}.")

    def _check_params(self):  # variant-specific checks
        pass

    # ----------------------------------------------------------------- variant hooks
    def _init_state(self, moving, fixed):
        raise NotImplementedError

    def _m_step(self, post, moving, fixed, state, sigma2):
        raise NotImplementedError

    def _penalty(self, state) -> float:
        return 0.0

    def _make_transform(self, state, moving):
        raise NotImplementedError

    # ----------------------------------------------------------------- the loop
    def fit(self, moving, fixed, *, true_moving=None):
        """Register ``moving`` (Y, M x D) onto ``fixed`` (X, N x D); returns ``self``.

        Parameters
        ----------
        moving, fixed : array_like of shape (M, D) and (N, D)
            Neither is modified.
        true_moving : array_like of shape (M, D), optional
            Where each moving point truly belongs in the fixed frame; when given,
            ``history_["error"]`` holds ``|true_moving - T(Y)|`` per iteration.
        """
        return self._fit(moving, fixed, true_moving=true_moving, prior=None)

    def _validate(self, moving, fixed, true_moving):
        moving = as_points(moving, name="moving", n_dims=ANY_DIMS)
        fixed = as_points(fixed, name="fixed", n_dims=ANY_DIMS)
        if fixed.shape[1] != moving.shape[1]:
            raise InputError(
                f"`moving` and `fixed` must have the same number of dimensions; got {moving.shape[1]} and {fixed.shape[1]}."
            )
        if true_moving is not None:
            true_moving = as_points(true_moving, name="true_moving", n_dims=(moving.shape[1],))
            if true_moving.shape != moving.shape:
                raise InputError(f"`true_moving` must have the shape of `moving` {moving.shape}; got {true_moving.shape}.")
        return moving, fixed, true_moving

    def _fit(self, moving, fixed, *, true_moving, prior: CentralityPrior | None):
        self._check_common()
        self._check_params()
        moving, fixed, true_moving = self._validate(moving, fixed, true_moving)
        spread = max(initial_sigma2(fixed, fixed), initial_sigma2(moving, moving), 1e-300)
        floor = _SIGMA2_FLOOR * spread
        sigma2 = initial_sigma2(moving, fixed) if self.sigma2 is None else float(self.sigma2)
        sigma2 = max(sigma2, floor)
        state = self._init_state(moving, fixed)
        moving_t = self._apply(state, moving)
        history = {"objective": [], "sigma2": [], "error": [], "method": []}
        converged = False
        previous = None
        bar = None
        if self.progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=self.max_iter, desc=type(self).__name__, unit="iter", leave=False)
        try:
            iteration = 0
            while True:
                post = _e_step(moving_t, fixed, sigma2, self.w, prior, method=self.method)
                objective = post.neg_log_likelihood + self._penalty(state)
                error = None if true_moving is None else float(np.linalg.norm(true_moving - moving_t))
                history["objective"].append(objective)
                history["sigma2"].append(sigma2)
                history["error"].append(error)
                history["method"].append(post.method)
                if self.callback is not None:
                    info = IterationInfo(iteration, self._make_transform(state, moving), moving_t.copy(), sigma2, objective, error)
                    if self.callback(info) is True:
                        break
                if previous is not None and abs(objective - previous) <= self.tol * max(abs(objective), 1e-300):
                    converged = True
                    break
                if iteration > 0 and sigma2 <= floor:
                    converged = True  # the sets coincide to rounding error
                    break
                if iteration >= self.max_iter:
                    break
                if post.n_p <= 1e-12 * fixed.shape[0]:
                    warnings.warn(
                        f"{type(self).__name__}: every fixed point was explained by the outlier term at iteration "
                        f"{iteration} (sigma2={sigma2:.3g}, w={self.w}); stopped. Try a smaller `w` or a larger `sigma2`.",
                        ConvergenceWarning,
                        stacklevel=3,
                    )
                    break
                previous = objective
                state, moving_t, sigma2 = self._m_step(post, moving, fixed, state, sigma2)
                if not math.isfinite(sigma2) or sigma2 <= floor:
                    sigma2 = floor
                iteration += 1
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(sigma2=f"{sigma2:.3g}")
        finally:
            if bar is not None:
                bar.close()
        if not converged and iteration >= self.max_iter and self.max_iter > 0 and self.tol > 0:
            warnings.warn(
                f"{type(self).__name__} stopped at max_iter={self.max_iter} before the relative change of the "
                f"objective fell below tol={self.tol}.",
                ConvergenceWarning,
                stacklevel=3,
            )
        self.transform_ = self._make_transform(state, moving)
        self.moving_transformed_ = moving_t
        self.sigma2_ = float(sigma2)
        self.n_iter_ = iteration
        self.converged_ = converged
        self.history_ = {
            "objective": np.array(history["objective"]),
            "sigma2": np.array(history["sigma2"]),
            "error": None if true_moving is None else np.array(history["error"]),
            "method": history["method"],
        }
        self.correspondence_ = post.best
        self.posteriors_ = post
        self._fixed = fixed
        self._prior = prior
        return self

    def _apply(self, state, moving):
        return self._make_transform(state, moving)(moving)

    # ----------------------------------------------------------------- results
    def transform(self, points) -> np.ndarray:
        """Apply the fitted transform to new points."""
        self._check_fitted()
        return self.transform_(points)

    def posterior(self) -> np.ndarray:
        """The full posterior matrix ``P`` (M x N) of the final state; ``P[m, n] = P(m | x_n)``.

        Memory is M x N doubles, so it refuses sets above 50 million pairs; the fitted
        ``posteriors_`` (its row and column sums) and ``correspondence_`` are always there.
        """
        self._check_fitted()
        n_moving, n_fixed = self.moving_transformed_.shape[0], self._fixed.shape[0]
        if n_moving * n_fixed > 50_000_000:
            raise InputError(
                f"posterior() builds an M x N matrix; M x N = {n_moving * n_fixed:,} exceeds 50,000,000. "
                "Use `correspondence_` or `posteriors_` instead."
            )
        return dense_posterior(self.moving_transformed_, self._fixed, self.sigma2_, self.w, self._prior)

    def _check_fitted(self):
        if not hasattr(self, "transform_"):
            raise InputError(f"This {type(self).__name__} is not fitted yet; call fit(moving, fixed) first.")


class RigidCPD(_CPD):
    """Rigid (``scale=False``) or similarity (``scale=True``) Coherent Point Drift.

    EM on a Gaussian mixture centred on the transformed moving points with an outlier
    component of weight ``w`` (SPEC section 3). Stops when the relative change of the
    objective ``-sum_n log(sum_m exp(-|x_n - T(y_m)|^2 / 2 sigma2) + c) + N D/2 log sigma2``
    between two E-steps is at most ``tol``, after ``max_iter`` M-steps, or when sigma2
    reaches 1e-14 of the data's spread (the sets coincide).

    Parameters
    ----------
    scale : bool, default=True
        Estimate an isotropic scale (similarity) or not (rigid).
    w : float in [0, 1), default=0
        Weight of the uniform outlier component.
    max_iter : int, default=150
        Maximum number of M-steps.
    tol : float, default=1e-5
        Tolerance on the relative change of the objective.
    sigma2 : float, optional
        Initial variance; by default ``sum |x_n - y_m|^2 / (D M N)``.
    method : {'auto', 'dense', 'truncated', 'fgt'}, default='auto'
        E-step path: every pair ('dense'); for each fixed point only the moving points whose
        term is above exp(-36.8)/M of its largest ('truncated', a cell grid: equal to dense to
        rounding); a fast Gauss transform ('fgt', about 1e-8 of the total weight; CPD only,
        not GPD). 'auto' takes the cheapest by a cost model at each iteration (always dense
        below 4 million pairs).
    callback : callable, optional
        Called with an :class:`IterationInfo` after each E-step; return ``True`` to stop.
    progress : bool, default=False
        Show a progress bar on stderr.

    Attributes
    ----------
    transform_ : RigidTransform or SimilarityTransform
    moving_transformed_ : ndarray of shape (M, D)
    sigma2_ : float
    n_iter_ : int
        Number of M-steps taken.
    converged_ : bool
    history_ : dict
        ``objective``, ``sigma2`` and ``error`` (or None without ``true_moving``), entry ``k``
        for the state after ``k`` M-steps; ``method`` the E-step path of each.
    correspondence_ : ndarray of shape (N,)
        For each fixed point the most probable moving point, -1 for an outlier.
    posteriors_ : Posteriors
        The E-step statistics of the final state.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((40, 2))
    >>> r = np.array([[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    >>> x = 1.5 * y @ r.T + [0.2, -0.1]
    >>> reg = RigidCPD(scale=True, tol=1e-10).fit(y, x)
    >>> round(reg.transform_.scale, 6), bool(np.allclose(reg.moving_transformed_, x, atol=1e-6))
    (1.5, True)
    """

    def __init__(self, *, scale=True, w=0.0, max_iter=150, tol=1e-5, sigma2=None, method="auto", callback=None, progress=False):
        super().__init__(w=w, max_iter=max_iter, tol=tol, sigma2=sigma2, method=method, callback=callback, progress=progress)
        self.scale = scale

    def _check_params(self):
        if not isinstance(self.scale, (bool, np.bool_)):
            raise TypeError(f"`RigidCPD.scale` must be a bool; got {self.scale!r}.")

    def _init_state(self, moving, fixed):
        dim = moving.shape[1]
        return SimilarityTransform(np.eye(dim), np.zeros(dim)) if self.scale else RigidTransform(np.eye(dim), np.zeros(dim))

    def _m_step(self, post, moving, fixed, state, sigma2):
        transform, sigma2 = rigid_m_step(post, moving, fixed, scale=bool(self.scale))
        return transform, transform(moving), sigma2

    def _make_transform(self, state, moving):
        return state


class AffineCPD(_CPD):
    """Affine Coherent Point Drift; the parameters and attributes of :class:`RigidCPD`.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((40, 3))
    >>> a = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.1, 0.0, 1.2]])
    >>> reg = AffineCPD(tol=1e-12).fit(y, y @ a.T + 0.3)
    >>> bool(np.allclose(reg.transform_.linear, a, atol=1e-6))
    True
    """

    def _init_state(self, moving, fixed):
        dim = moving.shape[1]
        return AffineTransform(np.eye(dim), np.zeros(dim))

    def _m_step(self, post, moving, fixed, state, sigma2):
        transform, sigma2 = affine_m_step(post, moving, fixed)
        return transform, transform(moving), sigma2

    def _make_transform(self, state, moving):
        return state


class NonRigidCPD(_CPD):
    """Non-rigid Coherent Point Drift: a motion-coherent displacement field.

    ``T(Y) = Y + G W`` with ``G[i, j] = exp(-|y_i - y_j|^2 / (2 beta^2))``, regularised by
    ``lam / 2 tr(W^T G W)`` (added to the objective). Other parameters and attributes as in
    :class:`RigidCPD`; ``transform_`` is a :class:`NonRigidTransform` that can move any point.

    Parameters
    ----------
    beta : float, default=2.0
        Width of the Gaussian kernel, in the units of the points.
    lam : float, default=2.0
        Strength of the smoothness regularisation (lambda of the CPD paper).
    low_rank : int, 'auto' or None, default='auto'
        Number of eigenpairs of ``G`` kept (the CPD paper's fast variant, O(M K^2) per
        iteration instead of an O(M^3) solve). None solves exactly; 'auto' is exact up to
        500 moving points and keeps ``ceil(sqrt(M))`` eigenpairs (at least 50) above.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).random((50, 2))
    >>> x = y + 0.05 * np.sin(3 * y[:, ::-1])
    >>> reg = NonRigidCPD(beta=0.5, lam=0.5, tol=1e-8).fit(y, x)
    >>> bool(np.linalg.norm(reg.moving_transformed_ - x) < 0.1 * np.linalg.norm(y - x))
    True
    """

    def __init__(
        self, *, beta=2.0, lam=2.0, low_rank="auto", w=0.0, max_iter=150, tol=1e-5, sigma2=None, method="auto",
        callback=None, progress=False,
    ):
        super().__init__(w=w, max_iter=max_iter, tol=tol, sigma2=sigma2, method=method, callback=callback, progress=progress)
        self.beta = beta
        self.lam = lam
        self.low_rank = low_rank

    def _check_params(self):
        check_float(self.beta, name="NonRigidCPD.beta", low=0.0, low_open=True)
        check_float(self.lam, name="NonRigidCPD.lam", low=0.0, low_open=True)
        if not (self.low_rank is None or self.low_rank == "auto"):
            check_int(self.low_rank, name="NonRigidCPD.low_rank", low=1)

    def _rank(self, n_moving: int):
        if self.low_rank is None:
            return None
        if self.low_rank == "auto":
            if n_moving <= 500:
                return None
            rank = max(50, math.ceil(math.sqrt(n_moving)))
            return None if rank >= n_moving - 1 else rank
        if self.low_rank >= n_moving - 1:
            return None  # ARPACK needs k < n; a full-rank "approximation" is the exact kernel
        return int(self.low_rank)

    def _init_state(self, moving, fixed):
        rank = self._rank(moving.shape[0])
        kernel = gaussian_kernel(moving, moving, self.beta) if rank is None else LowRankKernel(moving, self.beta, rank)
        return {"kernel": kernel, "w": np.zeros_like(moving)}

    def _apply(self, state, moving):
        return moving.copy()

    def _penalty(self, state) -> float:
        w, kernel = state["w"], state["kernel"]
        if not np.any(w):
            return 0.0
        g_term = kernel.penalty(w) if isinstance(kernel, LowRankKernel) else float(np.sum(w * (kernel @ w)))
        return 0.5 * self.lam * g_term

    def _m_step(self, post, moving, fixed, state, sigma2):
        w, moved, sigma2 = nonrigid_m_step(post, moving, fixed, state["kernel"], self.lam, sigma2)
        return {"kernel": state["kernel"], "w": w}, moved, sigma2

    def _make_transform(self, state, moving):
        kernel, w = state["kernel"], state["w"]
        if isinstance(kernel, LowRankKernel):
            # G Q Q^T W ~ Q diag(values) Q^T W: coefficients projected on the kept eigenvectors
            # give a field defined everywhere that matches the low-rank iterate at the
            # moving points up to the discarded tail of G's spectrum
            w = kernel.vectors @ (kernel.vectors.T @ w)
        return NonRigidTransform(moving, w, self.beta)
