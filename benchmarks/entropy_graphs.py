"""Time and quality of the entropy graphs (MWME, MSTME) against the number of points.

One process, seeded uniform random points in the unit square. Prints

1. seconds against n for MWME greedy, local and exact, and MSTME greedy and exchange,
   with the growth exponent fitted to log(time) = a log(n) + b over the largest sizes;
2. the MWME solvers' gap to the exact optimum on 20 random sets for each n = 8..16
   (mean and worst, in percent of the optimum);
3. the objective gain of the MSTME edge exchange over the greedy.

    python benchmarks/entropy_graphs.py            # n up to 2000
    python benchmarks/entropy_graphs.py --quick
"""

from __future__ import annotations

import argparse
import os
import statistics
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
    args = parser.parse_args()

    import centrality_vision as cv
    from centrality_vision.graphs import mstme_graph, mwme_graph

    print(f"cpus={os.cpu_count()} threads={cv.get_num_threads()}")
    rng = np.random.default_rng(0)
    warm = rng.random((10, 2))
    for m in ("exact", "greedy", "local"):
        mwme_graph(warm, method=m)
    for m in ("greedy", "exchange"):
        mstme_graph(warm, method=m)

    sizes = [50, 100, 200, 400] if args.quick else [100, 250, 500, 1000, 2000]
    limits = {"mwme local": 200 if args.quick else 500, "mstme exchange": 200 if args.quick else 400}
    rows = {
        "mwme greedy": lambda p: mwme_graph(p, method="greedy"),
        "mwme local": lambda p: mwme_graph(p, method="local"),
        "mstme greedy": lambda p: mstme_graph(p, lam=0.5),
        "mstme exchange": lambda p: mstme_graph(p, lam=0.5, method="exchange"),
    }
    print(f"\n1. median seconds (uniform random points, default_rng(n))")
    print(f"{'method':<16}" + "".join(f"{n:>10}" for n in sizes) + f"{'exponent':>10}")
    for name, fn in rows.items():
        ts = []
        for n in sizes:
            if n > limits.get(name, 10**9):
                ts.append(None)
                continue
            points = np.random.default_rng(n).random((n, 2))
            ts.append(_time(lambda: fn(points), 1 if n >= 1000 else 3))
        cells = "".join(f"{t:>10.3f}" if t is not None else f"{'-':>10}" for t in ts)
        print(f"{name:<16}{cells}{_exponent(sizes, ts):>10.2f}")
    exact_sizes = [10, 12, 14, 16] if args.quick else [10, 12, 14, 16, 18]
    ts = [_time(lambda: mwme_graph(np.random.default_rng(n).random((n, 2)), method="exact"), 1) for n in exact_sizes]
    print(f"{'mwme exact':<16}" + "".join(f"{f'n={n}':>10}" for n in exact_sizes))
    print(f"{'':<16}" + "".join(f"{t:>10.3f}" for t in ts) + f"   (grows as 2^n n: ratio per +2 points {np.median(np.array(ts[1:]) / np.array(ts[:-1])):.1f}x)")

    print("\n2. MWME gap to the exact optimum, percent (20 seeded sets per n)")
    print(f"{'n':>4}{'greedy mean':>13}{'greedy worst':>14}{'local mean':>12}{'local worst':>13}{'local optimal':>15}")
    n_sets = 8 if args.quick else 20
    for n in range(8, 17):
        gaps = {"greedy": [], "local": []}
        for s in range(n_sets):
            points = np.random.default_rng([n, s]).random((n, 2))
            best = mwme_graph(points, method="exact").cost
            for m in gaps:
                gaps[m].append(100 * (mwme_graph(points, method=m).cost - best) / best)
        g, l = np.array(gaps["greedy"]), np.array(gaps["local"])
        print(f"{n:>4}{g.mean():>13.2f}{g.max():>14.2f}{l.mean():>12.2f}{l.max():>13.2f}{np.mean(l < 1e-9):>15.2f}")

    print("\n3. MSTME (normalised weights): objective W - lam H, greedy vs exchange")
    print(f"{'n':>6}{'lam':>6}{'greedy':>10}{'exchange':>10}{'gain %':>9}{'edges changed':>15}")
    for n in ([50, 100] if args.quick else [50, 100, 200]):
        points = np.random.default_rng(n).random((n, 2))
        for lam in (0.5, 2.0, 5.0, 10.0):
            g, e = mstme_graph(points, lam=lam), mstme_graph(points, lam=lam, method="exchange")
            changed = len(_edge_set(g.graph) ^ _edge_set(e.graph)) // 2
            print(f"{n:>6}{lam:>6.1f}{g.cost:>10.3f}{e.cost:>10.3f}{100 * (g.cost - e.cost) / abs(g.cost):>9.2f}{changed:>15}")


def _edge_set(graph):
    from scipy import sparse

    coo = sparse.triu(graph, k=1).tocoo()
    return set(zip(coo.row.tolist(), coo.col.tolist()))


if __name__ == "__main__":
    main()
