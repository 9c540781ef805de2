"""Two partial scans: each set lacks a part the other has. CPD beside trimmed ICP.

CPD's outlier term models points of the fixed set that no moving point explains; it has no
term for moving points without a counterpart. Two partial scans of one object have both.
Each seeded problem draws two independent 1,000-point samples of the Stanford bunny
(../shared/data/bunny/bunny.txt, or $BUNNY) and cuts from each a 20% slab across its own
random direction; the fixed set is then turned about a random axis (by 0 degrees in the
first case, by a uniform 0-180 degrees in the others) and shifted; in the third case both
sets also get 20% uniform clutter in their bounding boxes. Rigid fits
(``scale=False``); success = rotation error below 5 degrees. In the turned cases every CPD
starts from ``init='global'``, and ICP only refines a CPD pose (it is local).

Methods: ``RigidCPD`` with w = 0.2 and 'auto'; ``ICP(trim=0.3)`` from the identity (first
case only); and the two-stage fit the ``w`` docstring advises, ``ICP(trim=0.3,
init=cpd.transform_)`` after ``RigidCPD(w='auto')``. Trimming 0.3 drops the 30% worst pairs,
a little more than the share that does not overlap.

Run:  python benchmarks/partial_overlap.py [SEEDS]   (default 20; ~1-2 min on 2 cores)
Output: printed and appended to results/benchmarks/partial_overlap.txt (``--out -``: not).
"""

import argparse
import os
import time
import warnings

import numpy as np

from centrality_vision.registration import ICP, RigidCPD

HERE = os.path.dirname(os.path.abspath(__file__))
BUNNY = os.environ.get("BUNNY", os.path.join(HERE, "..", "..", "shared", "data", "bunny", "bunny.txt"))
SUCCESS_DEGREES = 5.0


def rotation_error(found, true):
    """Angle in degrees of ``found @ true.T``."""
    return float(np.degrees(np.arccos(np.clip((np.trace(found @ true.T) - 1) / 2, -1, 1))))


def random_rotation(rng, max_degrees):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    angle = np.radians(rng.uniform(0, max_degrees))
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def problem(points, seed, max_degrees, clutter=0.0):
    rng = np.random.default_rng([7, seed])

    def scan():
        sample = points[rng.choice(len(points), 1000, replace=False)]
        direction = rng.normal(size=3)
        along = (sample - sample.mean(0)) @ (direction / np.linalg.norm(direction))
        sample = sample[along < np.quantile(along, 0.8)]
        extra = rng.uniform(sample.min(0), sample.max(0), (int(round(clutter * len(sample))), 3))
        return rng.permutation(np.vstack([sample, extra]))

    moving, fixed = scan(), scan()
    rotation = random_rotation(rng, max_degrees)
    return moving, fixed @ rotation.T + rng.normal(0, 0.05, 3), rotation


def methods(max_degrees):
    init = "global" if max_degrees else None
    out = {
        "cpd w=0.2": lambda y, x: RigidCPD(scale=False, w=0.2, init=init, random_state=0).fit(y, x),
        "cpd w=auto": lambda y, x: RigidCPD(scale=False, w="auto", init=init, random_state=0).fit(y, x),
    }
    if not max_degrees:
        out["icp trim=0.3"] = lambda y, x: ICP(trim=0.3).fit(y, x)

    def two_stage(y, x):
        cpd = RigidCPD(scale=False, w="auto", init=init, random_state=0).fit(y, x)
        return ICP(trim=0.3, init=cpd.transform_).fit(y, x)

    out["cpd w=auto + icp trim=0.3"] = two_stage
    return out


def run(seeds):
    points = np.loadtxt(BUNNY)
    lines = [
        "load average (1, 5, 15 min): %.2f %.2f %.2f  (2 cores shared: compare times as ratios)" % os.getloadavg(),
        f"two partial bunny scans (1,000 points each, a different 20% slab cut from each), rigid fits, {seeds} seeds;"
        f" success = rotation error < {SUCCESS_DEGREES:g} deg",
        f"{'case':28s} {'method':28s} {'success':>8s} {'median deg':>10s} {'max deg':>8s} {'median s':>8s}",
    ]
    cases = (("same pose", 0, 0.0), ("turned 0-180 deg, global", 180, 0.0), ("turned, 20% clutter, global", 180, 0.2))
    for label, max_degrees, clutter in cases:
        for name, fit in methods(max_degrees).items():
            errors, seconds = [], []
            for seed in range(seeds):
                moving, fixed, rotation = problem(points, seed, max_degrees, clutter)
                started = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    fitted = fit(moving, fixed)
                seconds.append(time.perf_counter() - started)
                errors.append(rotation_error(fitted.transform_.rotation, rotation))
            errors = np.array(errors)
            lines.append(
                f"{label:28s} {name:28s} {np.mean(errors < SUCCESS_DEGREES):8.0%} {np.median(errors):10.2f} "
                f"{errors.max():8.1f} {np.median(seconds):8.3f}"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("seeds", nargs="?", type=int, default=20, help="seeded problems per case (default: 20)")
    parser.add_argument(
        "--out",
        default=os.path.join(HERE, "..", "results", "benchmarks", "partial_overlap.txt"),
        help="the file the table is appended to ('-': none; default: %(default)s)",
    )
    args = parser.parse_args()
    text = run(args.seeds)
    print(text)
    if args.out != "-":
        with open(args.out, "a") as out:
            out.write(f"\n# python benchmarks/partial_overlap.py {args.seeds}\n{text}\n")
