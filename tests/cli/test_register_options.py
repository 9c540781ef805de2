"""``centrality-vision register``'s pose, outlier, landmark and ICP options reach the estimators."""

import json

import numpy as np
import pytest

from centrality_vision.cli import main


def _rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.fixture(scope="module")
def fish():
    from centrality_vision.datasets import load_fish

    return load_fish().fixed


def _error_line(capsys):
    err = capsys.readouterr().err
    lines = [line for line in err.strip().splitlines() if "error:" in line]
    assert "Traceback" not in err and len(lines) == 1, err
    return lines[0]


def _register(tmp_path, moving, fixed, *options, name="r.json"):
    np.save(tmp_path / "m.npy", moving)
    np.save(tmp_path / "f.npy", fixed)
    argv = ["register", str(tmp_path / "m.npy"), str(tmp_path / "f.npy"), *options, "--out", str(tmp_path / name)]
    assert main(argv) == 0
    return json.loads((tmp_path / name).read_text())


def _angle_error(record, angle):
    rotation = np.asarray(record["transform"]["rotation"])
    found = np.arctan2(rotation[1, 0], rotation[0, 0])
    return abs((found - angle + np.pi) % (2 * np.pi) - np.pi)


def test_init_global_recovers_a_pose_that_plain_cpd_misses(tmp_path, fish):
    angle = np.deg2rad(150)
    fixed = 1.3 * fish @ _rotation(angle).T + np.array([2.0, -1.0])
    plain = _register(tmp_path, fish, fixed, "--tol", "1e-9", name="plain.json")
    found = _register(tmp_path, fish, fixed, "--tol", "1e-9", "--init", "global", "--seed", "3", name="global.json")
    assert _angle_error(plain, angle) > np.deg2rad(30)  # a wrong basin from the centroids-aligned start
    assert _angle_error(found, angle) < 1e-6 and abs(found["transform"]["scale"] - 1.3) < 1e-6
    assert "init='global'" in found["estimator"] and "random_state=3" in found["estimator"]
    assert found["parameters"]["init"] == "global" and found["parameters"]["seed"] == 3


def test_landmarks_file_pins_pairs_and_escapes_the_wrong_basin(tmp_path, fish):
    angle = np.deg2rad(150)
    fixed = fish @ _rotation(angle).T
    # a header line and commas: the same reader as the point files
    (tmp_path / "pairs.csv").write_text("moving,fixed\n0,0\n30,30\n60,60\n")
    record = _register(tmp_path, fish, fixed, "--transform", "rigid", "--landmarks", str(tmp_path / "pairs.csv"))
    assert record["landmarks"] == [[0, 0], [30, 30], [60, 60]]
    assert max(record["landmark_distances"]) < 1e-3
    assert _angle_error(record, angle) < 1e-6


def test_w_auto_estimates_the_clutter_share(tmp_path, fish):
    rng = np.random.default_rng(1)
    rotated = fish @ _rotation(0.2).T
    clutter = rng.uniform(rotated.min(axis=0) - 0.2, rotated.max(axis=0) + 0.2, size=(30, 2))
    fixed = np.vstack([rotated, clutter])
    record = _register(tmp_path, fish, fixed, "--transform", "rigid", "--w", "auto", "--tol", "1e-9")
    assert record["parameters"]["w"] == "auto"
    assert abs(record["w"] - 30 / 121) < 0.02  # the true share of clutter
    assert _angle_error(record, 0.2) < 1e-9
    fixed_w = _register(tmp_path, fish, fixed, "--transform", "rigid", "--w", "0.1", name="w.json")
    assert fixed_w["w"] == 0.1


def test_n_neighbors_reaches_the_estimator(tmp_path, fish):
    fixed = fish @ _rotation(0.1).T + 0.05
    record = _register(tmp_path, fish, fixed, "--transform", "nonrigid", "--n-neighbors", "10", "--tol", "1e-8")
    assert "n_neighbors=10" in record["estimator"]
    assert np.allclose(record["moving_transformed"], fixed, atol=1e-3)
    gpd = _register(tmp_path, fish, fixed, "--method", "gpd", "--n-neighbors", "10", name="gpd.json")
    assert "n_neighbors=10" in gpd["estimator"]


def test_icp_trim_ignores_the_moving_points_without_partner(tmp_path, fish):
    # the fixed set lacks the last 21 of the fish's 91 points
    fixed = fish[:70] @ _rotation(0.2).T + np.array([0.1, -0.05])
    options = ("--method", "icp", "--transform", "rigid", "--tol", "1e-10", "--max-iter", "200")
    plain = _register(tmp_path, fish, fixed, *options, name="plain.json")
    trimmed = _register(tmp_path, fish, fixed, *options, "--trim", "0.25", name="trim.json")
    assert _angle_error(plain, 0.2) > 1e-3
    assert _angle_error(trimmed, 0.2) < 1e-9
    assert "trim=0.25" in trimmed["estimator"]
    within = _register(tmp_path, fish, fixed, *options, "--max-distance", "0.5", name="within.json")
    assert "max_distance=0.5" in within["estimator"]


def test_icp_max_distance_that_leaves_no_pair_is_a_one_line_error(tmp_path, capsys, fish):
    np.save(tmp_path / "m.npy", fish)
    np.save(tmp_path / "f.npy", fish + 0.1)
    argv = ["register", str(tmp_path / "m.npy"), str(tmp_path / "f.npy"), "--method", "icp"]
    assert main([*argv, "--max-distance", "1e-9", "--out", str(tmp_path / "r.json")]) == 2
    assert "--max-distance 1e-09 leaves ICP only 0 pairs at the start" in _error_line(capsys)


def test_icp_point_to_plane_in_3d(tmp_path):
    rng = np.random.default_rng(4)
    u, v = rng.uniform(-1, 1, size=(2, 400))
    moving = np.column_stack([u, v, 0.3 * np.sin(2 * u) * np.cos(2 * v)])  # a smooth bumpy sheet
    c, s = np.cos(0.05), np.sin(0.05)
    rotation = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    fixed = moving @ rotation.T + np.array([0.02, 0.0, 0.01])
    options = ("--method", "icp", "--transform", "rigid", "--metric", "point_to_plane", "--tol", "1e-12")
    record = _register(tmp_path, moving, fixed, *options, "--max-iter", "200")
    assert "metric='point_to_plane'" in record["estimator"]
    np.testing.assert_allclose(record["transform"]["rotation"], rotation, atol=1e-6)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--method", "icp", "--init", "global"], "--init is an option of --method cpd or gpd; got --method icp"),
        (["--method", "icp", "--n-neighbors", "5"], "--n-neighbors is an option of --method cpd or gpd"),
        (["--method", "icp", "--landmarks", "x.csv"], "--landmarks is an option of --method cpd or gpd"),
        (["--trim", "0.1"], "--trim is an option of --method icp; got --method cpd"),
        (["--method", "gpd", "--max-distance", "1"], "--max-distance is an option of --method icp; got --method gpd"),
        (["--method", "icp", "--metric", "point_to_plane"], "--metric point_to_plane fits a rigid motion"),
        # given at their defaults, or ignored before (and recorded as used)
        (["--method", "icp", "--init", "none"], "--init is an option of --method cpd or gpd; got --method icp"),
        (["--method", "icp", "--w", "0.5"], "--w is an option of --method cpd or gpd; got --method icp"),
        (["--method", "cpd", "--kappa", "0.2"], "--kappa is an option of --method gpd; got --method cpd"),
        (["--centrality", "degree"], "--centrality is an option of --method gpd; got --method cpd"),
        (["--method", "gpd", "--k", "4"], "--k is an option of --graph knn; got --graph delaunay"),
        (["--beta", "3"], "--beta is an option of --transform nonrigid; got --transform similarity"),
        (["--transform", "affine", "--lam", "3"], "--lam is an option of --transform nonrigid; got --transform affine"),
    ],
)
def test_options_of_another_method_are_refused_before_reading(tmp_path, capsys, options, message):
    # the files do not exist: the combination is refused first
    argv = ["register", str(tmp_path / "no-m.npy"), str(tmp_path / "no-f.npy"), *options]
    assert main([*argv, "--out", str(tmp_path / "r.json")]) == 2
    assert message in _error_line(capsys)
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("value", ["1", "1.5", "-0.1", "nan", "autox", ""])
def test_bad_w_is_a_usage_error(tmp_path, capsys, value):
    np.save(tmp_path / "m.npy", np.random.default_rng(0).random((12, 2)))
    with pytest.raises(SystemExit) as info:
        main(["register", str(tmp_path / "m.npy"), str(tmp_path / "m.npy"), "--w", value])
    assert info.value.code == 2
    assert f"argument --w: must be a number in [0, 1) or auto; got {value!r}" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("0 0 1\n", "expected two columns, a moving row and a fixed row per line; got 3 columns"),
        ("0.5 0\n", "the rows must be whole numbers; got 0.5"),
        ("0 0\n1 500\n", "--landmarks fixed indices must be in [0, 40); got 500"),
        ("0 0\n-1 3\n", "--landmarks moving indices must be in [0, 40); got -1"),
        ("0 0\n0 3\n", "--landmarks must pin each moving point at most once"),
        ("1e300 0\n", "a row number must be below 2^62"),
        ("0 0 1 2\n", "must have 2 or 3 coordinates; got 4 columns."),  # not "pick ... with --columns"
        (None, "no such file"),
    ],
)
def test_bad_landmark_files_are_one_line_errors(tmp_path, capsys, content, message):
    points = np.random.default_rng(0).random((40, 2))
    np.save(tmp_path / "m.npy", points)
    if content is not None:
        (tmp_path / "pairs.txt").write_text(content)
    argv = ["register", str(tmp_path / "m.npy"), str(tmp_path / "m.npy"), "--landmarks", str(tmp_path / "pairs.txt")]
    assert main([*argv, "--out", str(tmp_path / "r.json")]) == 2
    line = _error_line(capsys)
    assert message in line and "--landmarks" in line
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("header", ["i,j", "id,index", "moving,fixed"])
def test_a_landmarks_header_names_both_columns(tmp_path, header):
    # "i" and "id" name an index column in a point file; here they are the two rows: the
    # file was refused ("got 1 columns ... pick the coordinates with --columns")
    from centrality_vision.cli.register import _read_landmarks

    (tmp_path / "pairs.csv").write_text(f"{header}\n0,3\n5,7\n")
    np.testing.assert_array_equal(_read_landmarks(tmp_path / "pairs.csv"), [[0, 3], [5, 7]])


def test_the_library_advice_names_the_init_option():
    # CPD's collapse warning ends "or a starting pose (`init`)": on the command line, --init
    import argparse

    from centrality_vision.cli import _in_cli_words
    from centrality_vision.cli.register import add_parser

    parser = add_parser(argparse.ArgumentParser().add_subparsers())
    said = _in_cli_words("Try a smaller `w`, or a starting pose (`init`).", parser)
    assert said == "Try a smaller --w, or a starting pose (--init)."


def test_gpd_duplicates_are_named_by_file_and_row(tmp_path, capsys, fish):
    # GPD built its graph on the normalised set: the error showed normalised coordinates,
    # named `moving`, and advised another --graph (every graph refuses duplicates) or
    # `moving_graph=` (no such option).
    moving = fish * 100.0 + 1000.0
    moving[5] = moving[4]
    np.save(tmp_path / "m.npy", moving)
    np.save(tmp_path / "f.npy", fish)
    argv = [
        "register",
        str(tmp_path / "m.npy"),
        str(tmp_path / "f.npy"),
        "--method",
        "gpd",
        "--out",
        str(tmp_path / "r.json"),
    ]
    assert main(argv) == 2
    line = _error_line(capsys)
    assert f"MOVING ({tmp_path / 'm.npy'}) must not contain duplicate points" in line
    assert f"rows 4 and 5, both {moving[4].tolist()}" in line
    assert "remove the duplicates." in line and "moving_graph" not in line and "Python" not in line


def test_library_settings_read_as_options(tmp_path, capsys, fish):
    # "max_iter=1 ... tol=1e-06" in the library is "--max-iter 1 ... --tol 1e-06" here
    _register(tmp_path, fish, fish[::-1] + 0.1, "--method", "icp", "--max-iter", "1")
    # and the library's class is the command's method and transform (it said "ICP", and
    # "RigidCPD" for --transform similarity)
    assert "warning: ICP (similarity) stopped at --max-iter 1 before meeting --tol 1e-06." in capsys.readouterr().err
    _register(tmp_path, fish, fish[::-1] + 0.1, "--transform", "similarity", "--max-iter", "1")
    assert "warning: CPD (similarity) stopped at --max-iter 1 before" in capsys.readouterr().err


def test_a_register_warning_names_no_library_attribute(tmp_path, capsys, fish):
    _register(tmp_path, fish[:1], fish)
    err = capsys.readouterr().err
    assert "the fitted transform is right on MOVING" in err and "transform_" not in err


@pytest.mark.parametrize(("method", "estimator"), [("icp", "ICP"), ("cpd", "RigidCPD")])
def test_iteration_limits_default_to_the_methods_own(tmp_path, method, estimator):
    # audit F19: --max-iter 150 and --tol 1e-5 (CPD's) were passed to ICP, whose own are 100 and 1e-6
    import inspect

    from centrality_vision import registration

    signature = inspect.signature(getattr(registration, estimator)).parameters
    fixed = np.random.default_rng(0).random((30, 2))
    record = _register(tmp_path, fixed + 0.01, fixed, "--method", method, "--transform", "rigid")
    assert record["parameters"]["max_iter"] == signature["max_iter"].default
    assert record["parameters"]["tol"] == signature["tol"].default
    given = _register(tmp_path, fixed + 0.01, fixed, "--method", method, "--transform", "rigid", "--max-iter", "7")
    assert given["parameters"]["max_iter"] == 7


def test_an_estimators_parameter_reads_as_the_option():
    # API audit (errors): estimators name `RigidCPD.tol`, which the command line showed as is
    import argparse

    from centrality_vision.cli import _in_cli_words
    from centrality_vision.cli.register import add_parser

    parser = add_parser(argparse.ArgumentParser().add_subparsers())
    args = parser.parse_args(["m.txt", "f.txt", "--out", "x.json"])
    said = _in_cli_words("`NonRigidCPD.lam` must be positive; `RigidCPD.tol` too, and `tol`.", parser, args)
    assert said == "--lam must be positive; --tol too, and --tol."


def test_a_fit_ended_by_a_collapse_is_not_said_to_reach_max_iter(tmp_path, capsys, fish):
    """A collapse onto a one-point fixed set ended CPD after 25 of 150 iterations, and the status
    line said "stopped at --max-iter without converging"."""
    _register(tmp_path, fish, fish[:1], "--method", "cpd")
    err = capsys.readouterr().err
    assert "stopped early without converging (see the warning above)" in err
    assert "stopped at --max-iter" not in err
    _register(tmp_path, fish, fish[::-1] + 0.1, "--method", "cpd", "--max-iter", "2", name="limited.json")
    assert "stopped at --max-iter without converging after 2 iterations" in capsys.readouterr().err


def test_the_record_lists_only_the_options_that_applied(tmp_path, fish):
    record = _register(tmp_path, fish, fish[::-1] + 0.1, "--method", "icp")
    assert not {"w", "init", "centrality", "graph", "k", "kappa", "beta", "lam"} & set(record["parameters"])
    assert record["parameters"]["method"] == "icp" and "trim" in record["parameters"]
    record = _register(tmp_path, fish, fish[::-1] + 0.1, "--transform", "nonrigid", name="n.json")
    assert record["parameters"]["beta"] > 0 and "trim" not in record["parameters"]


def test_a_record_lists_the_values_a_run_used_and_no_other_option(tmp_path):
    # audit 26 L3: GPD on a Delaunay graph recorded the k of k-NN, ICP and a CPD run without
    # the global search recorded a seed, and ICP's trim and metric were null, not the values used
    fixed = np.random.default_rng(1).random((25, 2))
    gpd = _register(tmp_path, fixed + 0.01, fixed, "--method", "gpd", "--centrality", "degree")["parameters"]
    assert gpd["graph"] == "delaunay" and "k" not in gpd and "seed" not in gpd
    knn = _register(tmp_path, fixed + 0.01, fixed, "--method", "gpd", "--graph", "knn", "--k", "4")["parameters"]
    assert knn["k"] == 4
    icp = _register(tmp_path, fixed + 0.01, fixed, "--method", "icp")["parameters"]
    assert icp["trim"] == 0.0 and icp["metric"] == "point_to_point" and "seed" not in icp
    seeded = _register(tmp_path, fixed + 0.01, fixed, "--init", "global", "--seed", "5")["parameters"]
    assert seeded["seed"] == 5


def test_a_record_beside_an_output_never_replaces_another_file(tmp_path, capsys):
    # audit 26 L5: --out al.csv then --out al.ply wrote both records to al.json (al.csv was left
    # described by the other run), and --out mvv.csv replaced a user's own mvv.json
    fixed = np.random.default_rng(2).random((20, 3))
    np.save(tmp_path / "m.npy", fixed + 0.01)
    np.save(tmp_path / "f.npy", fixed)

    def run(out):
        return main(["register", str(tmp_path / "m.npy"), str(tmp_path / "f.npy"), "--out", str(tmp_path / out)])

    assert run("al.csv") == 0 and run("al.csv") == 0  # a run again replaces its own record
    before = (tmp_path / "al.json").read_bytes()
    assert run("al.ply") == 2
    assert "al.json, which is the record of al.csv" in _error_line(capsys)
    assert (tmp_path / "al.json").read_bytes() == before and not (tmp_path / "al.ply").exists()
    (tmp_path / "mine.json").write_text('{"notes": 1}\n')
    assert run("mine.csv") == 2 and "did not write" in _error_line(capsys)
    assert (tmp_path / "mine.json").read_text() == '{"notes": 1}\n' and not (tmp_path / "mine.csv").exists()
    (tmp_path / "al.csv").unlink()  # a record whose output is gone is replaced
    assert run("al.ply") == 0 and json.loads((tmp_path / "al.json").read_text())["file"] == "al.ply"
