import json

import numpy as np

from centrality_vision.experiments import fig_5_3


def test_fig_5_3_quick(tmp_path, capsys):
    assert fig_5_3.main(["--quick", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fig-5.3.json").read_text())
    methods = record["methods"]
    assert set(methods) == set(fig_5_3.METHODS)
    for m in methods.values():
        errors = np.asarray(m["errors"])
        assert len(errors) == m["n_iter"] + 1 and errors[-1] < 1e-3 * errors[0]
        assert {"3", "6", "9"} <= set(m["snapshots"])
    # the thesis' claim for the fish under a similarity transform: closeness-GPD is faster than CPD
    assert methods["closeness"]["below"]["0.01"] < methods["CPD"]["below"]["0.01"]
    assert (tmp_path / "fig-5.3.png").stat().st_size > 10_000 and (tmp_path / "fig-5.4.png").stat().st_size > 10_000
    assert "closeness" in capsys.readouterr().out


def test_fig_5_5_quick(tmp_path):
    from centrality_vision.experiments import fig_5_5

    moving, fixed, true_moving, linear, shift = fig_5_5.problem(0)
    assert moving.shape[1] == 3 and moving.shape[0] < 392 and fixed.shape[0] < 392
    assert np.allclose(true_moving, moving @ linear.T + shift)
    assert fig_5_5.main(["--quick", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fig-5.5.json").read_text())
    # affine CPD with 8% missing on each side heads for the true transform (30 iterations here)
    errors = record["methods"]["CPD"]["errors"]
    assert errors[-1] < 0.01 * errors[0]
    assert {"fig-5.5.png", "fig-5.6.png"} <= {p.name for p in tmp_path.iterdir()}


def test_fig_5_7_quick(tmp_path):
    from centrality_vision.experiments import fig_5_7

    moving, fixed, true_moving = fig_5_7.problem(0)
    assert fixed.shape[0] == moving.shape[0] - fig_5_7.N_MISSING + fig_5_7.N_OUTLIERS
    assert fig_5_7.main(["--quick", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fig-5.7.json").read_text())
    for m in record["methods"].values():
        assert m["errors"][-1] < 0.8 * m["errors"][0]  # every method reduces the misalignment
    assert {"fig-5.7.png", "fig-5.8.png"} <= {p.name for p in tmp_path.iterdir()}


def test_table_5_1_quick(tmp_path, capsys):
    from centrality_vision.experiments import table_5_1

    for kind in table_5_1.CLASSES:
        pts = table_5_1.make_set(kind, 0, n_points=40)
        assert pts.shape[1] == 2 and abs(np.ptp(pts, axis=0).max() - 1) < 1e-12
        np.testing.assert_array_equal(pts, table_5_1.make_set(kind, 0, n_points=40))  # seeded
    assert table_5_1.main(["--quick", "--out", str(tmp_path), "--scheduler", "serial"]) == 0
    record = json.loads((tmp_path / "table-5.1-quick.json").read_text())
    assert set(record["summary"]) == set(table_5_1.CLASSES)
    for kind in table_5_1.CLASSES:
        for m in table_5_1.METHODS:
            cell = record["summary"][kind][m]
            assert 0 <= cell["converged"] <= 100 and len(cell["iterations"]) == 4
    text = capsys.readouterr().out
    assert "Table 5.3" in text and "| 100" in text  # ours | thesis side by side
    lines = (tmp_path / "table-5.1-quick.jsonl").read_text().splitlines()
    assert len(lines) == 20  # one line per unit, kept for a resumed run


def test_table_2_1_and_fig_7_1_reproduce_the_thesis(tmp_path):
    from centrality_vision.experiments import fig_7_1, table_2_1

    assert all(table_2_1.run()["claims"].values())
    assert table_2_1.main(["--out", str(tmp_path / "t")]) == 0
    result = fig_7_1.run()
    assert all(result["claims"].values())
    assert result["ours"]["exhaustive"]["degrees"] == [3, 2, 1, 1, 1]
    assert fig_7_1.main(["--out", str(tmp_path / "f")]) == 0
    assert (tmp_path / "f" / "fig-7.1.png").stat().st_size > 5_000


def test_report_gathers_tables_and_figures(tmp_path):
    from centrality_vision.experiments.report import run_all

    path = run_all(tmp_path, quick=True, only=["table-2.1", "fig-7.1"])
    text = path.read_text()
    assert "## table-2.1" in text and "## fig-7.1" in text
    assert "0.83 | 0.83" in text  # closeness of node b, ours | thesis
    assert "![fig-7.1](fig-7.1/fig-7.1.png)" in text
