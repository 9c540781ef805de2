"""Time the Table 4.1 shape experiment: per image per centrality, and the whole run.

One process, the bundled Kimia-99 images. Prints the median seconds per image for each
centrality on the 8-neighbour pixel graphs (noiseless and 10% salt noise), then runs the
whole Table 4.1 experiment (99 images x 4 noise levels, naive Bayes on 5 histogram
features and 3 comparison forests, with 5-fold held-out accuracy) with a cold cache and
prints its wall-clock time, split into centralities and classifiers.

    python benchmarks/shapes.py            # full
    python benchmarks/shapes.py --quick    # 27 images, for a smoke run

Three other measurements, each on its own (outputs committed in results/benchmarks/):

    python benchmarks/shapes.py --cv           # cross_val_score n_jobs=1 vs 2, cold shared disk cache
    python benchmarks/shapes.py --rotation     # held-out accuracy on test shapes rotated by 37 degrees
    python benchmarks/shapes.py --eigenvector  # why eigenvector histograms collapse under salt noise
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cv", action="store_true")
    parser.add_argument("--rotation", action="store_true")
    parser.add_argument("--eigenvector", action="store_true")
    args = parser.parse_args()
    if args.cv or args.rotation or args.eigenvector:
        sys.path.insert(0, os.path.dirname(__file__))
        from _common import load_line, table

        print(load_line("timings are inflated by the other processes"))
        if args.cv:
            cross_validation_jobs(table)
        if args.rotation:
            rotation(table, args.seed)
        if args.eigenvector:
            eigenvector_collapse(table, args.seed)
        print(load_line("timings are inflated by the other processes"))
        return

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
    print(
        f"\nwhole Table 4.1 run ({result.n_images} images x {len(result.noise_levels)} noise levels, cold cache): "
        f"{total:.1f} s  (centralities {result.seconds['centralities']:.1f} s, "
        f"classifiers {result.seconds['classifiers']:.1f} s)"
    )
    print(table_4_1.format_table(result))


def cross_validation_jobs(table) -> None:
    """5-fold cross_val_score of closeness histograms + naive Bayes on Kimia-99, n_jobs=1 vs 2.

    Each run starts with an empty cache directory (cold): with n_jobs=2 the two worker
    processes share it, each image computed once by one of them.
    """
    from joblib import Parallel, delayed
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.naive_bayes import GaussianNB
    from sklearn.pipeline import make_pipeline

    from centrality_vision.datasets import load_kimia99
    from centrality_vision.shapes import CentralityHistogram

    data = load_kimia99()
    folds = StratifiedKFold(5, shuffle=True, random_state=0)
    rows, scores = [], {}
    # Start the two worker processes (imports, compiled kernels loaded) before timing, as
    # in a session that has used joblib once: joblib keeps its workers between calls.
    Parallel(n_jobs=2)(delayed(_warm_worker)() for _ in range(2))
    for repeat in range(2):
        for jobs in (1, 2):
            with tempfile.TemporaryDirectory() as cache:
                model = make_pipeline(CentralityHistogram(centrality="closeness", cache=cache), GaussianNB())
                t = time.perf_counter()
                score = cross_val_score(model, data.images, data.labels, cv=folds, n_jobs=jobs)
                seconds = time.perf_counter() - t
                files = len([f for f in os.listdir(cache) if f.endswith(".npy")])
            scores.setdefault(jobs, []).append(seconds)
            rows.append([f"run {repeat + 1}", str(jobs), f"{seconds:.1f}", f"{score.mean():.3f}", str(files)])
    print(
        "\ncross_val_score(CentralityHistogram(cache=<empty dir>) + GaussianNB, Kimia-99, 5 folds; "
        "joblib's two workers started before the first run"
    )
    print(table(["run", "n_jobs", "seconds", "accuracy", "images computed"], rows))
    one, two = statistics.median(scores[1]), statistics.median(scores[2])
    print(f"median n_jobs=1 {one:.1f} s, n_jobs=2 {two:.1f} s: n_jobs=2 is {one / two:.2f}x as fast")


def _warm_worker() -> int:
    import numpy as np

    from centrality_vision.shapes import CentralityCache, shape_centralities

    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    return len(shape_centralities([square], ["closeness"], cache=CentralityCache()))


def _rotate(image, degrees):
    from scipy import ndimage

    padded = np.pad(image, max(image.shape) // 3).astype(float)
    return ndimage.rotate(padded, degrees, order=1, reshape=True) > 0.5


def rotation(table, seed: int) -> None:
    """Kimia-99, 5-fold: train on upright shapes, test on the held-out ones upright and rotated by 37 degrees."""
    from sklearn.model_selection import StratifiedKFold
    from sklearn.naive_bayes import GaussianNB
    from sklearn.pipeline import make_pipeline

    from centrality_vision.datasets import load_kimia99
    from centrality_vision.shapes import (
        CentralityComparisonForest,
        CentralityHistogram,
        pairwise_shape_distances,
        shape_centralities,
    )

    data = load_kimia99()
    rotated = [_rotate(image, 37) for image in data.images]
    t = time.perf_counter()
    for weights in (False, True):  # once, in parallel, into the in-memory cache the models read
        shape_centralities(list(data.images) + rotated, ["closeness"], weights=weights, n_jobs=2)
    print(f"  closeness of {2 * len(rotated)} images, hops and weighted: {time.perf_counter() - t:.0f} s", flush=True)
    folds = list(StratifiedKFold(5, shuffle=True, random_state=seed).split(data.images, data.labels))
    models = {
        "NB closeness histogram, hops": make_pipeline(CentralityHistogram(), GaussianNB()),
        "NB closeness histogram, weights=True": make_pipeline(CentralityHistogram(weights=True), GaussianNB()),
        "comparison forest closeness, hops": CentralityComparisonForest(n_estimators=100, n_comparisons=500),
        "comparison forest closeness, weights=True": CentralityComparisonForest(
            n_estimators=100, n_comparisons=500, weights=True
        ),
    }
    rows = []
    for name, model in models.items():
        upright, turned = [], []
        t = time.perf_counter()
        for train, test in folds:
            from sklearn.base import clone

            fitted = clone(model).fit([data.images[i] for i in train], data.labels[train])
            upright.append(np.mean(fitted.predict([data.images[i] for i in test]) == data.labels[test]))
            turned.append(np.mean(fitted.predict([rotated[i] for i in test]) == data.labels[test]))
        a, b = float(np.mean(upright)), float(np.mean(turned))
        rows.append([name, f"{a:.3f}", f"{b:.3f}", f"{b - a:+.3f}", f"{time.perf_counter() - t:.0f}"])
        print(f"  {name}: done", flush=True)
    # 1-NN on the outline-profile distance (no training beyond the stored shapes)
    d = pairwise_shape_distances(list(data.images) + rotated, n_jobs=2)
    n = len(data.images)
    upright, turned = [], []
    for train, test in folds:
        upright.append(np.mean(data.labels[train[np.argmin(d[np.ix_(test, train)], axis=1)]] == data.labels[test]))
        turned.append(np.mean(data.labels[train[np.argmin(d[np.ix_(test + n, train)], axis=1)]] == data.labels[test]))
    a, b = float(np.mean(upright)), float(np.mean(turned))
    rows.append(["1-NN outline-profile distance", f"{a:.3f}", f"{b:.3f}", f"{b - a:+.3f}", ""])
    print(
        f"\nKimia-99, 5-fold (StratifiedKFold shuffle, seed {seed}): trained on upright shapes; "
        "test shapes upright and rotated by 37 degrees"
    )
    print(table(["model", "upright", "rotated 37", "difference", "seconds"], rows))


def eigenvector_collapse(table, seed: int) -> None:
    """Localisation of the leading eigenvector under salt noise, and the hole-filling fix."""
    from scipy import ndimage
    from sklearn.naive_bayes import GaussianNB

    from centrality_vision import centrality as cen
    from centrality_vision.datasets import load_kimia99
    from centrality_vision.graphs import pixel_graph, salt_noise
    from centrality_vision.shapes import CentralityHistogram

    data = load_kimia99()
    levels = (0.0, 0.01, 0.05, 0.10)
    noisy = {
        level: [
            salt_noise(image, level, seed=np.random.default_rng([seed, j, i])) if level else image
            for i, image in enumerate(data.images)
        ]
        for j, level in enumerate(levels)
    }

    def participation(x):  # share of the nodes the unit vector effectively spreads over
        return float((x**2).sum() ** 2 / (x**4).sum() / x.size)

    rows = []
    for fill in (False, True):
        for level in levels:
            ratios, first_bin, top_share = [], [], []
            for mask in noisy[level]:
                graph, _ = pixel_graph(ndimage.binary_fill_holes(mask) if fill else mask)
                x = cen.eigenvector(graph)
                ratios.append(participation(x))
                first_bin.append(float(np.mean(x < 1 / 40)))
                top = np.sort(x**2)[::-1]
                top_share.append(float(top[: max(1, top.size // 100)].sum() / top.sum()))
            rows.append(
                [
                    "holes filled" if fill else "as thesis",
                    f"{level:.0%}",
                    f"{np.median(ratios):.3f}",
                    f"{np.median(first_bin):.3f}",
                    f"{np.median(top_share):.3f}",
                ]
            )
    print("\nLeading adjacency eigenvector of the Kimia-99 pixel graphs (medians over 99 images)")
    print(table(["graph", "noise", "participation ratio", "share in bin 1 of 40", "mass on top 1% pixels"], rows))

    rows = []
    for fill in (False, True):
        model = CentralityHistogram(centrality="eigenvector", fill_holes=fill)
        classifier = GaussianNB().fit(model.fit_transform(noisy[0.0]), data.labels)
        accuracy, majority = [], []
        for level in levels:
            predicted = classifier.predict(model.transform(noisy[level]))
            accuracy.append(f"{np.mean(predicted == data.labels):.2f}")
            classes, counts = np.unique(predicted, return_counts=True)
            majority.append(f"{classes[np.argmax(counts)]} x{counts.max()}")
        rows.append([f"fill_holes={fill}", *accuracy, majority[1]])
    print("\nNaive Bayes on eigenvector histograms, trained on clean Kimia-99, tested on all 99 at each noise")
    print(table(["features", "0%", "1%", "5%", "10%", "most predicted at 1%"], rows))


if __name__ == "__main__":
    main()
