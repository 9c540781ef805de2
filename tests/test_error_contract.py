"""The error contract, checked on the source: no bare ``raise ValueError`` or ``raise Exception``.

Every bad input raises :class:`~centrality_vision.exceptions.InputError` (a ValueError) or a
TypeError naming the parameter; a state that cannot happen raises a documented internal error
(e.g. ``RuntimeError("internal error: ...")``, which the command line shows as a bug with its
traceback). Numba kernel modules (files named ``*_kernels.py``) may raise builtin errors: numba
cannot raise the package's exceptions, and their callers validate the inputs first.
"""

from __future__ import annotations

import ast
from pathlib import Path

import centrality_vision

PACKAGE = Path(centrality_vision.__file__).parent
FORBIDDEN = {"ValueError", "Exception"}


def _bare_raises(path: Path, root: Path = PACKAGE.parent) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if not isinstance(node, ast.Raise) or node.exc is None:
            continue
        raised = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
        if isinstance(raised, ast.Name) and raised.id in FORBIDDEN:
            found.append((node.lineno, f"{path.relative_to(root)}:{node.lineno}: raise {raised.id}"))
    return [text for _, text in sorted(found)]


def _offenders() -> list[str]:
    return [
        hit
        for path in sorted(PACKAGE.rglob("*.py"))
        if not path.name.endswith("_kernels.py")
        for hit in _bare_raises(path)
    ]


def test_the_scan_finds_a_bare_raise(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text(
        "def f(x):\n    if x:\n        raise ValueError('no')\n    raise Exception\n    raise TypeError\n"
    )
    assert _bare_raises(sample, tmp_path) == ["sample.py:3: raise ValueError", "sample.py:4: raise Exception"]


def test_no_bare_value_error_or_exception_outside_kernel_modules():
    offenders = _offenders()
    assert not offenders, "bare raises (use InputError naming the parameter):\n" + "\n".join(offenders)


def test_every_exception_and_warning_of_the_package_is_exported_at_the_top():
    # API audit F18: CollapseWarning and MatchingWarning, which the library emits, were
    # importable only from centrality_vision.exceptions
    import inspect

    import centrality_vision
    from centrality_vision import exceptions

    defined = {
        name for name, obj in vars(exceptions).items() if inspect.isclass(obj) and obj.__module__ == exceptions.__name__
    }
    assert defined == {
        "CentralityVisionError",
        "InputError",
        "CodeChangedError",
        "ConvergenceWarning",
        "CollapseWarning",
        "MatchingWarning",
    }
    assert defined <= set(centrality_vision.__all__)
    assert all(getattr(centrality_vision, name) is getattr(exceptions, name) for name in defined)
