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
    python benchmarks/shapes.py --rotation     # held-out accuracy on test shapes rotated by 15, 37, 60 degrees
    python benchmarks/shapes.py --rotation --cache DIR   # keep / reuse the centralities in DIR
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
    parser.add_argument("--cache", default=None, help="--rotation: a directory that keeps the centralities")
    args = parser.parse_args()
    if args.cv or args.rotation or args.eigenvector:
        sys.path.insert(0, os.path.dirname(__file__))
        from _common import load_line, table

        print(load_line("timings are inflated by the other processes"))
        if args.cv:
            cross_validation_jobs(table)
        if args.rotation:
            rotation(table, args.seed, args.cache)
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

    sys.path.insert(0, os.path.dirname(__file__))
    from _common import load_line

    print(f"cpus={os.cpu_count()} threads={cv.get_num_threads()}")
    print(load_line("timings are inflated by the other processes"))
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
    processes share it, each image computed once by one of them. With n_jobs=1 the
    centrality kernels already run on a pool of threads, one per core; the third
    configuration, n_jobs=1 on one kernel thread, shows what one core does alone, so the
    speed-up of the two parallel forms (threads inside a fold, processes across folds)
    can be read off. Each configuration runs three times, interleaved; the load average
    beside each run says how many cores the other processes on the machine took.
    """
    from joblib import Parallel, delayed
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.naive_bayes import GaussianNB
    from sklearn.pipeline import make_pipeline

    import centrality_vision as cv
    from centrality_vision.datasets import load_kimia99
    from centrality_vision.shapes import CentralityHistogram

    data = load_kimia99()
    folds = StratifiedKFold(5, shuffle=True, random_state=0)
    rows, scores, cpus = [], {}, {}
    # Start the two worker processes (imports, compiled kernels loaded) before timing, as
    # in a session that has used joblib once: joblib keeps its workers between calls.
    Parallel(n_jobs=2)(delayed(_warm_worker)() for _ in range(2))
    configurations = [("n_jobs=1", 1, None), ("n_jobs=2", 2, None), ("n_jobs=1, 1 thread", 1, 1)]
    for repeat in range(3):
        for label, jobs, threads in configurations:
            with tempfile.TemporaryDirectory() as cache:
                model = make_pipeline(CentralityHistogram(centrality="closeness", cache=cache), GaussianNB())
                cv.set_num_threads(threads)
                try:
                    cpu = _cpu_seconds()
                    t = time.perf_counter()
                    score = cross_val_score(model, data.images, data.labels, cv=folds, n_jobs=jobs)
                    seconds = time.perf_counter() - t
                    cpu = _cpu_seconds() - cpu
                finally:
                    cv.set_num_threads(None)
                files = len([f for f in os.listdir(cache) if f.endswith(".npy")])
            scores.setdefault(label, []).append(seconds)
            load = os.getloadavg()[0]
            rows.append(
                [
                    f"run {repeat + 1}",
                    label,
                    f"{seconds:.1f}",
                    f"{cpu:.1f}",
                    f"{score.mean():.3f}",
                    str(files),
                    f"{load:.1f}",
                ]
            )
            cpus.setdefault(label, []).append(cpu)
    print(
        "\ncross_val_score(CentralityHistogram(cache=<empty dir>) + GaussianNB, Kimia-99, 5 folds; "
        f"joblib's two workers started before the first run; {cv.get_num_threads()} kernel threads by default"
    )
    headers = ["run", "configuration", "seconds", "CPU seconds", "accuracy", "images computed", "load (1 min)"]
    print(table(headers, rows))
    median = {label: statistics.median(values) for label, values in scores.items()}
    one, two, single = median["n_jobs=1"], median["n_jobs=2"], median["n_jobs=1, 1 thread"]
    print(
        f"medians: n_jobs=1 {one:.1f} s, n_jobs=2 {two:.1f} s, n_jobs=1 on one thread {single:.1f} s: "
        f"n_jobs=2 is {one / two:.2f}x as fast as n_jobs=1; against one core, processes give "
        f"{single / two:.2f}x and the kernel's threads {single / one:.2f}x"
    )
    work = {label: statistics.median(values) for label, values in cpus.items()}
    print(
        "median CPU seconds (this process and its joblib workers): "
        + ", ".join(f"{label} {value:.1f}" for label, value in work.items())
    )


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process and of its child processes (joblib's workers) so far."""
    import psutil

    total = 0.0
    processes = [psutil.Process()]
    processes += processes[0].children(recursive=True)
    for process in processes:
        try:
            times = process.cpu_times()
        except psutil.NoSuchProcess:
            continue
        total += times.user + times.system
    return total


def _warm_worker() -> int:
    import numpy as np

    from centrality_vision.shapes import CentralityCache, shape_centralities

    square = np.zeros((6, 6), dtype=bool)
    square[1:5, 1:5] = True
    return len(shape_centralities([square], ["closeness"], cache=CentralityCache()))


def _turned(image, degrees):
    """The shape on a larger canvas turned by ``degrees`` (bilinear, thresholded at one half)."""
    from scipy import ndimage

    padded = np.pad(image, max(image.shape) // 3).astype(float)
    return ndimage.rotate(padded, degrees, order=1, reshape=True) > 0.5 if degrees else padded > 0.5


def _cropped(mask):
    rows, cols = np.nonzero(mask)
    return np.pad(mask[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1], 1)


ANGLES = (15, 37, 60)


def rotation(table, seed: int, cache=None) -> None:
    """Kimia-99, 5-fold: train on upright shapes, test on the held-out ones upright and rotated.

    Test shapes are turned by each of :data:`ANGLES`, and by 37 degrees and back (the
    resampling alone, no net rotation). Beside the accuracies: how far rotation moves a
    shape's weighted closeness histogram (L1), against how far apart shapes of one class
    are, and how much it changes a shape's mean inner distance (the 8-neighbour metric's
    anisotropy). Naive Bayes is run with scikit-learn's default ``var_smoothing`` (1e-9)
    and with ``var_smoothing`` chosen by an inner 5-fold cross-validation on the
    training shapes only.
    """
    from sklearn.base import clone
    from sklearn.model_selection import GridSearchCV, StratifiedKFold
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
    sets = {"upright": [_cropped(image) for image in data.images]}
    for angle in ANGLES:
        sets[f"{angle}"] = [_cropped(_turned(image, angle)) for image in data.images]
    sets["37 and back"] = [_cropped(_turned(_turned(image, 37), -37)) for image in data.images]
    t = time.perf_counter()
    for weights, names in ((True, list(sets)), (False, ["upright", "37"])):
        images = [image for name in names for image in sets[name]]
        shape_centralities(images, ["closeness"], weights=weights, n_jobs=2, cache=cache)
    print(
        f"  weighted closeness of {len(sets) * len(data.images)} images, hop counts of {2 * len(data.images)}: "
        f"{time.perf_counter() - t:.0f} s{' (disk cache ' + cache + ')' if cache else ''}",
        flush=True,
    )
    folds = list(StratifiedKFold(5, shuffle=True, random_state=seed).split(data.images, data.labels))
    tuned = GridSearchCV(
        GaussianNB(),
        {"var_smoothing": [1e-9, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1]},
        cv=StratifiedKFold(5, shuffle=True, random_state=seed + 1),
    )
    every = list(sets)
    models = {
        "NB closeness histogram, hops": (make_pipeline(CentralityHistogram(cache=cache), GaussianNB()), ["37"]),
        "NB closeness histogram, weights=True": (
            make_pipeline(CentralityHistogram(weights=True, cache=cache), GaussianNB()),
            every[1:],
        ),
        "  same, var_smoothing by inner CV": (
            make_pipeline(CentralityHistogram(weights=True, cache=cache), tuned),
            every[1:],
        ),
        "comparison forest closeness, hops": (
            CentralityComparisonForest(n_estimators=100, n_comparisons=500, cache=cache),
            ["37"],
        ),
        "comparison forest closeness, weights=True": (
            CentralityComparisonForest(n_estimators=100, n_comparisons=500, weights=True, cache=cache),
            every[1:],
        ),
        "  same, orientation='principal'": (
            CentralityComparisonForest(
                n_estimators=100, n_comparisons=500, weights=True, orientation="principal", cache=cache
            ),
            every[1:],
        ),
    }
    rows, chosen = [], []
    for name, (model, tests) in models.items():
        scores = {key: [] for key in ["upright", *tests]}
        for train, test in folds:
            fitted = clone(model).fit([sets["upright"][i] for i in train], data.labels[train])
            if hasattr(fitted, "steps") and hasattr(fitted[-1], "best_params_"):
                chosen.append(fitted[-1].best_params_["var_smoothing"])
            for key in scores:
                scores[key].append(np.mean(fitted.predict([sets[key][i] for i in test]) == data.labels[test]))
        upright = float(np.mean(scores["upright"]))
        cells = [f"{np.mean(scores[key]):.3f}" if key in scores else "" for key in every]
        worst = min(float(np.mean(scores[key])) - upright for key in tests)
        rows.append([name, *cells, f"{worst:+.3f}"])
        print(f"  {name}: done", flush=True)
    # 1-NN on the outline-profile distance (no training beyond the stored shapes)
    n = len(data.images)
    d = pairwise_shape_distances([image for key in every for image in sets[key]], n_jobs=2)
    scores = {key: [] for key in every}
    for train, test in folds:
        for k, key in enumerate(every):
            nearest = train[np.argmin(d[np.ix_(test + k * n, train)], axis=1)]
            scores[key].append(np.mean(data.labels[nearest] == data.labels[test]))
    upright = float(np.mean(scores["upright"]))
    worst = min(float(np.mean(scores[key])) - upright for key in every[1:])
    rows.append(["1-NN outline-profile distance", *[f"{np.mean(scores[key]):.3f}" for key in every], f"{worst:+.3f}"])
    print(
        f"\nKimia-99, 5-fold (StratifiedKFold shuffle, seed {seed}): trained on upright shapes; test shapes upright, "
        "rotated by 15, 37 and 60 degrees, and rotated by 37 and back; worst = lowest rotated minus upright"
    )
    print(table(["model", *every, "worst"], rows))
    print(f"var_smoothing chosen by the inner cross-validation in the 5 folds: {chosen}")

    records = {key: shape_centralities(sets[key], ["closeness"], weights=True, cache=cache) for key in every}
    features = {key: CentralityHistogram(weights=True, cache=cache).fit_transform(sets[key]) for key in every}
    base = features["upright"]
    apart = np.abs(base[:, None] - base[None]).sum(axis=2)
    same = (data.labels[:, None] == data.labels[None]) & ~np.eye(n, dtype=bool)
    rows = [["shapes of one class (median)", f"{np.median(apart[same]):.3f}", ""]]
    rows.append(["shapes of different classes (median)", f"{np.median(apart[~same & ~np.eye(n, dtype=bool)]):.3f}", ""])
    for key in every[1:]:
        moved = np.abs(features[key] - base).sum(axis=1)
        ratio = [
            float(np.mean(1 / turned["closeness"]) / np.mean(1 / upright["closeness"]))
            for turned, upright in zip(records[key], records["upright"])
            if np.all(turned["closeness"] > 0)
        ]
        spread = f"{np.median(ratio):.4f} ({min(ratio):.4f} to {max(ratio):.4f})"
        rows.append([f"each shape: upright vs {key} (median)", f"{np.median(moved):.3f}", spread])
    print("\nweighted closeness histograms (40 bins): L1 distances; each shape's mean inner distance turned / upright")
    print(table(["pair", "L1 between histograms", "mean distance ratio: median (range)"], rows))


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
