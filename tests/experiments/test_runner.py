import json
import os

import pytest

from centrality_vision.exceptions import CodeChangedError, InputError
from centrality_vision.experiments._runner import Unit, _checksum, _connect, load_results, run_units, unit_id
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


def _shaped(x):
    return {"pair": (x, x + 1), "by_index": {0: x}}


def _unstorable(x):
    return {"values": __import__("numpy").arange(x)}


def test_a_run_and_its_resumption_hand_out_the_same_values(tmp_path):
    """The first run returned the unit's own objects (a tuple, int keys) and a resumed run the
    JSON it read back (a list, str keys): the same experiment saw different types."""
    units = [Unit(f"u{i}", _shaped, {"x": i}) for i in range(3)]
    first = run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    again = run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert first == again == {f"u{i}": {"pair": [i, i + 1], "by_index": {"0": i}} for i in range(3)}


def test_a_result_json_cannot_hold_is_named_with_its_unit(tmp_path):
    with pytest.raises(TypeError, match=r"unit 'u3' returned a result that cannot be stored as JSON.*ndarray"):
        run_units([Unit("u3", _unstorable, {"x": 3})], tmp_path / "r.jsonl", scheduler="serial", progress=False)


def _colliding(x):
    return {"per_seed": [{"n": x, 1: "one", "1": "text one"}]}


def test_a_result_whose_keys_collide_in_json_is_refused_not_halved(tmp_path):
    """Keys 1 and "1" are one key in JSON: the stored result kept only one value, silently
    (audit 31)."""
    with pytest.raises(TypeError, match=r"unit 'c' returned .*the keys 1 and '1' are the same in JSON"):
        run_units([Unit("c", _colliding, {"x": 0})], tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert load_results(tmp_path / "r.jsonl") == {}


def test_a_crash_keeps_what_finished_and_a_rerun_does_the_rest(tmp_path):
    units = [Unit(f"u{i}", _square, {"x": i if i != 3 else -1, "marker_dir": str(tmp_path)}) for i in range(5)]
    with pytest.raises(RuntimeError, match="boom"):
        run_units(units, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert {i.split("#")[0] for i in load_results(tmp_path / "r.jsonl")} == {"u0", "u1", "u2"}
    fixed = units[:3] + [Unit("u3", _square, {"x": 3, "marker_dir": str(tmp_path)})] + units[4:]
    before = _calls(tmp_path)
    out = run_units(fixed, tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert _calls(tmp_path) - before == 2 and out["u3"]["square"] == 9


def test_a_torn_last_line_is_dropped(tmp_path):
    path = tmp_path / "r.jsonl"
    path.write_text(json.dumps({"key": "a", "result": 1, "check": _checksum("a", 1)}) + "\n" + '{"key": "b", "res')
    assert load_results(path) == {"a": 1}
    unit = Unit("b", _square, {"x": 2, "marker_dir": str(tmp_path)})
    out = run_units([unit], path, scheduler="serial", progress=False)
    assert out == {"b": {"x": 2, "square": 4}}
    assert load_results(path) == {"a": 1, unit_id(unit): {"x": 2, "square": 4}}


def test_process_pool_and_dask_give_identical_results(tmp_path):
    units = [
        Unit(f"{k}/{i}", register_set, {"kind": k, "index": i, "n_points": 30})
        for k in ("random", "contour")
        for i in range(2)
    ]
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


def test_other_parameters_in_the_same_file_are_recomputed_never_reused(tmp_path, capsys):
    """A unit with the same label but another seed (or size) never gets the stored result."""
    path = tmp_path / "r.jsonl"
    first = run_units(
        [Unit("u", _square, {"x": 2, "marker_dir": str(tmp_path)})], path, scheduler="serial", progress=False
    )
    second = run_units(
        [Unit("u", _square, {"x": 3, "marker_dir": str(tmp_path)})], path, scheduler="serial", progress=False
    )
    assert first == {"u": {"x": 2, "square": 4}} and second == {"u": {"x": 3, "square": 9}}
    assert _calls(tmp_path) == 2
    assert "1 stored result(s) are not units of this run" in capsys.readouterr().err
    # both stay in the file; asking for the first again reads it, computing nothing
    again = run_units(
        [Unit("u", _square, {"x": 2, "marker_dir": str(tmp_path)})], path, scheduler="serial", progress=False
    )
    assert again == first and _calls(tmp_path) == 2
    # a run that needs fewer of the stored units (fewer seeds) says so without blaming parameters
    capsys.readouterr()
    both = [
        Unit("a", _square, {"x": 4, "marker_dir": str(tmp_path)}),
        Unit("b", _square, {"x": 5, "marker_dir": str(tmp_path)}),
    ]
    run_units(both, tmp_path / "s.jsonl", scheduler="serial", progress=False)
    run_units(both[:1], tmp_path / "s.jsonl", scheduler="serial", progress=False)
    err = capsys.readouterr().err
    assert "1 stored result(s) are not units of this run" in err and "Computing 0 of 1" in err


def test_damaged_or_edited_lines_are_recomputed_never_read(tmp_path, capsys):
    """Lines that are not a record of this runner, or whose result was edited, were read back
    (an edited iteration count flipped a thesis claim) or crashed the run (TypeError, KeyError,
    UnicodeDecodeError). Each is counted in a note (audit 26 L9: a resume recomputed work
    without saying why)."""
    unit = Unit("u", _square, {"x": 2, "marker_dir": str(tmp_path)})
    path = tmp_path / "r.jsonl"
    good = run_units([unit], path, scheduler="serial", progress=False)
    line = path.read_bytes()
    edited = line.replace(b'"square":4', b'"square":5')
    assert edited != line
    damaged = [b"\xff\xfe\x00garbage\x80\n", b"[1,2]\n", b"null\n", b"{}\n", b'"abc"\n', b'{"key":[1],"result":1}\n']
    damaged += [b'{"key":"' + unit_id(unit).encode() + b'","result":null}\n', edited]
    damaged += [b"[" * 200_000 + b"\n"]  # nested past the JSON parser: was a RecursionError
    capsys.readouterr()
    for text in damaged:
        path.write_bytes(text)
        assert load_results(path) == {}
        before = _calls(tmp_path)
        assert run_units([unit], path, scheduler="serial", progress=False) == good
        assert _calls(tmp_path) == before + 1
        assert "skipped 1 damaged line (" in capsys.readouterr().err
    run_units([unit], path, scheduler="serial", progress=False)  # the damaged line is still there: said so
    assert "they are left in the file, and a unit of this run whose result was among them" in capsys.readouterr().err
    path.write_bytes(line)  # one whole record
    assert run_units([unit], path, scheduler="serial", progress=False) == good
    assert "damaged" not in capsys.readouterr().err
    path.write_bytes(b"".join(damaged[:3]) + line + b'{"key": "b", "res')  # and a torn last line
    run_units([unit], path, scheduler="serial", progress=False)
    assert "skipped 4 damaged lines" in capsys.readouterr().err


def test_an_address_that_is_not_a_dask_scheduler_is_an_error_not_a_hang():
    """An HTTP server's address as --scheduler: distributed's Client waited forever for the
    handshake (its own timeout does not cover it); another peer's reply raised MemoryError."""
    import time

    def silent(address, timeout):  # what Client() does against a listener that never answers
        time.sleep(60)

    started = time.perf_counter()
    with pytest.raises(InputError, match="could not be reached as a Dask scheduler: no answer within 1 s"):
        _connect(silent, "tcp://127.0.0.1:8787", seconds=1.0)
    assert time.perf_counter() - started < 10

    def garbled(address, timeout):  # a peer whose reply reads as a huge frame length
        raise MemoryError("Unable to allocate 3.07 EiB")

    with pytest.raises(InputError, match=r"tcp://127.0.0.1:9.*MemoryError: Unable to allocate"):
        _connect(garbled, "tcp://127.0.0.1:9", seconds=5.0)


def test_unit_ids_change_with_every_parameter_the_version_and_the_code(monkeypatch):
    import centrality_vision
    from centrality_vision import _provenance

    base = unit_id(Unit("k", _square, {"x": 1, "marker_dir": "d"}))
    assert base == unit_id(Unit("k", _square, {"marker_dir": "d", "x": 1}))  # argument order is irrelevant
    assert base != unit_id(Unit("k", _square, {"x": 1, "marker_dir": "e"}))
    assert base != unit_id(Unit("k", register_set, {"x": 1, "marker_dir": "d"}))
    monkeypatch.setattr(_provenance, "code_digest", lambda: "0" * 16)  # the same version, edited code
    assert base != unit_id(Unit("k", _square, {"x": 1, "marker_dir": "d"}))
    monkeypatch.undo()
    monkeypatch.setattr(centrality_vision, "__version__", "0.0.0-other")
    assert base != unit_id(Unit("k", _square, {"x": 1, "marker_dir": "d"}))


class _Hidden:
    """An object whose repr does not show its state."""

    def __init__(self, value):
        self.value = value

    def __repr__(self):
        return "_Hidden()"


def test_unit_ids_tell_apart_values_that_print_alike():
    """An estimator was keyed by its repr, which rounds an ``init`` transform's arrays to 8
    digits: translations 0.1 and 0.100000001 shared a unit id, and the second run was handed
    the first one's result. JSON writes dict keys as strings ({1: x} and {"1": x} collided;
    keys of mixed types raised a bare TypeError)."""
    import numpy as np

    from centrality_vision.registration import RigidCPD
    from centrality_vision.transforms import SimilarityTransform

    def key(value):
        return unit_id(Unit("k", _square, {"x": value}))

    def init(shift):
        return RigidCPD(init=SimilarityTransform(rotation=np.eye(2), translation=np.array([shift, 0.0])))

    assert repr(init(0.1)) == repr(init(0.100000001))
    assert key(init(0.1)) != key(init(0.100000001))
    assert key(init(0.1)) == key(init(0.1))
    assert key(RigidCPD(w=0.1)) != key(RigidCPD(w=0.2))
    assert key({1: "a"}) != key({"1": "a"})
    assert key({1: "a", "b": 2}) == key({"b": 2, 1: "a"})
    assert key(_Hidden(1)) != key(_Hidden(2))
    assert key(_Hidden(1)) == key(_Hidden(1))


_KILL_SCRIPT = """
import sys
from centrality_vision.experiments._runner import Unit, run_units
sys.path.insert(0, {tests!r})
from test_runner import _sleeper
units = [Unit(f"u{{i}}", _sleeper, {{"marker_dir": {folder!r}}}) for i in range(2)]
run_units(units, {folder!r} + "/r.jsonl", scheduler={scheduler!r}, workers=2, progress=False)
"""


def _sleeper(marker_dir):
    open(os.path.join(marker_dir, f"pid-{os.getpid()}"), "w").close()
    import time

    time.sleep(120)
    return 0


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (exited, not yet reaped by its new parent) counts as gone
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("scheduler", ["processes"])
def test_a_killed_run_leaves_no_orphan_workers(tmp_path, scheduler):
    import signal
    import subprocess
    import sys
    import time

    script = _KILL_SCRIPT.format(tests=os.path.dirname(__file__), folder=str(tmp_path), scheduler=scheduler)
    parent = subprocess.Popen([sys.executable, "-c", script])
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len([p for p in os.listdir(tmp_path) if p.startswith("pid-")]) < 2:
            time.sleep(0.2)
        workers = [int(p[4:]) for p in os.listdir(tmp_path) if p.startswith("pid-")]
        assert len(workers) == 2 and all(_alive(w) for w in workers)
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    assert not any(_alive(w) for w in workers)


@pytest.mark.parametrize(("workers", "error"), [(0, ValueError), (-2, ValueError), (1.5, TypeError)])
def test_run_units_checks_workers_first(tmp_path, workers, error):
    with pytest.raises(error, match="`workers`"):
        run_units([], tmp_path / "r.jsonl", workers=workers, progress=False)


def test_seed_list_checks_seed_and_seeds():
    from centrality_vision.experiments._common import seed_list

    with pytest.raises(ValueError, match="`seed`"):
        seed_list(-1, 3, False)
    with pytest.raises(ValueError, match="`seeds`"):
        seed_list(0, 10**9, False)
    assert seed_list(2**32 - 3, 3, False)[-1] == 2**32 - 1  # scikit-learn's random_state range
    with pytest.raises(ValueError, match="`seed`"):
        seed_list(2**32, 1, False)


def test_every_experiment_is_registered_once():
    import ast
    import inspect

    import centrality_vision.experiments as experiments

    tree = ast.parse(inspect.getsource(experiments))
    names = [
        node.args[0].value
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Experiment"
    ]
    assert len(names) == len(set(names)) == len(experiments.REGISTRY)


@pytest.mark.skipif(os.name != "posix", reason="process groups and SIGINT")
def test_ctrl_c_on_a_pool_run_ends_it_at_once(tmp_path):
    # Ctrl-C reaches every process of the group: the run said "interrupted" and then waited
    # forever on its pool's workers
    import signal
    import subprocess
    import sys
    import time

    script = (
        "import functools, time, sys\n"
        "from centrality_vision.experiments._runner import Unit, run_units\n"
        "units = [Unit(f'u{i}', functools.partial(time.sleep, 120), {}) for i in range(4)]\n"
        f"run_units(units, {str(tmp_path / 'r.jsonl')!r}, scheduler='processes', workers=2, progress=False)\n"
    )
    run = subprocess.Popen([sys.executable, "-c", script], start_new_session=True, stderr=subprocess.PIPE)
    try:
        time.sleep(8)  # the workers are started and sleeping in their units
        assert run.poll() is None
        os.killpg(run.pid, signal.SIGINT)
        _, err = run.communicate(timeout=30)
        assert b"KeyboardInterrupt" in err
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGKILL)
            run.communicate()
    for _ in range(100):  # every worker of the group ends too (the resource tracker at its pace)
        try:
            os.killpg(run.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        left = subprocess.run(["ps", "-o", "pid,stat,args", "-g", str(run.pid)], capture_output=True, text=True)
        raise AssertionError(f"processes of the run are left 10 s after it:\n{left.stdout}")


def _edited_then(x, marker_dir):
    """A unit during which the package's files "change" (in the process that runs it)."""
    from centrality_vision import _provenance

    if x == 2:
        _provenance.current_code_digest = lambda: "e" * 16
    return _square(x, marker_dir)


@pytest.mark.parametrize("scheduler", ["serial", "processes"])
def test_a_result_of_code_edited_during_the_run_is_not_stored(tmp_path, scheduler):
    """The key's digest was read when the run started; a unit computed after the files
    changed (by a worker started later, or a module imported lazily) was stored under it, and
    a later run of the original code read the edited code's result back."""
    from centrality_vision import _provenance

    real = _provenance.current_code_digest
    units = [Unit(f"u{i}", _edited_then, {"x": i, "marker_dir": str(tmp_path)}) for i in range(4)]
    try:
        with pytest.raises(CodeChangedError, match=r"code digest was [0-9a-f]{16} when it started and e{16} once unit"):
            run_units(units, tmp_path / "r.jsonl", scheduler=scheduler, workers=1, progress=False)
    finally:
        _provenance.current_code_digest = real
    stored = {i.split("#")[0] for i in load_results(tmp_path / "r.jsonl")}
    assert stored == {"u0", "u1"}  # u2 ran edited code: not stored, and the run stopped
    again = run_units(units[:2], tmp_path / "r.jsonl", scheduler="serial", progress=False)
    assert again == {f"u{i}": {"x": i, "square": i * i} for i in range(2)}
