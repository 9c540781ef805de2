import json
import os

import pytest

from centrality_vision.experiments._runner import Unit, load_results, run_units
from centrality_vision.experiments.table_5_1 import register_set


def _square(x, marker_dir):
    """A unit that leaves a file per call, so tests can count the calls (any process)."""
    open(os.path.join(marker_dir, f"call-{x}-{os.getpid()}-{os.urandom(4).hex()}"), "w").close()
    if x < 0:
        raise RuntimeError("boom")
    return {"x": x, "square": x * x}


def _calls(folder):
    return len([p for p in os.listdir(folder) if p.startswith("call-")])


def test_results_are_appended_and_reused(tmp_path):
    units = [Unit(f"u{i}", _square, {"x": i, "marker_dir": str(tmp_path)}) for i in range(5)]
    out = run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert out == {f"u{i}": {"x": i, "square": i * i} for i in range(5)}
    assert _calls(tmp_path) == 5
    assert len((tmp_path / "r.jsonl").read_text().splitlines()) == 5
    again = run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert again == out and _calls(tmp_path) == 5  # nothing recomputed


def test_a_crash_keeps_what_finished_and_a_rerun_does_the_rest(tmp_path):
    units = [Unit(f"u{i}", _square, {"x": i if i != 3 else -1, "marker_dir": str(tmp_path)}) for i in range(5)]
    with pytest.raises(RuntimeError, match="boom"):
        run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert set(load_results(tmp_path / "r.jsonl")) == {"u0", "u1", "u2"}
    fixed = units[:3] + [Unit("u3", _square, {"x": 3, "marker_dir": str(tmp_path)})] + units[4:]
    before = _calls(tmp_path)
    out = run_units(fixed, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert _calls(tmp_path) - before == 2 and out["u3"]["square"] == 9


def test_a_torn_last_line_is_dropped(tmp_path):
    path = tmp_path / "r.jsonl"
    path.write_text(json.dumps({"key": "a", "result": 1}) + "\n" + '{"key": "b", "res')
    assert load_results(path) == {"a": 1}
    out = run_units([Unit("b", _square, {"x": 2, "marker_dir": str(tmp_path)})], path, scheduler="serial", progress=False)
    assert out == {"b": {"x": 2, "square": 4}}
    assert load_results(path) == {"a": 1, "b": {"x": 2, "square": 4}}


def test_process_pool_and_dask_give_identical_results(tmp_path):
    units = [Unit(f"{k}/{i}", register_set, {"kind": k, "index": i, "n_points": 30}) for k in ("random", "contour") for i in range(2)]
    serial = run_units(units, tmp_path / "serial.jsonl", scheduler="serial", progress=False)
    pool = run_units(units, tmp_path / "pool.jsonl", scheduler="processes", workers=2, progress=False)
    assert pool == serial
    pytest.importorskip("distributed")
    dask = run_units(units, tmp_path / "dask.jsonl", scheduler="dask", workers=2, progress=False)
    assert dask == serial


def test_bad_runner_arguments(tmp_path):
    unit = Unit("a", _square, {"x": 1, "marker_dir": str(tmp_path)})
    with pytest.raises(ValueError, match="scheduler"):
        run_units([unit], tmp_path / "r.jsonl", scheduler="threads")
    with pytest.raises(ValueError, match="unique keys"):
        run_units([unit, unit], tmp_path / "r.jsonl", scheduler="serial")
