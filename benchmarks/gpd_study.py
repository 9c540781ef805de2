"""GPD on point sets that differ: does the centrality prior still help, and which variant does?

Two settings of the thesis, each over seeded problems (``--seeds``, default 20):

face   fig. 5.5: the 3D face under a random affine map (A = I + 0.2 N(0, 1), t ~ N(0, 1)),
       8% of the points missing on opposite sides of the two sets;
       ``AffineCPD(w=0.1, tol=1e-8, max_iter=150)``.
fish   fig. 5.7: the fish bent by a random smooth field, the dorsal fin (10 points) missing
       from the fixed set and 20 uniform outliers added;
       ``NonRigidCPD(beta=2, lam=2, w=0.2, tol=1e-8, max_iter=100)``.

Methods: CPD, and GPD with each of the thesis' four centralities (closeness, degree,
betweenness, eigenvector) under these variants of the prior:

prior      the thesis: Delaunay graphs, the prior at full weight throughout;
anneal     ``prior_schedule='anneal'``: the prior's weight scaled by sigma2 / sigma2_0;
until      ``prior_schedule=0.05``: the prior while sigma2 >= 5% of its start, then CPD;
knn        k-NN graphs (k = 8) instead of Delaunay, full prior (a graph that changes less
           when points go missing or are added far away).

Per setting, method and variant: the median error ``|T(Y) - true|`` over seeds after 10
iterations and at the end (median and mean), the
median number of iterations to reach 1% of the initial error (where reached), and in how
many seeds the method beats / loses to CPD: where both reach 1% of the initial error, by
the number of iterations to get there; where one does, that one; where neither does, by
a final error lower (higher) by more than 1%; anything else is a tie. Everything is seeded; both settings use the
library defaults otherwise (``normalize=True``).

Run:  nice -n 5 python benchmarks/gpd_study.py [--seeds 20] [--settings face fish]
      (or in parts: ``--first 0 --last 9 --save part1.json`` ..., then ``--merge part*.json``)
Output: printed tables; the committed copy is results/benchmarks/gpd_study.txt.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_line, table

from centrality_vision.exceptions import ConvergenceWarning
from centrality_vision.registration import GPD, AffineCPD, NonRigidCPD

CENTRALITIES = ("closeness", "degree", "betweenness", "eigenvector")
VARIANTS = {
    "prior": dict(graph="delaunay"),
    "anneal": dict(graph="delaunay", prior_schedule="anneal"),
    "until": dict(graph="delaunay", prior_schedule=0.05),
    "knn": dict(graph="knn", k=8),
}


def face_problem(seed):
    from centrality_vision.experiments import fig_5_5

    moving, fixed, true_moving, _, _ = fig_5_5.problem(seed)
    return moving, fixed, true_moving, AffineCPD(w=0.1, tol=1e-8, max_iter=150)


def fish_problem(seed):
    from centrality_vision.experiments import fig_5_7

    moving, fixed, true_moving = fig_5_7.problem(seed)
    return moving, fixed, true_moving, NonRigidCPD(beta=2.0, lam=2.0, w=0.2, tol=1e-8, max_iter=100)


SETTINGS = {"face": face_problem, "fish": fish_problem}


def _first_below(errors, level):
    hit = np.flatnonzero(errors <= level)
    return int(hit[0]) if hit.size else None


def run_one(estimator, moving, fixed, true_moving):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        estimator.fit(moving, fixed, true_moving=true_moving)
    errors = estimator.history_["error"]
    return {
        "final": float(errors[-1]),
        "initial": float(errors[0]),
        "at10": float(errors[min(10, errors.size - 1)]),
        "to_1pct": _first_below(errors, 0.01 * errors[0]),
    }


def study(setting, seeds):
    make = SETTINGS[setting]
    records = {}  # (variant, centrality) -> list of per-seed results; ("-", "CPD") for CPD
    for seed in seeds:
        moving, fixed, true_moving, base = make(seed)
        records.setdefault(("-", "CPD"), []).append(run_one(base, moving, fixed, true_moving))
        for variant, options in VARIANTS.items():
            for centrality in CENTRALITIES:
                gpd = GPD(base, centrality=centrality, **options)
                records.setdefault((variant, centrality), []).append(run_one(gpd, moving, fixed, true_moving))
    return records


def _compare(run, cpd) -> int:
    """+1 when ``run`` beats CPD on a seed, -1 when it loses, 0 for a tie.

    Both reach 1% of the initial error: fewer iterations wins. One reaches it: that one
    wins. Neither: a final error lower by more than 1% wins.
    """
    if run["to_1pct"] is not None and cpd["to_1pct"] is not None:
        return int(np.sign(cpd["to_1pct"] - run["to_1pct"]))
    if (run["to_1pct"] is None) != (cpd["to_1pct"] is None):
        return 1 if run["to_1pct"] is not None else -1
    if run["final"] < 0.99 * cpd["final"]:
        return 1
    return -1 if run["final"] > 1.01 * cpd["final"] else 0


def summarise(records, seeds):
    cpd = records[("-", "CPD")]
    rows = []
    for (variant, method), runs in records.items():
        finals = np.array([r["final"] for r in runs])
        at10 = np.array([r.get("at10", np.nan) for r in runs])  # NaN in parts saved before it was kept
        reached = [r["to_1pct"] for r in runs if r["to_1pct"] is not None]
        if method == "CPD":
            beats = loses = "-"
        else:
            outcomes = [_compare(r, c) for r, c in zip(runs, cpd)]
            beats, loses = f"{outcomes.count(1)}/{seeds}", f"{outcomes.count(-1)}/{seeds}"
        rows.append(
            [
                method,
                variant,
                f"{np.nanmedian(at10):.4g}" if np.any(np.isfinite(at10)) else "-",
                f"{np.median(finals):.4g}",
                f"{np.mean(finals):.4g}",
                f"{len(reached)}/{seeds}",
                "-" if not reached else f"{np.median(reached):.0f}",
                beats,
                loses,
            ]
        )
    return rows


def main(argv=None) -> int:
    import json

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds 0 .. seeds-1")
    parser.add_argument("--first", type=int, default=None, help="run only seeds first .. last")
    parser.add_argument("--last", type=int, default=None)
    parser.add_argument("--settings", nargs="+", choices=sorted(SETTINGS), default=["face", "fish"])
    parser.add_argument("--save", help="write the per-seed records to this JSON file")
    parser.add_argument("--merge", nargs="+", help="print the tables of saved JSON parts instead of running")
    args = parser.parse_args(argv)
    print(load_line())
    headers = [
        "method",
        "variant",
        "err @10 (median)",
        "final err (median)",
        "final err (mean)",
        "reached 1%",
        "iters to 1% (median)",
        "beats CPD",
        "loses to CPD",
    ]
    if args.merge:
        merged = {}
        for path in args.merge:
            for setting, part in json.loads(Path(path).read_text()).items():
                for key, runs in part["records"].items():
                    merged.setdefault(setting, {"records": {}, "seconds": 0.0})["records"].setdefault(key, []).extend(
                        runs
                    )
                merged[setting]["seconds"] += part["seconds"]
        for setting, part in merged.items():
            records = {tuple(key.split("|")): runs for key, runs in part["records"].items()}
            n = len(records[("-", "CPD")])
            print(f"\n## {setting}: {n} seeds ({part['seconds']:.0f} s in all)\n")
            print(table(headers, summarise(records, n)))
        return 0
    first = 0 if args.first is None else args.first
    last = args.seeds - 1 if args.last is None else args.last
    seeds = list(range(first, last + 1))
    saved = {}
    for setting in args.settings:
        started = time.perf_counter()
        records = study(setting, seeds)
        seconds = time.perf_counter() - started
        saved[setting] = {"records": {"|".join(key): runs for key, runs in records.items()}, "seconds": seconds}
        print(f"\n## {setting}: seeds {first}..{last} ({seconds:.0f} s)\n")
        print(table(headers, summarise(records, len(seeds))))
    if args.save:
        Path(args.save).write_text(json.dumps(saved))
    print()
    print(load_line())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
