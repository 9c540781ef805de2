"""Time the Table 4.1 shape experiment: per image per centrality, and the whole run.

One process, the bundled Kimia-99 images. Prints the median seconds per image for each
centrality on the 8-neighbour pixel graphs (noiseless and 10% salt noise), then runs the
whole Table 4.1 experiment (99 images x 4 noise levels, naive Bayes on 5 histogram
features and 3 comparison forests, with 5-fold held-out accuracy) with a cold cache and
prints its wall-clock time, split into centralities and classifiers.

    python benchmarks/shapes.py            # full
    python benchmarks/shapes.py --quick    # 27 images, for a smoke run
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    import centrality_vision as cv
    from centrality_vision import centrality as cen
    from centrality_vision.datasets import load_kimia99
    from centrality_vision.experiments import table_4_1
    from centrality_vision.graphs import pixel_graph, salt_noise
    from centrality_vision.shapes import SHAPE_CENTRALITIES, default_cache

    print(f"cpus={os.cpu_count()} threads={cv.get_num_threads()}")
    data = load_kimia99()
    images = data.images[:: 11 if args.quick else 1]
    # warm-up: compile the kernels
    warm, _ = pixel_graph(images[0])
    for name in SHAPE_CENTRALITIES:
        cen.compute(warm, name)

    print(f"\nper image, {len(images)} Kimia-99 images (mean {np.mean([im.sum() for im in images]):.0f} pixels):")
    print(f"{'centrality':<14}{'noiseless median s':>20}{'10% noise median s':>20}{'total s':>10}")
    for name in SHAPE_CENTRALITIES:
        times = {0.0: [], 0.1: []}
        for i, image in enumerate(images):
            for rate in times:
                graph, _ = pixel_graph(salt_noise(image, rate, seed=i) if rate else image)
                t = time.perf_counter()
                cen.compute(graph, name)
                times[rate].append(time.perf_counter() - t)
        total = sum(sum(v) for v in times.values())
        print(f"{name:<14}{statistics.median(times[0.0]):>20.4f}{statistics.median(times[0.1]):>20.4f}{total:>10.2f}")

    default_cache.clear()
    t = time.perf_counter()
    result = table_4_1.run(quick=args.quick, seed=args.seed, progress=False)
    total = time.perf_counter() - t
    print(f"\nwhole Table 4.1 run ({result.n_images} images x {len(result.noise_levels)} noise levels, cold cache): "
          f"{total:.1f} s  (centralities {result.seconds['centralities']:.1f} s, classifiers {result.seconds['classifiers']:.1f} s)")
    print(table_4_1.format_table(result))


if __name__ == "__main__":
    main()
