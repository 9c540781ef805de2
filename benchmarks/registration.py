#!/usr/bin/env python
"""Benchmark our Coherent Point Drift against rustcpd, biocpd, probreg, pycpd and cycpd (rigid and non-rigid, 2D).

One process, the same seeded data for every library. For each size n the moving set Y
(n x 2) is n points sampled inside a Kimia-99 silhouette (``--shape``, default ``dog1``:
uniformly among the shape's pixels, with a uniform jitter of half a pixel), or, with
``--shape gmm``, from a Gaussian mixture of 4 anisotropic clusters; it is centred and
scaled so that its extent (the longer side of its bounding box) is ``--extent`` (3 units),
so that the default kernel width beta = 2 is sensible. The fixed set X (n x 2, rows
shuffled) is

* rigid:     ``X = s Y R^T + t + noise``, R a 30 degree rotation, s = 1.2, t = (0.3, -0.2);
* non-rigid: ``X = Y + 0.05 extent (sin(y_2), sin(y_1)) + noise`` (a smooth field);

with Gaussian noise of standard deviation ``0.005 extent``. ``true_moving`` (where each
moving point truly belongs) is the noiseless transformed Y. The final error is the RMS
``|true_moving - T(Y)|_F / sqrt(n)``, in the units of the data.

==========  =================================================================================
library     calls (all with w = 0, the same numeric ``--tol`` and ``--max-iter``)
==========  =================================================================================
ours        ``RigidCPD(scale=True, w=0, tol, max_iter).fit(Y, X)``,
            ``NonRigidCPD(beta, lam, low_rank="auto", w=0, tol, max_iter).fit(Y, X)``
ours32      the same with ``precision="float32"`` (the dense E-step's exponentials in float32)
ours-acc    ``ours`` with ``accelerate=True`` (SQUAREM extrapolation of the EM iterates);
            ``ours32-acc`` both
pycpd       ``RigidRegistration(X=X, Y=Y, tolerance, max_iterations, w=0).register()``,
            ``DeformableRegistration(X=X, Y=Y, alpha=lam, beta=beta, ...).register()``
cycpd       ``rigid_registration(X=X, Y=Y, scale=True, tolerance, max_iterations, w=0,
            verbose=False, print_reg_params=False).register()``,
            ``deformable_registration(X=X, Y=Y, alpha=lam, beta=beta, low_rank=True,
            num_eig=K, ...).register()``
==========  =================================================================================

The timed part is the constructor plus ``fit``/``register`` (pycpd and cycpd compute the
initial variance and the kernel G in their constructors).

The stopping criteria differ; the same numbers mean different things
--------------------------------------------------------------------------
Let ``L = -sum_n log(sum_m exp(-|x_n - T(y_m)|^2 / (2 sigma2)) + c) + N D/2 log sigma2``
be CPD's negative log-likelihood (c = 0 for w = 0).

* ours: stops when ``|L_k - L_{k-1}| <= tol * |L_k|`` (RELATIVE change of L between two
  E-steps; for non-rigid, L includes ``lam/2 tr(W^T G W)``), after ``max_iter`` M-steps,
  or when sigma2 falls to 1e-14 of the data's spread.
* pycpd 2.0.0 rigid: stops when ``|q_k - q_{k-1}| <= tolerance`` (ABSOLUTE) where
  ``q = (xPx - 2 s tr(A R) + s^2 yPy) / (2 sigma2) + D Np/2 log sigma2`` is the EM bound
  Q (expected complete-data negative log-likelihood) evaluated after the M-step with the
  new (s, R, t) and the sigma2 of the E-step (q_0 = inf, so at least 2 iterations), or
  after ``max_iterations``.
* pycpd 2.0.0 deformable: stops when ``|sigma2_k - sigma2_{k-1}| <= tolerance``: the
  ABSOLUTE change of the variance (squared data units), or after ``max_iterations``. It
  always solves the exact M x M system (no low-rank option in 2.0.0).
* cycpd 0.28 rigid: stops when ``|E_k - E_{k-1}| <= tolerance`` (ABSOLUTE) where E_k is
  L computed in the k-th E-step (the same quantity as ours; E_0 = 0, so the first change
  is |E_1|), when sigma2 <= machine epsilon (absolute), or after ``max_iterations``.
* cycpd 0.28 deformable (``low_rank=True``): the same, with E_k = L + ``alpha/2 tr(W^T Q S
  Q^T W)`` (the penalty with the new W). Its ``low_rank=False`` path is not usable in 0.28:
  it raises AttributeError (``A_times``) and never updates its error, so it would always
  run ``max_iterations``. We therefore use the low-rank path with ``num_eig`` = K =
  ``--cycpd-num-eig`` (default: the rank ours uses above 500 points,
  ``max(50, ceil(sqrt(n)))``); cycpd computes it with a full ``numpy.linalg.eigh`` of G.

With w = 0 and the same tol, ours (relative) stops much earlier than cycpd (absolute) when
|L| >> 1, and pycpd's quantities are on other scales altogether: this is why the tables
report iterations and the final error next to the seconds, not seconds alone.
``--ours-tol`` sets ours' tolerance on its own (e.g. to match an absolute tolerance).

Ours' NonRigidCPD (``low_rank="auto"``) is exact up to 500 moving points and keeps
``max(50, ceil(sqrt(M)))`` eigenpairs of G above (``--low-rank`` overrides); pycpd is
always exact (an M x M solve per iteration).

One workaround: cycpd 0.28's rigid ``update_variance`` leaves sigma2 as a 1x1 ndarray,
which its Cython E-step rejects under NumPy 2 (``TypeError: only 0-dimensional arrays``)
unless ``verbose=True`` (whose printing unwraps it); we subclass it to turn sigma2 into a
float after each update (no measurable cost), instead of timing the printing.

Threads: ours via ``centrality_vision.set_num_threads(--threads)`` (default: all the
cores this process may use). numpy/BLAS threads (used by pycpd, cycpd and our non-rigid
M-step) are left at their defaults; the header prints them when threadpoolctl is
installed, and ``--blas-threads N`` limits them (through threadpoolctl) for every library.
On a loaded machine OpenBLAS' spinning threads can slow small BLAS calls tenfold; watch the
load average printed at the start and the end.

Usage::

    python benchmarks/registration.py --quick                      # 500 points, one run
    python benchmarks/registration.py                              # 1,000 and 5,000 points
    python benchmarks/registration.py --sizes 1000 2000 --only ours,cycpd --repeat 5
    python benchmarks/registration.py --with-large                 # + ours rigid at 100,000
    python benchmarks/registration.py --json results.json
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from _common import fmt_s, load_line, probreg_beta, table

OURS_LIBS = ("ours", "ours32", "ours-acc", "ours32-acc")
LIBRARIES = (*OURS_LIBS, "rustcpd", "biocpd", "probreg", "pycpd", "cycpd")
CASES = ("rigid", "nonrigid")
DEFAULT_SIZES = (1000, 5000)
QUICK_SIZES = (500,)
DEFAULT_LARGE = 100_000
SLOW_N = 5000  # --repeat defaults to 1 from this size (3 below)
SINGLE_RUN_S = 20.0  # a first run longer than this is not repeated

ANGLE_DEG = 30.0
SCALE = 1.2
SHIFT = (0.3, -0.2)
NOISE = 0.005  # noise standard deviation, times the extent
DEFORM = 0.05  # non-rigid displacement amplitude, times the extent
OURS_EXACT_MAX = 500  # NonRigidCPD(low_rank="auto") is exact up to this many moving points


def _cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=None,
        help="numbers of points n (default: %s; --quick: %s)"
        % (" ".join(map(str, DEFAULT_SIZES)), " ".join(map(str, QUICK_SIZES))),
    )
    p.add_argument("--cases", default=",".join(CASES), help="comma list of cases (default: %(default)s)")
    p.add_argument("--only", default=",".join(LIBRARIES), help="comma list of libraries (default: %(default)s)")
    p.add_argument(
        "--tol",
        type=float,
        default=1e-5,
        help="tolerance given to every library (default: %(default)g; the criteria differ, see the module docstring)",
    )
    p.add_argument(
        "--ours-tol", type=float, default=None, help="ours' tolerance on the relative change of L (default: --tol)"
    )
    p.add_argument("--max-iter", type=int, default=150, help="iteration cap for every library (default: %(default)s)")
    p.add_argument("--beta", type=float, default=2.0, help="non-rigid kernel width (default: %(default)g)")
    p.add_argument(
        "--lam", type=float, default=2.0, help="non-rigid regularisation (pycpd/cycpd alpha; default: %(default)g)"
    )
    p.add_argument(
        "--low-rank",
        default="auto",
        help="ours' NonRigidCPD low_rank: auto, none (exact) or a number of eigenpairs (default: %(default)s)",
    )
    p.add_argument(
        "--cycpd-num-eig",
        type=int,
        default=None,
        help="cycpd deformable num_eig (default: max(50, ceil(sqrt(n))), capped at n - 1)",
    )
    p.add_argument(
        "--extent", type=float, default=3.0, help="the moving set is scaled to this extent (default: %(default)g units)"
    )
    p.add_argument(
        "--shape",
        default="dog1",
        help="Kimia-99 silhouette to sample (default: %(default)s) or 'gmm' for a Gaussian mixture",
    )
    p.add_argument("--seed", type=int, default=0, help="data seed (default: %(default)s)")
    p.add_argument(
        "--repeat",
        type=int,
        default=None,
        help="runs per measurement, median reported (default: 3 for n < %d, 1 above)" % SLOW_N,
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="smoke run: sizes %s unless --sizes is given, one run, no large case" % " ".join(map(str, QUICK_SIZES)),
    )
    p.add_argument("--large", type=int, default=None, metavar="N", help="also run ours alone, rigid, on N points")
    p.add_argument("--with-large", action="store_true", help="same as --large %d" % DEFAULT_LARGE)
    p.add_argument(
        "--large-shape",
        default="outline:dog1",
        help="data of the large case: a --shape value, or 'outline:NAME' for points along "
        "the outline of a Kimia-99 silhouette (default: %(default)s)",
    )
    p.add_argument(
        "--threads",
        type=int,
        default=_cores(),
        help="threads for ours (default: all cores, %(default)s); numpy/BLAS stay at their defaults",
    )
    p.add_argument(
        "--blas-threads",
        type=int,
        default=None,
        help="limit numpy/BLAS threads (all libraries) via threadpoolctl; default: leave them at their defaults",
    )
    p.add_argument(
        "--max-gib",
        type=float,
        default=8.0,
        help="skip a run whose estimated dense arrays exceed this many GiB (default: %(default)g)",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="also write all raw rows as JSON")
    p.add_argument(
        "--estep",
        action="store_true",
        help="instead: time each E-step path and 'auto' (the planner) against sigma2 (--estep-sizes)",
    )
    p.add_argument("--estep-sizes", type=int, nargs="+", default=[3000, 20000])
    p.add_argument("--repeat-estep", type=int, default=5)
    p.add_argument(
        "--figure",
        metavar="PATH",
        default=None,
        help="log-log figure of seconds against n per library (from this run's rows, or --from-json)",
    )
    p.add_argument(
        "--from-json",
        metavar="PATH",
        nargs="+",
        default=None,
        help="with --figure: read rows from these JSON files instead of running",
    )
    args = p.parse_args(argv)
    if args.from_json and not args.figure:
        p.error("--from-json only redraws a figure: give --figure PATH (where to write it)")

    def split(s, allowed, what):
        items = [x.strip() for x in s.split(",") if x.strip()]
        bad = [x for x in items if x not in allowed]
        if bad or not items:
            p.error("unknown or empty %s: %s (choose from %s)" % (what, ", ".join(bad), ", ".join(allowed)))
        return list(dict.fromkeys(items))

    args.only = split(args.only, LIBRARIES, "library")
    args.cases = split(args.cases, CASES, "case")
    if args.sizes is None:
        args.sizes = list(QUICK_SIZES if args.quick else DEFAULT_SIZES)
    if any(n < 10 for n in args.sizes):
        p.error("--sizes must be >= 10")
    if args.repeat is not None and args.repeat < 1:
        p.error("--repeat must be >= 1")
    if args.quick and args.repeat is None:
        args.repeat = 1
    if args.with_large and args.large is None:
        args.large = DEFAULT_LARGE
    if args.quick and args.large is not None:
        print("--quick: the large case (%d points) is skipped" % args.large)
        args.large = None
    if args.large is not None and args.large < 10:
        p.error("--large must be >= 10")
    if args.threads < 1:
        p.error("--threads must be >= 1")
    if args.blas_threads is not None and args.blas_threads < 1:
        p.error("--blas-threads must be >= 1")
    if args.ours_tol is None:
        args.ours_tol = args.tol
    lr = str(args.low_rank).lower()
    if lr == "auto":
        args.low_rank = "auto"
    elif lr == "none":
        args.low_rank = None
    else:
        try:
            args.low_rank = int(lr)
        except ValueError:
            p.error("--low-rank must be auto, none or an int")
    return args


# --------------------------------------------------------------------------- imports


def _try_import(name):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pycpd: SyntaxWarning "is not" with a literal
            import importlib

            return importlib.import_module(name), None
    except Exception as exc:
        return None, "%s: %s" % (type(exc).__name__, exc)


def _import_ours():
    def attempt():
        import centrality_vision
        from centrality_vision.exceptions import ConvergenceWarning
        from centrality_vision.registration import NonRigidCPD, RigidCPD

        return centrality_vision, RigidCPD, NonRigidCPD, ConvergenceWarning

    try:
        return attempt(), None
    except ModuleNotFoundError as exc:
        if "centrality_vision" not in str(exc):
            return None, "%s: %s" % (type(exc).__name__, exc)
        src = Path(__file__).resolve().parents[1] / "src"
        if src.is_dir():
            sys.path.insert(0, str(src))
            try:
                return attempt(), None
            except Exception as exc2:
                return None, "%s: %s" % (type(exc2).__name__, exc2)
        return None, "%s: %s" % (type(exc).__name__, exc)
    except Exception as exc:
        return None, "%s: %s" % (type(exc).__name__, exc)


OURS, _ours_err = _import_ours()
pycpd, _pycpd_err = _try_import("pycpd")
cycpd, _cycpd_err = _try_import("cycpd")
rustcpd, _rustcpd_err = _try_import("rustcpd")
biocpd, _biocpd_err = _try_import("biocpd")
probreg_cpd, _probreg_err = _try_import("probreg.cpd")
IMPORT_ERRORS = {
    "ours": _ours_err,
    "ours32": _ours_err,
    "ours-acc": _ours_err,
    "ours32-acc": _ours_err,
    "pycpd": _pycpd_err,
    "cycpd": _cycpd_err,
    "rustcpd": _rustcpd_err,
    "biocpd": _biocpd_err,
    "probreg": _probreg_err,
}
AVAILABLE = {
    "ours": OURS is not None,
    "ours32": OURS is not None,
    "ours-acc": OURS is not None,
    "ours32-acc": OURS is not None,
    "pycpd": pycpd is not None,
    "cycpd": cycpd is not None,
    "rustcpd": rustcpd is not None,
    "biocpd": biocpd is not None,
    "probreg": probreg_cpd is not None,
}


# --------------------------------------------------------------------------- data


@dataclass
class Problem:
    case: str
    n: int
    moving: np.ndarray  # Y
    fixed: np.ndarray  # X (rows shuffled)
    true_moving: np.ndarray  # noiseless T(Y), aligned with Y
    extent: float
    noise_sigma: float
    shape: str

    @property
    def initial_rms(self):
        return rms(self.true_moving, self.moving)


def rms(a, b):
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / math.sqrt(len(a)))


_SHAPE_CACHE = {}


def _kimia_pixels(name):
    if name not in _SHAPE_CACHE:
        from centrality_vision.datasets import load_kimia99

        mask = load_kimia99().image(name)
        rows, cols = np.nonzero(mask)
        _SHAPE_CACHE[name] = np.column_stack([cols, -rows]).astype(np.float64)  # x right, y up
    return _SHAPE_CACHE[name]


def base_shape(n, seed, shape, extent):
    """(n x 2 moving set, description): the same for both cases at a given n."""
    rng = np.random.default_rng([seed, n])
    pts = None
    desc = None
    if shape.startswith("outline:"):
        from centrality_vision.datasets import contour_points, load_kimia99

        name = shape.split(":", 1)[1]
        pts = contour_points(load_kimia99().image(name), n)[:, ::-1] * [1.0, -1.0]
        pts = pts + rng.uniform(-0.25, 0.25, (n, 2))
        desc = "Kimia-99 '%s' outline, points equally spaced by arc length" % name
    elif shape != "gmm":
        try:
            pix = _kimia_pixels(shape)
            pts = pix[rng.integers(0, len(pix), n)] + rng.uniform(-0.5, 0.5, (n, 2))
            desc = "Kimia-99 '%s' (%d pixels), points uniform inside" % (shape, len(pix))
        except Exception as exc:
            print(
                "  ! Kimia-99 shape %r unavailable (%s: %s); using a Gaussian mixture"
                % (shape, type(exc).__name__, exc)
            )
            pts = None
    if pts is None:
        crng = np.random.default_rng([seed, 0])  # the mixture itself does not depend on n
        centres = crng.uniform(-1.0, 1.0, (4, 2))
        scales = crng.uniform(0.1, 0.35, (4, 2))
        angles = crng.uniform(0.0, np.pi, 4)
        k = rng.integers(0, 4, n)
        z = rng.standard_normal((n, 2)) * scales[k]
        c, s = np.cos(angles[k]), np.sin(angles[k])
        pts = centres[k] + np.column_stack([c * z[:, 0] - s * z[:, 1], s * z[:, 0] + c * z[:, 1]])
        desc = "Gaussian mixture of 4 anisotropic clusters"
    pts = pts - pts.mean(axis=0)
    pts *= extent / np.ptp(pts, axis=0).max()
    return pts, desc


def make_problem(case, n, args, shape=None):
    y, desc = base_shape(n, args.seed, args.shape if shape is None else shape, args.extent)
    rng = np.random.default_rng([args.seed, n, 1 + CASES.index(case)])
    sigma = NOISE * args.extent
    if case == "rigid":
        a = math.radians(ANGLE_DEG)
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        true = SCALE * y @ rot.T + np.asarray(SHIFT)
    else:
        true = y + DEFORM * args.extent * np.column_stack([np.sin(y[:, 1]), np.sin(y[:, 0])])
    fixed = true + rng.normal(0.0, sigma, true.shape)
    fixed = fixed[rng.permutation(n)]
    return Problem(case, n, np.ascontiguousarray(y), np.ascontiguousarray(fixed), true, args.extent, sigma, desc)


# --------------------------------------------------------------------------- the calls
# Each runner takes (Y, X) and returns (T(Y), iterations, stop reason); it is timed whole.
# A library that reports neither (probreg) returns None for both.


def _cycpd_num_eig(n, args):
    k = args.cycpd_num_eig if args.cycpd_num_eig is not None else max(50, math.ceil(math.sqrt(n)))
    return max(1, min(k, n - 1))


def _ours_rank(n, args):
    if args.low_rank is None:
        return None
    if args.low_rank == "auto":
        return None if n <= OURS_EXACT_MAX else max(50, math.ceil(math.sqrt(n)))
    return None if args.low_rank >= n - 1 else args.low_rank


def _cycpd_rigid_class():
    class Rigid(cycpd.rigid_registration):
        """cycpd 0.28's rigid registration with sigma2 kept a Python float (see docstring)."""

        def update_variance(self):
            super().update_variance()
            self.sigma2 = float(np.asarray(self.sigma2).reshape(-1)[0])

    return Rigid


_CYCPD_RIGID = None


def make_runner(lib, case, n, args, method="auto"):
    """(callable(Y, X) -> (TY, n_iter, stop), parameters dict)."""
    tol, max_iter = args.tol, args.max_iter
    if lib in OURS_LIBS:
        _, RigidCPD, NonRigidCPD, ConvergenceWarning = OURS
        precision = "float32" if lib.startswith("ours32") else "float64"
        accelerate = lib.endswith("-acc")
        kwargs = {
            "w": 0.0,
            "tol": args.ours_tol,
            "max_iter": max_iter,
            "precision": precision,
            "accelerate": accelerate,
        }
        if case == "rigid":
            kwargs = {"scale": True, **kwargs}
            params = dict(kwargs)
        else:
            # normalize=False: beta and lam in the data's units, as every peer reads them (ours'
            # default reads them in a frame of unit RMS radius, here 0.94 of the data's: a kernel
            # 6% narrower, which at 5,000 points falls into the wrong basin every library at
            # beta 1.9 falls into, RMS 0.22 for 2.3e-3; rustcpd, exact: 0.23)
            kwargs = {"beta": args.beta, "lam": args.lam, "low_rank": args.low_rank, "normalize": False, **kwargs}
            params = {**kwargs, "rank_used": _ours_rank(n, args) or "exact"}
        cls = RigidCPD if case == "rigid" else NonRigidCPD

        def make():
            return cls(method=method, **kwargs)

        def run(y, x):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                est = make().fit(y, x)
            return est.moving_transformed_, int(est.n_iter_), "tol" if est.converged_ else "max_iter"

        return run, params

    if lib == "rustcpd":
        k = _cycpd_num_eig(n, args)
        if case == "rigid":

            def call(y, x):
                return rustcpd.register_rigid(x, y, scale=True, tolerance=tol, max_iterations=max_iter)

            params = {"scale": True, "tolerance": tol, "max_iterations": max_iter}
        else:
            low = None if n <= OURS_EXACT_MAX else k

            def call(y, x):
                return rustcpd.register_deformable(
                    x,
                    y,
                    alpha=args.lam,
                    beta=args.beta,
                    low_rank=low,
                    low_rank_method="pivoted_cholesky",
                    tolerance=tol,
                    max_iterations=max_iter,
                )

            params = {
                "alpha": args.lam,
                "beta": args.beta,
                "low_rank": low,
                "low_rank_method": "pivoted_cholesky",
                "tolerance": tol,
                "max_iterations": max_iter,
            }

        def run(y, x):
            res = call(y, x)
            return np.asarray(res.points), int(res.iterations), "tol" if res.iterations < max_iter else "max_iter"

        return run, params

    if lib == "biocpd":
        k = _cycpd_num_eig(n, args)
        if case == "rigid":

            def make(y, x):
                return biocpd.RigidRegistration(X=x, Y=y, scale=True, tolerance=tol, max_iterations=max_iter, w=0.0)

            params = {"scale": True, "tolerance": tol, "max_iterations": max_iter, "use_kdtree": "default (True, k=10)"}
        else:

            def make(y, x):
                return biocpd.DeformableRegistration(
                    X=x, Y=y, alpha=args.lam, beta=args.beta, num_eig=k, tolerance=tol, max_iterations=max_iter, w=0.0
                )

            params = {
                "alpha": args.lam,
                "beta": args.beta,
                "num_eig": k,
                "tolerance": tol,
                "max_iterations": max_iter,
                "use_kdtree": "default (True, k=10)",
            }

        def run(y, x):
            reg = make(y, x)
            ty = reg.register()[0]
            it = int(getattr(reg, "iteration", -1))
            return ty, it, "tol" if it < max_iter else "max_iter"

        return run, params

    if lib == "probreg":
        kind = "rigid" if case == "rigid" else "nonrigid"
        # its kernel's beta is a variance (CPD's width squared, see probreg_beta) and its M-step
        # CPD's lambda sigma2, so it gets beta^2 and lam itself
        extra = {} if case == "rigid" else {"beta": probreg_beta(args.beta), "lmd": args.lam}

        def run(y, x):
            n_dims = y.shape[1]
            if kind == "rigid" and n_dims == 2:
                # its rigid transform is 3D only: a zero third coordinate keeps the fit in the
                # plane (checked: 500 points turned 30 degrees and scaled 1.2, recovered to 2e-15)
                y, x = (np.column_stack([p, np.zeros(len(p))]) for p in (y, x))
            res = probreg_cpd.registration_cpd(y, x, tf_type_name=kind, w=0.0, maxiter=max_iter, tol=tol, **extra)
            return np.asarray(res.transformation.transform(y))[:, :n_dims], None, None  # (not reported)

        return run, {"tf_type_name": kind, "w": 0.0, "maxiter": max_iter, "tol": tol, **extra}

    if lib == "pycpd":
        if case == "rigid":

            def make(y, x):
                return pycpd.RigidRegistration(X=x, Y=y, tolerance=tol, max_iterations=max_iter, w=0)

            params = {"tolerance": tol, "max_iterations": max_iter, "w": 0}
        else:

            def make(y, x):
                return pycpd.DeformableRegistration(
                    X=x, Y=y, alpha=args.lam, beta=args.beta, tolerance=tol, max_iterations=max_iter, w=0
                )

            params = {
                "alpha": args.lam,
                "beta": args.beta,
                "tolerance": tol,
                "max_iterations": max_iter,
                "w": 0,
                "exact": True,
            }

        def run(y, x):
            reg = make(y, x)
            ty, _ = reg.register()
            stop = "tol" if reg.diff <= reg.tolerance else "max_iter"
            return ty, int(reg.iteration), stop

        return run, params

    if lib == "cycpd":
        global _CYCPD_RIGID
        common = {"tolerance": tol, "max_iterations": max_iter, "w": 0.0, "verbose": False, "print_reg_params": False}
        if case == "rigid":
            if _CYCPD_RIGID is None:
                _CYCPD_RIGID = _cycpd_rigid_class()
            cls = _CYCPD_RIGID

            def make(y, x):
                return cls(X=x, Y=y, scale=True, **common)

            params = dict(common, scale=True)
        else:
            k = _cycpd_num_eig(n, args)

            def make(y, x):
                return cycpd.deformable_registration(
                    X=x, Y=y, alpha=args.lam, beta=args.beta, low_rank=True, num_eig=k, **common
                )

            params = dict(common, alpha=args.lam, beta=args.beta, low_rank=True, num_eig=k)

        def run(y, x):
            reg = make(y, x)
            ty, _ = reg.register()
            if reg.err <= reg.tolerance:
                stop = "tol"
            elif float(np.asarray(reg.sigma2).reshape(-1)[0]) <= np.finfo(float).eps:
                stop = "sigma2"
            else:
                stop = "max_iter"
            return ty, int(reg.iteration), stop

        return run, {k: v for k, v in params.items() if k not in ("verbose", "print_reg_params")}

    raise ValueError(lib)


def estimated_gib(lib, case, n, args):
    """Rough peak of the dense arrays a run allocates (M = N = n, D = 2)."""
    d = 2
    if lib == "pycpd":  # M x N x D differences, M x N P / den / exp
        b = 8.0 * n * n * (2 * d + 3)
        if case == "nonrigid":  # G via tiled M x M x D arrays, diag(P1), A
            b += 8.0 * n * n * (3 * d + 4)
    elif lib == "probreg":  # dense M x N posterior and distance arrays
        b = 8.0 * n * n * 4
    elif lib == "cycpd":
        b = 64.0 * n * d
        if case == "nonrigid":  # G via M x M x D differences, eigh
            b += 8.0 * n * n * (2 * d + 4)
    else:
        b = 64.0 * n * d
        if case == "nonrigid" and _ours_rank(n, args) is None:
            b += 8.0 * n * n * 4
    return b / 1024**3


# --------------------------------------------------------------------------- measurement


@dataclass
class Row:
    case: str
    n: int
    library: str
    status: str  # ok | not installed | skipped | error
    times: list = field(default_factory=list)
    n_iter: int | None = None
    stop: str | None = None
    error: float | None = None
    note: str = ""
    params: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    ratio: float | None = None

    @property
    def median(self):
        return statistics.median(self.times) if self.times else float("nan")


def measure(lib, problem, args, repeat):
    if not AVAILABLE[lib]:
        return Row(problem.case, problem.n, lib, "not installed", note=IMPORT_ERRORS[lib] or "")
    gib = estimated_gib(lib, problem.case, problem.n, args)
    if gib > args.max_gib:
        return Row(
            problem.case,
            problem.n,
            lib,
            "skipped",
            note="needs ~%.1f GiB of dense arrays (> --max-gib %g)" % (gib, args.max_gib),
        )
    try:  # (a peer whose API changed fails while its call is set up: its row says so)
        run, params = make_runner(lib, problem.case, problem.n, args)
    except Exception as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return Row(problem.case, problem.n, lib, "error", note="%s: %s" % (type(exc).__name__, msg))
    row = Row(problem.case, problem.n, lib, "ok", params=params)
    caught = []
    try:
        for i in range(repeat):
            with warnings.catch_warnings(record=True) as w:
                warnings.simplefilter("always")
                t0 = time.perf_counter()
                ty, n_iter, stop = run(problem.moving, problem.fixed)
                row.times.append(time.perf_counter() - t0)
            caught.extend("%s: %s" % (x.category.__name__, x.message) for x in w)
            if i == 0 and row.times[0] > SINGLE_RUN_S:
                break
    except Exception as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return Row(problem.case, problem.n, lib, "error", note="%s: %s" % (type(exc).__name__, msg), params=params)
    row.n_iter, row.stop = n_iter, stop
    row.error = rms(problem.true_moving, np.asarray(ty, dtype=np.float64))
    row.warnings = sorted(set(caught))
    return row


def warm_up(libs, cases, args):
    """Run every selected call once on 60 points: numba compiles our kernels (dense and
    truncated E-step paths), the other libraries load their extension modules."""
    small = argparse.Namespace(**vars(args))
    small.max_iter = 5
    t0 = time.perf_counter()
    msgs = []
    for case in cases:
        prob = make_problem(case, 60, small)
        for lib in libs:
            methods = ("dense", "truncated") if lib in OURS_LIBS else ("auto",)
            for method in methods:
                try:
                    run, _ = make_runner(lib, case, 60, small, method=method)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        run(prob.moving, prob.fixed)
                except Exception as exc:
                    msgs.append("%s %s (%s): %s: %s" % (lib, case, method, type(exc).__name__, exc))
    return time.perf_counter() - t0, msgs


# --------------------------------------------------------------------------- output


def _blas_info():
    try:
        from threadpoolctl import threadpool_info

        pools = threadpool_info()
        if not pools:
            return "no BLAS/OpenMP pool found"
        return ", ".join(
            "%s %s: %s threads" % (p.get("internal_api"), p.get("user_api"), p.get("num_threads")) for p in pools
        )
    except Exception:
        env = {
            k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS") if k in os.environ
        }
        return "library defaults (threadpoolctl not installed; env %s)" % (env or "unset")


def _mem_total():
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemTotal:"):
                    return "%.1f GiB" % (int(line.split()[1]) / 1024**2)
    except OSError:
        pass
    return "?"


def machine_info(args):
    import scipy

    def ver(mod, dist=None):
        if mod is None:
            return "not installed"
        v = getattr(mod, "__version__", None)
        if v is None and dist:
            try:
                from importlib.metadata import version

                v = version(dist)
            except Exception:
                v = "?"
        return v

    try:
        import numba

        numba_v = numba.__version__
    except Exception:
        numba_v = "not installed"
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "cores_available": _cores(),
        "memory": _mem_total(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba_v,
        "centrality_vision": OURS[0].__version__ if OURS is not None else "not importable",
        "pycpd": ver(pycpd, "pycpd"),
        "rustcpd": ver(rustcpd, "rustcpd"),
        "biocpd": ver(biocpd, "biocpd"),
        "probreg": ver(probreg_cpd, "probreg"),
        "cycpd": ver(cycpd, "cycpd"),
        "ours_threads": OURS[0].get_num_threads() if OURS is not None else None,
        "blas": _blas_info(),
    }


def _limit_blas(n):
    """Keep a threadpoolctl limit alive for the whole run; None when not requested."""
    if n is None:
        return None, None
    try:
        from threadpoolctl import threadpool_limits

        return threadpool_limits(limits=n, user_api="blas"), None
    except Exception as exc:
        return None, "%s: %s" % (type(exc).__name__, exc)


def main(args):
    if OURS is not None:
        OURS[0].set_num_threads(args.threads)
    blas_limit, blas_err = _limit_blas(args.blas_threads)
    info = machine_info(args)
    libs = list(args.only)

    print("=" * 78)
    print("CPD registration benchmark: ours vs pycpd vs cycpd (2D, w = 0)")
    print(
        "machine: %s, %s, os.cpu_count() = %s (%s usable), memory %s"
        % (info["platform"], info["processor"], info["cpu_count"], info["cores_available"], info["memory"])
    )
    print("python %s | numpy %s | scipy %s | numba %s" % (info["python"], info["numpy"], info["scipy"], info["numba"]))
    print(
        "centrality_vision %s | pycpd %s | cycpd %s | rustcpd %s | biocpd %s | probreg %s"
        % (info["centrality_vision"], info["pycpd"], info["cycpd"], info["rustcpd"], info["biocpd"], info["probreg"])
    )
    print(
        "threads: ours %s (centrality_vision.set_num_threads); numpy/BLAS (pycpd, cycpd and our "
        "non-rigid M-step) %s: %s"
        % (
            info["ours_threads"],
            "at their defaults" if args.blas_threads is None else "limited by --blas-threads %d" % args.blas_threads,
            info["blas"],
        )
    )
    if blas_err:
        print("  ! --blas-threads ignored: threadpoolctl unavailable (%s)" % blas_err)
    for lib in libs:
        if not AVAILABLE[lib]:
            print("%s: not installed (%s)" % (lib, IMPORT_ERRORS[lib]))
    print(
        "tol %g (ours %g, relative change of L; pycpd: absolute change of Q (rigid) / sigma2 "
        "(deformable); cycpd: absolute change of L) | max_iter %d" % (args.tol, args.ours_tol, args.max_iter)
    )
    print(
        "non-rigid: beta %g, lam (alpha) %g in the data's units (ours: normalize=False); ours low_rank=%r "
        "(exact up to %d points), pycpd exact, "
        "cycpd low-rank num_eig=%s"
        % (args.beta, args.lam, args.low_rank, OURS_EXACT_MAX, args.cycpd_num_eig or "max(50, ceil(sqrt(n)))")
    )
    print(
        "repeat: %s (median; a single run, marked *, when the first run takes > %g s)"
        % (args.repeat if args.repeat is not None else "3 for n < %d, 1 above" % SLOW_N, SINGLE_RUN_S)
    )
    print(load_line())
    print("=" * 78)

    # data
    print("\ndata (seed %d, built once, the same arrays for every library):" % args.seed)
    problems = []
    for case in args.cases:
        for n in args.sizes:
            problems.append(make_problem(case, n, args))
    if args.large is not None and args.large not in args.sizes and "rigid" in args.cases and "ours" in libs:
        problems.append(make_problem("rigid", args.large, args, shape=args.large_shape))
    for pr in problems:
        what = (
            "s=%g, %g deg, t=%s" % (SCALE, ANGLE_DEG, SHIFT)
            if pr.case == "rigid"
            else "%g*extent*(sin y2, sin y1)" % DEFORM
        )
        print(
            "  %-8s n = %7d  %s; extent %.3g, noise sigma %.3g; %s; initial RMS |true - Y| = %.4f"
            % (pr.case, pr.n, pr.shape, pr.extent, pr.noise_sigma, what, pr.initial_rms)
        )

    # warm-up
    avail = [lib for lib in libs if AVAILABLE[lib]]
    dt, msgs = warm_up(avail, args.cases, args)
    print("\nwarm-up: every call run once on 60 points before timing (numba compiles ours' kernels): %.2f s" % dt)
    for m in msgs:
        print("  ! warm-up failed: %s" % m)

    # runs
    rows = []
    for pr in problems:
        large = pr.n == args.large and pr.n not in args.sizes
        repeat = 1 if large else (args.repeat or (1 if pr.n >= SLOW_N else 3))
        for lib in ["ours"] if large else libs:
            print("  running %-8s n = %7d  %-6s" % (pr.case, pr.n, lib), end="", flush=True)
            row = measure(lib, pr, args, repeat)
            rows.append(row)
            print(
                " %s"
                % (
                    fmt_s(row)
                    + (
                        " s, %s iterations, RMS %.2e" % ("?" if row.n_iter is None else row.n_iter, row.error)
                        if row.status == "ok"
                        else ""
                    )
                ),
                flush=True,
            )

    # ratios
    for row in rows:
        ours = next(
            (r for r in rows if r.case == row.case and r.n == row.n and r.library == "ours" and r.status == "ok"), None
        )
        if row.status == "ok" and ours is not None:
            row.ratio = row.median / ours.median

    # tables
    print()
    for case in args.cases:
        crows = [r for r in rows if r.case == case]
        if not crows:
            continue
        body = []
        notes = []
        for r in crows:
            ok = r.status == "ok"
            body.append(
                [
                    r.n,
                    r.library,
                    fmt_s(r),
                    len(r.times) if ok else "-",
                    r.n_iter if ok and r.n_iter is not None else "-",
                    r.stop if ok and r.stop is not None else "-",
                    "%.2e" % r.error if ok else "-",
                    "%.2f" % r.ratio if r.ratio is not None else "-",
                ]
            )
            if r.note and r.status != "not installed":
                notes.append("n=%d %s: %s: %s" % (r.n, r.library, r.status, r.note))
            for w in r.warnings:
                notes.append("n=%d %s: warning %s" % (r.n, r.library, w[:200]))
        print(
            "### %s  (seconds: median of the runs, * = single run; RMS = |true - T(Y)|_F / sqrt(n); "
            "ratio = library s / ours s; iters and stop '-': the library does not report them)" % case
        )
        print(
            table(
                ["n", "library", "seconds", "runs", "iters", "stop", "RMS error", "lib/ours"],
                body,
                align=[">", "<", ">", ">", ">", "<", ">", ">"],
            )
        )
        for note in dict.fromkeys(notes):
            print("  note: " + note)
        print()

    print(load_line())
    if args.json:
        out = {
            "machine": info,
            "args": {k: v for k, v in vars(args).items()},
            "data": [
                {
                    "case": p.case,
                    "n": p.n,
                    "shape": p.shape,
                    "extent": p.extent,
                    "noise_sigma": p.noise_sigma,
                    "initial_rms": p.initial_rms,
                }
                for p in problems
            ],
            "rows": [
                {
                    "case": r.case,
                    "n": r.n,
                    "library": r.library,
                    "status": r.status,
                    "median_s": r.median if r.status == "ok" else None,
                    "times_s": r.times,
                    "n_iter": r.n_iter,
                    "stop": r.stop,
                    "rms_error": r.error,
                    "ratio_to_ours": r.ratio,
                    "params": r.params,
                    "note": r.note,
                    "warnings": r.warnings,
                }
                for r in rows
            ],
        }
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(out, indent=2, default=str))
        print("results written to %s" % args.json)
    if args.figure:
        figure(
            [
                {"case": r.case, "n": r.n, "library": r.library, "median_s": r.median if r.status == "ok" else None}
                for r in rows
            ],
            args.figure,
        )
    return 0


# --------------------------------------------------------------------------- E-step paths


def _median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def run_estep(args):
    """Each E-step path and 'auto' (a planner, after its probe) per sigma2, in one process.

    The calls are interleaved (one of each path per round, ``--repeat-estep`` rounds), so a
    swing of the machine's load falls on every path alike; a path over 3x the fastest in
    the first round is not repeated (its single time is marked ``*``: it cannot be the
    fastest). 'auto' is judged twice: its own calls' median over the fastest path's median,
    and the median of the path it picked over the fastest one (the same work, so the ratio
    shows the choice apart from the timing noise of separate calls). 'carried' is one planner
    per size called at every half decade of sigma2 from 1 down, as a fit shrinks sigma2: the
    path it runs at each decade was chosen at its last probe, up to 10x sigma2 away.
    """
    from centrality_vision.registration._estep import EStepPlanner, _e_step

    paths = ("dense", "truncated", "fgt")
    print("E-step paths vs sigma2: uniform 2D points in the unit square, moving = fixed (permuted) + N(0, 0.001^2),")
    print(
        "w = 0; milliseconds, median of %d or more interleaved rounds (as many as 1 s of the fastest path"
        " takes, 40 at most; a path over 3x the fastest after round 1: its one time, *);"
        " auto = one EStepPlanner probed once at that sigma2, then timed like the others (its probe is amortised"
        " over the iterations of a fit; probe ms = the probe call); carried = one planner per size called at"
        " every half decade of sigma2 from 1 down, as in a fit: the path it runs at that sigma2" % args.repeat_estep
    )
    print(load_line())
    rows = []
    for n in args.estep_sizes:
        rng = np.random.default_rng([args.seed, n])
        fixed = rng.random((n, 2))
        moving = fixed[rng.permutation(n)] + rng.normal(0, 1e-3, (n, 2))
        for m in ("dense", "truncated", "fgt"):  # numba compiles (or loads) each path's kernels
            _e_step(moving[:200], fixed[:200], 0.01, 0.0, method=m)
        carried = EStepPlanner()
        for sigma2 in [10.0**-k for k in range(0, 13)]:
            if sigma2 < 1.0:
                carried(moving, fixed, sigma2 * math.sqrt(10.0), 0.0)
            carried(moving, fixed, sigma2, 0.0)
            planner = EStepPlanner()
            start = time.perf_counter()
            planner(moving, fixed, sigma2, 0.0)
            probe = time.perf_counter() - start
            calls = {
                m: (lambda m=m: _e_step(moving, fixed, sigma2, 0.0, method=m))  # noqa: B023 (called at once)
                for m in paths
            }
            calls["auto"] = lambda: planner(moving, fixed, sigma2, 0.0)  # noqa: B023
            times = {m: [] for m in calls}
            active = list(calls)
            rounds = args.repeat_estep
            round_ = 0
            while round_ < rounds:
                for m in active:
                    t0 = time.perf_counter()
                    try:
                        calls[m]()
                    except MemoryError:
                        times[m].append(math.inf)
                        continue
                    times[m].append(time.perf_counter() - t0)
                if round_ == 0:
                    first = min(times[m][0] for m in paths)
                    active = [m for m in active if m == "auto" or times[m][0] <= 3 * first]
                    # short calls suffer most from a busy machine's time slices: more rounds
                    rounds = max(rounds, min(40, math.ceil(1.0 / max(first, 1e-9))))
                round_ += 1
            ms = {m: 1e3 * statistics.median(times[m]) for m in calls}
            single = [m for m in paths if len(times[m]) == 1 and rounds > 1]
            fastest_path = min(paths, key=ms.get)
            fastest = ms[fastest_path]
            row = {
                "n": n,
                "sigma2": sigma2,
                **ms,
                "single": single,
                "probe_ms": 1e3 * probe,
                "probe_timings_ms": {m: 1e3 * t for m, t in planner.timings.items()},
                "winner": planner.winner,
                "fastest": fastest_path,
                "auto_over_fastest": ms["auto"] / fastest,
                "picked_over_fastest": ms[planner.winner] / fastest,
                "carried": carried.winner,
                "carried_over_fastest": ms[carried.winner] / fastest,
                "carried_probes": carried.probes,
                "load": os.getloadavg()[0],
            }
            rows.append(row)
            print(
                "  n=%d sigma2=%.0e  %s  probe %.1f  auto picked %s (fastest %s): auto %.2fx,"
                " picked path %.2fx; carried %s %.2fx  load %.1f"
                % (
                    n,
                    sigma2,
                    "  ".join("%s %.1f%s" % (m, ms[m], "*" if m in single else "") for m in (*paths, "auto")),
                    row["probe_ms"],
                    planner.winner,
                    fastest_path,
                    row["auto_over_fastest"],
                    row["picked_over_fastest"],
                    row["carried"],
                    row["carried_over_fastest"],
                    row["load"],
                ),
                flush=True,
            )
    body = [
        [
            r["n"],
            "%.0e" % r["sigma2"],
            *("%.1f%s" % (r[m], "*" if m in r["single"] else "") for m in paths),
            "%.1f" % r["auto"],
            "%.1f" % r["probe_ms"],
            r["winner"],
            r["fastest"],
            "%.2f" % r["auto_over_fastest"],
            "%.2f" % r["picked_over_fastest"],
            r["carried"],
            "%.2f" % r["carried_over_fastest"],
            "%.1f" % r["load"],
        ]
        for r in rows
    ]
    print()
    print(
        table(
            [
                "n",
                "sigma2",
                "dense ms",
                "truncated ms",
                "fgt ms",
                "auto ms",
                "probe ms",
                "auto took",
                "fastest",
                "auto/fastest",
                "picked/fastest",
                "carried took",
                "carried/fastest",
                "load 1 min",
            ],
            body,
        )
    )
    for n in args.estep_sizes:
        sub = [r for r in rows if r["n"] == n]
        print(
            "n=%d: worst auto/fastest %.2f, worst picked/fastest %.2f, worst carried/fastest %.2f"
            " (the carried planner probed %d times over 25 sigma2 values); sigma2 values with auto/fastest > 1.25: %s"
            % (
                n,
                max(r["auto_over_fastest"] for r in sub),
                max(r["picked_over_fastest"] for r in sub),
                max(r["carried_over_fastest"] for r in sub),
                sub[-1]["carried_probes"],
                ", ".join("%.0e" % r["sigma2"] for r in sub if r["auto_over_fastest"] > 1.25) or "none",
            )
        )
    print(load_line())
    return rows


# --------------------------------------------------------------------------- uniform data at scale
# (registration_large.py's hard case)


def _scaled_problem(n, dim, case, seed):
    """Points uniform in a 3-unit cube; rigid: 30 degrees about (1, 1, 1) (2D: the plane's),
    scale 1.2, shift; affine: a fixed shear; non-rigid: 0.15 (sin y2, sin y1[, sin y1])."""
    rng = np.random.default_rng([seed, n, dim])
    y = rng.random((n, dim)) * 3.0 - 1.5
    a = math.radians(ANGLE_DEG)
    if dim == 2:
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    else:
        k = np.ones(3) / math.sqrt(3)
        kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        rot = np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx
    if case == "rigid":
        true = SCALE * y @ rot.T + 0.2
    elif case == "affine":
        lin = np.eye(dim) + 0.15 * np.triu(np.ones((dim, dim)), 1) + 0.05 * np.eye(dim)
        true = y @ lin.T - 0.1
    else:
        field = np.column_stack([np.sin(y[:, 1]), np.sin(y[:, 0])] + ([np.sin(y[:, 0] + y[:, 1])] if dim == 3 else []))
        true = y + 0.15 * field
    fixed = true + rng.normal(0.0, NOISE * 3.0, true.shape)
    return np.ascontiguousarray(y), np.ascontiguousarray(fixed[rng.permutation(n)]), true


# --------------------------------------------------------------------------- figure


def figure(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = sorted({r["case"] for r in rows})
    colours = {lib: "C%d" % i for i, lib in enumerate(sorted({r["library"] for r in rows}))}
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        libs = sorted({r["library"] for r in rows if r["case"] == case})
        for lib in libs:
            pts = sorted(
                (r["n"], r["median_s"]) for r in rows if r["case"] == case and r["library"] == lib and r.get("median_s")
            )
            if pts:
                ax.loglog(*zip(*pts), "o-", label=lib, color=colours[lib], lw=2.2 if lib.startswith("ours") else 1.2)
        ax.set_title(case)
        ax.set_xlabel("points per set n")
        ax.set_ylabel("seconds (median)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    print("figure written to %s" % path)


def entry(args):
    if OURS is not None:
        OURS[0].set_num_threads(args.threads)
    if args.from_json:
        rows = [r for path in args.from_json for r in json.loads(Path(path).read_text())["rows"]]
        figure(rows, args.figure)
        return 0
    if args.estep:
        blas_limit, _ = _limit_blas(args.blas_threads)
        out = {"machine": machine_info(args), "args": vars(args)}
        out["estep"] = run_estep(args)
        if args.json:
            Path(args.json).parent.mkdir(parents=True, exist_ok=True)
            Path(args.json).write_text(json.dumps(out, indent=2, default=str))
            print("results written to %s" % args.json)
        return 0
    return main(args)


if __name__ == "__main__":
    try:
        sys.exit(entry(parse_args()))
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception:
        traceback.print_exc()
        sys.exit(1)
