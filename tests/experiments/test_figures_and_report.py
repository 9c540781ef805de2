import json
import re

import matplotlib
import numpy as np
import pytest

from centrality_vision.experiments import EXPERIMENTS, REGISTRY, RUNNER_EXPERIMENTS, experiment_argv


def test_the_registry_is_the_one_list():
    assert EXPERIMENTS == {name: e.module for name, e in REGISTRY.items()}
    assert set(RUNNER_EXPERIMENTS) == {name for name, e in REGISTRY.items() if e.runner}
    # fig-5.1 takes neither seeds (its claims are checked on every point) nor a scheduler
    assert experiment_argv("fig-5.1", "o", scheduler="dask", seeds=4) == ["--out=o", "--seed=0"]
    assert experiment_argv("fig-5.3", "o", seeds=4) == ["--out=o", "--seed=0", "--seeds=4"]
    assert experiment_argv("table-5.1", "o", quick=True, scheduler="dask")[-2:] == ["--quick", "--scheduler=dask"]
    with pytest.raises(ValueError, match="name"):
        experiment_argv("fig-9.9", "o")


def test_no_experiment_switches_the_matplotlib_backend(tmp_path, monkeypatch):
    from centrality_vision.experiments import fig_5_10, table_2_1

    def refuse(*args, **kwargs):
        raise AssertionError("matplotlib.use called by library code")

    monkeypatch.setattr(matplotlib, "use", refuse)
    assert table_2_1.main(["--out", str(tmp_path / "t")]) == 0
    assert fig_5_10.main(["--quick", "--out", str(tmp_path / "f")]) == 0
    assert (tmp_path / "f" / "fig-5.10-quick.png").stat().st_size > 10_000


def test_fig_5_10_draws_the_sets_table_5_1_registers(tmp_path):
    from centrality_vision.experiments import fig_5_10, table_5_1

    result = fig_5_10.run(seed=3, index=5)
    for kind in table_5_1.CLASSES:
        np.testing.assert_array_equal(result["sets"][kind], table_5_1.make_set(kind, 5, seed=3))


def test_fig_5_1_prior_is_eq_5_1_and_posteriors_are_distributions(tmp_path):
    from centrality_vision.experiments import fig_5_1

    result = fig_5_1.run(seed=0)
    c = result["chosen"]
    v, vx = np.asarray(result["v_moving"]), result["v_fixed"][c]
    counts, edges = np.histogram(v, bins=10, range=(0, 1))
    h = counts[np.clip(np.searchsorted(edges, v, side="right") - 1, 0, 9)]
    by_hand = h * np.exp(-((v - vx) ** 2) / (2 * result["phi2"]))
    np.testing.assert_allclose(result["column"]["prior_gpd"], by_hand / by_hand.sum(), rtol=1e-9)
    np.testing.assert_allclose(result["column"]["prior_cpd"], 1 / v.size)
    for key in ("posterior_cpd", "posterior_gpd"):
        assert sum(result["column"][key]) == pytest.approx(1.0)
    # Delaunay graphs and closeness are similarity-invariant: each point's partner has its closeness
    np.testing.assert_allclose(result["v_fixed"], result["v_moving"], atol=1e-12)
    assert all(cell["n"] == v.size for cell in result["odds"].values())
    paths = fig_5_1.plot(result, tmp_path)
    assert [p.name for p in paths] == ["fig-5.1.png", "fig-5.2.png"] and all(p.stat().st_size > 10_000 for p in paths)


def test_fig_4_2_distances_and_figures(tmp_path):
    from centrality_vision.datasets import load_kimia99
    from centrality_vision.experiments import fig_4_2

    names = list(load_kimia99().names)
    d = fig_4_2.histogram_distances(names.index("fish14"), 0, seed=0)
    assert set(d) == set(fig_4_2.CENTRALITIES) and all(0 <= v <= 1 for v in d.values())
    # 5% of the pixels removed: interior pixels lose neighbours, so the degree histogram moves
    assert d["degree"] > 0.05
    result = {"seed": 0, "shapes": ["fish14"]}
    paths = fig_4_2.plot(result, tmp_path)
    assert {p.name for p in paths} == {
        "fig-4.1.png",
        "fig-4.2.png",
        "fig-4.3.png",
        "fig-4.4.png",
        "fig-4.5.png",
        "fig-4.6.png",
    }


def test_report_index_and_computed_explanations(tmp_path):
    from centrality_vision.experiments.report import run_all, write_report

    path = run_all(tmp_path, quick=True, only=["table-2.1", "fig-5.10"])
    text = path.read_text()
    assert "## table-2.1" in text and "0.83 | 0.83" in text  # closeness of node b, ours | thesis
    assert (
        "| fig. 5.10 | Sample point-sets of 495 database used | "
        "[fig-5.10/fig-5.10-quick.png](fig-5.10/fig-5.10-quick.png) |" in text
    )
    assert "| fig. 2.12 | A toy example for graph centralities | [table-2.1/table-2.1-quick.png]" in text
    assert "| fig. 4.2 | Centrality distribution of graphs | **missing**" in text  # not run here, and said so
    assert "| fig. 1.1 | Scene Understanding | none:" in text
    assert "**What the numbers show.** 4 of 4 centralities equal" in text
    # the code it ran and how long: a report read later says what made it
    from centrality_vision._provenance import code_digest

    assert re.search(rf"code digest `{code_digest()}`, written \d{{4}}-\d\d-\d\d \d\d:\d\d UTC; this run took", text)
    # the paragraph is computed from the stored result: change a number, the sentence changes
    record = json.loads((tmp_path / "table-2.1" / "table-2.1-quick.json").read_text())
    record["claims"]["degree equals Table 2.1 to two decimals"] = False
    (tmp_path / "table-2.1" / "table-2.1-quick.json").write_text(json.dumps(record))
    text = write_report(tmp_path, ["table-2.1"], quick=True, seed=0).read_text()
    assert "3 of 4 centralities equal" in text and "degree differ" in text
    assert "this run took" not in text  # (written from stored results: nothing was timed)


def test_report_says_why_an_experiment_did_not_run(tmp_path, monkeypatch):
    from centrality_vision.experiments import fig_5_5
    from centrality_vision.experiments.report import run_all

    def missing(face_dir=None):
        raise FileNotFoundError("fig-5.5 needs the CPD face (test)")

    monkeypatch.setattr(fig_5_5, "face_points", missing)
    text = run_all(tmp_path, quick=True, only=["fig-5.5"]).read_text()
    assert "**Not run here.** fig-5.5 needs the CPD face (test)" in text


def test_quick_and_full_runs_share_a_folder_and_the_report_takes_only_its_own_runs_files(tmp_path):
    # a quick run wrote the same names as a full run (overwriting its tables and figures), and
    # the report listed every .txt/.png in the folder: the other run's, and stale ones
    from centrality_vision.experiments.report import run_all, write_report

    run_all(tmp_path, quick=False, only=["table-2.1"])
    folder = tmp_path / "table-2.1"
    full_files = {path.name: path.read_bytes() for path in folder.iterdir()}
    record = json.loads((folder / "table-2.1.json").read_text())
    record["claims"]["degree equals Table 2.1 to two decimals"] = False
    (folder / "table-2.1.json").write_text(json.dumps(record))
    run_all(tmp_path, quick=True, only=["table-2.1"])
    # the full run's files are all still there, unchanged but for the edit above
    assert {"table-2.1.txt", "table-2.1.png", "table-2.1.files.json"} <= set(full_files)
    for name, content in full_files.items():
        assert name == "table-2.1.json" or (folder / name).read_bytes() == content, name
    assert {"table-2.1-quick.txt", "table-2.1-quick.json", "table-2.1-quick.png"} <= {p.name for p in folder.iterdir()}
    # files left by hand (or by an older version) are in no report
    (folder / "table-2.1-old.png").write_bytes((folder / "table-2.1.png").read_bytes())
    (folder / "table-2.1-quick-notes.txt").write_text("STALE TABLE\n")
    full = write_report(tmp_path, ["table-2.1"], quick=False, seed=0).read_text()
    quick = write_report(tmp_path, ["table-2.1"], quick=True, seed=0).read_text()
    assert "3 of 4 centralities equal" in full and "4 of 4 centralities equal" in quick
    for text, other in ((full, "-quick"), (quick, "table-2.1.png")):
        assert "STALE TABLE" not in text and "table-2.1-old.png" not in text and other not in text
        assert text.count("```text") == 1


def test_a_run_that_fails_while_writing_changes_nothing_in_its_folder(tmp_path):
    from centrality_vision.experiments._common import outputs_of, run_outputs

    with run_outputs(tmp_path, "fig-0", quick=False) as stage:
        (stage / "fig-0.txt").write_text("first")
    before = {path.name: path.read_bytes() for path in tmp_path.iterdir()}
    with pytest.raises(RuntimeError, match="plot failed"):
        with run_outputs(tmp_path, "fig-0", quick=False) as stage:
            (stage / "fig-0.txt").write_text("second")
            raise RuntimeError("plot failed")
    assert {path.name: path.read_bytes() for path in tmp_path.iterdir()} == before
    assert [path.read_text() for path in outputs_of(tmp_path, "fig-0", quick=False)] == ["first"]
    # a staging folder left by a killed run is cleared by the next run
    (tmp_path / ".writing-fig-0").mkdir()
    (tmp_path / ".writing-fig-0" / "fig-9.png").write_text("debris")
    with run_outputs(tmp_path, "fig-0", quick=False) as stage:
        (stage / "fig-0.txt").write_text("third")
    assert [path.name for path in outputs_of(tmp_path, "fig-0", quick=False)] == ["fig-0.txt"]
    assert not (tmp_path / ".writing-fig-0").exists() and not (tmp_path / "fig-9.png").exists()


def test_fig_4_2_closeness_tied_with_another_centrality_does_not_change_least():
    from centrality_vision.experiments import fig_4_2

    d = {"betweenness": 0.3, "closeness": 0.1, "degree": 0.5, "eigenvector": 0.2}
    assert fig_4_2._claims(d)[fig_4_2.CLOSENESS_MOST]
    assert not fig_4_2._claims(d | {"eigenvector": 0.1})[fig_4_2.CLOSENESS_MOST]
    assert not fig_4_2._claims(d | {"betweenness": 0.05})[fig_4_2.CLOSENESS_MOST]


def test_fig_5_1_a_partner_tied_with_others_is_ranked_after_them():
    from centrality_vision.experiments.fig_5_1 import partner_ranks

    prior = np.full((12, 2), 0.05)
    prior[:, 1] = np.linspace(0.2, 0.01, 12)
    # fixed point 0: all twelve moving points tie, so the partner is not "among the ten"
    assert partner_ranks(prior) == [12, 2]
    prior[0, 0] = 0.06
    assert partner_ranks(prior)[0] == 1


def test_a_report_place_that_cannot_be_written_is_refused_before_any_experiment_runs(tmp_path, monkeypatch):
    """A folder named report.md was found only after every experiment had run (78 s quick,
    about 80 min full), as a bare ``[Errno 21] Is a directory``."""
    from centrality_vision.exceptions import InputError
    from centrality_vision.experiments import table_2_1
    from centrality_vision.experiments.report import run_all

    (tmp_path / "report.md").mkdir()
    ran = []
    monkeypatch.setattr(table_2_1, "main", lambda argv: ran.append(argv) or 0)
    with pytest.raises(InputError, match=r"`out`: .*report.md is a folder, not a file"):
        run_all(tmp_path, quick=True, only=["table-2.1"])
    assert not ran


def test_a_file_in_the_staging_folder_s_place_or_a_folder_in_the_results_file_s_is_handled(tmp_path):
    """A file where a run stages its outputs gave ``[Errno 20] Not a directory``; a folder
    where the results file goes gave ``[Errno 21] Is a directory``."""
    from centrality_vision.exceptions import InputError
    from centrality_vision.experiments._common import outputs_of, run_outputs
    from centrality_vision.experiments._runner import Unit, run_units

    (tmp_path / ".writing-fig-0").write_text("debris")
    with run_outputs(tmp_path, "fig-0", quick=False) as stage:
        (stage / "fig-0.txt").write_text("table")
    assert [path.name for path in outputs_of(tmp_path, "fig-0", quick=False)] == ["fig-0.txt"]
    (tmp_path / "fig-0.jsonl").mkdir()
    with pytest.raises(InputError, match=r"`path` must be a results file .*fig-0.jsonl.*which is a folder"):
        run_units([Unit("u", abs, {"x": 1})], tmp_path / "fig-0.jsonl", scheduler="serial", progress=False)


def test_a_folder_in_an_output_file_s_place_changes_nothing_in_the_run_s_folder(tmp_path):
    """The move failed half way: the last run's manifest was gone and some of its files were
    replaced by the failed run's, though the docstring promises no change on an error."""
    from centrality_vision.exceptions import InputError
    from centrality_vision.experiments._common import outputs_of, run_outputs, tally

    with run_outputs(tmp_path, "fig-0", quick=False) as stage:
        (stage / "fig-0.json").write_text("first")
        (stage / "fig-0.txt").write_text("first")
    (tmp_path / "fig-0.txt").unlink()
    (tmp_path / "fig-0.txt").mkdir()
    before = {path.name: path.is_dir() or path.read_text() for path in tmp_path.iterdir()}
    with pytest.raises(InputError, match=r"fig-0.txt is a folder where fig-0 writes a file"):
        with run_outputs(tmp_path, "fig-0", quick=False) as stage:
            (stage / "fig-0.json").write_text("second")
            (stage / "fig-0.txt").write_text("second")
    assert {path.name: path.is_dir() or path.read_text() for path in tmp_path.iterdir()} == before
    assert [path.name for path in outputs_of(tmp_path, "fig-0", quick=False)] == ["fig-0.json"]
    with pytest.raises(TypeError, match="claim 'c' must be True or False in every draw; got nan"):
        tally([{"c": True}, {"c": float("nan")}])  # bool(nan) is True: it counted as holding
