"""The code digest keys stored results: it must change with anything that can change a result."""

import importlib.metadata
import shutil
from pathlib import Path

import pytest

import centrality_vision
from centrality_vision import _provenance


@pytest.fixture
def package_copy(tmp_path, monkeypatch):
    """A copy of the package's files whose digest :func:`code_digest` computes."""
    source = Path(centrality_vision.__file__).resolve().parent
    copy = tmp_path / "centrality_vision"
    shutil.copytree(source, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(_provenance, "__file__", str(copy / "_provenance.py"))
    _provenance.code_digest.cache_clear()
    yield copy
    _provenance.code_digest.cache_clear()


def _digest():
    _provenance.code_digest.cache_clear()
    return _provenance.code_digest()


def test_digest_changes_with_a_bundled_data_file(package_copy):
    """Only the Python sources were hashed: a stored result computed from other bundled data
    (an edited fish outline, a replaced Kimia image) was read back as if it were current."""
    base = _digest()
    fish = package_copy / "datasets" / "data" / "cpd" / "fish_target.txt"
    fish.write_text(fish.read_text() + "\n")
    assert _digest() != base


def test_digest_changes_with_a_source_file_and_ignores_caches(package_copy):
    base = _digest()
    cache = package_copy / "graphs" / "__pycache__"
    cache.mkdir()
    (cache / "_knn.cpython-311.pyc").write_bytes(b"compiled")
    (package_copy / "registration" / "kernel.nbi").write_bytes(b"numba index")
    assert _digest() == base  # interpreter and numba caches are not the package
    (package_copy / "graphs" / "__init__.py").write_text("# edited\n", encoding="utf-8")
    assert _digest() != base


def test_digest_changes_with_a_dependency_version(monkeypatch):
    """The versions of the libraries a result was computed with are part of its key."""
    base = _digest()
    real = importlib.metadata.version

    def other_numpy(name):
        return "0.0.1" if name == "numpy" else real(name)

    monkeypatch.setattr(importlib.metadata, "version", other_numpy)
    try:
        assert any(v == "numpy==0.0.1" for v in _provenance._runtime_versions())
        assert _digest() != base
    finally:
        monkeypatch.undo()
        _provenance.code_digest.cache_clear()


def test_current_digest_sees_an_edit_after_the_digest_was_read(package_copy):
    """The digest is read once per process; code loaded later (a lazily imported module, a
    worker started later) may be an edited file's: current_code_digest() tells."""
    base = _digest()
    assert _provenance.current_code_digest() == base
    source = package_copy / "registration" / "_cpd.py"
    source.write_text(source.read_text(encoding="utf-8") + "# edited\n", encoding="utf-8")
    edited = _provenance.current_code_digest()
    assert edited != base and _provenance.code_digest() == base
    (package_copy / "graphs" / "_new.py").write_text("", encoding="utf-8")  # a file added
    assert _provenance.current_code_digest() not in (base, edited)
    source.write_text(source.read_text(encoding="utf-8").removesuffix("# edited\n"), encoding="utf-8")
    (package_copy / "graphs" / "_new.py").unlink()
    assert _provenance.current_code_digest() == base  # restored: the same bytes
