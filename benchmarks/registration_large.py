#!/usr/bin/env python
"""Large point sets: ours (``MultiscaleCPD``) at 100,000 and 1,000,000 points, 2D and 3D.

Each case runs in its own process (so that the peak resident memory printed is that case's),
one after the other. The data are seeded and the transforms known, so every row reports the
RMS distance of the registered moving set to the true positions (``RMS``) beside the initial
one. Cases:

* ``outline``: points along the Kimia-99 ``dog1`` outline (``registration.py``'s large-case
  data), 2D, noise 0.5% of the 3-unit extent; rigid (30 degrees, scale 1.2, shift) and
  non-rigid (a smooth sine field of 5% of the extent).
* ``bunny``: the Stanford bunny's points (``../shared/data/bunny``) drawn with replacement and
  jittered by 0.5% of its extent, scaled to 3 units, 3D; rigid (30 degrees about (1, 1, 1),
  scale 1.2), affine (a shear) and non-rigid (0.15 sin of the other coordinates).
* ``uniform``: points uniform in a 3-unit square (``registration.py --million``'s data): no
  structure but the square's edges at the scale of a subsample, the hard case for any
  coarse-to-fine scheme.

Where a full-resolution fit fits in time (rigid, 100,000 outline points; non-rigid, 20,000),
it runs too, and the coarse-to-fine result is compared with it.

Run: ``nice -n 5 python benchmarks/registration_large.py [--n 1000000] [--cases ...]``.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import resource
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_line, table

ROOT = Path(__file__).resolve().parent.parent
BUNNY = ROOT.parent / "shared" / "data" / "bunny" / "bunny.txt"
NOISE = 0.015  # 0.5% of the 3-unit extent


def _rotation_3d(degrees):
    k = np.ones(3) / math.sqrt(3.0)
    a = math.radians(degrees)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx


def problem(data, case, n, seed=0):
    """``(moving, fixed, true_moving)``: fixed rows shuffled, noise ``NOISE``."""
    rng = np.random.default_rng([seed, n, len(data), len(case)])
    if data == "outline":
        import registration as r

        args = r.parse_args([])
        pr = r.make_problem("rigid" if case == "rigid" else "nonrigid", n, args, shape="outline:dog1")
        return pr.moving, pr.fixed, pr.true_moving
    if data == "uniform":
        import registration as r

        return r._scaled_problem(n, 2, case, seed)
    base = np.loadtxt(BUNNY)
    extent = float(np.ptp(base, axis=0).max())
    y = base[rng.integers(0, len(base), n)] + rng.normal(0.0, 0.005 * extent, (n, 3))
    y = (y - y.mean(axis=0)) * (3.0 / extent)
    if case == "rigid":
        true = 1.2 * y @ _rotation_3d(30.0).T + 0.2
    elif case == "affine":
        true = y @ (np.eye(3) + 0.15 * np.triu(np.ones((3, 3)), 1) + 0.05 * np.eye(3)).T - 0.1
    else:
        true = y + 0.15 * np.column_stack([np.sin(y[:, 1]), np.sin(y[:, 0]), np.sin(y[:, 0] + y[:, 1])])
    fixed = true + rng.normal(0.0, NOISE, true.shape)
    return y, fixed[rng.permutation(n)], true


def _estimator(case, how):
    from centrality_vision.registration import AffineCPD, MultiscaleCPD, NonRigidCPD, RigidCPD

    make = {
        "rigid": lambda: RigidCPD(tol=1e-5),
        "affine": lambda: AffineCPD(tol=1e-5),
        "nonrigid": lambda: NonRigidCPD(beta=2.0, lam=2.0, tol=1e-5),
    }[case]
    if how == "full":
        return make()
    if how == "multiscale":
        return MultiscaleCPD(make())
    return MultiscaleCPD(make(), sizes=(5_000, 20_000, int(how.split("+")[1])))


def _one(data, case, n, how, queue):
    y, x, true = problem(data, case, n)
    est = _estimator(case, how)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a full-resolution fit may stop at max_iter: reported by n_iter
        t = time.perf_counter()
        est.fit(y, x)
        seconds = time.perf_counter() - t
    rms = float(np.sqrt(np.mean(np.sum((est.moving_transformed_ - true) ** 2, axis=1))))
    initial = float(np.sqrt(np.mean(np.sum((y - true) ** 2, axis=1))))
    levels = getattr(est, "levels_", None)
    detail = (
        ", ".join("%d pts %d it %.1f s" % (lv["n_moving"], lv["n_iter"], lv["seconds"]) for lv in levels)
        if levels
        else "full resolution, %d iterations" % est.n_iter_
    )
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    queue.put((seconds, rms, initial, peak, detail, est.moving_transformed_ if n <= 200_000 else None))


def run_case(data, case, n, how):
    """One fit in a fresh process: (seconds, RMS, initial RMS, peak MiB, levels, T(Y) or None)."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_one, args=(data, case, n, how, queue))
    proc.start()
    out = queue.get()
    proc.join()
    return out


CASES = {
    "outline": ("rigid", "nonrigid"),
    "bunny": ("rigid", "affine", "nonrigid"),
    "uniform": ("rigid",),
}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=1_000_000, help="points per set of the large cases")
    p.add_argument("--data", default=",".join(CASES), help="comma list of %s" % ", ".join(CASES))
    p.add_argument("--compare", action="store_true", help="also the full-resolution comparisons (minutes)")
    args = p.parse_args(argv)
    print("MultiscaleCPD defaults (sizes=(5000, 20000), refine_max_iter=10); each case in a fresh process")
    print(load_line())
    rows = []
    for data in [d.strip() for d in args.data.split(",") if d.strip()]:
        for case in CASES[data]:
            if data == "bunny" and not BUNNY.exists():
                print("  ! %s not found: bunny cases skipped" % BUNNY)
                break
            sec, rms, initial, peak, detail, _ = run_case(data, case, args.n, "multiscale")
            dim = 3 if data == "bunny" else 2
            rows.append(
                [data, f"{dim}D", case, f"{args.n:,}", f"{sec:.2f}", f"{rms:.3e}", f"{initial:.3f}", f"{peak:.0f}"]
            )
            print("  %-8s %-9s n=%d  %.2f s  RMS %.3e  (%s)" % (data, case, args.n, sec, rms, detail), flush=True)
    print()
    print(table(["data", "D", "case", "n", "seconds", "RMS", "initial RMS", "peak RSS MiB"], rows))
    if args.compare:
        print("\nfull resolution beside coarse to fine (outline data):")
        crow = []
        for case, n, hows in (
            ("rigid", 100_000, ("full", "multiscale", "multiscale+100000")),
            ("nonrigid", 20_000, ("full", "multiscale")),
        ):
            outs = {how: run_case("outline", case, n, how) for how in hows}
            ref = outs["full"][5]
            for how, (sec, rms, _initial, peak, detail, moved) in outs.items():
                diff = float(np.sqrt(np.mean(np.sum((moved - ref) ** 2, axis=1))))
                crow.append([case, f"{n:,}", how, f"{sec:.2f}", f"{rms:.3e}", f"{diff:.2e}", f"{peak:.0f}", detail])
                print("  %-8s %-18s %.2f s RMS %.3e (%s)" % (case, how, sec, rms, detail), flush=True)
        print()
        print(
            table(
                ["case", "n", "fit", "seconds", "RMS to truth", "RMS to full fit", "peak RSS MiB", "levels"],
                crow,
                align=["<", ">", "<", ">", ">", ">", ">", "<"],
            )
        )
    print(load_line())


if __name__ == "__main__":
    main()
