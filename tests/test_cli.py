import json

import numpy as np

from centrality_vision.cli import main


def test_demo_writes_figures_and_results(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    names = {p.name for p in tmp_path.iterdir()}
    assert {"fish_delaunay_closeness.png", "fish_delaunay_centralities.png", "cow1_closeness.png", "demo.json"} <= names
    record = json.loads((tmp_path / "demo.json").read_text())
    assert record["graph"]["n_nodes"] == 91
    saved = np.load(tmp_path / "fish_delaunay_centralities.npz")
    assert saved["closeness"].shape == (91,) and np.all(saved["closeness"] > 0)
    assert "most central points by closeness" in capsys.readouterr().out


def test_demo_unknown_shape_is_a_one_line_error(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--shape", "unicorn"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unicorn" in err[0]


def test_no_command_prints_help(capsys):
    assert main([]) == 0
    assert "demo" in capsys.readouterr().out


def test_reproduce_rejects_unknown_experiment(capsys):
    import pytest

    with pytest.raises(SystemExit) as info:
        main(["reproduce", "table-9.9"])
    assert info.value.code == 2
    assert "invalid choice" in capsys.readouterr().err
