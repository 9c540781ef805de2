"""The outlier weight w on the bunny: w = 0, 0.1, 0.3 and 'auto', with missing parts and clutter.

Each seeded problem: N_BUNNY (default 1000) points of the Stanford bunny
(../shared/data/bunny/bunny.txt, or $BUNNY), rotated by 40 degrees about a random axis and
shifted; the fixed set loses a contiguous part (the points with the smallest projection on
a random direction) and gains uniform clutter in its bounding box, optionally with noise.
Rigid CPD (normalize=True, tol=1e-8) with each w; the rotation error in degrees (median /
max over seeds), the estimate of w='auto' beside the true clutter fraction, and the median
seconds of one fit (w=0 and auto; the machine's load is printed: compare ratios).

Run:  N_BUNNY=1000 nice -n 5 python benchmarks/outlier_weight.py 5   (CONFIGS=0,1 for a subset)
Output: results/benchmarks/outlier_weight.txt
"""

import os
import sys
import time
import warnings
from multiprocessing import Pool

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
BUNNY = os.environ.get("BUNNY", os.path.join(HERE, "..", "..", "shared", "data", "bunny", "bunny.txt"))
B = np.loadtxt(BUNNY)
WS = [0.0, 0.1, 0.3, "auto"]
CONFIGS = [
    dict(missing=0.2, outliers=0.1),
    dict(missing=0.2, outliers=0.1, noise=0.01),
    dict(missing=0.0, outliers=0.0),
    dict(missing=0.2, outliers=0.5),
    dict(missing=0.4, outliers=0.3, noise=0.01),
]


if os.environ.get("CONFIGS"):  # e.g. CONFIGS=0,1: a subset of the settings above
    CONFIGS = [CONFIGS[int(i)] for i in os.environ["CONFIGS"].split(",")]


def rot_err(a, b):
    return float(np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1))))


N_POINTS = int(os.environ.get("N_BUNNY", 1000))


def problem(seed, n=N_POINTS, missing=0.2, outliers=0.1, noise=0.0, angle=40):
    rng = np.random.default_rng(seed)
    y = B[rng.choice(len(B), n, replace=False)]
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = np.radians(angle)
    r = np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k
    x = y @ r.T + rng.normal(0, 0.1, 3)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    keep = np.argsort(x @ d)[int(missing * n) :]  # a contiguous part removed
    x = x[keep] + rng.normal(0, noise, (len(keep), 3))
    lo, hi = x.min(0), x.max(0)
    x = np.vstack([x, rng.uniform(lo, hi, (int(outliers * n), 3))])
    return y, x[rng.permutation(len(x))], r, int(outliers * n) / len(x)


def one(job):
    warnings.simplefilter("ignore")
    from centrality_vision.registration import RigidCPD

    ci, seed = job
    y, x, r, frac = problem(seed, **CONFIGS[ci])
    out = []
    for w in WS:
        t0 = time.perf_counter()
        reg = RigidCPD(scale=False, w=w, tol=1e-8).fit(y, x)
        out.append((rot_err(reg.transform_.rotation, r), reg.w_, time.perf_counter() - t0))
    return ci, seed, frac, out


if __name__ == "__main__":
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    with Pool(2) as pool:
        res = pool.map(one, [(ci, s) for ci in range(len(CONFIGS)) for s in range(seeds)])
    print(
        f"bunny, {N_POINTS} moving points, rotation 40 deg about a random axis, "
        f"RigidCPD(scale=False, tol=1e-8), {seeds} seeds"
    )
    print(
        "rotation error in degrees: median / max over seeds; auto: estimated w_ (median) vs the true clutter fraction"
    )
    for ci, cfg in enumerate(CONFIGS):
        rows = [r for r in res if r[0] == ci]
        cells = []
        for wi, w in enumerate(WS):
            e = [r[3][wi][0] for r in rows]
            cells.append(f"w={w}: {np.median(e):.3f} / {np.max(e):.3f}")
        west = np.median([r[3][3][1] for r in rows])
        frac = rows[0][2]
        sec = np.median([r[3][0][2] for r in rows]), np.median([r[3][3][2] for r in rows])
        print(
            cfg, " | ".join(cells), f"| auto w_ {west:.3f} (clutter {frac:.3f}) | s w=0 {sec[0]:.2f} auto {sec[1]:.2f}"
        )
