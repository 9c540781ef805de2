import json

import numpy as np

from centrality_vision.experiments import fig_6_4, fig_7_4


def test_fig_6_4_quick(tmp_path, capsys):
    assert fig_6_4.main(["--quick", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fig-6.4.json").read_text())
    acc = np.asarray(record["accuracy"])
    assert acc.shape == (9, 3)
    assert acc[:, 0].mean() >= 0.95  # noiseless similarity transforms
    assert acc[:, 0].mean() >= acc[:, -1].mean()
    assert (tmp_path / "fig-6.4.png").stat().st_size > 10_000
    assert "mean" in capsys.readouterr().out


def test_fig_7_4_perturbation_and_share():
    rng = np.random.default_rng(0)
    points = rng.random((20, 2))
    moved = fig_7_4.perturb(points, 0.1, np.random.default_rng(1))
    assert np.all(np.linalg.norm(moved - points, axis=1) <= 0.1 + 1e-12)
    from centrality_vision.graphs import delaunay_graph

    # no movement: every edge is stable
    assert fig_7_4.stable_share(points, delaunay_graph, 0.0, 5, np.random.default_rng(2)) == 1.0
    big = fig_7_4.stable_share(points, delaunay_graph, 0.5, 5, np.random.default_rng(2))
    assert 0.0 <= big < 1.0


def test_fig_7_4_quick(tmp_path):
    assert fig_7_4.main(["--quick", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fig-7.4.json").read_text())
    assert record["levels"] == [1, 5, 10]
    for name in fig_7_4.DATASETS:
        for graph in fig_7_4.GRAPHS:
            shares = np.asarray(record["shares"][name][graph])
            assert shares.shape == (3, 3) and np.all((shares >= 0) & (shares <= 1))
            # more noise never keeps more edges, in the median
            med = np.median(shares, axis=1)
            assert med[0] >= med[-1]
    assert {"fig-7.4.png", "fig-7.3-fish.png", "fig-7.5-cow1.png"} <= {p.name for p in tmp_path.iterdir()}
