#!/usr/bin/env python
"""The dense CPD E-step alone: the kernel of an earlier commit against today's, float64 and float32.

One process, the same seeded data for every variant: M = N uniform points in the unit
square (2D), ``w = 0.1``, sigma2 from 1 to 1e-6. The earlier kernel (``--old``, a git
revision; default the commit before the rows were grouped by four) is read with
``git show`` into a temporary folder and driven exactly as ``_estep._dense`` drove it then
(the same chunking over the thread pool). Each round calls every variant once, in turn;
the table gives the median per variant over the rounds and the ratios. Before timing, each
variant's statistics are compared with the earlier kernel's: the largest difference of
``P1``, ``P X``, ``P^T 1`` and the log-denominators relative to each array's largest entry,
and whether the most probable moving point of every fixed point is the same.

Usage::

    python benchmarks/estep_dense.py                         # 1,000 3,000 10,000 points
    python benchmarks/estep_dense.py --sizes 1000 --rounds 9
"""

from __future__ import annotations

import argparse
import atexit
import importlib.util
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import load_line, table

ROOT = Path(__file__).resolve().parents[1]
KERNELS = "src/centrality_vision/registration/_kernels.py"
SIGMA2 = (1.0, 1e-2, 1e-4, 1e-6)
W = 0.1


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 3000, 10000])
    p.add_argument("--rounds", type=int, default=None, help="rounds per case (default: 7, 3 from 10,000 points)")
    p.add_argument("--old", default="2ad11df", help="git revision of the earlier kernel (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


def load_old_kernels(revision):
    """The ``_kernels`` module of ``revision``, imported under another name."""
    text = subprocess.run(
        ["git", "show", "%s:%s" % (revision, KERNELS)], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    folder = Path(tempfile.mkdtemp(prefix="estep_dense_"))
    atexit.register(shutil.rmtree, folder, True)  # (one folder was left per run)
    path = folder / "old_registration_kernels.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("old_registration_kernels", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(args):
    sys.path.insert(0, str(ROOT / "src"))
    from centrality_vision.registration import _estep as E

    old = load_old_kernels(args.old)

    def old_dense(moving_t, fixed, inv2s2, log_c):
        """``_estep._dense`` as it was: one row buffer, the old kernel's signature."""
        n_moving, n_dims = moving_t.shape
        yt = np.ascontiguousarray(moving_t.T)
        lw, vy, vx, scale, inv2phi2 = E._prior_arrays(None)
        pt1 = np.empty(fixed.shape[0])
        log_den = np.empty(fixed.shape[0])
        best = np.empty(fixed.shape[0], dtype=np.int64)

        def work(lo, hi, p1, pxt):
            row = np.empty(n_moving)
            old.dense_rows(
                fixed, yt, lo, hi, inv2s2, log_c, lw, vy, vx, scale, inv2phi2, row, p1, pxt, pt1, log_den, best
            )

        p1, pxt = E._reduce_rows(work, fixed.shape[0], n_moving, n_dims)
        return p1, pxt.T.copy(), pt1, log_den, best

    print("Dense E-step: kernel at %s ('old') against today's, float64 and float32" % args.old)
    print("M = N uniform 2D points, w = %g; median of rounds, each calling every variant once" % W)
    print(load_line())
    rng = np.random.default_rng(args.seed)
    body = []
    for n in args.sizes:
        moving_t, fixed = rng.random((n, 2)), rng.random((n, 2))
        rounds = args.rounds or (3 if n >= 10000 else 7)
        for sigma2 in SIGMA2:
            inv2s2 = 1.0 / (2.0 * sigma2)
            log_c = E.log_outlier_constant(sigma2, W, 2, n, n)
            args_ = (moving_t, fixed, inv2s2, log_c)
            variants = {
                "old": lambda a=args_: old_dense(*a),
                "float64": lambda a=args_: E._dense(*a, None, False),
                "float32": lambda a=args_: E._dense(*a, None, True),
            }
            ref = variants["old"]()
            agree = {}
            for name in ("float64", "float32"):
                got = variants[name]()
                diff = max(
                    float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)) for a, b in zip(got[:4], ref[:4])
                )
                agree[name] = (diff, bool(np.array_equal(got[4], ref[4])))
            times = {name: [] for name in variants}
            for _ in range(rounds):
                for name, call in variants.items():
                    t0 = time.perf_counter()
                    call()
                    times[name].append(time.perf_counter() - t0)
            med = {name: statistics.median(ts) for name, ts in times.items()}
            body.append(
                [
                    n,
                    "%g" % sigma2,
                    "%.2f" % (1e3 * med["old"]),
                    "%.2f" % (1e3 * med["float64"]),
                    "%.2f" % (1e3 * med["float32"]),
                    "%.2f" % (med["old"] / med["float64"]),
                    "%.2f" % (med["old"] / med["float32"]),
                    "%.2f" % (med["float64"] / med["float32"]),
                    "%.0e %s" % (agree["float64"][0], "same" if agree["float64"][1] else "DIFFERENT"),
                    "%.0e %s" % (agree["float32"][0], "same" if agree["float32"][1] else "DIFFERENT"),
                ]
            )
            print("  n=%d sigma2=%g done (%s)" % (n, sigma2, load_line()), flush=True)
    print()
    print(
        table(
            [
                "n",
                "sigma2",
                "old ms",
                "f64 ms",
                "f32 ms",
                "old/f64",
                "old/f32",
                "f64/f32",
                "f64 vs old: diff, best",
                "f32 vs old: diff, best",
            ],
            body,
        )
    )
    print(load_line())


if __name__ == "__main__":
    main(parse_args())
