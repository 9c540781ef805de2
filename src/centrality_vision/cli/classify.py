"""``centrality-vision classify``: cross-validated shape classification by centrality histograms."""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

from .._validation import counted
from ._common import (
    CENTRALITY_NAMES,
    MAX_BINS,
    add_out,
    add_plot,
    add_progress,
    add_seed,
    in_path,
    number,
    options,
    progress_on,
    pyplot,
    refuse_unused,
    say,
    subparser,
)
from ._output import parameters_block, write_output

NAME = "classify"
CLASSIFIERS = ("nb", "svm", "forest")


def add_parser(sub) -> argparse.ArgumentParser:
    parser = subparser(
        sub,
        NAME,
        summary="Cross-validated shape classification of a folder of silhouettes by centrality histograms.",
        description="Every image in IMAGES_DIR (.png, .bmp, .gif, .tif, .jpg, ...) is read as a binary\n"
        "silhouette; its label is the file name without extension, trailing digits and the\n"
        "separator before them (cow1.png, cow-1.png, cow_01.png -> cow), or comes from --labels.\n"
        "Features: the normalised histogram of a pixel-graph centrality (thesis ch. 4), computed\n"
        "once per image (the histogram learns nothing from the data, so this leaks nothing\n"
        "between folds). Classifier: Gaussian naive Bayes (nb, the thesis'), an RBF support\n"
        "vector machine on standardised features (svm) or a random forest (forest). Accuracy\n"
        "by scikit-learn's cross_validate with StratifiedKFold (shuffled with --seed); each\n"
        "image is predicted by the model of the fold that did not see it, for the confusion\n"
        "matrix. If the smallest class has fewer images than --folds, the number of folds is\n"
        "reduced to its size (a note says so); every class needs 2 images.",
        example="centrality-vision classify kimia99/ --labels kimia99/labels.csv --centrality closeness \\\n"
        "    --classifier svm --out kimia.json --plot kimia_confusion.png",
    )
    parser.add_argument("images_dir", type=in_path, metavar="IMAGES_DIR", help="folder of silhouette images")
    parser.add_argument("--labels", metavar="FILE.csv", help="CSV with columns file,label (instead of the file names)")
    parser.add_argument(
        "--centrality",
        choices=CENTRALITY_NAMES + ("all",),
        default="closeness",
        help="centrality whose histogram is the feature; 'all' concatenates four (default: %(default)s)",
    )
    parser.add_argument(
        "--bins", type=number(int, low=2, high=MAX_BINS), default=40, help="histogram bins (default: %(default)s)"
    )
    parser.add_argument(
        "--connectivity", type=int, choices=(8, 4), default=8, help="pixel neighbourhood (default: %(default)s)"
    )
    parser.add_argument(
        "--scaling",
        choices=("max", "minmax"),
        default="max",
        help="values divided by their largest (max, the thesis') or mapped onto [0, 1] (minmax) before "
        "binning (default: %(default)s)",
    )
    parser.add_argument(
        "--weights",
        action="store_true",
        help="shortest paths by Euclidean pixel edge lengths (1 and sqrt 2) instead of hop counts: nearly "
        "the same features for a turned shape",
    )
    parser.add_argument(
        "--fill-holes",
        action="store_true",
        help="fill background regions enclosed by the shape first (salt noise punches such holes)",
    )
    parser.add_argument(
        "--classifier",
        choices=CLASSIFIERS,
        default="nb",
        help="nb: Gaussian naive Bayes, svm: RBF SVM, forest: random forest (default: %(default)s)",
    )
    parser.add_argument(
        "--trees",
        type=number(int, low=1, high=100_000),
        default=300,
        help="trees of --classifier forest (default: %(default)s)",
    )
    parser.add_argument(
        "--folds", type=number(int, low=2), default=5, help="cross-validation folds (default: %(default)s)"
    )
    add_seed(parser, "the fold shuffling and of the forest")
    parser.add_argument(
        "--foreground",
        choices=("auto", "dark", "light"),
        default="auto",
        help="which side of the threshold is the shape (default: %(default)s)",
    )
    add_out(parser, ".json", ".csv", what="; .csv: one row per image (file, label, predicted, fold)")
    add_plot(parser, "the confusion matrix")
    add_progress(parser)
    parser.set_defaults(run=run, _parser=parser)
    return parser


def label_of(path: Path) -> str:
    """Kimia style: ``cow1.png``, ``cow-1.png``, ``cow_01.png`` -> ``cow``; a name of digits keeps them."""
    return re.sub(r"[\s_.-]*\d+$", "", path.stem) or path.stem


def _read_labels(path) -> dict:
    import csv

    from ..exceptions import InputError

    path = Path(path)
    if not path.is_file():
        raise InputError(f"--labels: {path}: " + ("is a folder, not a CSV file." if path.is_dir() else "no such file."))
    try:
        with path.open("r", encoding="utf-8-sig", newline="") as handle:
            reader = csv.DictReader(handle)
            if reader.fieldnames is None:
                raise InputError(
                    f"--labels: {path}: the file is empty; expected a CSV with columns 'file' and 'label'."
                )
            if not {"file", "label"} <= set(reader.fieldnames):
                raise InputError(
                    f"--labels: {path}: a labels file must be a CSV with columns 'file' and 'label'; got "
                    f"{reader.fieldnames}."
                )
            labels, lines = {}, {}
            for row in reader:
                file, label = row["file"], row["label"]
                if not file or not label or not label.strip():
                    raise InputError(
                        f"--labels: {path}: line {reader.line_num} must give a file and its label; got {file!r} "
                        f"and {label!r}."
                    )
                if file in labels:  # (the last row won: a second label silently changed the truth)
                    raise InputError(
                        f"--labels: {path}: line {reader.line_num} labels {file!r} again (line {lines[file]} "
                        "did); each file must be listed once."
                    )
                labels[file], lines[file] = label, reader.line_num
            return labels
    except UnicodeDecodeError as exc:
        bad = exc.object[exc.start]
        raise InputError(
            f"--labels: {path}: must be a UTF-8 text file; got byte {bad:#04x}, not UTF-8 there."
        ) from None
    except csv.Error as exc:
        raise InputError(f"--labels: {path}: not a readable CSV file ({exc}).") from None


_APPLIES = {"trees": ("classifier", ("forest",))}  # the options one classifier uses


def _classifier(name: str, seed: int, trees: int = 300):
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.naive_bayes import GaussianNB
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    if name == "svm":
        return make_pipeline(StandardScaler(), SVC(kernel="rbf", random_state=seed))
    if name == "forest":
        return RandomForestClassifier(n_estimators=trees, random_state=seed, n_jobs=1)
    return GaussianNB()


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..exceptions import InputError
    from ..io import IMAGE_SUFFIXES, read_shape

    refuse_unused(args, _APPLIES, {"classifier": args.classifier})
    started = time.perf_counter()
    folder = Path(args.images_dir)
    if not folder.is_dir():
        raise InputError(
            f"{folder}: " + ("is a file, not a folder of images." if folder.exists() else "no such folder.")
        )
    files = sorted(path for path in folder.iterdir() if path.suffix.lower() in IMAGE_SUFFIXES and path.is_file())
    if not files:
        raise InputError(f"{folder}: holds no images ({', '.join(IMAGE_SUFFIXES)}).")
    if args.labels:
        given = _read_labels(args.labels)
        missing = [path.name for path in files if path.name not in given]
        if missing:
            raise InputError(f"{args.labels}: no label for {len(missing)} image(s), e.g. {missing[0]!r}.")
        labels = np.array([given[path.name] for path in files])
        unused = sorted(set(given) - {path.name for path in files})
        if unused:  # (a misspelt name would otherwise go unnoticed)
            say(f"note: {len(unused)} row(s) of {args.labels} name no image of {folder}, e.g. {unused[0]!r}")
    else:
        labels = np.array([label_of(path) for path in files])
    images = [read_shape(path, foreground=args.foreground) for path in files]
    classes, counts = np.unique(labels, return_counts=True)
    say(f"read {counted(len(files), 'image')} in {counted(classes.size, 'class', 'classes')} from {folder}")
    if classes.size < 2:
        raise InputError(
            f"{folder}: classification needs at least 2 classes; every image is labelled {str(classes[0])!r}."
        )
    smallest = int(counts.min())
    if smallest < 2:
        lonely = [str(name) for name in classes[counts == 1]]
        hint = (
            "" if args.labels else " (classes come from the file names less their digits; --labels FILE.csv names them)"
        )
        raise InputError(
            f"{folder}: every class needs at least 2 images for cross-validation; "
            f"{counted(len(lonely), 'class has', 'classes have')} 1, e.g. {lonely[0]!r}{hint}."
        )
    n_splits = min(args.folds, smallest)
    note = None
    if n_splits < args.folds:
        note = (
            f"the smallest class ({str(classes[np.argmin(counts)])!r}) has {smallest} images, "
            f"fewer than --folds {args.folds}: using {n_splits} folds"
        )
        say("note: " + note)

    from sklearn.metrics import confusion_matrix
    from sklearn.model_selection import StratifiedKFold, cross_validate

    from ..shapes import CentralityHistogram

    histogram = CentralityHistogram(
        centrality=args.centrality,
        bins=args.bins,
        connectivity=args.connectivity,
        scaling=args.scaling,
        weights=args.weights,
        fill_holes=args.fill_holes,
        progress=progress_on(args),
    )
    tic = time.perf_counter()
    features = histogram.fit_transform(images)
    say(f"features: {features.shape[1]} per image in {time.perf_counter() - tic:.1f} s")
    if np.all(features == features[0]):
        raise InputError(
            f"{folder}: every image has the same {args.centrality} histogram (are the shapes copies of one "
            "another?); a classifier has nothing to learn from."
        )
    model = _classifier(args.classifier, args.seed, args.trees)
    splitter = StratifiedKFold(n_splits=n_splits, shuffle=True, random_state=args.seed)
    folds = cross_validate(model, features, labels, cv=splitter, return_estimator=True, return_indices=True)
    scores = folds["test_score"]
    predicted = np.empty_like(labels)
    fold_of = np.empty(labels.size, dtype=np.int64)
    for fold, (fitted, test) in enumerate(zip(folds["estimator"], folds["indices"]["test"])):
        predicted[test] = fitted.predict(features[test])  # each image predicted by the model that did not see it
        fold_of[test] = fold
    accuracy = float(np.mean(scores))
    say(
        f"accuracy {accuracy:.3f} +- {float(np.std(scores)):.3f} over {n_splits} folds "
        f"({time.perf_counter() - started:.1f} s)"
    )
    confusion = confusion_matrix(labels, predicted, labels=classes)
    # the folds' mean accuracy weighs unequal folds equally: the matrix counts every image once
    correct = int(np.trace(confusion))
    histogram_params = {key: value for key, value in histogram.get_params().items() if key not in ("progress", "cache")}
    record = {
        "command": NAME,
        "parameters": parameters_block(
            {
                **options(args, applies=_APPLIES),
                "histogram": histogram_params,
                "classifier_estimator": " ".join(repr(model).split()),
            }
        ),
        "cross_validation": {"splitter": "StratifiedKFold(shuffle=True)", "n_splits": n_splits, "note": note},
        "accuracy": accuracy,
        "accuracy_std": float(np.std(scores)),
        "images_correct": correct,
        "pooled_accuracy": correct / labels.size,
        "fold_accuracy": scores,
        "classes": classes.tolist(),
        "class_counts": counts,
        "confusion": confusion,
        "confusion_meaning": "confusion[i][j]: images of class i predicted as class j",
        "images": [
            {"file": path.name, "label": str(truth), "predicted": str(guess), "fold": int(fold)}
            for path, truth, guess, fold in zip(files, labels, predicted, fold_of)
        ],
        "seconds": round(time.perf_counter() - started, 3),
    }
    table = {
        key: np.array([image[key] for image in record["images"]]) for key in ("file", "label", "predicted", "fold")
    }
    if args.out.lower().endswith(".csv"):
        del record["images"]  # the table holds them
    written = write_output(args.out, record, table=table)
    if args.plot:
        _plot(args, labels, predicted, classes, correct, n_splits)
        written.append(Path(args.plot))
    print(
        f"accuracy {accuracy:.3f} (mean of {n_splits} cross-validation folds; {correct} of {len(files)} images "
        f"right, {counted(classes.size, 'class', 'classes')})"
    )
    say(f"wrote {', '.join(map(str, written))}")
    return 0


def _plot(args, labels, predicted, classes, correct, n_splits) -> None:
    from sklearn.metrics import ConfusionMatrixDisplay

    from ..plotting import save_figure

    plt = pyplot()
    size = max(4.5, 0.45 * classes.size + 2)
    fig, ax = plt.subplots(figsize=(size, size))
    ConfusionMatrixDisplay.from_predictions(
        labels,
        predicted,
        labels=classes,
        ax=ax,
        cmap="Blues",
        colorbar=False,
        xticks_rotation="vertical",
        include_values=classes.size <= 20,
    )
    ax.set_title(
        f"{args.centrality} histograms, {args.classifier}: {correct} of {labels.size} right "
        f"({correct / labels.size:.2f}; {n_splits}-fold CV)"
    )
    save_figure(fig, args.plot)
