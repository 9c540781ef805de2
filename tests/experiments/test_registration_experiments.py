import json
import os

import numpy as np
import pytest

from centrality_vision.experiments import fig_5_3, table_5_1
from centrality_vision.experiments._common import tally


def test_fig_5_3_quick_checks_its_claims_over_seeds(tmp_path, capsys):
    assert fig_5_3.main(["--quick", "--out", str(tmp_path), "--seeds", "3", "--scheduler", "serial"]) == 0
    record = json.loads((tmp_path / "fig-5.3-quick.json").read_text())
    methods = record["methods"]
    assert set(methods) == set(fig_5_3.METHODS)
    for m in methods.values():
        errors = np.asarray(m["errors"])
        assert len(errors) == m["n_iter"] + 1 and errors[-1] < 1e-3 * errors[0]
        assert {"3", "6", "9"} <= set(m["snapshots"])
    # the odds are the tally of the per-seed claims, and seed 0's own claims are among them
    assert record["seeds"] == [0, 1, 2] and len(record["per_seed"]) == 3
    assert record["odds"] == tally([r["claims"] for r in record["per_seed"]])
    assert record["per_seed"][0]["claims"] == record["claims"]
    # each seed draws its own transform
    assert len({json.dumps(r["transform"]) for r in record["per_seed"]}) == 3
    for figure in ("fig-5.3-quick.png", "fig-5.4-quick.png"):
        assert (tmp_path / figure).stat().st_size > 10_000
    out = capsys.readouterr().out
    assert "Claims over 3 seeds" in out and "holds in" in out and 'thesis: "' in out


def _methods(reach: dict) -> dict:
    return {m: {"below": {"0.01": k}} for m, k in reach.items()}


def test_fig_5_3_a_tie_with_betweenness_or_degree_is_not_the_quickest_decay():
    reach = {"betweenness": 7, "closeness": 5, "degree": 9, "eigenvector": 5, "CPD": 12}
    assert fig_5_3._claims(_methods(reach))[fig_5_3.FASTEST]  # tied only with each other: both quickest
    assert not fig_5_3._claims(_methods(reach | {"degree": 5}))[fig_5_3.FASTEST]
    assert not fig_5_3._claims(_methods(reach | {"betweenness": 4}))[fig_5_3.FASTEST]
    assert not fig_5_3._claims(_methods(dict.fromkeys(reach)))[fig_5_3.FASTEST]  # nobody reached 1%


def test_median_iterations_count_a_seed_that_never_reached_1_percent_as_beyond_the_cap():
    from centrality_vision.experiments import fig_5_5

    # closeness reaches 1% in 3 iterations on one seed and never on two: its median is beyond
    # the cap, not 3 (the median over the one seed that got there)
    per_seed = [
        {
            "below": {m: {"0.01": k} for m, k in zip(fig_5_3.METHODS, row)},
            "error_at_10": dict.fromkeys(fig_5_3.METHODS, 0.1),
        }
        for row in ([4, 3, 6, 5, 10], [4, None, 6, 5, None], [5, None, 7, 5, 12])
    ]
    result = {"per_seed": per_seed, "max_iter": 40}
    text = fig_5_3.explain(result)
    assert "betweenness 4, closeness more than 40, degree 6, eigenvector 5, CPD 12" in text
    assert "CPD needs 3.00x, 2.00x, 2.40x the iterations of GPD with betweenness, degree, eigenvector" in text
    per_seed[0]["below"]["CPD"]["0.01"] = None
    text = fig_5_3.explain(result)
    assert "CPD more than 40 (not reached" in text and "CPD needs more than 10.00x, more than 6.67x" in text
    assert "closeness more than 40" in fig_5_5.explain(result) and "nan" not in fig_5_5.explain(result)
    # exactly half the seeds beyond the cap: closeness's median is (3 + x) / 2 and CPD's
    # (12 + x) / 2 with x > 40, so more than 21.5 and 26, not more than 40 (printed before)
    per_seed.append({"below": {m: {"0.01": k} for m, k in zip(fig_5_3.METHODS, [4, 3, 6, 5, 12])}})
    text = fig_5_3.explain(result)
    assert "betweenness 4, closeness more than 21.5, degree 6, eigenvector 5, CPD more than 26 (" in text
    assert "CPD needs more than 6.50x, more than 4.33x, more than 5.20x the iterations" in text


def test_fig_5_3_transform_is_a_seeded_similarity():
    moving, fixed, t = fig_5_3.problem(4)
    a = np.radians(t["rotation_deg"])
    rotation = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    np.testing.assert_allclose(fixed, t["scale"] * moving @ rotation.T + t["translation"])
    assert -60 <= t["rotation_deg"] <= 60 and 0.75 <= t["scale"] <= 1.5
    np.testing.assert_array_equal(fig_5_3.problem(4)[1], fixed)


def test_fig_5_5_cpd_and_gpd_recover_the_affine_map(tmp_path):
    from centrality_vision.experiments import fig_5_5

    moving, fixed, true_moving, linear, shift = fig_5_5.problem(0)
    assert moving.shape[1] == 3 and moving.shape[0] < 392 and fixed.shape[0] < 392
    assert np.allclose(true_moving, moving @ linear.T + shift)
    assert fig_5_5.main(["--quick", "--out", str(tmp_path), "--seeds", "1", "--scheduler", "serial"]) == 0
    record = json.loads((tmp_path / "fig-5.5-quick.json").read_text())
    assert set(record["odds"]) == set(fig_5_5.CLAIMS)
    assert {"fig-5.5-quick.png", "fig-5.6-quick.png"} <= {p.name for p in tmp_path.iterdir()}
    if os.environ.get("CENTRALITY_VISION_TEST_FACE_STAND_IN"):
        # the stand-in surface (tests/conftest.py) is not the face: within the quick run's 30
        # iterations no method (CPD included) reaches 1% there, so only the face is held to it
        pytest.skip("convergence to 1% is checked on the CPD face only (GPL, not in this checkout)")
    # affine CPD and every GPD variant, with 8% missing on each side, head for the true map
    for name, method in record["methods"].items():
        errors = method["errors"]
        assert errors[-1] < 0.01 * errors[0], name


def test_fig_5_5_says_clearly_when_the_face_is_missing(tmp_path):
    from centrality_vision.experiments import fig_5_5

    with pytest.raises(FileNotFoundError, match="needs the CPD face"):
        fig_5_5.main(["--quick", "--out", str(tmp_path / "o"), "--face-dir", str(tmp_path)])
    assert not (tmp_path / "o").exists()  # nothing written


def test_fig_5_7_quick(tmp_path):
    from centrality_vision.experiments import fig_5_7

    moving, fixed, true_moving = fig_5_7.problem(0)
    assert fixed.shape[0] == moving.shape[0] - fig_5_7.N_MISSING + fig_5_7.N_OUTLIERS
    assert fig_5_7.main(["--quick", "--out", str(tmp_path), "--seeds", "2", "--scheduler", "serial"]) == 0
    record = json.loads((tmp_path / "fig-5.7-quick.json").read_text())
    for name, m in record["methods"].items():
        assert m["errors"][-1] <= m["errors"][0], name  # no method makes the misalignment worse
        if name != "eigenvector":  # eigenvector-GPD stalls on this problem (a finding, reported)
            assert m["errors"][-1] < 0.6 * m["errors"][0], name
    assert all(cell["n"] == 2 for cell in record["odds"].values())
    assert {"fig-5.7-quick.png", "fig-5.8-quick.png"} <= {p.name for p in tmp_path.iterdir()}


def test_table_5_1_cells_follow_from_the_sets(tmp_path, capsys):
    for kind in table_5_1.CLASSES:
        pts = table_5_1.make_set(kind, 0, n_points=40)
        assert pts.shape[1] == 2 and abs(np.ptp(pts, axis=0).max() - 1) < 1e-12
        np.testing.assert_array_equal(pts, table_5_1.make_set(kind, 0, n_points=40))  # seeded
    assert table_5_1.main(["--quick", "--out", str(tmp_path), "--scheduler", "serial", "--seeds", "2"]) == 0
    record = json.loads((tmp_path / "table-5.1-quick.json").read_text())
    text = capsys.readouterr().out
    lines = text.splitlines()
    table_5_3 = lines[lines.index("Table 5.3: % converged") + 2 :][: len(table_5_1.CLASSES)]
    for kind, line in zip(table_5_1.CLASSES, table_5_3):
        for j, m in enumerate(table_5_1.METHODS):
            cell = record["summary"][kind][m]
            ok = np.asarray(cell["succeeded"])
            its = np.asarray(cell["iterations"])
            # the printed share and mean are those of the sets' own records
            assert cell["converged"] == pytest.approx(100 * ok.mean())
            if ok.any():
                assert cell["mean"] == pytest.approx(its[ok].mean())
            assert f"{cell['converged']:.0f} | {table_5_1.THESIS['converged'][kind][j]:.0f}" in line
    # the speed-up ratios are CPD's mean over each variant's, per seed
    s0 = record["speedup"]["0"]["cluster"]["closeness"]
    assert s0 == pytest.approx(
        record["summary"]["cluster"]["CPD"]["mean"] / record["summary"]["cluster"]["closeness"]["mean"]
    )
    assert "Speed-up" in text and "2.67" in text  # the thesis' 60.56 / 22.72 beside ours
    assert all(cell["n"] == 2 for cell in record["odds"].values())
    assert len((tmp_path / "table-5.1-quick.jsonl").read_text().splitlines()) == 40  # 2 seeds x 20 units, kept


def test_table_5_1_a_tie_for_the_fewest_iterations_is_no_method_s_win():
    """Ties went to the method listed first: the shipped full run's contour tie (closeness and
    eigenvector both at 1443/99 iterations, seed 1) counted as closeness being fastest."""
    row = {m: {"mean": 20.0} for m in table_5_1.METHODS}
    row["closeness"] = {"mean": 14.0}
    assert table_5_1._fastest(row) == "closeness"
    assert table_5_1._fastest(row | {"eigenvector": {"mean": 14.0}}) is None
    assert table_5_1._fastest(row | {"CPD": {"mean": 13.0}, "degree": {"mean": None}}) == "CPD"
    assert table_5_1._fastest({m: {"mean": None} for m in table_5_1.METHODS}) is None


def test_table_5_1_never_reports_another_seeds_numbers(tmp_path):
    """Re-running with another seed into the same folder computes that seed, never reuses the old one."""
    kwargs = dict(quick=True, out=tmp_path, scheduler="serial", progress=False, n_sets=1)
    first = table_5_1.run(seed=0, **kwargs)
    again = table_5_1.run(seed=7, **kwargs)
    fresh = table_5_1.run(seed=7, **{**kwargs, "out": tmp_path / "fresh"})
    assert again["seed"] == 7 and again["summary"] == fresh["summary"]
    assert again["summary"] != first["summary"]
    assert table_5_1.format_table(again) == table_5_1.format_table(fresh)


def test_table_2_1_and_fig_7_1_reproduce_the_thesis(tmp_path):
    from centrality_vision.experiments import fig_7_1, table_2_1

    assert all(table_2_1.run()["claims"].values())
    assert table_2_1.main(["--out", str(tmp_path / "t")]) == 0
    result = fig_7_1.run()
    assert all(result["claims"].values())
    assert result["ours"]["exhaustive"]["degrees"] == [3, 2, 1, 1, 1]
    assert fig_7_1.main(["--out", str(tmp_path / "f")]) == 0
    assert (tmp_path / "f" / "fig-7.1.png").stat().st_size > 5_000


def test_table_2_1_explanation_follows_the_numbers():
    from centrality_vision.experiments import table_2_1

    result = table_2_1.run()
    assert table_2_1.explain(result).startswith("4 of 4 centralities equal")
    result["ours"]["closeness"][1] += 0.05
    result["claims"]["closeness equals Table 2.1 to two decimals"] = False
    text = table_2_1.explain(result)
    assert text.startswith("3 of 4") and "closeness differ" in text and "0.05" in text


def test_fig_7_1_table_gives_the_msts_cost_under_the_figures_lambda():
    # found by a fuzz run: the table printed the MST's cost at lambda 0 (4.00) under the
    # heading lambda = 1, where the text said 3.28
    from centrality_vision.experiments import fig_7_1

    result = fig_7_1.run()
    mst = result["ours"]["mst"]
    expected = f"{mst['weight'] - result['lam'] * mst['entropy']:.2f}"
    row = next(line for line in fig_7_1.format_table(result).splitlines() if line.strip().startswith("MST "))
    assert expected in row.split() and expected in fig_7_1.explain(result)


def test_odds_never_print_an_interval_that_rounds_to_nothing():
    # 1000 of 1000 has a 95% interval of 99.6-100%: whole percents printed '100-100%'
    from centrality_vision.experiments._common import percents, share
    from centrality_vision.experiments._compare import odds_sentences

    always = tally([{"c": True}] * 1000)
    assert "(95% interval 99.6-100.0%)" in share(always["c"])
    once = tally([{"c": True}] + [{"c": False}] * 999)
    assert '"c" holds in 1 of 1000 seeds (0.10%, 95% interval 0.02-0.56%)' in odds_sentences(once)[0]
    assert share(tally([{"c": True}] * 17 + [{"c": False}] * 3)["c"]) == "holds in 17 of 20 (95% interval 64-95%)"
    for k, n in [(0, 1), (1, 3), (499, 1000), (999, 1000), (99_999, 100_000)]:
        cell = tally([{"c": True}] * k + [{"c": False}] * (n - k))["c"]
        low, high = (float(t) for t in percents(cell["low"], cell["high"]))
        assert low < high and (0 < low or cell["low"] == 0) and (high < 100 or cell["high"] == 1)
