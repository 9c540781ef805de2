#!/usr/bin/env python
"""Registration benchmark suite: the field's protocols, ours beside five CPD libraries.

One command runs everything, resumably (each finished unit is appended as one JSON line to
``<out>.jsonl`` by the project's runner and skipped on a re-run; a unit's key holds every
parameter that shapes its result), then prints the tables and writes ``<out>.txt``,
``<out>.json`` and the figures ``<out>-synthetic.png`` and ``<out>-rotation.png``.

Families (2D outlines: the CPD fish, 91 points, and the Kimia-99 ``dog1`` outline, 100
points by arc length; each centred and scaled to unit RMS radius):

==============  ==========================================================================
family          fixed set X from the moving set Y (rows of X always shuffled)
==============  ==========================================================================
deformation     ``warp(Y)``: a Gaussian-RBF warp, 12 control points drawn from Y, width
                0.5, weights ~ N(0, std^2) per coordinate, std 0.02 .. 0.08 (5 levels)
noise           ``warp(Y) + N(0, std^2)``, std 0 .. 0.05 (6 levels), warp std 0.04
outliers        ``warp(Y)`` plus ``r * M`` uniform points in its bounding box, r = 0 .. 2
                (5 levels), warp std 0.04
occlusion       ``warp(Y)`` without the ``f * M`` points nearest a random point of it (a
                contiguous part), f = 0 .. 0.5 (6 levels), warp std 0.04
==============  ==========================================================================

The error of a pair is the mean distance ``mean_m |T(y_m) - warp(y_m)|`` to the true
positions (in units of the RMS radius); a pair succeeds when it is below 0.05. Every method
gets the same pairs (seeded by family, shape, level and pair index), the same ``w``
(deformation and noise 0, outliers 0.5, occlusion 0.1), ``beta`` = 2, ``lam`` (``alpha``) = 3
(the CPD paper's fish settings), the same numeric tolerance (1e-7) and iteration cap (150).

Rotation (the 2D fish and the 3D Stanford bunny, 1,000 points drawn once with seed 0 from
``../shared/data/bunny/bunny.txt``, or ``--bunny``): X is Y rotated by the level's angle
(2D: either sign; 3D: about a random axis), translated by N(0, 1), with Gaussian noise 0.01,
the 20% of points nearest a random point removed (a missing part) and 20% outliers
(uniform in the bounding box), rows shuffled; ``w`` = 0.2 for every method. A trial
succeeds when the rotation error is below 5 degrees (the rotation of each method's output
is read by a least-squares fit of its transformed moving points, so every library's
convention is handled alike).

Methods. Ours: ``NonRigidCPD`` / ``RigidCPD(scale=False)`` (``cpd``: CPD's dense model; ``cpd-acc``
the same with ``accelerate=True``), the same
with ``n_neighbors=10`` (``cpd-knn``: the k-nearest-neighbour E-step, biocpd's model and k) and
with ``n_neighbors=10, w="auto"`` (``cpd-knn-auto``), ``GPD`` over the dense one with
each centrality on Delaunay graphs (``gpd-<centrality>``; only closeness in the rotation
family), rigid ``ICP``, and on the rotation family each of those started from
``global_pose_search`` (``+global``: the function ``RigidCPD(init="global")`` calls, applied
to Y here and followed by the plain fit, so that ICP and GPD get the same start).
Peers: pycpd 2.0 (its rigid registration always estimates a scale), cycpd 0.28 (deformable:
low-rank with ``num_eig`` = M - 1), probreg 0.3.8 (``registration_cpd``; its kernel is
``exp(-|d|^2 / (2 b))``, a variance where CPD has a width, so it gets ``b = beta^2``; the
convention is measured on probreg's own kernel at each run), rustcpd 4.0
(``low_rank=None``: exact) and biocpd 1.3 (``low_rank=False``). Each library's tolerance
means something else (see ``registration.py``); they get the same number. A library that
fails on a case is reported with its error instead of a number.

Run it with ``nice -n 5 python benchmarks/registration_suite.py [--pairs 20] [--trials 20]
[--workers 2]``; ``--quick`` is a smoke run (2 pairs, 2 trials, 3 angles). A full run writes
``results/benchmarks/registration-suite.*`` (``--out PREFIX`` elsewhere); ``--quick`` and
``--explain`` write into ``<temp>/centrality-vision-benchmarks/`` unless given ``--out``.
``--explain N [--sections ...]`` runs controlled experiments on N of the suite's pairs per
case: biocpd's and probreg's departures from CPD switched off in turn, GPD's prior with its
parts removed, every library's solution scored by CPD's own objective (which library
optimises the common model best, and which wins by another model), probreg's iterates, and
the levels ``cpd-knn-auto`` misses, pair by pair (``--sections misses``).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one thread per worker: 2 workers share 2 cores

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, load_line, probreg_beta, scratch_dir, table  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
BUNNY = ROOT.parent / "shared" / "data" / "bunny" / "bunny.txt"

FAMILIES = {
    "deformation": [0.02, 0.035, 0.05, 0.065, 0.08],
    "noise": [0.0, 0.01, 0.02, 0.03, 0.04, 0.05],
    "outliers": [0.0, 0.5, 1.0, 1.5, 2.0],
    "occlusion": [0.0, 0.1, 0.2, 0.3, 0.4, 0.5],
}
FAMILY_W = {"deformation": 0.0, "noise": 0.0, "outliers": 0.5, "occlusion": 0.1}
BASE_WARP = 0.04
WARP_WIDTH = 0.5
N_CONTROL = 12
SUCCESS_ERROR = 0.05
ANGLES = [0, 30, 60, 90, 120, 150, 180]
ROTATION_SETTINGS = {"noise": 0.01, "missing": 0.2, "outliers": 0.2, "w": 0.2}
SUCCESS_DEGREES = 5.0
SETTINGS = {"beta": 2.0, "lam": 3.0, "tol": 1e-7, "max_iter": 150}
CENTRALITIES = ("degree", "betweenness", "closeness", "harmonic", "eigenvector", "eccentricity")
PEERS = ("pycpd", "cycpd", "probreg", "rustcpd", "biocpd")
# ours: CPD's dense model with the family's w ("cpd"), the k-nearest-neighbour model with the
# same w ("cpd-knn", n_neighbors=KNN, biocpd's k) and with w="auto" ("cpd-knn-auto")
KNN = 10
OURS_CPD = ("cpd", "cpd-acc", "cpd-knn", "cpd-knn-auto")
# GPD: "gpd-<centrality>" over the dense "cpd" (the thesis' constant prior); a "-knn-auto"
# suffix puts it over "cpd-knn-auto", and "-anneal" fades the prior with sigma2
# (prior_schedule="anneal")
GPD_METHODS = tuple(f"gpd-{c}" for c in CENTRALITIES) + (
    "gpd-closeness-knn-auto",
    "gpd-closeness-knn-auto-anneal",
)
NONRIGID_METHODS = OURS_CPD + GPD_METHODS + ("icp",) + PEERS
ROTATION_METHODS = (
    "cpd",
    "cpd+global",
    "cpd-knn",
    "gpd-closeness",
    "gpd-closeness+global",
    "icp",
    "icp+global",
) + PEERS
SHAPES_2D = ("fish", "dog1")
# A method whose code changed since its units were stored gets a revision in its unit key,
# so that a re-run computes it anew instead of reusing the stored result.
# ("probreg_beta": "beta" stays in every unit's settings so that the other methods' stored
# results are still found; probreg's own units carry "beta-variance": they pass beta^2)
REVISION = {
    "cpd-knn": "moving-frame",
    "cpd-knn-auto": "moving-frame",
    "cpd-acc": "log-sigma2",
    "probreg": "beta-variance",
}


def _method_key(method):
    return f"{method}@{REVISION[method]}" if method in REVISION else method


# ----------------------------------------------------------------------------- data
def _unit(points):
    points = np.asarray(points, dtype=float)
    points = points - points.mean(axis=0)
    return points / math.sqrt(np.mean(np.sum(points * points, axis=1)))


def load_shape(name, bunny_points=1000):
    from centrality_vision.datasets import contour_points, load_fish, load_kimia99

    if name == "fish":
        return _unit(load_fish().moving)
    if name == "bunny":
        raw = np.loadtxt(BUNNY)
        pick = np.random.default_rng(0).choice(raw.shape[0], size=min(bunny_points, raw.shape[0]), replace=False)
        return _unit(raw[np.sort(pick)])
    return _unit(contour_points(load_kimia99().image(name), 100))


def rbf_warp(points, rng, std):
    """``p + sum_j W_j exp(-|p - c_j|^2 / (2 width^2))``: 12 control points from the set."""
    control = points[rng.choice(points.shape[0], size=N_CONTROL, replace=False)]
    weights = rng.normal(scale=std, size=(N_CONTROL, points.shape[1]))
    d2 = np.sum((points[:, None, :] - control[None, :, :]) ** 2, axis=2)
    return points + np.exp(-d2 / (2 * WARP_WIDTH**2)) @ weights


def _remove_part(points, fraction, rng):
    n_drop = int(round(fraction * points.shape[0]))
    centre = points[rng.integers(points.shape[0])]
    return points[np.argsort(np.sum((points - centre) ** 2, axis=1), kind="stable")[n_drop:]]


def _add_outliers(points, count, rng):
    if count == 0:
        return points
    lo, hi = points.min(axis=0), points.max(axis=0)
    return np.vstack([points, rng.uniform(lo, hi, size=(count, points.shape[1]))])


def synthetic_pair(family, shape, level, pair):
    """``(Y, X, true)`` for one seeded pair of a Chui-Rangarajan family."""
    y = load_shape(shape)
    rng = np.random.default_rng(
        [list(FAMILIES).index(family), SHAPES_2D.index(shape), FAMILIES[family].index(level), pair]
    )
    true = rbf_warp(y, rng, level if family == "deformation" else BASE_WARP)
    x = true
    if family == "noise":
        x = x + rng.normal(scale=level, size=x.shape)
    elif family == "outliers":
        x = _add_outliers(x, int(round(level * y.shape[0])), rng)
    elif family == "occlusion":
        x = _remove_part(x, level, rng)
    return y, x[rng.permutation(x.shape[0])], true


def rotation_about(n_dims, degrees, rng):
    a = math.radians(degrees)
    if n_dims == 2:
        a *= rng.choice([-1.0, 1.0])
        return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def rotation_pair(shape, degrees, trial, bunny_points=1000):
    """``(Y, X, R)``: Y rotated by R, translated, noisy, a part missing, outliers added."""
    y = load_shape(shape, bunny_points)
    rng = np.random.default_rng([7, ("fish", "bunny").index(shape), int(degrees), trial])
    r = rotation_about(y.shape[1], degrees, rng)
    x = y @ r.T + rng.normal(size=y.shape[1])
    x = _remove_part(x, ROTATION_SETTINGS["missing"], rng)
    x = x + rng.normal(scale=ROTATION_SETTINGS["noise"], size=x.shape)
    x = _add_outliers(x, int(round(ROTATION_SETTINGS["outliers"] * y.shape[0])), rng)
    return y, x[rng.permutation(x.shape[0])], r


# ----------------------------------------------------------------------------- methods
def _preload_libusb():
    """open3d 0.20 (imported by probreg) needs libusb-1.0; load the wheel's copy if there is one."""
    try:
        import ctypes

        import libusb_package

        ctypes.CDLL(str(libusb_package.get_library_path()), mode=ctypes.RTLD_GLOBAL)
    except Exception:
        pass


def peer_nonrigid(name, y, x, w):
    """A peer's non-rigid CPD of ``y`` onto ``x`` at the suite's settings: ``(T(Y), C)``.

    ``C`` (M x D) are its kernel coefficients, ``T(Y) = Y + G C`` with ``G`` the Gaussian
    kernel of width ``beta`` on ``Y`` (probreg's ``beta`` is that kernel's variance: it gets
    ``beta**2``; cycpd runs low-rank with M - 1 eigenpairs, biocpd with its own defaults).
    """
    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]
    if name in ("pycpd", "biocpd"):
        import biocpd
        import pycpd

        kw = {"low_rank": False} if name == "biocpd" else {}
        cls = (biocpd if name == "biocpd" else pycpd).DeformableRegistration
        reg = cls(X=x, Y=y, alpha=lam, beta=beta, w=w, tolerance=tol, max_iterations=max_iter, **kw)
        return np.asarray(reg.register()[0]), np.asarray(reg.W)
    if name == "cycpd":
        import cycpd

        reg = cycpd.deformable_registration(
            X=x,
            Y=y,
            alpha=lam,
            beta=beta,
            low_rank=True,
            num_eig=y.shape[0] - 1,
            w=w,
            tolerance=tol,
            max_iterations=max_iter,
            verbose=False,
            print_reg_params=False,
        )
        return np.asarray(reg.register()[0]), np.asarray(reg.W)
    if name == "probreg":
        _preload_libusb()
        from probreg import cpd as probreg_cpd

        res = probreg_cpd.registration_cpd(
            y, x, tf_type_name="nonrigid", w=w, maxiter=max_iter, tol=tol, beta=probreg_beta(beta), lmd=lam
        )
        return np.asarray(res.transformation.transform(y)), np.asarray(res.transformation.w)
    if name == "rustcpd":
        import rustcpd

        res = rustcpd.register_deformable(
            x, y, alpha=lam, beta=beta, low_rank=None, max_iterations=max_iter, tolerance=tol, outlier_weight=w
        )
        return np.asarray(res.points), np.asarray(res.weights)
    raise ValueError(f"unknown peer {name!r}")


def run_method(method, y, x, *, rigid, w, seed):
    """The moving set after registration by ``method`` (M x D), and extra info."""
    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]
    base, _, glob = method.partition("+")
    info = {}
    if base in OURS_CPD or base == "icp" or base.startswith("gpd-"):
        from centrality_vision.registration import GPD, ICP, NonRigidCPD, RigidCPD
        from centrality_vision.registration._pose import global_pose_search

        start = y
        pose = None
        if glob:
            t0 = time.perf_counter()
            pose = global_pose_search(y, x, scale=False, w=w, random_state=seed)
            info["search_s"] = time.perf_counter() - t0
            start = pose(y)
        if base == "icp":
            return ICP(max_iter=max_iter, tol=tol).fit(start, x).moving_transformed_, info
        centrality, schedule, over = None, None, base
        if base.startswith("gpd-"):
            spec = base[4:]
            if spec.endswith("-anneal"):
                spec, schedule = spec[: -len("-anneal")], "anneal"
            over = "cpd-knn-auto" if spec.endswith("-knn-auto") else "cpd"
            centrality = spec[: -len("-knn-auto")] if over == "cpd-knn-auto" else spec
        model = {"n_neighbors": KNN} if over.startswith("cpd-knn") else {}
        if over == "cpd-acc":
            model = {"accelerate": True}
        if over == "cpd-knn-auto":
            w = "auto"
        if rigid:
            cpd = RigidCPD(scale=False, w=w, tol=tol, max_iter=max_iter, **model)
        else:
            cpd = NonRigidCPD(beta=beta, lam=lam, w=w, tol=tol, max_iter=max_iter, **model)
        est = cpd if centrality is None else GPD(cpd, centrality=centrality, graph="delaunay", prior_schedule=schedule)
        return est.fit(start, x).moving_transformed_, info
    if base in PEERS and not rigid:
        return peer_nonrigid(base, y, x, w)[0], info
    if base == "pycpd":
        import pycpd

        return pycpd.RigidRegistration(X=x, Y=y, w=w, tolerance=tol, max_iterations=max_iter).register()[0], info
    if base == "cycpd":
        import cycpd

        class Rigid(cycpd.rigid_registration):  # cycpd 0.28 keeps sigma2 a 1x1 array under NumPy 2
            def update_variance(self):
                super().update_variance()
                self.sigma2 = float(np.asarray(self.sigma2).reshape(-1)[0])

        reg = Rigid(
            X=x,
            Y=y,
            scale=False,
            w=w,
            tolerance=tol,
            max_iterations=max_iter,
            verbose=False,
            print_reg_params=False,
        )
        return np.asarray(reg.register()[0]), info
    if base == "probreg":
        _preload_libusb()
        from probreg import cpd as probreg_cpd

        res = probreg_cpd.registration_cpd(
            y, x, tf_type_name="rigid", w=w, maxiter=max_iter, tol=tol, update_scale=False
        )
        return np.asarray(res.transformation.transform(y)), info
    if base == "rustcpd":
        import rustcpd

        res = rustcpd.register_rigid(x, y, scale=False, max_iterations=max_iter, tolerance=tol, outlier_weight=w)
        return np.asarray(res.points), info
    if base == "biocpd":
        import biocpd

        reg = biocpd.RigidRegistration(X=x, Y=y, scale=False, w=w, tolerance=tol, max_iterations=max_iter)
        return np.asarray(reg.register()[0]), info
    raise ValueError(f"unknown method {method!r}")


def _angle(r1, r2):
    d = r1.T @ r2
    cos = (np.trace(d) - 1) / 2 if d.shape[0] == 3 else np.trace(d) / 2
    return math.degrees(math.acos(min(1.0, max(-1.0, cos))))


def _attempt(method, y, x, *, rigid, w, seed):
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    try:
        moved, info = run_method(method, y, x, rigid=rigid, w=w, seed=seed)
        moved = np.asarray(moved, dtype=float)
        if moved.shape != y.shape or not np.all(np.isfinite(moved)):
            return None, {"status": f"bad output {moved.shape}"}, time.perf_counter() - t0
    except Exception as exc:  # a peer that cannot run a case is reported, not fatal
        return None, {"status": f"{type(exc).__name__}: {str(exc)[:80]}"}, time.perf_counter() - t0
    return moved, info, time.perf_counter() - t0


def synthetic_unit(family, shape, level, method, pairs, settings):
    """All pairs of one (family, shape, level) for one method: per-pair error, time, status."""
    out = []
    for pair in range(pairs):
        y, x, true = synthetic_pair(family, shape, level, pair)
        moved, info, seconds = _attempt(method, y, x, rigid=False, w=FAMILY_W[family], seed=pair)
        err = None if moved is None else float(np.mean(np.linalg.norm(moved - true, axis=1)))
        out.append({"error": err, "seconds": seconds, "status": info.get("status", "ok")})
    return out


def rotation_unit(shape, degrees, method, trials, settings, bunny_points):
    """All trials of one (shape, angle) for one method: rotation error, time, status."""
    from centrality_vision.transforms import fit_similarity

    out = []
    for trial in range(trials):
        y, x, r = rotation_pair(shape, degrees, trial, bunny_points)
        moved, info, seconds = _attempt(method, y, x, rigid=True, w=ROTATION_SETTINGS["w"], seed=trial)
        err = None if moved is None else _angle(fit_similarity(y, moved, scale=True).rotation, r)
        out.append(
            {"error": err, "seconds": seconds, "search_s": info.get("search_s"), "status": info.get("status", "ok")}
        )
    return out


# ----------------------------------------------------------------------------- units
def build_units(args):
    from centrality_vision.experiments._runner import Unit

    settings = {
        **SETTINGS,
        "success_error": SUCCESS_ERROR,
        "warp_width": WARP_WIDTH,
        "base_warp": BASE_WARP,
        "knn": KNN,
        "probreg_beta": "beta",
    }
    units = []
    for family in args.families:
        if family == "rotation":
            continue
        for shape in SHAPES_2D:
            for level in FAMILIES[family]:
                for method in args.methods_nonrigid:
                    key = json.dumps(
                        ["syn", family, shape, level, _method_key(method), args.pairs, FAMILY_W[family], settings],
                        sort_keys=True,
                    )
                    units.append(
                        Unit(
                            key,
                            synthetic_unit,
                            dict(
                                family=family,
                                shape=shape,
                                level=level,
                                method=method,
                                pairs=args.pairs,
                                settings=settings,
                            ),
                        )
                    )
    units.sort(key=lambda u: u.kwargs["method"].startswith("gpd-"))  # stable: GPD units last
    if "rotation" in args.families:
        rsettings = {**SETTINGS, **ROTATION_SETTINGS}
        for shape in ("fish", "bunny"):
            for degrees in args.angles:
                for method in args.methods_rotation:
                    key = json.dumps(
                        ["rot", shape, degrees, _method_key(method), args.trials, args.bunny, rsettings],
                        sort_keys=True,
                    )
                    units.append(
                        Unit(
                            key,
                            rotation_unit,
                            dict(
                                shape=shape,
                                degrees=degrees,
                                method=method,
                                trials=args.trials,
                                settings=rsettings,
                                bunny_points=args.bunny,
                            ),
                        )
                    )
    return units


# ----------------------------------------------------------------------------- report
def _summ(rows, threshold):
    errors = [r["error"] for r in rows if r["error"] is not None]
    failed = [r["status"] for r in rows if r["error"] is None]
    if not errors:
        return {
            "mean": None,
            "success": None,
            "seconds": None,
            "failed": len(failed),
            "status": failed[0] if failed else "none",
        }
    # a run that failed counts as unsuccessful
    return {
        "mean": float(np.mean(errors)),
        "median": float(np.median(errors)),
        "success": sum(e < threshold for e in errors) / len(rows),
        "seconds": float(np.median([r["seconds"] for r in rows])),
        "failed": len(failed),
        "status": failed[0] if failed else "ok",
    }


def _cell(c, text):
    """A table cell: the value, '-' for a unit not run, 'fail' when the library failed on every pair."""
    if c["status"] == "not run":
        return "-"
    if c["mean"] is None and c.get("success") is None:
        return "fail"
    return text + ("!" if c["failed"] else "")


def _paired_ratio(mine, peer, resamples=4000):
    """Mean-error ratio ``mine / peer`` over the pairs both finished: its 95% paired bootstrap
    interval (seeded), the number of pairs ``peer`` did better on, and the number of pairs."""
    both = [(a["error"], b["error"]) for a, b in zip(mine, peer) if a["error"] is not None and b["error"] is not None]
    a, b = np.array(both).T
    pick = np.random.default_rng(0).integers(0, a.size, size=(resamples, a.size))
    lo, hi = np.percentile(a[pick].mean(axis=1) / b[pick].mean(axis=1), [2.5, 97.5])
    return float(lo), float(hi), int(np.sum(b < a)), int(a.size)


def report(args, units, results):
    lines = [
        f"registration suite  |  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  |  "
        + load_line("timings are inflated; compare ratios")
    ]
    lines.append(
        f"pairs per synthetic level: {args.pairs}; trials per rotation angle: {args.trials}; "
        f"bunny points: {args.bunny}; workers: {args.workers}"
    )
    lines.append(
        f"settings: {SETTINGS}; w per family: {FAMILY_W}; success: mean error < {SUCCESS_ERROR} (synthetic), "
        f"rotation error < {SUCCESS_DEGREES} deg"
    )
    lines.append(
        "settings per library (non-rigid): cpd = NonRigidCPD(beta, lam, w, tol, max_iter) [dense model]; "
        f"cpd-acc = the same with accelerate=True; cpd-knn = the same with n_neighbors={KNN}; "
        f"cpd-knn-auto = n_neighbors={KNN}, w='auto'; "
        "gpd-<centrality> = GPD(cpd, centrality, graph='delaunay'), '-knn-auto': over cpd-knn-auto, "
        "'-anneal': prior_schedule='anneal'; pycpd DeformableRegistration(alpha=lam, beta, w, "
        "tolerance, max_iterations); cycpd deformable_registration(alpha=lam, beta, low_rank, num_eig=M-1, w); "
        "probreg registration_cpd('nonrigid', beta=beta^2 (its kernel's variance), lmd=lam, w, maxiter, tol); "
        "rustcpd register_deformable("
        "alpha=lam, beta, low_rank=None, outlier_weight=w); biocpd DeformableRegistration(alpha=lam, beta, "
        "low_rank=False, w) [its defaults: k=10 nearest-neighbour E-step, float32]"
    )
    lines.append(
        "cells: '!' = the library raised on some pairs (its mean is over the others; not counted as best peer), "
        "'fail' = on all, '-' = not run"
    )
    summary = {"synthetic": {}, "rotation": {}, "args": vars(args)}
    syn_res, rot_res = {}, {}
    for u in units:
        if u.key not in results:
            continue
        k = u.kwargs
        if "family" in k:
            syn_res[(k["family"], k["shape"], k["level"], k["method"])] = results[u.key]
        else:
            rot_res[(k["shape"], k["degrees"], k["method"])] = results[u.key]
    missing = {"mean": None, "success": None, "seconds": None, "failed": 0, "status": "not run"}
    checks, exact_checks, all_checks, best_peer_of = [], [], {}, {}
    for family in [f for f in args.families if f != "rotation"]:
        for shape in SHAPES_2D:
            rows = []
            for level in FAMILIES[family]:
                cells = {}
                for method in args.methods_nonrigid:
                    res = syn_res.get((family, shape, level, method))
                    cells[method] = dict(missing) if res is None else _summ(res, SUCCESS_ERROR)
                summary["synthetic"].setdefault(family, {}).setdefault(shape, {})[str(level)] = cells
                peers = [
                    (cells[p]["mean"], p)
                    for p in PEERS
                    if p in cells and cells[p]["mean"] is not None and cells[p]["failed"] == 0
                ]
                best_peer = min(peers)[0] if peers else None
                if peers:
                    best_peer_of[(family, shape, level)] = min(peers)[1]
                for config in OURS_CPD + GPD_METHODS:
                    mine = cells.get(config, {}).get("mean")
                    if best_peer not in (None, 0) and mine is not None:
                        all_checks.setdefault(config, []).append((family, shape, level, mine / best_peer))
                ours = cells.get("cpd", {}).get("mean")
                ratio = None if best_peer in (None, 0) or ours is None else ours / best_peer
                knn = cells.get("cpd-knn", {}).get("mean")
                knn_ratio = None if best_peer in (None, 0) or knn is None else knn / best_peer
                if ratio is not None:
                    checks.append((family, shape, level, ratio))
                exact_peers = [
                    cells[p]["mean"]
                    for p in ("pycpd", "cycpd", "rustcpd")
                    if p in cells and cells[p]["mean"] is not None and cells[p]["failed"] == 0
                ]
                if exact_peers and ours is not None and min(exact_peers) > 0:
                    exact_checks.append((family, shape, level, ours / min(exact_peers)))
                row = [level]
                for method in args.methods_nonrigid:
                    c = cells[method]
                    row.append(
                        _cell(c, f"{c['mean']:.4f}/{100 * (c['success'] or 0):.0f}%" if c["mean"] is not None else "")
                    )
                row.append("-" if ratio is None else f"{ratio:.3f}")
                row.append("-" if knn_ratio is None else f"{knn_ratio:.3f}")
                rows.append(row)
            lines.append("")
            lines.append(
                f"[{family}] {shape}: mean error / success rate per level  "
                "(cpd/best peer = ours' mean error over the best peer's)"
            )
            lines.append(table([family] + list(args.methods_nonrigid) + ["cpd/best peer", "knn/best peer"], rows))
    if checks:
        worst = max(checks, key=lambda c: c[3])
        n_ok = sum(c[3] <= 1.05 for c in checks)
        lines.append("")
        lines.append(
            f"check: our CPD's mean error within 5% of the best peer's on {n_ok} of {len(checks)} "
            f"family/shape/levels; worst ratio {worst[3]:.3f} at {worst[:3]}"
        )
        exact = [c for c in exact_checks if c[3] is not None]
        if exact:
            worst_exact = max(exact, key=lambda c: c[3])
            lines.append(
                f"check: against the exact-CPD peers only (pycpd, cycpd, rustcpd) within 5% on "
                f"{sum(c[3] <= 1.05 for c in exact)} of {len(exact)}; "
                f"worst ratio {worst_exact[3]:.3f} at {worst_exact[:3]}"
            )
        summary["check_cpd_vs_best_peer"] = {"within_5pct": n_ok, "cases": len(checks), "worst": list(worst)}
        for config, cases in all_checks.items():
            worst_c = max(cases, key=lambda c: c[3])
            n_c = sum(c[3] <= 1.05 for c in cases)
            lines.append(
                f"check: {config} within 5% of the best peer on {n_c} of {len(cases)}; "
                f"worst ratio {worst_c[3]:.3f} at {worst_c[:3]}"
            )
            if config in ("cpd-knn-auto", "gpd-closeness-knn-auto-anneal"):
                for family, shape, level, ratio in cases:
                    if ratio > 1.05:
                        peer = best_peer_of[(family, shape, level)]
                        lo, hi, better, n = _paired_ratio(
                            syn_res[(family, shape, level, config)], syn_res[(family, shape, level, peer)]
                        )
                        lines.append(
                            f"    {config} at {family}/{shape}/{level}: {ratio:.3f} of {peer}'s; paired bootstrap 95% "
                            f"{lo:.3f}-{hi:.3f}; {peer} better on {better} of {n} pairs"
                        )
            summary.setdefault("checks", {})[config] = {"within_5pct": n_c, "cases": len(cases), "worst": list(worst_c)}
        if {"cpd", "cpd-knn"} <= set(all_checks):
            best_of = [(a[0], a[1], a[2], min(a[3], b[3])) for a, b in zip(all_checks["cpd"], all_checks["cpd-knn"])]
            worst_b = max(best_of, key=lambda c: c[3])
            lines.append(
                f"check: the better of cpd and cpd-knn (our two models at the peers' w) within 5% of the best peer on "
                f"{sum(c[3] <= 1.05 for c in best_of)} of {len(best_of)}; worst ratio {worst_b[3]:.3f} at {worst_b[:3]}"
            )
        best_ours = {}
        for cases in all_checks.values():
            for family, shape, level, ratio in cases:
                key = (family, shape, level)
                best_ours[key] = min(best_ours.get(key, np.inf), ratio)
        if best_ours:
            lines.append(
                f"check: the best of our {len(all_checks)} configurations at each level (the best of "
                f"{len(all_checks)} against the best of {len(PEERS)}: not one configuration) within 5% on "
                f"{sum(r <= 1.05 for r in best_ours.values())} of {len(best_ours)}; "
                f"worst ratio {max(best_ours.values()):.3f}"
            )
        gpd_rows = []
        for family in summary["synthetic"]:
            for shape in summary["synthetic"][family]:
                cells_by_level = summary["synthetic"][family][shape]
                row = [f"{family}/{shape}"]
                for config in OURS_CPD:
                    if config in args.methods_nonrigid:
                        row.append(
                            f"{100 * np.mean([c[config]['success'] or 0 for c in cells_by_level.values()]):.1f}%"
                        )
                for m in GPD_METHODS:
                    if m in args.methods_nonrigid:
                        row.append(f"{100 * np.mean([cl[m]['success'] or 0 for cl in cells_by_level.values()]):.1f}%")
                gpd_rows.append(row)
        lines.append("")
        lines.append("success rate averaged over levels: CPD beside GPD (over the dense CPD) with each centrality")
        lines.append(
            table(
                ["family/shape"]
                + [c for c in OURS_CPD if c in args.methods_nonrigid]
                + [m for m in GPD_METHODS if m in args.methods_nonrigid],
                gpd_rows,
            )
        )
    if "rotation" in args.families:
        for shape in ("fish", "bunny"):
            rows, trows = [], []
            for degrees in args.angles:
                row, trow = [degrees], [degrees]
                for method in args.methods_rotation:
                    res = rot_res.get((shape, degrees, method))
                    c = dict(missing) if res is None else _summ(res, SUCCESS_DEGREES)
                    searches = [r["search_s"] for r in res or [] if r.get("search_s") is not None]
                    c["search_s"] = float(np.median(searches)) if searches else None
                    summary["rotation"].setdefault(shape, {}).setdefault(str(degrees), {})[method] = c
                    row.append(_cell(c, f"{100 * c['success']:.0f}%" if c["success"] is not None else ""))
                    trow.append("-" if c["seconds"] is None else f"{c['seconds']:.3f}")
                rows.append(row)
                trows.append(trow)
            lines.append("")
            lines.append(
                f"[rotation] {shape}: success rate (rotation error < {SUCCESS_DEGREES} deg) per initial angle, "
                f"noise {ROTATION_SETTINGS['noise']}, {int(100 * ROTATION_SETTINGS['missing'])}% missing, "
                f"{int(100 * ROTATION_SETTINGS['outliers'])}% outliers, w = {ROTATION_SETTINGS['w']}"
            )
            lines.append(table(["angle"] + list(args.methods_rotation), rows))
            lines.append(f"[rotation] {shape}: median seconds per registration (the machine is shared: compare ratios)")
            lines.append(table(["angle"] + list(args.methods_rotation), trows))
            cells = summary["rotation"][shape]
            if "cpd" in args.methods_rotation and "cpd+global" in args.methods_rotation:
                done = [str(a) for a in args.angles if cells[str(a)]["cpd+global"]["status"] != "not run"]
                if not done:
                    continue
                plain = np.median([cells[a]["cpd"]["seconds"] or np.nan for a in done])
                glob = np.median([cells[a]["cpd+global"]["seconds"] or np.nan for a in done])
                worst = min(cells[a]["cpd+global"]["success"] or 0 for a in done)
                lines.append(
                    f"global search ({shape}): lowest success over angles {', '.join(done)}: {100 * worst:.1f}% of "
                    f"{args.trials} trials; "
                    f"median seconds search + CPD {glob:.3f} vs one plain CPD {plain:.3f} (ratio {glob / plain:.2f})"
                )
                summary["rotation"][shape]["global_check"] = {
                    "lowest_success": worst,
                    "seconds_global": glob,
                    "seconds_plain": plain,
                }
    lines.append("")
    lines.append(load_line("timings are inflated; compare ratios"))
    return "\n".join(lines), summary


def figures(args, summary, out):
    import matplotlib

    matplotlib.use("Agg")  # a script, not the library
    import matplotlib.pyplot as plt

    palette = plt.get_cmap("tab20").colors
    colour = {m: palette[k % len(palette)] for k, m in enumerate(dict.fromkeys(NONRIGID_METHODS + ROTATION_METHODS))}
    syn = summary["synthetic"]
    if syn:
        fams = list(syn)
        fig, axes = plt.subplots(2 * len(SHAPES_2D), len(fams), figsize=(4 * len(fams), 12), squeeze=False)
        for j, family in enumerate(fams):
            for i, shape in enumerate(SHAPES_2D):
                levels = list(syn[family][shape])
                for method in args.methods_nonrigid:
                    style = "-" if method in ("cpd", "icp") or method in PEERS else ":"
                    err = [syn[family][shape][lv][method]["mean"] for lv in levels]
                    suc = [syn[family][shape][lv][method]["success"] for lv in levels]
                    xs = [float(lv) for lv in levels]
                    axes[2 * i, j].plot(
                        xs,
                        [np.nan if e is None else e for e in err],
                        style,
                        color=colour[method],
                        marker="o",
                        ms=3,
                        label=method,
                    )
                    axes[2 * i + 1, j].plot(
                        xs,
                        [np.nan if s is None else s for s in suc],
                        style,
                        color=colour[method],
                        marker="o",
                        ms=3,
                        label=method,
                    )
                axes[2 * i, j].set_title(f"{family} / {shape}: mean error")
                axes[2 * i, j].set_yscale("log")
                axes[2 * i + 1, j].set_title(f"{family} / {shape}: success")
                axes[2 * i + 1, j].set_ylim(-0.05, 1.05)
        axes[0, -1].legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(f"{out}-synthetic.png", dpi=90)
        plt.close(fig)
    rot = summary["rotation"]
    if rot:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4))
        for ax, shape in zip(axes, ("fish", "bunny")):
            for method in args.methods_rotation:
                suc = [rot[shape][str(a)][method]["success"] for a in args.angles]
                ax.plot(
                    args.angles,
                    [np.nan if s is None else s for s in suc],
                    "-" if "+global" in method else "--",
                    color=colour[method.partition("+")[0]] if "+global" not in method else colour[method],
                    marker="o",
                    ms=3,
                    label=method,
                )
            ax.set_title(f"{shape}: success (rotation error < {SUCCESS_DEGREES} deg)")
            ax.set_xlabel("initial rotation (degrees)")
            ax.set_ylim(-0.05, 1.05)
        axes[1].legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(f"{out}-rotation.png", dpi=90)
        plt.close(fig)


# ----------------------------------------------------------------------------- why the peers differ
EXPLAIN_CASES = [
    ("outliers", "fish", 1.0),
    ("outliers", "dog1", 2.0),
    ("occlusion", "fish", 0.3),
    ("occlusion", "dog1", 0.3),
    ("deformation", "fish", 0.05),
    ("deformation", "dog1", 0.02),
]


def _variant_errors(cases, variants, pairs):
    """``{case: {variant: [mean error of each pair]}}``: each ``variants[name](Y, X, w)`` (the
    moving set after registration) on the suite's pairs of each (family, shape, level)."""
    out = {}
    for family, shape, level in cases:
        errs = out[(family, shape, level)] = {name: [] for name in variants}
        for pair in range(pairs):
            y, x, true = synthetic_pair(family, shape, level, pair)
            for name, fn in variants.items():
                moved = np.asarray(fn(y, x, FAMILY_W[family]), dtype=float)
                errs[name].append(float(np.mean(np.linalg.norm(moved - true, axis=1))))
    return out


# the levels where probreg is the best peer, and the level where its narrower kernel of the
# earlier runs had made it so (deformation/dog1/0.08)
EXPLAIN_PROBREG_CASES = [
    ("occlusion", "dog1", 0.0),
    ("outliers", "dog1", 1.0),
    ("noise", "dog1", 0.02),
    ("deformation", "dog1", 0.08),
]


def _explain_probreg(pairs):
    """probreg 0.3.8 with each of its departures from CPD switched off in turn, beside our dense CPD.

    Its departures: ``CoherentPointDrift._N_DIM = 3`` also for 2D data (sigma2 is the residual
    divided by 3 N_P instead of 2 N_P, and the outlier constant takes ``(2 pi sigma2)^(3/2)``),
    its kernel matrix in float32, and (in this suite's earlier runs only) a kernel of width
    ``sqrt(2)`` where CPD's is ``beta`` = 2. Each variant patches probreg's class attribute or
    kernel function for its runs and restores them.
    """
    from probreg import cpd as probreg_cpd
    from probreg import math_utils

    from centrality_vision.registration import NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]
    kernel32, n_dim = math_utils.rbf_kernel, probreg_cpd.CoherentPointDrift._N_DIM

    def kernel64(a, b, variance):
        d2 = np.sum((np.asarray(a)[:, None, :] - np.asarray(b)[None, :, :]) ** 2, axis=2)
        return np.exp(-d2 / (2.0 * variance))

    def probreg(y, x, w, *, dims=n_dim, kernel=kernel32, width=beta):
        probreg_cpd.CoherentPointDrift._N_DIM, math_utils.rbf_kernel = dims, kernel
        try:
            res = probreg_cpd.registration_cpd(
                y, x, tf_type_name="nonrigid", w=w, maxiter=max_iter, tol=tol, beta=probreg_beta(width), lmd=lam
            )
            return np.asarray(res.transformation.transform(y))
        finally:
            probreg_cpd.CoherentPointDrift._N_DIM, math_utils.rbf_kernel = n_dim, kernel32

    variants = {
        "cpd (dense)": lambda y, x, w: (
            NonRigidCPD(beta=beta, lam=lam, w=w, tol=tol, max_iter=max_iter).fit(y, x).moving_transformed_
        ),
        "probreg": lambda y, x, w: probreg(y, x, w),
        "probreg, 2 dims": lambda y, x, w: probreg(y, x, w, dims=2),
        "probreg, float64 kernel": lambda y, x, w: probreg(y, x, w, kernel=kernel64),
        "probreg, 2 dims, float64": lambda y, x, w: probreg(y, x, w, dims=2, kernel=kernel64),
        "probreg, width sqrt(2)": lambda y, x, w: probreg(y, x, w, width=math.sqrt(beta)),
    }
    rows = []
    for (family, shape, level), errs in _variant_errors(EXPLAIN_PROBREG_CASES, variants, pairs).items():
        cpd = np.array(errs["cpd (dense)"])
        better = int(np.sum(np.array(errs["probreg"]) < cpd))
        rows.append(
            [f"{family}/{shape}/{level}"] + [f"{np.mean(e):.4f}" for e in errs.values()] + [f"{better}/{pairs}"]
        )
    head = (
        f"probreg with its departures from CPD switched off in turn (mean error over {pairs} suite pairs; "
        "'2 dims': its sigma2 and outlier constant in the data's 2 dimensions instead of 3; "
        "'width sqrt(2)': the kernel the suite's earlier runs gave it)"
    )
    return head + "\n" + table(["case"] + list(variants) + ["probreg better"], rows)


# where GPD over the k-NN model with w="auto" differs most from that CPD (suite tables)
EXPLAIN_GPD_CASES = [
    ("occlusion", "fish", 0.3),
    ("occlusion", "fish", 0.4),
    ("occlusion", "dog1", 0.3),
    ("occlusion", "dog1", 0.4),
    ("noise", "fish", 0.05),
]


def _explain_gpd(pairs):
    """GPD's constant closeness prior over ``cpd-knn-auto`` with each of its parts removed.

    The prior has two parts (thesis eq. 5.10): the histogram weight ``h(m)`` of each moving
    point and the Gaussian on the centrality difference of a pair. ``bins=1`` removes the
    first (one bin: ``h`` is constant), ``phi=1e6`` the second (the Gaussian is flat); the
    last variant keeps both but gives GPD each set's centralities randomly permuted (seeded
    by the pair), so the prior's values are those of the real one but carry no topology.
    """
    from centrality_vision.registration import GPD, NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]

    def cpd():
        return NonRigidCPD(beta=beta, lam=lam, w="auto", tol=tol, max_iter=max_iter, n_neighbors=KNN)

    def gpd(**kw):
        return GPD(cpd(), centrality="closeness", graph="delaunay", **kw)

    names = ["cpd-knn-auto", "gpd-closeness-knn-auto", "no histogram (bins=1)", "no difference term (phi=1e6)"]
    names.append("centralities permuted")
    rows = []
    for family, shape, level in EXPLAIN_GPD_CASES:
        errs = {name: [] for name in names}
        for pair in range(pairs):
            y, x, true = synthetic_pair(family, shape, level, pair)
            full = gpd().fit(y, x)
            rng = np.random.default_rng([11, pair])
            fits = {
                "cpd-knn-auto": cpd().fit(y, x),
                "gpd-closeness-knn-auto": full,
                "no histogram (bins=1)": gpd(bins=1).fit(y, x),
                "no difference term (phi=1e6)": gpd(phi=1e6).fit(y, x),
                "centralities permuted": gpd().fit(
                    y,
                    x,
                    moving_centrality=rng.permutation(full.moving_centrality_),
                    fixed_centrality=rng.permutation(full.fixed_centrality_),
                ),
            }
            for name, est in fits.items():
                errs[name].append(float(np.mean(np.linalg.norm(est.moving_transformed_ - true, axis=1))))
        rows.append(
            [f"{family}/{shape}/{level}"]
            + [f"{np.mean(e):.4f}/{100 * np.mean(np.array(e) < SUCCESS_ERROR):.0f}%" for e in errs.values()]
        )
    head = (
        f"GPD's constant closeness prior over cpd-knn-auto, each part removed (mean error / success over {pairs} "
        "suite pairs)"
    )
    return head + "\n" + table(["case"] + names, rows)


# the levels that cpd-knn-auto misses by more than 5% (suite tables), and one it meets
EXPLAIN_OBJECTIVE_CASES = [
    ("occlusion", "dog1", 0.0),
    ("noise", "dog1", 0.0),
    ("deformation", "fish", 0.08),
    ("deformation", "dog1", 0.08),
]


def cpd_objective(moved, fixed, control, coefficients, width, *, lam, w):
    """Non-rigid CPD's objective at a solution, minimised over sigma2 (lower is better).

    ``-sum_n log p(x_n) + lam / 2 tr(C^T G C)`` for ``T(Y) = moved``, where ``p`` is CPD's
    mixture (``M`` Gaussians of variance ``sigma2`` at the moved points, weight ``1 - w``, and
    a constant density ``1 / N``, weight ``w``) and ``G`` the Gaussian kernel of ``width`` on
    the ``control`` points. Every library's solution is scored under this one model.
    """
    from scipy.optimize import minimize_scalar
    from scipy.special import logsumexp

    moved, fixed = np.asarray(moved, dtype=float), np.asarray(fixed, dtype=float)
    n_moving, dim = moved.shape
    n_fixed = fixed.shape[0]
    d2 = np.sum((fixed[:, None, :] - moved[None, :, :]) ** 2, axis=2)

    def nll(log_sigma2):
        s2 = math.exp(log_sigma2)
        comp = logsumexp(-d2 / (2 * s2), axis=1) - math.log(n_moving) - dim / 2 * math.log(2 * math.pi * s2)
        comp = comp + math.log1p(-w)
        return -float(np.sum(np.logaddexp(comp, math.log(w / n_fixed)) if w > 0 else comp))

    d2_min = float(np.mean(np.min(d2, axis=1)))
    centre = math.log(max(d2_min, 1e-300))
    best = minimize_scalar(nll, bounds=(centre - 20, centre + 20), method="bounded")
    c2 = np.sum((control[:, None, :] - control[None, :, :]) ** 2, axis=2)
    kernel = np.exp(-c2 / (2 * width**2))
    coefficients = np.asarray(coefficients, dtype=float)
    return best.fun + lam / 2 * float(np.sum(coefficients * (kernel @ coefficients)))


def _explain_objective(pairs):
    """Each library's solution scored by CPD's own objective, beside its error.

    A library whose solutions have a lower error but a higher objective than ours optimises
    another model (a departure), not CPD's better. Ours is fitted with ``normalize=False``
    here, so that its model is the peers' (no centring, ``beta`` in the data's units);
    ``cpd-knn-auto`` keeps its defaults and its solution is scored with the family's ``w``
    like every other.
    """
    from centrality_vision.registration import NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]

    def ours(y, x, w, **kw):
        tf = NonRigidCPD(beta=beta, lam=lam, w=w, tol=tol, max_iter=max_iter, **kw).fit(y, x).transform_
        # T(y) = L y + t + G C: the solution's own kernel width, control points and coefficients
        return tf(y), tf.control_points, tf.coefficients, tf.beta

    def peer(name):
        def run(y, x, w):
            moved, coefficients = peer_nonrigid(name, y, x, w)
            return moved, y, coefficients, beta

        return run

    methods = {
        "cpd (normalize=False)": lambda y, x, w: ours(y, x, w, normalize=False),
        "cpd-knn-auto": lambda y, x, w: ours(y, x, "auto", n_neighbors=KNN),
        **{name: peer(name) for name in PEERS},
    }
    rows = []
    for family, shape, level in EXPLAIN_OBJECTIVE_CASES:
        w = FAMILY_W[family]
        err = {name: [] for name in methods}
        obj = {name: [] for name in methods}
        for pair in range(pairs):
            y, x, true = synthetic_pair(family, shape, level, pair)
            for name, run in methods.items():
                moved, control, coefficients, width = run(y, x, w)
                err[name].append(float(np.mean(np.linalg.norm(np.asarray(moved) - true, axis=1))))
                obj[name].append(cpd_objective(moved, x, control, coefficients, width, lam=lam, w=w))
        ref = np.array(obj["cpd (normalize=False)"])
        cells = []
        for name in methods:
            diff = np.array(obj[name]) - ref
            cells.append(f"{np.mean(err[name]):.4f} {np.mean(diff):+.2f} {int(np.sum(diff < -0.01))}")
        rows.append([f"{family}/{shape}/{level}"] + cells)
    head = (
        f"each library's solution scored by CPD's objective (lam {lam:g}, beta {beta:g}, the family's w; minimised "
        f"over sigma2; lower is better), over {pairs} suite pairs. Cells: mean error, mean objective minus that of "
        "'cpd (normalize=False)' on the same pair, pairs on which it is lower by more than 0.01"
    )
    return head + "\n" + table(["case"] + list(methods), rows)


def _explain_biocpd(pairs):
    """What makes biocpd differ from CPD: each of its departures switched off in turn.

    biocpd 1.3's ``DeformableRegistration`` differs from CPD by its E-step (``use_kdtree=True``,
    ``k=10``: each moving point sees its 10 nearest fixed points), float32 and its start (no
    centring). Each is switched off in turn; ours with ``n_neighbors=10`` is run with our
    normalisation's start (both sets centred on the fixed set's mean, the caller's pose) and
    with ``normalize=False``.
    """
    import biocpd

    from centrality_vision.registration import NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]

    def bio(y, x, w, **kw):
        reg = biocpd.DeformableRegistration(
            X=x, Y=y, alpha=lam, beta=beta, low_rank=False, w=w, tolerance=tol, max_iterations=max_iter, **kw
        )
        return reg.register()[0]

    def ours(y, x, w, **kw):
        return NonRigidCPD(beta=beta, lam=lam, w=w, tol=tol, max_iter=max_iter, **kw).fit(y, x).moving_transformed_

    variants = {
        "cpd (dense)": lambda y, x, w: ours(y, x, w),
        "biocpd": lambda y, x, w: bio(y, x, w),
        "biocpd dense f32": lambda y, x, w: bio(y, x, w, use_kdtree=False),
        "biocpd dense f64": lambda y, x, w: bio(y, x, w, use_kdtree=False, dtype=np.float64),
        "biocpd knn f64": lambda y, x, w: bio(y, x, w, dtype=np.float64),
        "cpd knn10": lambda y, x, w: ours(y, x, w, n_neighbors=KNN),
        "cpd knn10 raw": lambda y, x, w: ours(y, x, w, n_neighbors=KNN, normalize=False),
        "cpd knn10 auto": lambda y, x, w: ours(y, x, "auto", n_neighbors=KNN),
    }
    lines = [f"biocpd with its departures from CPD switched off in turn; mean error over {pairs} suite pairs per case"]
    rows = [
        [f"{family}/{shape}/{level}"] + [f"{np.mean(e):.4f}" for e in errs.values()]
        for (family, shape, level), errs in _variant_errors(EXPLAIN_CASES, variants, pairs).items()
    ]
    lines.append(table(["case"] + list(variants), rows))
    return "\n".join(lines)


def _explain_trace(pairs):
    """probreg 0.3.8 beside CPD on one pair: sigma2 and error per iteration (``pairs`` unused)."""
    _preload_libusb()
    from probreg import cpd as probreg_cpd

    from centrality_vision.registration import NonRigidCPD

    beta, lam = SETTINGS["beta"], SETTINGS["lam"]
    lines = []
    y, x, true = synthetic_pair("deformation", "dog1", 0.02, 0)
    reg = probreg_cpd.NonRigidCPD(y, beta=probreg_beta(beta), lmd=lam)
    trace = []
    step = reg.maximization_step

    def traced(*a, **k):
        res = step(*a, **k)
        moved = np.asarray(res.transformation.transform(y))
        trace.append((res.sigma2, float(np.mean(np.linalg.norm(moved - true, axis=1)))))
        return res

    reg.maximization_step = traced
    reg.registration(x, w=0.0, maxiter=60, tol=0.0)
    cpd_trace = []
    NonRigidCPD(
        beta=beta,
        lam=lam,
        tol=0.0,
        max_iter=60,
        callback=lambda info: cpd_trace.append(
            (info.sigma2, float(np.mean(np.linalg.norm(info.moving_transformed - true, axis=1))))
        ),
    ).fit(y, x)
    lines.append(
        "probreg vs CPD on deformation/dog1/0.02 pair 0, 60 iterations without a stop rule: sigma2 and mean error "
        f"(probreg's kernel matrix dtype: {reg._tf_obj.g.dtype}; it divides sigma2 by 3 in 2D)"
    )
    trows = []
    for it in list(range(0, 60, 4)) + [59]:
        mine = cpd_trace[it + 1] if it + 1 < len(cpd_trace) else None
        trows.append(
            [
                it + 1,
                f"{trace[it][0]:.3g}",
                f"{trace[it][1]:.5f}",
                "-" if mine is None else f"{mine[0]:.3g}",
                "-" if mine is None else f"{mine[1]:.5f}",
            ]
        )
    lines.append(table(["iteration", "probreg sigma2", "probreg error", "cpd sigma2", "cpd error"], trows))
    return "\n".join(lines)


def _explain_smoothing(pairs):
    """Whether probreg's lead is its smoothing: our CPD at ``lam`` and at ``2/3 lam``.

    probreg takes 2D points as 3D (a zero third coordinate), so its sigma2 is 2/3 of CPD's
    and the M-step's ``lam sigma2`` acts as ``2/3 lam`` would in CPD. If our CPD at that
    ``lam`` matches probreg, probreg wins by weaker smoothing (another model), not by a
    better fit of the suite's model.
    """
    from centrality_vision.registration import NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]
    weak = lam * 2.0 / 3.0

    def ours(y, x, w, lam_used, **kw):
        reg = NonRigidCPD(beta=beta, lam=lam_used, w=w, tol=tol, max_iter=max_iter, **kw)
        return reg.fit(y, x).moving_transformed_

    methods = {
        f"cpd lam {lam:g}": lambda y, x, w: ours(y, x, w, lam),
        f"cpd lam {weak:g}": lambda y, x, w: ours(y, x, w, weak),
        f"cpd-knn-auto lam {lam:g}": lambda y, x, w: ours(y, x, "auto", lam, n_neighbors=KNN),
        f"cpd-knn-auto lam {weak:g}": lambda y, x, w: ours(y, x, "auto", weak, n_neighbors=KNN),
        f"probreg lam {lam:g}": lambda y, x, w: peer_nonrigid("probreg", y, x, w)[0],
    }
    rows = []
    for family, shape, level in EXPLAIN_OBJECTIVE_CASES:
        w = FAMILY_W[family]
        err = {name: [] for name in methods}
        for pair in range(pairs):
            y, x, true = synthetic_pair(family, shape, level, pair)
            for name, run in methods.items():
                err[name].append(float(np.mean(np.linalg.norm(np.asarray(run(y, x, w)) - true, axis=1))))
        ref = np.mean(err[f"probreg lam {lam:g}"])
        rows.append(
            [f"{family}/{shape}/{level}"] + [f"{np.mean(err[n]):.4f} ({np.mean(err[n]) / ref:.2f}x)" for n in methods]
        )
    head = (
        f"mean error over {pairs} suite pairs at the suite's lam {lam:g} and at {weak:g} (probreg's effective "
        "smoothing on 2D data); in brackets: over probreg's"
    )
    return head + "\n" + table(["case"] + list(methods), rows)


# the three levels where cpd-knn-auto missed the 5% mark in the recomputed suite, with the
# peer that beat it there
EXPLAIN_MISS_CASES = [
    ("occlusion", "dog1", 0.0, "probreg"),
    ("noise", "dog1", 0.0, "cycpd"),
    ("deformation", "fish", 0.08, "biocpd"),
]


def _explain_misses(pairs):
    """Where each remaining miss comes from, pair by pair: the k-NN model, ``w='auto'``, or the peer.

    For each level: the mean error of ``cpd-knn-auto``, of the same k-NN model at the family's
    ``w`` (the peers' setting), of the dense CPD and of the peer that beat it; how much of the
    gap to the peer the worst 2 and 5 pairs carry; and on how many pairs ``w='auto'`` estimated
    a positive weight where the family has no outliers.
    """
    from centrality_vision.registration import NonRigidCPD

    beta, lam, tol, max_iter = SETTINGS["beta"], SETTINGS["lam"], SETTINGS["tol"], SETTINGS["max_iter"]

    def fit(y, x, w, **kw):
        return NonRigidCPD(beta=beta, lam=lam, w=w, tol=tol, max_iter=max_iter, **kw).fit(y, x)

    rows = []
    for family, shape, level, peer in EXPLAIN_MISS_CASES:
        estimates = []

        def auto(y, x, w, estimates=estimates):
            reg = fit(y, x, "auto", n_neighbors=KNN)
            estimates.append(reg.w_)
            return reg.moving_transformed_

        variants = {
            "knn-auto": auto,
            "knn-w": lambda y, x, w: fit(y, x, w, n_neighbors=KNN).moving_transformed_,
            "dense": lambda y, x, w: fit(y, x, w).moving_transformed_,
            peer: lambda y, x, w, peer=peer: peer_nonrigid(peer, y, x, w)[0],
        }
        err = _variant_errors([(family, shape, level)], variants, pairs)[(family, shape, level)]
        e = {name: np.asarray(v) for name, v in err.items()}
        gap = e["knn-auto"] - e[peer]
        worst = np.sort(gap)[::-1]
        total = float(gap.sum())

        def share(n, worst=worst, total=total):
            return f"{worst[:n].sum() / total:.0%}" if total > 0 else "-"

        ratio = {name: float(v.mean() / e[peer].mean()) for name, v in e.items()}
        rows.append(
            [
                f"{family}/{shape}/{level} vs {peer}",
                f"{e['knn-auto'].mean():.4f} ({ratio['knn-auto']:.3f}x)",
                f"{e['knn-w'].mean():.4f} ({ratio['knn-w']:.3f}x)",
                f"{e['dense'].mean():.4f} ({ratio['dense']:.3f}x)",
                f"{e[peer].mean():.4f}",
                share(2),
                share(5),
                f"{int(np.sum(gap < 0))}/{pairs}",
                f"{int(np.sum(np.asarray(estimates) > 0.01))}/{pairs} (max {max(estimates):.2f})",
            ]
        )
    head = (
        f"the remaining misses, pair by pair ({pairs} suite pairs per level): mean error (in brackets: over the "
        f"peer's) of cpd-knn-auto, of the same k-NN model (k = {KNN}) at the family's w, of the dense CPD at the "
        "family's w, and of the peer; the share of cpd-knn-auto's total gap to the peer carried by its worst 2 and "
        "5 pairs; pairs where cpd-knn-auto is better; pairs where w='auto' estimated more than 0.01 (no level here "
        "has outliers)"
    )
    cols = ["level", "knn-auto", "knn w=family", "dense", "peer", "worst 2", "worst 5", "ours better", "w_ > 0.01"]
    return head + "\n" + table(cols, rows)


EXPLAIN_SECTIONS = {
    "biocpd": _explain_biocpd,
    "probreg": _explain_probreg,
    "gpd": _explain_gpd,
    "objective": _explain_objective,
    "smoothing": _explain_smoothing,
    "trace": _explain_trace,
    "misses": _explain_misses,
}


def explain(pairs, sections=None):
    """Controlled runs, one process, the suite's pairs: why peers and our variants differ from CPD.

    ``sections``: names from ``EXPLAIN_SECTIONS`` (default all, in that order).
    """
    warnings.simplefilter("ignore")
    lines = [load_line("compare within a row")]
    for name in sections or EXPLAIN_SECTIONS:
        lines += ["", EXPLAIN_SECTIONS[name](pairs)]
    return "\n".join(lines)


REPORT_ARGS = ("pairs", "trials", "bunny", "families", "angles", "methods")


def _refuse_other_report(parser, args):
    """Exit before any work if ``<out>.json`` holds a report made with other arguments.

    The finished units (``<out>.jsonl``) are keyed by their parameters and never reused under
    others, but the tables and figures are one file each: a run with other ``--pairs``,
    ``--trials``, ... would replace the stored report (the committed one is 100 pairs, 8
    trials) at its end. ``--overwrite`` allows it.
    """
    path = Path(args.out + ".json")
    if args.overwrite or not path.exists():
        return
    try:
        stored = json.loads(path.read_text()).get("args", {})
    except (OSError, UnicodeDecodeError, ValueError, AttributeError) as exc:
        parser.error(f"--out {args.out}: {path} is not a report of this suite ({exc}); give --overwrite or a new --out")
    ours = {k: getattr(args, k) for k in REPORT_ARGS}
    differ = {k: (stored.get(k), ours[k]) for k in REPORT_ARGS if stored.get(k) != ours[k]}
    if differ:
        parser.error(
            f"--out {args.out}: its report was made with other arguments "
            + ", ".join(f"{k} {old!r} (now {new!r})" for k, (old, new) in differ.items())
            + "; give those, --overwrite, or a new --out"
        )


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument(
        "--pairs", type=int, default=20, help="seeded pairs per synthetic level (the protocol's 100 is --pairs 100)"
    )
    p.add_argument("--trials", type=int, default=20, help="seeded trials per rotation angle")
    p.add_argument("--bunny", type=int, default=1000, help="bunny points (drawn once with seed 0)")
    p.add_argument("--families", default="deformation,noise,outliers,occlusion,rotation")
    p.add_argument("--methods", default=None, help="comma list; default: all")
    p.add_argument("--angles", default=",".join(map(str, ANGLES)))
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--scheduler", default="processes")
    p.add_argument(
        "--out",
        default=None,
        help="output prefix (default: results/benchmarks/registration-suite for a full run; --quick and "
        "--explain write into a scratch folder under the temporary directory, so that they never replace "
        "the committed tables)",
    )
    p.add_argument("--quick", action="store_true", help="smoke run: 2 pairs, 2 trials, angles 0,90,180")
    p.add_argument("--report-only", action="store_true", help="tables and figures from the finished units only")
    p.add_argument(
        "--overwrite", action="store_true", help="replace <out>.txt/.json/.png even if made with other arguments"
    )
    p.add_argument("--explain", type=int, default=0, help="N: the controlled runs of explain() on N pairs per case")
    p.add_argument(
        "--sections",
        default=None,
        help=f"with --explain: a comma list of {', '.join(EXPLAIN_SECTIONS)} (default all; a subset writes "
        "<out>-explain-<sections>.txt)",
    )
    args = p.parse_args(argv)
    scratch = args.out is None and bool(args.quick or args.explain)
    if args.out is None:
        args.out = str((scratch_dir() if scratch else RESULTS) / "registration-suite")
    if args.explain:
        sections = None if args.sections is None else [x.strip() for x in args.sections.split(",") if x.strip()]
        unknown = sorted(set(sections or ()) - set(EXPLAIN_SECTIONS))
        if unknown:
            p.error(f"--sections: unknown {unknown}; choose from {list(EXPLAIN_SECTIONS)}")
        text = explain(args.explain, sections)
        print(text)
        suffix = "" if sections is None else "-" + "-".join(sections)
        Path(args.out + f"-explain{suffix}.txt").write_text(text + "\n")
        print(f"written to {args.out}-explain{suffix}.txt")
        return
    if args.quick:
        args.pairs, args.trials, args.angles = 2, 2, "0,90,180"
        args.out += "-quick"
    args.families = [f.strip() for f in args.families.split(",") if f.strip()]
    args.angles = [int(a) for a in args.angles.split(",")]
    chosen = None if args.methods is None else {m.strip() for m in args.methods.split(",")}
    args.methods_nonrigid = [m for m in NONRIGID_METHODS if chosen is None or m in chosen]
    args.methods_rotation = [m for m in ROTATION_METHODS if chosen is None or m in chosen]

    from centrality_vision.experiments._runner import load_results, run_units, unit_id

    if not scratch:  # (a smoke run's scratch report is for the eye only)
        _refuse_other_report(p, args)
    units = build_units(args)
    path = Path(args.out + ".jsonl")
    print(load_line("timings are inflated; compare ratios"), flush=True)
    print(f"{len(units)} units; {len(load_results(path))} finished lines in {path}", flush=True)
    if args.report_only:
        done = load_results(path)
        wanted = len(units)
        units = [u for u in units if unit_id(u) in done]  # stored under their ids (key and digest)
        if len(units) < wanted:
            # (the stored report covers the units of its own run: one of other --pairs, --trials
            # or --angles finds fewer, and would have replaced it by a thinner or empty one)
            sys.exit(
                f"--report-only: {len(units)} of the {wanted} units asked for are finished in {path}; "
                "give the --pairs, --trials, --angles, --families and --methods of the run that wrote it "
                "(registration-suite.txt prints them), or a new --out. (Lines written before the results carried "
                "a checksum, as the committed ones of 2026-11-23, are not read.)"
            )
        results = {u.key: done[unit_id(u)] for u in units}
        args.families = [
            f
            for f in args.families
            if any((f == "rotation" and "degrees" in u.kwargs) or u.kwargs.get("family") == f for u in units)
        ]
    else:
        results = run_units(units, path, scheduler=args.scheduler, workers=args.workers, desc="registration-suite")
    text, summary = report(args, units, results)
    print(text)
    Path(args.out + ".txt").write_text(text + "\n")
    Path(args.out + ".json").write_text(json.dumps(summary, indent=1, default=str) + "\n")
    figures(args, summary, args.out)
    print(f"written to {args.out}.txt, .json, .jsonl and the figures")


if __name__ == "__main__":
    main()
