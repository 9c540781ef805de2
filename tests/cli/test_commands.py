import json
import os

import numpy as np
import pytest

from centrality_vision import __version__, cli
from centrality_vision.cli import main
from centrality_vision.transforms import NonRigidTransform


def test_demo_writes_figures_and_results(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    names = {p.name for p in tmp_path.iterdir()}
    assert {
        "fish_delaunay_closeness.png",
        "fish_delaunay_centralities.png",
        "cow1_closeness.png",
        "fish_registration.png",
        "fish_registration_errors.png",
        "demo.json",
    } <= names
    record = json.loads((tmp_path / "demo.json").read_text())
    assert record["graph"]["n_nodes"] == 91
    with np.load(tmp_path / "fish_delaunay_centralities.npz") as saved:
        closeness_values = saved["closeness"]
    assert closeness_values.shape == (91,) and np.all(closeness_values > 0)
    assert "most central points by closeness" in capsys.readouterr().out
    rms = record["registration"]["final_rms"]
    assert rms["CPD"] < 1e-6 and rms["GPD (closeness)"] < 1e-6  # both recover the similarity


def test_demo_unknown_shape_is_a_one_line_error(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "demo"), "--shape", "unicorn"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unicorn" in err[0] and "--shape: must be one of" in err[0]
    assert not (tmp_path / "demo").exists()  # the folder was made before the name was checked


def test_no_command_prints_help_as_a_usage_error(capsys):
    # audit 26 L8: no command printed the help and exited 0, as if something had run
    assert main([]) == 2
    captured = capsys.readouterr()
    assert "demo" in captured.err and not captured.out


def test_reproduce_rejects_unknown_experiment(capsys):
    with pytest.raises(SystemExit) as info:
        main(["reproduce", "table-9.9"])
    assert info.value.code == 2
    assert "invalid choice" in capsys.readouterr().err


# --------------------------------------------------------------------------------------
# capability subcommands: graph, centrality, register, match, classify
# --------------------------------------------------------------------------------------


def _points(n=12, seed=0, dim=2):
    return np.random.default_rng(seed).random((n, dim))


def _png(path, pixels):
    from skimage.io import imsave

    imsave(path, np.asarray(pixels, dtype=np.uint8), check_contrast=False)
    return path


def _one_line_error(capsys, *, only=False):
    """The error line on stderr: the last line, the only one saying "error:" (the only line at all if ``only``)."""
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert "Traceback" not in err and lines and "error:" in lines[-1], err
    assert sum("error:" in line for line in lines) == 1, err
    if only:
        assert len(lines) == 1, err
    return lines[-1]


def _rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.mark.parametrize("out", ["g.json", "g.npz", "g.csv"])
def test_graph_delaunay_has_3n_3_h_edges(tmp_path, out):
    from scipy.spatial import ConvexHull

    points = _points()
    np.savetxt(tmp_path / "p.txt", points)
    assert main(["graph", str(tmp_path / "p.txt"), "--kind", "delaunay", "--out", str(tmp_path / out)]) == 0
    n, h = len(points), len(ConvexHull(points).vertices)
    if out.endswith(".json"):
        record = json.loads((tmp_path / out).read_text())
        edges = np.array(record["edges"])
        assert record["n_edges"] == 3 * n - 3 - h
        assert record["parameters"]["kind"] == "delaunay" and record["parameters"]["version"] == __version__
        i, j, length = edges[:, 0].astype(int), edges[:, 1].astype(int), edges[:, 2]
    elif out.endswith(".npz"):
        with np.load(tmp_path / out, allow_pickle=False) as saved:
            i, j = saved["edges"].T
            length = saved["lengths"]
            assert json.loads(str(saved["parameters"]))["kind"] == "delaunay"
    else:
        table = np.loadtxt(tmp_path / out, delimiter=",", skiprows=1)
        i, j, length = table[:, 0].astype(int), table[:, 1].astype(int), table[:, 2]
        side = json.loads((tmp_path / "g.json").read_text())
        assert side["columns"] == ["i", "j", "length"] and side["parameters"]["kind"] == "delaunay"
    assert len(i) == 3 * n - 3 - h and np.all(i < j)
    assert np.allclose(length, np.linalg.norm(points[i] - points[j], axis=1))


@pytest.mark.parametrize(
    ("kind", "extra", "n_edges"),
    [
        ("emst", [], 11),
        ("complete", [], 66),
        ("mstme", ["--lam", "1.5"], 11),
        ("mwme", [], None),
        ("knn", ["--k", "3"], None),
    ],
)
def test_graph_kinds_and_plot(tmp_path, kind, extra, n_edges):
    np.save(tmp_path / "p.npy", _points())
    argv = [
        "graph",
        str(tmp_path / "p.npy"),
        "--kind",
        kind,
        *extra,
        "--out",
        str(tmp_path / "g.json"),
        "--plot",
        str(tmp_path / "g.png"),
    ]
    assert main(argv) == 0
    record = json.loads((tmp_path / "g.json").read_text())
    assert (tmp_path / "g.png").stat().st_size > 0
    if n_edges is not None:
        assert record["n_edges"] == n_edges
    if kind == "mwme":  # n - 1 distinct degrees
        assert len(set(record["degrees"])) == 11
    if kind == "knn":
        assert record["parameters"]["k"] == 3 and record["n_edges"] >= 12 * 3 // 2
    if kind == "mstme":
        assert record["parameters"]["lam"] == 1.5 and record["entropy"] > 0


def test_centrality_of_points_matches_the_graph(tmp_path):
    from centrality_vision.centrality import closeness
    from centrality_vision.graphs import delaunay_graph

    points = _points()
    np.savetxt(tmp_path / "p.csv", points, delimiter=",", header="x,y", comments="")
    out = tmp_path / "c.csv"
    assert (
        main(
            [
                "centrality",
                str(tmp_path / "p.csv"),
                "--centrality",
                "all",
                "--out",
                str(out),
                "--plot",
                str(tmp_path / "c.png"),
            ]
        )
        == 0
    )
    lines = out.read_text().splitlines()
    parameters = json.loads((tmp_path / "c.json").read_text())["parameters"]
    assert parameters["centrality"] == "all" and parameters["graph"] == "delaunay" and "seed" not in parameters
    header = lines[0].split(",")
    assert header == ["node", "x", "y", *cli.CENTRALITY_NAMES]
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    graph = delaunay_graph(points)
    assert np.array_equal(table[:, 0], np.arange(12)) and np.allclose(table[:, 1:3], points)
    assert np.array_equal(table[:, 3], (graph > 0).sum(axis=1))
    assert np.allclose(table[:, 5], closeness(graph))
    assert (tmp_path / "c.png").stat().st_size > 0

    assert (
        main(
            [
                "centrality",
                str(tmp_path / "p.csv"),
                "--centrality",
                "closeness",
                "--weights",
                "--out",
                str(tmp_path / "w.npy"),
            ]
        )
        == 0
    )
    side = json.loads((tmp_path / "w.json").read_text())
    assert side["columns"] == ["node", "x", "y", "closeness"] and side["parameters"]["weights"] is True
    assert np.allclose(np.load(tmp_path / "w.npy")[:, 3], closeness(graph, weights=True))


def test_centrality_of_an_image_gives_pixel_coordinates(tmp_path, capsys):
    pixels = np.full((7, 8), 255)  # a dark 3 x 3 square on white, Kimia style
    pixels[2:5, 3:6] = 0
    _png(tmp_path / "square.png", pixels)
    out = tmp_path / "c.json"
    assert (
        main(
            [
                "centrality",
                str(tmp_path / "square.png"),
                "--centrality",
                "degree",
                "--out",
                str(out),
                "--plot",
                str(tmp_path / "c.png"),
            ]
        )
        == 0
    )
    record = json.loads(out.read_text())
    assert record["input_kind"] == "image" and record["image_shape"] == [7, 8] and record["n_nodes"] == 9
    rows, cols = np.array(record["coordinates"]["row"]), np.array(record["coordinates"]["col"])
    degree = np.zeros((7, 8))
    degree[rows, cols] = record["centrality"]["degree"]
    assert degree[2:5, 3:6].tolist() == [[3, 5, 3], [5, 8, 5], [3, 5, 3]]
    assert "9 foreground pixels" in capsys.readouterr().err
    assert (tmp_path / "c.png").stat().st_size > 0


@pytest.mark.parametrize("out", ["r.json", "r.npz"])
def test_register_recovers_a_known_similarity(tmp_path, out):
    from centrality_vision.datasets import load_fish

    moving = load_fish().fixed
    rotation, translation, scale = _rotation(0.4), np.array([0.5, -0.2]), 1.3
    fixed = scale * moving @ rotation.T + translation
    np.savetxt(tmp_path / "moving.txt", moving)
    np.save(tmp_path / "fixed.npy", fixed)
    np.save(tmp_path / "true.npy", fixed)
    argv = [
        "register",
        str(tmp_path / "moving.txt"),
        str(tmp_path / "fixed.npy"),
        "--method",
        "cpd",
        "--transform",
        "similarity",
        "--tol",
        "1e-10",
        "--max-iter",
        "500",
        "--true-moving",
        str(tmp_path / "true.npy"),
        "--out",
        str(tmp_path / out),
        "--plot",
        str(tmp_path / "r.png"),
    ]
    assert main(argv) == 0
    if out.endswith(".json"):
        record = json.loads((tmp_path / out).read_text())
        transform, parameters = record["transform"], record["parameters"]
        history_error = record["history"]["alignment_rms"]
        assert record["fixed_to_moving"] == list(range(91))
    else:
        with np.load(tmp_path / out, allow_pickle=False) as saved:
            record = {key: saved[key] for key in saved.files}
        transform = {key.removeprefix("transform_"): record[key] for key in record if key.startswith("transform_")}
        parameters = json.loads(str(record["parameters"]))
        history_error = record["history_alignment_rms"]
    assert str(transform["type"]) == "similarity"
    assert abs(float(transform["scale"]) - scale) < 1e-6
    assert np.allclose(transform["rotation"], rotation, atol=1e-6) and np.allclose(
        transform["translation"], translation, atol=1e-6
    )
    assert np.allclose(record["moving_transformed"], fixed, atol=1e-6)
    assert bool(record["converged"]) and int(record["n_iter"]) >= 1 and float(record["final_alignment_rms"]) < 1e-6
    assert len(history_error) == int(record["n_iter"]) + 1
    assert parameters["tol"] == 1e-10 and parameters["max_iter"] == 500 and parameters["method"] == "cpd"
    assert (tmp_path / "r.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("method", "transform", "kind"),
    [
        ("icp", "rigid", "rigid"),
        ("gpd", "rigid", "rigid"),
        ("gpd", "nonrigid", "nonrigid"),
        ("cpd", "affine", "affine"),
    ],
)
def test_register_methods_and_transforms(tmp_path, method, transform, kind):
    moving = _points(30, seed=1)
    fixed = moving @ _rotation(0.05).T + 0.01
    np.save(tmp_path / "m.npy", moving)
    np.save(tmp_path / "f.npy", fixed)
    argv = [
        "register",
        str(tmp_path / "m.npy"),
        str(tmp_path / "f.npy"),
        "--method",
        method,
        "--transform",
        transform,
        "--tol",
        "1e-8",
        "--out",
        str(tmp_path / "r.json"),
        "--plot",
        str(tmp_path / "r.png"),
    ]
    assert main(argv) == 0
    record = json.loads((tmp_path / "r.json").read_text())
    assert record["transform"]["type"] == kind
    assert np.allclose(record["moving_transformed"], fixed, atol=1e-3)
    assert (record["sigma2"] is None) == (method == "icp")
    assert ("fixed_centrality" in record) == (method == "gpd")
    assert (tmp_path / "r.png").stat().st_size > 0
    # the written transform alone reproduces the registration (the nonrigid record dropped
    # the affine part before the field: 0.7 off on the fish)
    parts = {k: np.asarray(v) for k, v in record["transform"].items() if k != "type"}
    if kind == "nonrigid":
        fields = ("linear", "translation", "input_origin", "output_origin")
        rebuilt = NonRigidTransform(
            parts["control_points"], parts["coefficients"], float(parts["beta"]), **{f: parts[f] for f in fields}
        )
        np.testing.assert_allclose(rebuilt(moving), record["moving_transformed"], atol=1e-9)
    elif kind == "affine":
        np.testing.assert_allclose(moving @ parts["linear"].T + parts["translation"], record["moving_transformed"])
    else:
        moved = float(parts["scale"]) * moving @ parts["rotation"].T + parts["translation"]
        np.testing.assert_allclose(moved, record["moving_transformed"])


def test_register_icp_refuses_affine(tmp_path, capsys):
    np.save(tmp_path / "m.npy", _points())
    argv = [
        "register",
        str(tmp_path / "m.npy"),
        str(tmp_path / "m.npy"),
        "--method",
        "icp",
        "--transform",
        "affine",
        "--out",
        str(tmp_path / "r.json"),
    ]
    assert main(argv) == 2
    assert "ICP fits rigid or similarity transforms only" in _one_line_error(capsys, only=True)


def test_register_reports_non_convergence_as_a_one_line_warning(tmp_path, capsys):
    np.save(tmp_path / "m.npy", _points(20))
    np.save(tmp_path / "f.npy", _points(20, seed=3))
    argv = [
        "register",
        str(tmp_path / "m.npy"),
        str(tmp_path / "f.npy"),
        "--max-iter",
        "1",
        "--tol",
        "1e-12",
        "--out",
        str(tmp_path / "r.json"),
    ]
    assert main(argv) == 0
    record = json.loads((tmp_path / "r.json").read_text())
    assert record["converged"] is False and record["n_iter"] == 1
    assert record["warnings"] and record["warnings"][0].startswith("ConvergenceWarning")
    warnings_on_stderr = [line for line in capsys.readouterr().err.splitlines() if "warning:" in line]
    assert len(warnings_on_stderr) == 1


def test_match_recovers_a_permutation(tmp_path):
    fixed = _points(12, seed=4)
    perm = np.random.default_rng(5).permutation(12)
    moving = 0.5 * fixed[perm] @ _rotation(1.0).T + 3.0
    np.savetxt(tmp_path / "m.txt", moving)
    np.savetxt(tmp_path / "f.txt", fixed)
    argv = [
        "match",
        str(tmp_path / "m.txt"),
        str(tmp_path / "f.txt"),
        "--method",
        "mwme",
        "--mwme-solver",
        "greedy",
        "--out",
        str(tmp_path / "m.json"),
        "--plot",
        str(tmp_path / "m.png"),
    ]
    assert main(argv) == 0
    record = json.loads((tmp_path / "m.json").read_text())
    assert record["correspondence"] == perm.tolist()
    assert abs(record["transform"]["scale"] - 2.0) < 1e-9 and record["rms_residual"] < 1e-9
    assert record["parameters"]["mwme_solver"] == "greedy" and (tmp_path / "m.png").stat().st_size > 0


def _shapes_folder(folder, *, extra=()):
    """Kimia-style files: dark silhouettes on white, label = name without digits."""
    folder.mkdir()
    yy, xx = np.mgrid[:24, :24]
    for k, radius in enumerate((6, 8, 10), start=1):
        disk = (yy - 12) ** 2 + (xx - 12) ** 2 <= radius**2
        _png(folder / f"disk{k}.png", np.where(disk, 0, 255))
        bar = np.zeros((24, 24), bool)
        bar[12 - k : 12 + k, 2:22] = True
        _png(folder / f"bar{k}.png", np.where(bar, 0, 255))
    for name in extra:
        _png(folder / name, np.where((yy - 12) ** 2 + (xx - 12) ** 2 <= 25, 0, 255))
    return folder


def test_classify_cross_validates_with_fewer_folds_when_classes_are_small(tmp_path, capsys):
    folder = _shapes_folder(tmp_path / "shapes")
    out = tmp_path / "c.json"
    assert (
        main(["classify", str(folder), "--centrality", "degree", "--bins", "8", "--seed", "3", "--out", str(out)]) == 0
    )
    record = json.loads(out.read_text())
    assert record["classes"] == ["bar", "disk"] and record["class_counts"] == [3, 3]
    assert record["cross_validation"]["n_splits"] == 3 and "using 3 folds" in record["cross_validation"]["note"]
    assert len(record["fold_accuracy"]) == 3 and record["accuracy"] == pytest.approx(np.mean(record["fold_accuracy"]))
    images = record["images"]
    assert sorted(image["file"] for image in images) == sorted(p.name for p in folder.iterdir())
    assert all(image["label"] == image["file"].removesuffix(".png").rstrip("0123456789") for image in images)
    assert record["accuracy"] == pytest.approx(np.mean([image["label"] == image["predicted"] for image in images]))
    assert np.sum(record["confusion"]) == 6
    # the folds' mean weighs folds equally; the pooled share counts images, as the matrix does
    right = sum(image["label"] == image["predicted"] for image in images)
    assert record["images_correct"] == right == np.trace(record["confusion"])
    assert record["pooled_accuracy"] == pytest.approx(right / 6)
    assert record["parameters"]["seed"] == 3 and record["parameters"]["histogram"]["bins"] == 8
    captured = capsys.readouterr()
    assert "using 3 folds" in captured.err and "warning:" not in captured.err and captured.out.startswith("accuracy")


def test_classify_passes_the_histogram_options_on(tmp_path):
    """The command line had no way to set the histogram's connectivity, scaling, weights or
    hole filling; the record shows the histogram they made."""
    from centrality_vision.io import read_shape
    from centrality_vision.shapes import CentralityHistogram

    folder = _shapes_folder(tmp_path / "shapes")
    out = tmp_path / "c.json"
    options = ["--connectivity", "4", "--scaling", "minmax", "--weights", "--fill-holes"]
    assert main(["classify", str(folder), "--centrality", "closeness", "--bins", "8", *options, "--out", str(out)]) == 0
    histogram = json.loads(out.read_text())["parameters"]["histogram"]
    assert histogram["connectivity"] == 4 and histogram["scaling"] == "minmax"
    assert histogram["weights"] is True and histogram["fill_holes"] is True
    # the features are the estimator's with those settings
    files = sorted(folder.iterdir())
    images = [read_shape(path) for path in files]
    same = CentralityHistogram("closeness", bins=8, connectivity=4, scaling="minmax", weights=True, fill_holes=True)
    default = CentralityHistogram("closeness", bins=8)
    assert not np.array_equal(same.fit_transform(images), default.fit_transform(images))


def test_classify_refuses_features_that_never_vary(tmp_path, capsys):
    # found by a fuzz run: GaussianNB's divide-by-zero warnings were printed and every
    # image got one prediction
    folder = tmp_path / "copies"
    folder.mkdir()
    yy, xx = np.mgrid[:24, :24]
    for name in ("a1", "a2", "b1", "b2"):
        _png(folder / f"{name}.png", np.where((yy - 12) ** 2 + (xx - 12) ** 2 <= 36, 0, 255))
    assert main(["classify", str(folder), "--centrality", "degree", "--out", str(tmp_path / "c.json")]) == 2
    message = _one_line_error(capsys)
    assert "every image has the same degree histogram" in message and "copies" in message


@pytest.mark.parametrize("name", ["disk1.png", "new.PNG"])
def test_classify_refuses_a_plot_among_its_input_images(tmp_path, capsys, name):
    # found by fuzz round 15: --plot IMAGES_DIR/disk1.png replaced that silhouette with the
    # confusion figure (exit 0), and a new name added an image of its own class to the next run
    folder = _shapes_folder(tmp_path / "shapes")
    before = {path.name: path.read_bytes() for path in folder.iterdir()}
    argv = ["classify", str(folder), "--out", str(tmp_path / "c.json"), "--plot", str(folder / name)]
    assert main(argv) == 2
    assert "is an image in IMAGES_DIR, whose images are the input" in _one_line_error(capsys, only=True)
    assert before == {path.name: path.read_bytes() for path in folder.iterdir()}


def test_classify_notes_label_rows_that_name_no_image(tmp_path, capsys):
    folder = _shapes_folder(tmp_path / "shapes")
    rows = [f"{path.name},{path.stem.rstrip('0123456789')}" for path in sorted(folder.iterdir())]
    (tmp_path / "labels.csv").write_text("file,label\n" + "\n".join(rows + ["dsik1.png,disk"]) + "\n")
    argv = ["classify", str(folder), "--labels", str(tmp_path / "labels.csv"), "--out", str(tmp_path / "c.json")]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "note: 1 row(s) of" in err and "name no image of" in err and "'dsik1.png'" in err


def test_classify_needs_two_images_per_class(tmp_path, capsys):
    folder = _shapes_folder(tmp_path / "shapes", extra=["star1.png"])
    assert main(["classify", str(folder), "--out", str(tmp_path / "c.json")]) == 2
    message = _one_line_error(capsys)
    assert "'star'" in message and "--labels FILE.csv names them" in message  # (Kimia names: 'bonefishes')


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such file"),
        ("0 0 0 0\n1 1 1 1\n2 0 1 1\n", "columns"),
        ("0 0\nnan 1\n1 1\n", "NaN"),
        ("0 0\n1 1 1\n", "line 2"),
        ("", "no points"),
    ],
)
@pytest.mark.parametrize("command", ["graph", "centrality", "register", "match"])
def test_bad_point_files_are_one_line_errors(tmp_path, capsys, command, content, message):
    path = tmp_path / "bad.txt"
    if content is not None:
        path.write_text(content)
    good = tmp_path / "good.txt"
    np.savetxt(good, _points())
    argv = {
        "graph": ["graph", str(path), "--out", str(tmp_path / "g.json")],
        "centrality": ["centrality", str(path), "--out", str(tmp_path / "c.json")],
        "register": ["register", str(good), str(path), "--out", str(tmp_path / "r.json")],
        "match": ["match", str(path), str(good), "--out", str(tmp_path / "m.json")],
    }[command]
    assert main(argv) == 2
    line = _one_line_error(capsys, only=True)
    assert str(path) in line and message in line
    assert not list(tmp_path.glob("[gcrm].json"))


@pytest.mark.parametrize(
    ("content", "message"), [(b"GIF89a not a png", "not a readable PNG image"), (b"", "empty"), (None, "no such file")]
)
def test_bad_images_are_one_line_errors(tmp_path, capsys, content, message):
    path = tmp_path / "bad.png"
    if content is not None:
        path.write_bytes(content)
    assert main(["centrality", str(path), "--out", str(tmp_path / "c.json")]) == 2
    line = _one_line_error(capsys, only=True)
    assert str(path) in line and message in line


def test_other_input_errors_are_one_line(tmp_path, capsys):
    np.savetxt(tmp_path / "p.txt", _points(5))
    np.savetxt(tmp_path / "q.txt", _points(6))
    assert main(["graph", str(tmp_path / "p.txt"), "--kind", "knn", "--k", "5", "--out", str(tmp_path / "g.json")]) == 2
    assert "--k must be smaller" in _one_line_error(capsys)
    argv = ["match", str(tmp_path / "p.txt"), str(tmp_path / "q.txt"), "--method", "mwme"]
    argv += ["--out", str(tmp_path / "m.json")]
    assert main(argv) == 2
    assert "same size" in _one_line_error(capsys)
    assert main(["classify", str(tmp_path / "nowhere"), "--out", str(tmp_path / "c.json")]) == 2
    assert "no such folder" in _one_line_error(capsys)
    import imageio.v3 as iio

    iio.imwrite(tmp_path / "s.png", (np.arange(64).reshape(8, 8) * 4).astype(np.uint8))
    assert main(["centrality", str(tmp_path / "s.png"), "--threshold", "nan", "--out", str(tmp_path / "c.csv")]) == 2
    assert "--threshold must be a finite real number" in _one_line_error(capsys)


@pytest.mark.parametrize(
    "argv",
    [
        ["graph", "p.txt", "--out", "g.json", "--colour", "red"],
        ["graph", "p.txt", "--kind", "voronoi", "--out", "g.json"],
        ["graph", "p.txt", "--out", "g.xlsx"],
        ["centrality", "p.txt"],
        ["register", "m.txt", "f.txt", "--tol", "-1", "--out", "r.json"],
        ["register", "m.txt", "f.txt", "--columns", "", "--out", "r.json"],  # "internal error" before
        ["graph", "m.txt", "--columns", "x,,y", "--out", "g.json"],
        ["classify", "shapes", "--folds", "1", "--out", "c.json"],
    ],
)
def test_usage_errors_are_one_line_with_status_2(capsys, argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and f"centrality-vision {argv[0]}: error:" in err and "--help" in err


@pytest.mark.parametrize("command", ["graph", "centrality", "register", "match", "classify", "demo", "reproduce"])
def test_each_subcommand_has_help_with_an_example(capsys, command):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert f"centrality-vision {command}" in text and "example:" in text and "--out" in text


def test_choice_lists_match_the_library():
    from centrality_vision import cli
    from centrality_vision.centrality import CENTRALITIES
    from centrality_vision.registration import GRAPHS

    assert cli.CENTRALITY_NAMES == tuple(CENTRALITIES)
    assert set(cli.GPD_GRAPHS) == set(GRAPHS) - {"edgeless"}
    from centrality_vision.cli import _common
    from centrality_vision.graphs._entropy import LAM_MAX
    from centrality_vision.registration._cpd import KERNEL_RANGE
    from centrality_vision.shapes._histogram import MAX_BINS

    assert _common.MAX_BINS == MAX_BINS and _common.KERNEL_RANGE == KERNEL_RANGE and _common.LAM_MAX == LAM_MAX


def test_option_ranges_are_the_library_ranges(tmp_path, capsys):
    # fuzz round 6: --lam was checked against [0, inf) and then failed in the library at
    # 1e308; w's message gave [0.0, 1.0] for the range [0, 1)
    np.savetxt(tmp_path / "p.txt", np.random.default_rng(0).random((8, 2)))
    with pytest.raises(SystemExit):
        main(["graph", str(tmp_path / "p.txt"), "--kind", "mstme", "--lam", "1e308", "--out", str(tmp_path / "g.json")])
    assert "--lam: must be in [0, 1e+300]; got 1e308" in capsys.readouterr().err
    from centrality_vision.matching import match

    with pytest.raises(ValueError, match=r"`w` must be a finite number in \[0, 1\); got 1\.0"):
        match(np.eye(3), np.eye(3), w=1.0)
    with pytest.raises(ValueError, match=r"`w` must be a finite number in \[0, 1\); got 5\.0"):
        match(np.eye(3), np.eye(3), w=np.uint8(5))


def test_reproduce_runs_an_experiment_and_resumes_with_a_scheduler(tmp_path, capsys):
    assert main(["reproduce", "table-2.1", "--out", str(tmp_path)]) == 0
    assert "0.83 | 0.83" in capsys.readouterr().out
    assert (tmp_path / "table-2.1" / "table-2.1.json").is_file()
    args = ["reproduce", "fig-6.4", "--quick", "--seeds", "2", "--out", str(tmp_path), "--scheduler", "serial"]
    assert main(args) == 0
    lines = (tmp_path / "fig-6.4" / "fig-6.4-quick.jsonl").read_text().splitlines()
    assert len(lines) == 2 * 9  # one unit per seed and image, every 11th of the 99
    assert main(args) == 0  # a re-run finds every unit done and recomputes nothing
    assert (tmp_path / "fig-6.4" / "fig-6.4-quick.jsonl").read_text().splitlines() == lines


def test_reproduce_scheduler_only_where_it_applies(tmp_path, capsys):
    assert main(["reproduce", "table-2.1", "--out", str(tmp_path), "--scheduler", "serial"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--scheduler" in err and len(err.splitlines()) == 1


def test_reproduce_seeds_reach_the_claims_and_are_checked(tmp_path, capsys):
    assert main(["reproduce", "fig-5.3", "--quick", "--seeds", "2", "--out", str(tmp_path)]) == 0
    assert "of 2 seeds" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:  # argparse's usage error
        main(["reproduce", "fig-5.3", "--quick", "--seeds", "0", "--out", str(tmp_path)])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "argument --seeds: must be in [1, 100000]; got 0" in err


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--workers", "0"], "argument --workers: must be in [1, 1024]"),
        (["--workers", "-1"], "argument --workers: must be in [1, 1024]"),
        (["--seed", "-1"], "argument --seed: must be in [0,"),
        (["--seeds", "99999999999999999999999"], "argument --seeds: must be in [1, 100000]"),
        (["--seeds", "abc"], "argument --seeds: must be an integer"),
    ],
)
@pytest.mark.parametrize("experiment", ["fig-5.3", "all"])
def test_reproduce_checks_its_numbers_before_running_anything(tmp_path, capsys, experiment, options, message):
    with pytest.raises(SystemExit) as info:
        main(["reproduce", experiment, "--quick", *options, "--out", str(tmp_path)])
    assert info.value.code == 2
    assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing ran


@pytest.mark.parametrize("scheduler", ["tcp://", "tcp://localhost:notaport", "tcp://[::1", "tcp://host:70000", "bogus"])
def test_reproduce_refuses_a_malformed_scheduler_address(tmp_path, capsys, scheduler):
    assert main(["reproduce", "fig-5.3", "--quick", "--scheduler", scheduler, "--out", str(tmp_path)]) == 2
    assert "--scheduler must be one of" in _one_line_error(capsys, only=True)
    assert not list(tmp_path.iterdir())  # refused before the experiment's first part ran


@pytest.mark.parametrize("argv", [["demo"], ["reproduce", "fig-7.1"]], ids=["demo", "reproduce"])
@pytest.mark.parametrize("out", ["", "  "])
def test_an_empty_out_folder_is_refused(tmp_path, capsys, monkeypatch, argv, out):
    monkeypatch.chdir(tmp_path)  # an empty --out wrote into the current folder
    with pytest.raises(SystemExit) as info:
        main([*argv, "--out", out])
    assert info.value.code == 2
    assert "argument --out: must name a folder" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv", [["demo"], ["reproduce", "fig-7.1"], ["reproduce", "all", "--quick"]], ids=["demo", "one", "all"]
)
def test_out_that_is_a_file_is_a_named_one_line_error(tmp_path, capsys, argv):
    afile = tmp_path / "afile"
    afile.write_text("")
    assert main([*argv, "--out", str(afile)]) == 2
    message = _one_line_error(capsys, only=True)
    assert ": --out must be a folder that can be created" in message and "afile' is a file, not a folder" in message
    # an output folder under a file (fuzz round 15: it said only "Not a directory")
    assert main([*argv, "--out", str(afile / "sub")]) == 2
    assert f"({str(afile)!r} is a file, not a folder)" in _one_line_error(capsys, only=True)


@pytest.mark.parametrize(("command", "suffix"), [("centrality", ".NPY"), ("centrality", ".NPZ"), ("register", ".NPZ")])
def test_outputs_keep_an_upper_case_suffix(tmp_path, command, suffix):
    # "wrote C.NPY" while numpy wrote C.NPY.npy
    np.save(tmp_path / "m.npy", _points(12, seed=3))
    inputs = [str(tmp_path / "m.npy")] * (2 if command == "register" else 1)
    assert main([command, *inputs, "--out", str(tmp_path / f"out{suffix}")]) == 0
    written = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("out"))
    assert written == ([f"out{suffix}", "out.json"] if suffix == ".NPY" else [f"out{suffix}"])
    loaded = np.load(tmp_path / f"out{suffix}")
    assert loaded.shape[0] == 12 if suffix == ".NPY" else "parameters" in loaded


def test_a_nonrigid_record_without_an_affine_part_holds_the_identity():
    from centrality_vision.cli._common import transform_record

    record = transform_record(NonRigidTransform(np.zeros((2, 3)), np.ones((2, 3)), 1.0))
    np.testing.assert_array_equal(record["linear"], np.eye(3))
    for name in ("translation", "input_origin", "output_origin"):
        np.testing.assert_array_equal(record[name], np.zeros(3))


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--seed", "-1", "argument --seed: must be in [0, 4294967295]; got -1"),  # was sklearn's traceback
        ("--seed", "4294967296", "must be in [0, 4294967295]"),
        ("--bins", "100000000", "argument --bins: must be in [2, 100000]"),  # was killed for memory
        ("--bins", "1", "argument --bins: must be in [2, 100000]"),  # constant features: chance accuracy, exit 0
        ("--trees", "1000000000", "argument --trees: must be in [1, 100000]"),
    ],
)
def test_classify_bounds_its_numbers(tmp_path, capsys, option, value, message):
    folder = _shapes_folder(tmp_path / "shapes")
    with pytest.raises(SystemExit) as info:
        main(["classify", str(folder), option, value, "--out", str(tmp_path / "c.json")])
    assert info.value.code == 2 and message in capsys.readouterr().err


@pytest.mark.parametrize("size", [1e-300, 1e300])
def test_graph_edge_lengths_at_the_ends_of_float64(tmp_path, size):
    # the written lengths squared the differences: every length 0 at 1e-300, null (inf) at 1e300
    points = _points(20, seed=3) * size
    np.savetxt(tmp_path / "p.txt", points)
    assert main(["graph", str(tmp_path / "p.txt"), "--out", str(tmp_path / "g.json")]) == 0
    record = json.loads((tmp_path / "g.json").read_text())
    edges = np.array(record["edges"])
    i, j = edges[:, 0].astype(int), edges[:, 1].astype(int)
    truth = size * np.hypot(*(_points(20, seed=3)[i] - _points(20, seed=3)[j]).T)
    np.testing.assert_allclose(edges[:, 2], truth, rtol=1e-12)
    assert record["total_length"] == pytest.approx(truth.sum(), rel=1e-12)


@pytest.mark.parametrize(
    "argv",
    [
        ["centrality", "{p}", "--out", "{p}"],
        ["graph", "{p}", "--out", "{p}"],
        ["register", "{p}", "{q}", "--out", "{q}"],
    ],
    ids=["centrality", "graph", "register"],
)
def test_an_output_that_is_an_input_is_refused(tmp_path, capsys, argv):
    # `centrality p.csv --out p.csv` replaced the points with the table, exit 0
    paths = {"p": tmp_path / "p.csv", "q": tmp_path / "q.csv"}
    np.savetxt(paths["p"], _points(12, seed=1), delimiter=",")
    np.savetxt(paths["q"], _points(12, seed=2), delimiter=",")
    before = {name: path.read_bytes() for name, path in paths.items() if path.exists()}
    assert main([a.format(**{k: str(v) for k, v in paths.items()}) for a in argv]) == 2
    assert "an input that writing it would destroy" in _one_line_error(capsys, only=True)
    assert before == {name: path.read_bytes() for name, path in paths.items() if path.exists()}


def test_an_output_that_is_a_hard_link_to_an_input_is_refused(tmp_path, capsys):
    # found by fuzz round 7: the check compared resolved paths, and a hard link resolves to
    # its own name, so `register m.csv f.csv --out out.csv` replaced MOVING, exit 0
    moving, fixed, out = tmp_path / "m.csv", tmp_path / "f.csv", tmp_path / "out.csv"
    np.savetxt(moving, _points(12, seed=1), delimiter=",")
    np.savetxt(fixed, _points(12, seed=2), delimiter=",")
    os.link(moving, out)
    before = moving.read_bytes()
    assert main(["register", str(moving), str(fixed), "--out", str(out)]) == 2
    assert "is also MOVING, an input that writing it would destroy" in _one_line_error(capsys, only=True)
    assert moving.read_bytes() == before


def test_options_of_the_other_kind_of_input_are_refused(tmp_path, capsys):
    # --graph/--k with an image, --connectivity with points: ignored without a word, exit 0
    image = _png(tmp_path / "rect.png", np.pad(np.full((6, 8), 255), 4))
    np.savetxt(tmp_path / "p.txt", _points(12))
    out = str(tmp_path / "c.json")
    assert main(["centrality", str(image), "--graph", "knn", "--k", "100", "--out", out]) == 2
    assert "--graph, --k apply to point sets; INPUT" in _one_line_error(capsys, only=True)
    assert main(["centrality", str(tmp_path / "p.txt"), "--connectivity", "4", "--out", out]) == 2
    assert "--connectivity applies to images; INPUT" in _one_line_error(capsys, only=True)
    assert main(["centrality", str(image), "--connectivity", "4", "--out", out]) == 0


def test_centrality_plot_of_all_measures_on_a_3d_set(tmp_path):
    # eight 3D panels in a 3 x 3 grid: the hidden ninth broke matplotlib's layout (a traceback)
    np.save(tmp_path / "p.npy", _points(20, seed=4, dim=3))
    argv = ["centrality", str(tmp_path / "p.npy"), "--centrality", "all", "--out", str(tmp_path / "c.json")]
    assert main([*argv, "--plot", str(tmp_path / "c.png")]) == 0
    assert (tmp_path / "c.png").stat().st_size > 20_000


def test_output_places_are_checked_before_any_work(tmp_path, capsys):
    # the output was written and then the plot failed, or an OS error told after the whole run
    np.savetxt(tmp_path / "p.txt", _points())
    (tmp_path / "side.json").mkdir()
    (tmp_path / "afile").write_text("x")
    graph = ["graph", str(tmp_path / "p.txt")]
    cases = [
        (["--out", str(tmp_path / "side.csv")], "--out (its .json record beside it): ", "is a folder, not a file"),
        (["--out", str(tmp_path / "side.json")], "--out: ", "is a folder, not a file"),
        (["--out", str(tmp_path / "afile" / "g.json")], "--out: cannot create", "afile is a file, not a folder"),
        (["--out", str(tmp_path / "g.json"), "--plot", str(tmp_path / "afile" / "p.png")], "--plot: ", "a file"),
    ]
    for options, start, end in cases:
        assert main([*graph, *options]) == 2
        message = _one_line_error(capsys)
        assert start in message and end in message
    assert not (tmp_path / "side.csv").exists() and not (tmp_path / "g.json").exists()
    # a name that is only the suffix has none ("'.json' must end in .json" contradicted itself)
    with pytest.raises(SystemExit):
        main([*graph, "--out", str(tmp_path / ".json")])
    assert "/.json' is a name without a stem; give one, e.g. out.json" in capsys.readouterr().err


def test_a_plot_that_cannot_be_drawn_leaves_no_output(tmp_path, capsys):
    pixels = np.full((6, 6), 255, dtype=np.uint8)
    pixels[2, 2] = pixels[3, 3] = 0  # two diagonal pixels: no betweenness above 0 under 4-neighbours
    _png(tmp_path / "diag.png", pixels)
    argv = ["centrality", str(tmp_path / "diag.png"), "--connectivity", "4", "--centrality", "betweenness"]
    argv += ["--norm", "log", "--plot", str(tmp_path / "d.png"), "--out", str(tmp_path / "d.json")]
    assert main(argv) == 2
    assert "'log' needs at least one value > 0" in _one_line_error(capsys)
    assert not (tmp_path / "d.json").exists()


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--tol", "inf"], "argument --tol: must be a finite number; got 'inf'"),  # passed "(0, inf]"
        (["--transform", "nonrigid", "--beta", "1e308"], "argument --beta: must be in [1e-150, 1e+150]"),
        (["--transform", "nonrigid", "--lam", "1e-300"], "argument --lam: must be in [1e-150, 1e+150]"),
    ],
)
def test_register_options_out_of_the_library_range_are_usage_errors(tmp_path, capsys, options, message):
    np.save(tmp_path / "m.npy", _points())
    with pytest.raises(SystemExit) as info:
        main(
            ["register", str(tmp_path / "m.npy"), str(tmp_path / "m.npy"), *options, "--out", str(tmp_path / "r.json")]
        )
    assert info.value.code == 2 and message in capsys.readouterr().err


def test_register_records_what_ran(tmp_path, capsys):
    np.save(tmp_path / "m.npy", _points())
    argv = ["register", str(tmp_path / "m.npy"), str(tmp_path / "m.npy"), "--method", "gpd"]
    # k >= the number of points: the library took the complete graph while the record said k=200
    assert main([*argv, "--graph", "knn", "--k", "12", "--out", str(tmp_path / "r.json")]) == 2
    assert "--k must be smaller than the number of points of each set (12 and 12); got 12" in _one_line_error(capsys)
    # two identical runs record the same estimator (its callback's repr held a memory address)
    records = []
    for name in ("a.json", "b.json"):
        assert main([*argv, "--out", str(tmp_path / name)]) == 0
        records.append(json.loads((tmp_path / name).read_text())["estimator"])
    assert records[0] == records[1] and " at 0x" not in records[0]


def test_classify_tells_a_file_from_a_missing_folder(tmp_path, capsys):
    (tmp_path / "afile").write_text("x")
    assert main(["classify", str(tmp_path / "afile"), "--out", str(tmp_path / "c.json")]) == 2
    assert "afile: is a file, not a folder of images" in _one_line_error(capsys)
    folder = _shapes_folder(tmp_path / "shapes")
    assert main(["classify", str(folder), "--labels", str(tmp_path), "--out", str(tmp_path / "c.json")]) == 2
    assert "--labels: " in (message := _one_line_error(capsys)) and "is a folder, not a CSV file" in message


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"file,label\nbar0.png,b\xe9\n", "must be a UTF-8 text file; got byte 0xe9, not UTF-8 there"),
        (b"\x89PNG\r\n\x1a\n", "must be a UTF-8 text file; got byte 0x89, not UTF-8 there"),
        (b"file,label\nbar0.png\n", "line 2 must give a file and its label; got 'bar0.png' and None"),
        (b"file,label\nbar0.png,\n", "line 2 must give a file and its label; got 'bar0.png' and ''"),
        # a file listed twice kept its last label (the truth changed silently)
        (b"file,label\nbar0.png,a\nbar1.png,a\nbar0.png,b\n", "line 4 labels 'bar0.png' again (line 2 did)"),
        (b"", "the file is empty; expected a CSV with columns 'file' and 'label'"),  # (was "got None")
    ],
)
def test_classify_bad_label_files_are_one_line_errors(tmp_path, capsys, content, message):
    # a Latin-1 or binary file and a row without its label were "internal error"s;
    # an empty label made a class named ''
    folder = _shapes_folder(tmp_path / "shapes")
    (tmp_path / "labels.csv").write_bytes(content)
    argv = ["classify", str(folder), "--labels", str(tmp_path / "labels.csv"), "--out", str(tmp_path / "c.json")]
    assert main(argv) == 2
    assert message in _one_line_error(capsys)


def test_library_messages_name_the_command_line_options(tmp_path, capsys):
    # "`columns` must not repeat a column": the user typed --columns
    np.savetxt(tmp_path / "p.txt", _points())
    assert main(["graph", str(tmp_path / "p.txt"), "--columns", "0,0", "--out", str(tmp_path / "g.json")]) == 2
    message = _one_line_error(capsys)
    assert "--columns must not repeat a column" in message and "`columns`" not in message


@pytest.mark.parametrize("columns", [["--columns", "-1,0"], ["--columns=-1,0"], ["--columns", "-1, 0"]])
def test_a_negative_column_index_reaches_the_reader(tmp_path, capsys, columns):
    # with a space argparse took "-1,0" for an option: "expected one argument"
    np.savetxt(tmp_path / "p.txt", _points())
    assert main(["graph", str(tmp_path / "p.txt"), *columns, "--out", str(tmp_path / "g.json")]) == 2
    assert "index -1 is out of range" in _one_line_error(capsys)


def test_warnings_name_the_command_line_options_too(tmp_path, capsys, monkeypatch):
    import warnings

    from centrality_vision.cli import register

    real = register._estimator

    def warn_then_build(args, callback):
        warnings.warn("Try a smaller `w` or more `max_iter`.", UserWarning, stacklevel=2)
        return real(args, callback)

    monkeypatch.setattr(register, "_estimator", warn_then_build)
    np.save(tmp_path / "m.npy", _points())
    assert main(["register", str(tmp_path / "m.npy"), str(tmp_path / "m.npy"), "--out", str(tmp_path / "r.json")]) == 0
    err = capsys.readouterr().err
    assert "warning: Try a smaller --w or more --max-iter." in err


def test_the_before_panel_shows_the_moving_file_as_given(tmp_path, monkeypatch):
    # it showed CPD's iteration 0, the moving set already centred on the fixed set
    from centrality_vision import plotting

    drawn = {}
    real = plotting.plot_registration

    def spy(moving, fixed, **kwargs):
        drawn[kwargs.get("title")] = np.array(moving)
        return real(moving, fixed, **kwargs)

    monkeypatch.setattr(plotting, "plot_registration", spy)
    moving = _points(15, seed=6)
    np.save(tmp_path / "m.npy", moving)
    np.save(tmp_path / "f.npy", moving @ _rotation(0.3).T + 5.0)
    argv = ["register", str(tmp_path / "m.npy"), str(tmp_path / "f.npy"), "--out", str(tmp_path / "r.json")]
    assert main([*argv, "--plot", str(tmp_path / "r.png")]) == 0
    np.testing.assert_array_equal(drawn["before"], moving)


def _raising(exc):
    def run(args):
        raise exc

    return run


def _interrupt_inside_a_kernel():
    # what a compiled kernel does with Ctrl-C: a SystemError whose cause is the interrupt
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as interrupt:
        raise SystemError("<built-in function kernel> returned a result with an exception set") from interrupt


@pytest.mark.parametrize(
    ("run", "status", "said"),
    [
        (_raising(KeyboardInterrupt()), 130, "centrality-vision demo: interrupted"),
        (lambda args: _interrupt_inside_a_kernel(), 130, "centrality-vision demo: interrupted"),
        (_raising(SystemError("a real bug")), 1, "internal error"),
    ],
)
def test_an_interrupt_is_reported_as_one_even_from_inside_a_kernel(monkeypatch, capsys, run, status, said):
    from centrality_vision.cli import demo

    monkeypatch.setattr(demo, "run", run)
    assert main(["demo"]) == status
    assert said in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["match", "m.txt", "f.txt", "--method", "shape-context", "--refine", "cpd"],
            "--refine is an option of --method robust; got --method shape-context",
        ),
        (
            ["match", "m.txt", "f.txt", "--mwme-method", "exact"],  # the former name, as --mwme-solver
            "--mwme-solver is an option of --method mwme; got --method robust",
        ),
        (["reproduce", "table-2.1", "--workers", "3"], "--workers applies to"),
        (["register", "m.txt", "f.txt", "--seed", "3"], "--seed is an option of --init global; got --init none"),
        (["classify", "shapes", "--trees", "50"], "--trees is an option of --classifier forest; got --classifier nb"),
    ],
)
def test_an_option_the_run_would_ignore_is_refused(tmp_path, capsys, argv, message):
    # each ran with exit 0, the option ignored (and recorded among the parameters)
    np.savetxt(tmp_path / "m.txt", _points())
    np.savetxt(tmp_path / "f.txt", _points())
    argv = [str(tmp_path / a) if a.endswith(".txt") else a for a in argv]
    out = tmp_path / ("out" if argv[0] == "reproduce" else "out.json")
    assert main([*argv, "--out", str(out)]) == 2
    assert message in _one_line_error(capsys)
    assert not out.exists() or (out.is_dir() and not any(out.iterdir()))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["graph", "{p}", "--kind", "delaunay", "--k", "3"], "--k is an option of --kind knn; got --kind delaunay"),
        (["graph", "{p}", "--kind", "emst", "--lam", "0.9"], "--lam is an option of --kind mstme; got --kind emst"),
        (["centrality", "{p}", "--graph", "gabriel", "--k", "3"], "--k is an option of --graph knn"),
        (["centrality", "{p}", "--norm", "log"], "--norm is the colour scale of --plot"),
        (
            ["centrality", "{p}", "--centrality", "degree", "--weights"],
            "--weights is an option of --centrality betweenness",
        ),
        (
            ["centrality", "{p}", "--centrality", "closeness", "--strengths"],
            "--strengths is an option of --centrality degree",
        ),
    ],
)
def test_graph_and_centrality_refuse_options_the_run_would_not_use(tmp_path, capsys, argv, message):
    # fuzz round 6: each exited 0 and ignored the option without a word
    np.savetxt(tmp_path / "p.txt", np.random.default_rng(0).random((12, 2)))
    argv = [part.format(p=tmp_path / "p.txt") for part in argv] + ["--out", str(tmp_path / "o.json")]
    assert main(argv) == 2
    assert message in capsys.readouterr().err and not (tmp_path / "o.json").exists()


def test_options_that_apply_are_taken(tmp_path):
    np.savetxt(tmp_path / "p.txt", np.random.default_rng(0).random((12, 2)))
    p = str(tmp_path / "p.txt")
    assert main(["graph", p, "--kind", "knn", "--k", "3", "--out", str(tmp_path / "g.json")]) == 0
    argv = ["centrality", p, "--centrality", "all", "--weights", "--strengths", "--out", str(tmp_path / "c.json")]
    assert main(argv) == 0


def test_the_mstme_lam_default_is_the_librarys():
    import inspect

    from centrality_vision.cli import build_parser
    from centrality_vision.graphs import mstme_graph

    library = inspect.signature(mstme_graph).parameters["lam"].default
    for command in ("graph", "centrality"):
        args = build_parser().parse_args([command, "p.txt", "--out", "x.json"])
        assert args.lam == library


def test_centrality_option_is_named_as_in_register_and_classify_and_measure_still_works(tmp_path):
    # API audit F6: centrality said --measure where register and classify say --centrality
    np.save(tmp_path / "p.npy", np.random.default_rng(1).random((15, 2)))
    outputs = []
    for option in ("--centrality", "--measure"):
        out = tmp_path / f"c{option}.json"
        assert main(["centrality", str(tmp_path / "p.npy"), option, "harmonic", "--out", str(out)]) == 0
        record = json.loads(out.read_text())
        assert record["parameters"]["centrality"] == "harmonic"
        outputs.append(record["centrality"]["harmonic"])
    assert outputs[0] == outputs[1]


def test_a_single_experiment_says_the_report_beside_it_does_not_show_it(tmp_path, capsys):
    """Running one experiment after 'reproduce all' replaced its files and left report.md as
    it was, without a word."""
    out = tmp_path / "results"
    assert main(["reproduce", "table-2.1", "--quick", "--out", str(out)]) == 0
    assert "report.md" not in capsys.readouterr().err  # no report there: nothing to say
    (out / "report.md").write_text("# an earlier report\n")
    assert main(["reproduce", "table-2.1", "--quick", "--out", str(out)]) == 0
    assert "report.md is from an earlier 'reproduce all' and does not show this run" in capsys.readouterr().err


def test_records_list_only_the_options_that_applied(tmp_path):
    # round 17: an image's record listed the point-set graph's k and lam, and a Delaunay
    # graph's record the k of k-NN and the lam of MSTME
    np.savetxt(tmp_path / "p.csv", _points(12), delimiter=",")
    image = _png(tmp_path / "rect.png", np.pad(np.full((6, 8), 255), 4))
    assert main(["graph", str(tmp_path / "p.csv"), "--kind", "delaunay", "--out", str(tmp_path / "g.json")]) == 0
    assert main(["graph", str(tmp_path / "p.csv"), "--kind", "knn", "--k", "3", "--out", str(tmp_path / "k.json")]) == 0
    assert main(["centrality", str(image), "--centrality", "degree", "--out", str(tmp_path / "i.json")]) == 0
    assert (
        main(["centrality", str(tmp_path / "p.csv"), "--centrality", "degree", "--out", str(tmp_path / "c.json")]) == 0
    )
    record = {name: json.loads((tmp_path / f"{name}.json").read_text())["parameters"] for name in "gkic"}
    assert "k" not in record["g"] and "lam" not in record["g"] and record["g"]["kind"] == "delaunay"
    assert not any("seed" in parameters for parameters in record.values())  # (was "seed": null; none draws)
    assert record["k"]["k"] == 3 and "lam" not in record["k"]
    assert not {"graph", "k", "lam", "columns"} & set(record["i"]) and record["i"]["connectivity"] == 8
    assert not {"connectivity", "foreground", "threshold", "k", "lam"} & set(record["c"]) and record["c"]["graph"]


def _documented_examples():
    """Every example command line: each subcommand's --help epilog and the README's block."""
    import argparse
    import pathlib
    import re
    import shlex

    parser = cli.build_parser()
    sub = next(action for action in parser._actions if isinstance(action, argparse._SubParsersAction))
    lines = [line for child in sub.choices.values() for line in (child.epilog or "").splitlines()]
    readme = (pathlib.Path(__file__).parents[2] / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Command line\n\n```bash\n(.*?)```", readme, re.S).group(1)
    lines += block.splitlines()
    lines = re.sub(r"\\\n\s*", " ", "\n".join(lines)).splitlines()  # (a line continued by a backslash)
    return [shlex.split(line) for line in lines if line.strip().startswith("centrality-vision ")]


@pytest.mark.parametrize("words", _documented_examples(), ids=" ".join)
def test_documented_examples_parse_and_write_over_none_of_their_inputs(words):
    """The README's and --help's `centrality --plot cow1.png` on `cow1.png` could never run: the
    command refuses to write over its input (audit 26)."""
    args = cli.build_parser().parse_args(words[1:])
    outputs = [getattr(args, name, None) for name in ("out", "plot")]
    outputs = [str(path) for path in outputs if path is not None]
    for output in outputs:
        assert words.count(output) <= 1, f"{output} is written and also named elsewhere in {' '.join(words)}"


def test_every_command_takes_progress_and_no_progress():
    """The README promises --progress/--no-progress; `match` refused it (audit 26), so a
    script passing it to every command broke there."""
    import argparse

    parser = cli.build_parser()
    sub = next(action for action in parser._actions if isinstance(action, argparse._SubParsersAction))
    for name, child in sub.choices.items():
        options = {option for action in child._actions for option in action.option_strings}
        assert {"--progress", "--no-progress"} <= options, name


def test_library_advice_in_warnings_reads_as_options(tmp_path, capsys):
    """Warnings read `Pass foreground='auto' ...` and `match(method='robust')` in Python words on
    the command line (audit 26): they now name --foreground and --method."""
    pixels = np.full((40, 40), 255)
    pixels[10:30, 12:28] = 0  # a dark square on a light ground
    image = _png(tmp_path / "square.png", pixels)
    argv = ["centrality", str(image), "--centrality", "degree", "--foreground", "light", "--out"]
    assert main([*argv, str(tmp_path / "c.csv")]) == 0
    err = capsys.readouterr().err
    assert "looks inverted" in err and "Pass --foreground auto (grey images), --foreground dark or" in err
    rng = np.random.default_rng(0)
    fixed = rng.random((30, 2))
    np.savetxt(tmp_path / "f.txt", fixed)
    np.savetxt(tmp_path / "m.txt", fixed + rng.normal(0, 0.05, fixed.shape))
    argv = ["match", str(tmp_path / "m.txt"), str(tmp_path / "f.txt"), "--method", "mwme"]
    assert main([*argv, "--out", str(tmp_path / "m.json")]) == 0
    err = capsys.readouterr().err
    assert "not nearest neighbours" in err and "match's --method robust handles noise" in err
    assert "method=" not in err
