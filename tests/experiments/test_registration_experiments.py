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
