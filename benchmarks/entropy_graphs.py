"""Time and quality of the entropy graphs (MWME, MSTME) against the number of points.

One process, seeded uniform random points in the unit square. Prints

1. seconds against n for MWME greedy, local and exact, and MSTME greedy and exchange,
   with the growth exponent fitted to log(time) = a log(n) + b over the largest sizes;
2. the MWME solvers' gap to the exact optimum on 20 random sets for each n = 8..16
   (mean and worst, in percent of the optimum);
3. the objective gain of the MSTME edge exchange over the greedy, and the share of the MSTME's
   edges that are not MST edges, for both weight normalisations ("tree": weights divided by
   the MST's total length, the default; "edge": by its mean edge length), on random points
   and on the CPD fish and the Kimia-99 outlines cow1 and dog1 (100 points).

    python benchmarks/entropy_graphs.py            # n up to 2000
    python benchmarks/entropy_graphs.py --quick
    python benchmarks/entropy_graphs.py --only 3   # section 3 alone
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np


def _time(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def _exponent(ns, ts):
    ok = [(n, t) for n, t in zip(ns, ts) if t is not None and t > 1e-3]
    if len(ok) < 2:
        return float("nan")
    x, y = np.log([n for n, _ in ok[-3:]]), np.log([t for _, t in ok[-3:]])
    return float(np.polyfit(x, y, 1)[0]) if len(x) >= 2 else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--only", choices=("1", "2", "3"), default=None, help="run one section")
    args = parser.parse_args()
    if args.only == "3":
        _mstme_section(args.quick)
        return

    import centrality_vision as cv
    from centrality_vision.graphs import mstme_graph, mwme_graph

    sys.path.insert(0, os.path.dirname(__file__))
    from _common import load_line

    print(f"cpus={os.cpu_count()} threads={cv.get_num_threads()}")
    print(load_line("timings are inflated by the other processes"))
    rng = np.random.default_rng(0)
    warm = rng.random((10, 2))
    for m in ("exact", "greedy", "local"):
        mwme_graph(warm, solver=m)
    for m in ("greedy", "exchange"):
        mstme_graph(warm, solver=m)

    sizes = [50, 100, 200, 400] if args.quick else [100, 250, 500, 1000, 2000]
    limits = {"mwme local": 200 if args.quick else 500, "mstme exchange": 200 if args.quick else 400}
    rows = {
        "mwme greedy": lambda p: mwme_graph(p, solver="greedy"),
        "mwme local": lambda p: mwme_graph(p, solver="local"),
        "mstme greedy": lambda p: mstme_graph(p, lam=0.5),
        "mstme exchange": lambda p: mstme_graph(p, lam=0.5, solver="exchange"),
    }
    print("\n1. median seconds (uniform random points, default_rng(n))")
    print(f"{'method':<16}" + "".join(f"{n:>10}" for n in sizes) + f"{'exponent':>10}")
    for name, fn in rows.items():
        ts = []
        for n in sizes:
            if n > limits.get(name, 10**9):
                ts.append(None)
                continue
            points = np.random.default_rng(n).random((n, 2))
            ts.append(_time(lambda fn=fn, points=points: fn(points), 1 if n >= 1000 else 3))
        cells = "".join(f"{t:>10.3f}" if t is not None else f"{'-':>10}" for t in ts)
        print(f"{name:<16}{cells}{_exponent(sizes, ts):>10.2f}")
    exact_sizes = [10, 12, 14, 16] if args.quick else [10, 12, 14, 16, 18]
    ts = [
        _time(lambda n=n: mwme_graph(np.random.default_rng(n).random((n, 2)), solver="exact"), 1) for n in exact_sizes
    ]
    print(f"{'mwme exact':<16}" + "".join(f"{f'n={n}':>10}" for n in exact_sizes))
    print(
        f"{'':<16}"
        + "".join(f"{t:>10.3f}" for t in ts)
        + f"   (grows as 2^n n: ratio per +2 points {np.median(np.array(ts[1:]) / np.array(ts[:-1])):.1f}x)"
    )

    print("\n2. MWME gap to the exact optimum, percent (20 seeded sets per n)")
    print(f"{'n':>4}{'greedy mean':>13}{'greedy worst':>14}{'local mean':>12}{'local worst':>13}{'local optimal':>15}")
    n_sets = 8 if args.quick else 20
    for n in range(8, 17):
        gaps = {"greedy": [], "local": []}
        for s in range(n_sets):
            points = np.random.default_rng([n, s]).random((n, 2))
            best = mwme_graph(points, solver="exact").cost
            for m in gaps:
                gaps[m].append(100 * (mwme_graph(points, solver=m).cost - best) / best)
        g, loc = np.array(gaps["greedy"]), np.array(gaps["local"])
        print(
            f"{n:>4}{g.mean():>13.2f}{g.max():>14.2f}{loc.mean():>12.2f}{loc.max():>13.2f}{np.mean(loc < 1e-9):>15.2f}"
        )

    _mstme_section(args.quick)


def _mstme_section(quick: bool) -> None:
    from centrality_vision.datasets import contour_points, load_fish, load_kimia99
    from centrality_vision.graphs import mstme_graph

    print("\n3. MSTME: objective W - lam H (greedy vs exchange) and share of edges not in the MST")
    print(f"{'set':>10}{'norm':>6}{'lam':>6}{'greedy':>10}{'exchange':>10}{'gain %':>9}{'changed':>9}{'not MST':>9}")
    kimia = load_kimia99()
    sets = {f"random{n}": np.random.default_rng(n).random((n, 2)) for n in ([50, 100] if quick else [50, 100, 200])}
    sets |= {"fish": load_fish().fixed, **{name: contour_points(kimia.image(name), 100) for name in ("cow1", "dog1")}}
    for name, points in sets.items():
        for norm in ("tree", "edge"):
            for lam in (0.5, 1.0, 2.0):
                g = mstme_graph(points, lam=lam, normalize=norm)
                e = mstme_graph(points, lam=lam, normalize=norm, solver="exchange")
                changed = len(_edge_set(g.graph) ^ _edge_set(e.graph)) // 2
                gain = 100 * (g.cost - e.cost) / abs(g.cost) if g.cost else 0.0
                print(
                    f"{name:>10}{norm:>6}{lam:>6.1f}{g.cost:>10.3f}{e.cost:>10.3f}{gain:>9.2f}{changed:>9}{g.mst_share:>9.0%}"
                )


def _edge_set(graph):
    from scipy import sparse

    coo = sparse.triu(graph, k=1).tocoo()
    return set(zip(coo.row.tolist(), coo.col.tolist()))


if __name__ == "__main__":
    main()
