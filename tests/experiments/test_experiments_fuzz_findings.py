"""Inputs a fuzz run of the experiments, their runner and ``reproduce`` found mishandled: a
traceback from scikit-learn on seeds the parser accepted, stored results reused after the data
or under a moved cache, SystemExit from the in-process API, options ignored or checked late."""

import json
import subprocess
import sys

import numpy as np
import pytest

from centrality_vision.cli import main as cli_main
from centrality_vision.exceptions import InputError
from centrality_vision.experiments import REGISTRY, SEEDS_EXPERIMENTS, experiment_argv, run_experiment
from centrality_vision.experiments._common import MAX_SEED, percents, share, tally, wilson_interval
from centrality_vision.experiments._runner import Unit, run_units, unit_id


def _double(x):
    return {"x": 2 * x}


def _echo(values):
    return {"sum": float(np.sum(values))}


# ------------------------------------------------------------------ seeds and options
def test_seeds_stop_at_scikit_learn_s_range(capsys):
    # table-4.1 ran 30 s and then died in StratifiedKFold at --seed 2**32
    assert MAX_SEED == 2**32 - 1
    with pytest.raises(SystemExit) as info:
        cli_main(["reproduce", "table-4.1", "--quick", "--seed", str(2**32)])
    assert info.value.code == 2 and "--seed: must be in [0, 4294967295]" in capsys.readouterr().err


@pytest.mark.parametrize("module", [e.module for e in REGISTRY.values()])
@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"seed": None}, TypeError, "`seed` must be an int"),
        ({"seed": -1}, InputError, r"`seed` must be an int in \[0, 4294967295\]"),
        ({"seed": 1.5}, TypeError, "`seed` must be an int"),
        ({"seed": 2**64}, InputError, "`seed`"),
        ({"seed": True}, TypeError, "`seed` must be an int"),
        ({"quick": "yes"}, TypeError, "`quick` must be True or False"),
    ],
)
def test_every_run_checks_seed_and_quick_first(module, kwargs, error, match):
    from importlib import import_module

    run = import_module(f"centrality_vision.experiments.{module}").run
    with pytest.raises(error, match=match):
        run(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"quick": "no"}, TypeError, "`quick`"),
        ({"seed": None}, TypeError, "`seed`"),
        ({"seed": -1}, InputError, "`seed`"),
        ({"seeds": 0}, InputError, "`seeds`"),
        ({"seeds": {"fig-5.3": 4}}, TypeError, "`seeds`"),
        ({"workers": 0}, InputError, "`workers`"),
        ({"workers": "--quick"}, TypeError, "`workers`"),
        ({"workers": 2**31}, InputError, r"`workers` must be an int in \[1, 1024\]"),
        ({"scheduler": "bogus"}, InputError, "`scheduler`"),
    ],
)
def test_the_in_process_api_names_bad_options_instead_of_exiting(tmp_path, kwargs, error, match):
    # before: SystemExit(2) with the usage of `python -m ...table_2_1`, or the value passed on as text
    with pytest.raises(error, match=match):
        run_experiment("fig-5.3", tmp_path / "x", **kwargs)
    with pytest.raises(TypeError, match="`out`"):
        run_experiment("table-2.1", None)  # wrote into ./None before
    assert not (tmp_path / "x").exists()


def test_an_out_folder_whose_name_starts_with_a_dash(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert experiment_argv("table-2.1", "-odd")[0] == "--out=-odd"
    assert run_experiment("table-2.1", "-odd") == 0
    assert (tmp_path / "-odd" / "table-2.1.txt").is_file()


def test_seeds_go_only_to_the_experiments_that_check_claims_over_seeds(capsys):
    assert set(SEEDS_EXPERIMENTS) == {name for name, e in REGISTRY.items() if e.seeds}
    assert "fig-4.2" not in SEEDS_EXPERIMENTS and "fig-5.3" in SEEDS_EXPERIMENTS
    assert not any(a.startswith("--seeds") for a in experiment_argv("fig-4.2", "o", seeds=50))
    assert "--seeds=50" in experiment_argv("fig-5.3", "o", seeds=50)
    # (fig-4.2 --seeds 50 ran with the claims on seed 0 alone and said nothing)
    assert cli_main(["reproduce", "fig-4.2", "--quick", "--seeds", "50"]) == 2
    assert "--seeds applies to" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["--workers", "3000000000"], ["--workers", "2147483647"]])
def test_a_huge_worker_count_is_a_usage_error(argv, capsys):
    # an OverflowError traceback from ProcessPoolExecutor's semaphore before
    with pytest.raises(SystemExit) as info:
        cli_main(["reproduce", "fig-5.3", "--quick", *argv])
    assert info.value.code == 2 and "must be in [1, 1024]" in capsys.readouterr().err


def test_run_all_takes_seeds_per_experiment_and_checks_only(tmp_path):
    from centrality_vision.experiments.report import run_all

    with pytest.raises(TypeError, match="`only`"):
        run_all(tmp_path / "a", quick=True, only="table-2.1")  # KeyError: 't' before
    with pytest.raises(InputError, match="`only`"):
        run_all(tmp_path / "a", quick=True, only=["nope"])
    with pytest.raises(InputError, match="`seeds`"):
        run_all(tmp_path / "a", quick=True, seeds={"nope": 3}, only=["table-2.1"])
    assert not (tmp_path / "a").exists()  # checked before the folder is made
    path = run_all(tmp_path / "b", quick=True, seeds={"fig-7.1": 4}, only=["table-2.1", "fig-7.1"])
    assert path.is_file()


def test_fig_5_10_index_is_checked(tmp_path, capsys):
    from centrality_vision.experiments import fig_5_10

    for bad in ("-1", "99", "100000000000"):
        with pytest.raises(SystemExit):
            fig_5_10.main(["--out", str(tmp_path), "--index", bad])
        assert "must be in [0, 98]" in capsys.readouterr().err
    with pytest.raises(InputError, match=r"`index` must be an int in \[0, 98\]"):
        fig_5_10.run(index=99)


def test_experiments_that_take_no_scheduler_refuse_one_and_a_bad_one_is_refused_at_once(tmp_path, capsys):
    from centrality_vision.experiments import fig_5_3, fig_5_10

    with pytest.raises(SystemExit):
        fig_5_10.main(["--out", str(tmp_path), "--scheduler", "bogus"])  # accepted and ignored before
    with pytest.raises(SystemExit):
        fig_5_3.main(["--quick", "--out", str(tmp_path / "f"), "--scheduler", "bogus"])
    assert "--scheduler" in capsys.readouterr().err
    assert not (tmp_path / "f").exists()  # refused before the drawn seed's run


def test_python_m_prints_one_line_for_a_bad_argument(tmp_path):
    # a traceback before
    run = subprocess.run(
        [sys.executable, "-m", "centrality_vision.experiments.table_2_1", "--out", "/dev/null"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    assert "Traceback" not in run.stderr and run.stderr.startswith("error: --out must be a folder")


# ------------------------------------------------------------------ what a result is keyed by
def test_unit_ids_tell_large_arrays_apart():
    a = np.zeros(2000)
    b = a.copy()
    b[1000] = 1.0  # numpy's repr of both elides the middle: the same id before
    assert unit_id(Unit("u", _echo, {"values": a})) != unit_id(Unit("u", _echo, {"values": b}))
    assert unit_id(Unit("u", _echo, {"values": a})) == unit_id(Unit("u", _echo, {"values": a.copy()}))


def test_lambdas_and_closures_are_keyed_by_their_code_and_captured_values():
    # two lambdas of one scope, or two closures of one factory, shared an id before
    def scaled(k):
        def inner(x):
            return {"x": k * x}

        return inner

    first, second = (lambda x: {"x": x}), (lambda x: {"x": -x})
    ids = {unit_id(Unit("u", f, {"x": 1})) for f in (first, second, scaled(2), scaled(3))}
    assert len(ids) == 4
    assert unit_id(Unit("u", scaled(2), {"x": 1})) == unit_id(Unit("u", scaled(2), {"x": 1}))
    assert unit_id(Unit("u", _echo, {"values": first})) != unit_id(Unit("u", _echo, {"values": second}))


def test_closures_that_capture_dicts_with_keys_that_print_alike_are_told_apart():
    """Captured values went through plain JSON, which writes dict keys as strings: closures over
    ``{1: x}`` and ``{"1": x}`` shared an id (so did defaults)."""

    def over(table):
        def inner(x):
            return {"x": table}

        return inner

    def with_default(table):
        return lambda x, t=table: {"x": t}

    assert unit_id(Unit("u", over({1: 2}), {"x": 1})) != unit_id(Unit("u", over({"1": 2}), {"x": 1}))
    assert unit_id(Unit("u", with_default({1: 2}), {"x": 1})) != unit_id(Unit("u", with_default({"1": 2}), {"x": 1}))
    assert unit_id(Unit("u", over({1: 2}), {"x": 1})) == unit_id(Unit("u", over({1: 2}), {"x": 1}))


def test_a_module_run_as_main_keys_its_units_under_its_import_name(monkeypatch):
    """``python -m centrality_vision.experiments.fig_5_5`` keyed its units under
    ``__main__.seed_unit`` and ``reproduce fig-5.5`` under the module's name: neither resumed
    the other's run."""
    import types

    def as_main(func):
        copy = types.FunctionType(func.__code__, func.__globals__, func.__name__, func.__defaults__, func.__closure__)
        copy.__qualname__, copy.__module__ = func.__qualname__, "__main__"
        return copy

    main = types.ModuleType("__main__")
    main.__spec__ = types.SimpleNamespace(name=_double.__module__)
    monkeypatch.setitem(sys.modules, "__main__", main)
    assert unit_id(Unit("u", as_main(_double), {"x": 1})) == unit_id(Unit("u", _double, {"x": 1}))
    main.__spec__ = None  # `python script.py`: no import name to go by
    assert unit_id(Unit("u", as_main(_double), {"x": 1})) != unit_id(Unit("u", _double, {"x": 1}))


def test_callable_objects_and_partials_are_keyed_by_their_state():
    # found by fuzz round 7: a transform (an object with __call__) was keyed by its repr, which
    # elides large arrays: two that differ in row 1000 of 2000 shared an id
    import functools

    from centrality_vision.transforms import NonRigidTransform

    rng = np.random.default_rng(0)
    points, weights = rng.random((2000, 2)), rng.random((2000, 2))
    changed = weights.copy()
    changed[1000] += 5.0
    first, second = NonRigidTransform(points, weights, 1.0), NonRigidTransform(points, changed, 1.0)
    assert unit_id(Unit("u", _echo, {"values": first})) != unit_id(Unit("u", _echo, {"values": second}))
    same = NonRigidTransform(points.copy(), weights.copy(), 1.0)
    assert unit_id(Unit("u", _echo, {"values": first})) == unit_id(Unit("u", _echo, {"values": same}))
    # a partial by its function and arguments (its repr held an address: never found again)
    keyed = [unit_id(Unit("u", functools.partial(_double, x=x), {})) for x in (3, 3, 4)]
    assert keyed[0] == keyed[1] != keyed[2]


def test_volatile_arguments_stay_out_of_the_id(tmp_path):
    here = Unit("u", _double, {"x": 3, "cache_dir": str(tmp_path / "a")}, volatile=("cache_dir",))
    there = Unit("u", _double, {"x": 3, "cache_dir": str(tmp_path / "b")}, volatile=("cache_dir",))
    other = Unit("u", _double, {"x": 4, "cache_dir": str(tmp_path / "a")}, volatile=("cache_dir",))
    assert unit_id(here) == unit_id(there) != unit_id(other)


def test_a_copied_output_folder_keeps_its_results(tmp_path):
    # the absolute cache folder was in every fig-4.2 / table-4.1 unit id: a copy recomputed all
    import shutil

    from centrality_vision.experiments import fig_4_2

    def units(folder):
        return [
            Unit(
                f"0/{i}",
                fig_4_2.histogram_distances,
                {"image_index": i, "position": i, "seed": 0, "cache_dir": str(folder / "cache")},
                volatile=("cache_dir",),
            )
            for i in (0, 1)
        ]

    first = run_units(units(tmp_path / "a"), tmp_path / "a" / "r.jsonl", scheduler="serial", progress=False)
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    lines = (tmp_path / "b" / "r.jsonl").read_text().splitlines()
    again = run_units(units(tmp_path / "b"), tmp_path / "b" / "r.jsonl", scheduler="serial", progress=False)
    assert again == first and (tmp_path / "b" / "r.jsonl").read_text().splitlines() == lines


def test_fig_5_5_units_are_keyed_by_the_face_data(tmp_path, monkeypatch):
    # changed data under the same folder reused every per-seed result before
    from centrality_vision.experiments import fig_5_5

    # (a stand-in for the GPL face, which a fresh checkout may not have: the loader reads any 3D set)
    moving, fixed = np.random.default_rng(5).random((2, 60, 3))
    folder = tmp_path / "face"
    folder.mkdir()
    for name, points in (("face_source.txt", moving), ("face_target.txt", fixed)):
        np.savetxt(folder / name, points)
    before = fig_5_5.digest_of_face(str(folder))
    units = {}
    for label, noise in (("old", 0.0), ("new", 1e-3)):
        moved = moving + noise * np.random.default_rng(0).standard_normal(moving.shape)
        np.savetxt(folder / "face_source.txt", moved)
        digest = fig_5_5.digest_of_face(str(folder))
        units[label] = Unit(
            "seed-0", fig_5_5.seed_unit, {"seed": 0, "quick": True, "face_dir": str(folder), "face_digest": digest}
        )
    assert units["old"].kwargs["face_digest"] == before
    assert unit_id(units["old"]) != unit_id(units["new"])
    with pytest.raises(InputError, match="`face_dir`: the face data changed during the run"):
        fig_5_5.problem(0, str(folder), before)


# ------------------------------------------------------------------ odds as printed
@pytest.mark.parametrize("n", [7, 10, 27, 100, 495])
def test_a_claim_that_always_or_never_holds_prints_round_bounds(n):
    # 0.9999999999999999 was printed as 99.999999%
    assert wilson_interval(n, n)[1] == 1.0 and wilson_interval(0, n)[0] == 0.0
    cell = tally([{"a": True}] * n)["a"]
    assert share(cell).endswith("-100%)") and "99.9" not in share(cell)
    assert percents(wilson_interval(0, n)[0])[0] == "0"


def test_table_5_1_run_without_out_writes_nothing_in_the_working_folder(tmp_path, monkeypatch):
    from centrality_vision.experiments import table_5_1

    monkeypatch.chdir(tmp_path)
    result = table_5_1.run(quick=True, n_sets=1, scheduler="serial", progress=False)
    assert result["n_sets"] == 1 and not (tmp_path / "results").exists()
    json.dumps(result)  # still a JSON-able result


def test_every_experiment_run_says_where_it_wrote(tmp_path, capsys):
    """Most `reproduce` experiments wrote 4 to 6 files without a word (audit 26): the staged
    outputs are now listed on stderr as they land."""
    assert run_experiment("table-2.1", tmp_path, quick=True) == 0
    err = capsys.readouterr().err
    assert f"wrote {tmp_path}/: table-2.1-quick" in err
    assert "table-2.1-quick.txt" in err and "table-2.1-quick.json" in err


# ------------------------------------------------------------------ audit round 31
def test_a_face_without_spread_along_x_names_the_face_file(tmp_path):
    """Every point equal: the quantile cut left no point, and the error named `moving`."""
    from centrality_vision.experiments import fig_5_5

    for name in ("face_source.txt", "face_target.txt"):
        (tmp_path / name).write_text("1 2 3\n" * 10)
    with pytest.raises(InputError, match=r"`face_dir`: the face's face_source.txt must have points spread along x"):
        fig_5_5.problem(0, str(tmp_path))


@pytest.mark.parametrize("name", sorted(SEEDS_EXPERIMENTS))
def test_seed_plus_seeds_beyond_2_32_is_refused_before_anything_runs(tmp_path, name, monkeypatch):
    """fig-5.3 --seed 4294967295 --seeds 2 ran the whole --seed registration first and left an
    empty output folder."""
    import importlib

    from centrality_vision.experiments import check_options

    with pytest.raises(InputError, match=r"`seed` \+ `seeds` must stay below 2\*\*32"):
        check_options(seed=MAX_SEED, seeds=2)
    module = importlib.import_module(f"centrality_vision.experiments.{REGISTRY[name].module}")
    monkeypatch.setattr(module, "run", lambda **kwargs: pytest.fail("ran before the seeds were checked"))
    out = tmp_path / "out"
    with pytest.raises(InputError, match=r"`seed` \+ `seeds` must stay below 2\*\*32"):
        module.main(["--seed", str(MAX_SEED), "--seeds", "2", "--out", str(out)])
    assert not out.exists()
