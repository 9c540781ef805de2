"""``centrality-vision match``: every method of ``matching.match``, sets of different sizes, -1 for unmatched."""

from __future__ import annotations

import json

import numpy as np
import pytest

from centrality_vision.cli import main


def _outline(u):
    r = 1 + 0.3 * np.cos(3 * u)
    return np.c_[np.cos(u) * r, np.sin(u) * r]


def _rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.fixture(scope="module")
def partial_pair(tmp_path_factory):
    """60 fixed outline points; moving: 40 of them rotated, scaled by 2, shifted, plus 10 far outliers."""
    folder = tmp_path_factory.mktemp("match")
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    fixed = _outline(t)
    outliers = np.random.default_rng(1).uniform(4.0, 6.0, (10, 2))
    moving = 2.0 * np.vstack([fixed[:40], outliers]) @ _rotation(0.7).T + [3.0, -1.0]
    np.savetxt(folder / "m.txt", moving)
    np.savetxt(folder / "f.txt", fixed)
    return folder, moving, fixed


def test_robust_is_the_default_and_matches_sets_of_different_sizes(partial_pair, tmp_path):
    folder, moving, fixed = partial_pair
    argv = ["match", str(folder / "m.txt"), str(folder / "f.txt"), "--out", str(tmp_path / "m.json")]
    argv += ["--plot", str(tmp_path / "m.png")]
    assert main(argv) == 0
    record = json.loads((tmp_path / "m.json").read_text())
    correspondence = np.array(record["correspondence"])
    assert record["parameters"]["method"] == "robust" and correspondence.shape == (50,)
    assert correspondence[:40].tolist() == list(range(40))  # every outline point finds its original
    assert np.all(correspondence[40:] == -1)  # the outliers (at least 2 units away from the shape) stay unmatched
    assert record["n_matched"] == 40
    assert abs(record["transform"]["scale"] - 0.5) < 1e-6 and record["rms_residual"] < 1e-6
    assert (tmp_path / "m.png").stat().st_size > 0


def test_shape_context_writes_minus_one_for_points_without_partner(partial_pair, tmp_path):
    folder, moving, fixed = partial_pair
    out = tmp_path / "m.npz"
    argv = ["match", str(folder / "m.txt"), str(folder / "f.txt"), "--method", "shape-context", "--out", str(out)]
    assert main(argv) == 0
    with np.load(out) as data:
        correspondence = data["correspondence"]
        n_matched = int(data["n_matched"])
    assert correspondence.shape == (50,) and correspondence.min() >= -1 and correspondence.max() < 60
    assert n_matched == int(np.sum(correspondence >= 0)) and n_matched <= 50
    matched = correspondence[correspondence >= 0]
    assert len(set(matched.tolist())) == len(matched)  # Hungarian assignment: one-to-one


def test_mwme_refuses_sets_of_different_sizes_but_robust_refuses_3d(partial_pair, tmp_path, capsys):
    folder, moving, fixed = partial_pair
    argv = ["match", str(folder / "m.txt"), str(folder / "f.txt"), "--method", "mwme"]
    argv += ["--out", str(tmp_path / "m.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "same size" in err and "robust" in err
    cloud = np.random.default_rng(0).random((12, 3))
    np.savetxt(tmp_path / "c.txt", cloud)
    argv = ["match", str(tmp_path / "c.txt"), str(tmp_path / "c.txt"), "--out", str(tmp_path / "m.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "2D point sets only" in err and "--method mwme" in err
    assert not (tmp_path / "m.json").exists()


def test_mwme_matches_a_3d_permutation(tmp_path):
    fixed = np.random.default_rng(2).random((10, 3))
    perm = np.random.default_rng(3).permutation(10)
    np.savetxt(tmp_path / "m.txt", fixed[perm] + 1.0)
    np.savetxt(tmp_path / "f.txt", fixed)
    argv = ["match", str(tmp_path / "m.txt"), str(tmp_path / "f.txt"), "--method", "mwme", "--transform", "rigid"]
    assert main([*argv, "--out", str(tmp_path / "m.json")]) == 0
    record = json.loads((tmp_path / "m.json").read_text())
    assert record["correspondence"] == perm.tolist() and record["transform"]["type"] == "rigid"


def test_the_method_choices_are_the_library_methods():
    from centrality_vision.cli import match as command
    from centrality_vision.matching import METHODS

    assert command.METHODS == METHODS


def test_plot_matching_draws_unmatched_points_grey_without_lines():
    from matplotlib.figure import Figure

    from centrality_vision.plotting import plot_matching

    x = np.random.default_rng(0).random((6, 2))
    correspondence = np.array([0, -1, 2, -1, 4, 5])
    ax = Figure().add_subplot()
    plot_matching(x, x, correspondence, ax=ax)
    assert len(ax.collections[0].get_segments()) == 4  # lines only for the four matched points
    moving_colours = ax.collections[1].get_facecolors()
    assert np.allclose(moving_colours[[1, 3], :3], 0.6)
    fixed_colours = ax.collections[2].get_facecolors()
    assert np.allclose(fixed_colours[[1, 3], :3], 1.0) and not np.allclose(fixed_colours[0, :3], 1.0)


def test_library_advice_reads_as_match_options(tmp_path, capsys):
    # match spells the library's method='local' as --mwme-solver local (its own --method
    # is another choice) and scale=True as --transform similarity
    points = np.random.default_rng(0).random((25, 2))
    np.savetxt(tmp_path / "a.txt", points)
    argv = ["match", str(tmp_path / "a.txt"), str(tmp_path / "a.txt"), "--method", "mwme", "--mwme-solver", "exact"]
    assert main([*argv, "--out", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert "error: --mwme-solver exact solves sets of up to 20 points" in err
    assert "Use --mwme-solver local or --mwme-solver greedy." in err


def test_scale_advice_names_the_transform_option():
    import argparse

    from centrality_vision.cli import _in_cli_words
    from centrality_vision.cli.match import add_parser

    parser = add_parser(argparse.ArgumentParser().add_subparsers())
    args = parser.parse_args(["m.txt", "f.txt", "--out", "x.json"])
    said = _in_cli_words("not reliable; use `scale=True`. From Python, try this.", parser, args)
    assert said == "not reliable; use --transform similarity."
    # fuzz round 6: the rigid limit named the library's `scale=False`
    said = _in_cli_words("`scale=False` needs `moving` and `fixed` of comparable extent.", parser, args)
    assert said == "--transform rigid needs MOVING (m.txt) and FIXED (f.txt) of comparable extent."


def test_no_match_leaves_the_rms_out_of_npz_rather_than_nan(tmp_path, capsys, monkeypatch):
    # fuzz round 6: the .npz stored rms_residual = nan (the .json stores null)
    from centrality_vision.matching import _shape_context

    monkeypatch.setattr(_shape_context, "shape_context_assignment", lambda m, f: (np.full(len(m), -1), {}))
    np.savetxt(tmp_path / "line.txt", np.c_[np.arange(30.0), np.zeros(30)])
    np.savetxt(tmp_path / "cloud.txt", np.random.default_rng(0).random((30, 2)))
    argv = ["match", str(tmp_path / "line.txt"), str(tmp_path / "cloud.txt"), "--method", "shape-context"]
    assert main([*argv, "--out", str(tmp_path / "m.npz")]) == 0
    stored = np.load(tmp_path / "m.npz")
    assert int(stored["n_matched"]) == 0 and "rms_residual" not in stored.files
    assert all(np.all(np.isfinite(stored[key])) for key in stored.files if stored[key].dtype.kind == "f")
    err = capsys.readouterr().err
    assert "paired 0 point" in err and "no RMS residual (no point matched)" in err


def test_robust_options_reach_the_library_and_the_record(partial_pair, tmp_path, capsys):
    # round 17: the command exposed none of n_neighbors, n_candidates and w
    from centrality_vision.matching import match

    folder, _, fixed = partial_pair  # (CPD suits whole sets: the partial one's outliers collapse it)
    moving = 2.0 * fixed[::-1] @ _rotation(0.7).T + [3.0, -1.0]
    np.savetxt(tmp_path / "whole.txt", moving)
    base = ["match", str(tmp_path / "whole.txt"), str(folder / "f.txt")]
    argv = [*base, "--n-neighbors", "5", "--n-candidates", "3", "--refine", "cpd", "--w", "0.1"]
    assert main([*argv, "--out", str(tmp_path / "m.json")]) == 0
    record = json.loads((tmp_path / "m.json").read_text())
    parameters = record["parameters"]
    assert (parameters["n_neighbors"], parameters["n_candidates"], parameters["w"]) == (5, 3, 0.1)
    library = match(moving, fixed, n_neighbors=5, n_candidates=3, refine="cpd", w=0.1)
    assert record["correspondence"] == library.correspondence.tolist()
    # options of another method or refinement are refused, and left out of the record
    capsys.readouterr()
    assert main([*base, "--w", "0.1", "--out", str(tmp_path / "x.json")]) == 2
    assert "--w is an option of --refine cpd; got --refine icp" in capsys.readouterr().err
    assert main([*base, "--method", "shape-context", "--n-neighbors", "5", "--out", str(tmp_path / "x.json")]) == 2
    assert "--n-neighbors is an option of --method robust" in capsys.readouterr().err
    assert main([*base, "--out", str(tmp_path / "d.json")]) == 0
    default = json.loads((tmp_path / "d.json").read_text())["parameters"]
    assert default["n_neighbors"] == 8 and "w" not in default
