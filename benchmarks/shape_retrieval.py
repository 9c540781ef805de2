"""Shape retrieval on the field's protocols: MPEG-7 bullseye, Kimia-99 top-10, MPEG-7 1-NN.

One process. Prints, beside the published numbers:

- Kimia-99 (bundled): for ranks 1..10, how many of the 99 queries find a shape of their
  class there (the query left out); total out of 990.
- MPEG-7 CE-Shape-1 part B (not bundled; ``--mpeg7 DIR``, default the shared data folder):
  the bullseye score (same-class shapes among the 40 nearest, query included, out of
  28,000) and the nearest-neighbour accuracy with 10 training shapes per class (mean of
  10 random splits), plus the wall-clock time of all 1,400 x 1,400 distances.
- Kimia-216: not run (the data is not available here).

Each distance is given as it is and after diffusion re-ranking (reported separately).

    python benchmarks/shape_retrieval.py                    # everything, about 10 min on 2 busy cores
    python benchmarks/shape_retrieval.py --skip-mpeg7       # Kimia-99 only
    python benchmarks/shape_retrieval.py --methods profile  # the outline-profile distance only
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
from _common import load_line, table

PUBLISHED_BULLSEYE = [
    ("shape context (Belongie et al. 2002)", 76.51),
    ("inner-distance shape context (Ling and Jacobs 2007)", 85.40),
    ("shape tree (Felzenszwalb and Schwartz 2007)", 87.70),
    ("height functions (Wang et al. 2012)", 90.35),
]
PUBLISHED_KIMIA99 = [
    ("shape context", [97, 91, 88, 85, 84, 77, 75, 66, 56, 37]),
    ("inner-distance shape context", [99, 99, 99, 98, 98, 97, 97, 98, 94, 79]),
    ("height functions", [99, 99, 99, 99, 98, 99, 99, 96, 95, 88]),
]
# The histogram methods (the thesis' features, weighted closeness) on shapes resized to
# about 32 x 32 pixels; the profile method at its default 48 x 48.
METHODS = {
    "profile": {"method": "profile"},
    "closeness chi2": {"method": "chi2", "centrality": "closeness", "resolution": 32},
    "closeness EMD": {"method": "emd", "centrality": "closeness", "resolution": 32},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mpeg7", default=None, help="folder of the MPEG-7 GIFs (default: the shared data folder)")
    parser.add_argument("--skip-mpeg7", action="store_true")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    parser.add_argument("--n-jobs", type=int, default=2)
    args = parser.parse_args()

    from centrality_vision.datasets import load_kimia99, load_mpeg7
    from centrality_vision.shapes import (
        bullseye_score,
        diffusion_rerank,
        nearest_neighbour_accuracy,
        pairwise_shape_distances,
        retrieval_counts,
    )

    print(f"cores={os.cpu_count()} n_jobs={args.n_jobs}")
    print(load_line("timings are inflated by the other processes"))
    kimia = load_kimia99()
    rows = [[name, *counts, sum(counts)] for name, counts in PUBLISHED_KIMIA99]
    for name in args.methods:
        t = time.perf_counter()
        d = pairwise_shape_distances(kimia.images, n_jobs=args.n_jobs, **METHODS[name])
        seconds = time.perf_counter() - t
        for tag, matrix in ((name, d), (name + " + diffusion", diffusion_rerank(d))):
            counts = retrieval_counts(matrix, kimia.labels, k=10).tolist()
            rows.append([f"ours: {tag}" + (f" ({seconds:.0f} s)" if matrix is d else ""), *counts, sum(counts)])
    print("\nKimia-99: queries (of 99) with a same-class shape at each rank; total of 990")
    print(table(["method", *map(str, range(1, 11)), "total"], rows))

    if args.skip_mpeg7:
        return
    t = time.perf_counter()
    mpeg7 = load_mpeg7(args.mpeg7)
    print(f"\nMPEG-7: {len(mpeg7)} shapes read in {time.perf_counter() - t:.0f} s")
    rows = [[name, f"{score:.2f}", "", ""] for name, score in PUBLISHED_BULLSEYE]
    for name in args.methods:
        t = time.perf_counter()
        d = pairwise_shape_distances(mpeg7.images, n_jobs=args.n_jobs, **METHODS[name])
        seconds = time.perf_counter() - t
        for tag, matrix in ((name, d), (name + " + diffusion", diffusion_rerank(d))):
            bullseye = 100 * bullseye_score(matrix, mpeg7.labels)
            accuracy = 100 * nearest_neighbour_accuracy(matrix, mpeg7.labels, n_train=10, n_splits=10, seed=0)
            rows.append([f"ours: {tag}", f"{bullseye:.2f}", f"{accuracy:.2f}", f"{seconds:.0f}" if matrix is d else ""])
        print(f"  {name}: {len(mpeg7)} x {len(mpeg7)} distances in {seconds:.0f} s on {args.n_jobs} jobs", flush=True)
    print("\nMPEG-7 bullseye (%) and 1-NN accuracy with 10 training shapes per class (%, mean of 10 splits)")
    print(table(["method", "bullseye", "1-NN acc", "seconds"], rows))
    print("\nKimia-216 top-11: not run, the data set is not available here.")
    print(load_line("timings are inflated by the other processes"))


if __name__ == "__main__":
    main()
