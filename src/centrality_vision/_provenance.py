"""What a stored result was computed with, so that it is never read back under other code.

Results kept on disk (the experiments' unit files, :class:`~centrality_vision.shapes.CentralityCache`
files) carry :func:`code_digest` in their key: a result computed by another version of the
package, by the same version edited (a development install), with other bundled data, or under
other versions of the libraries the package runs on, has another key and is recomputed, never
reused.

The digest is read once per process, but code runs that was loaded later (a module imported
lazily, a worker process started later, a remote Dask worker): a result is stored only where
:func:`current_code_digest`, read after it was computed, is still the digest of its key. (A
file edited during a long run had the edited code's results stored under the digest of the
code the run started with, and a later run of that code read them back.)
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import platform
import re
from pathlib import Path

__all__ = ["code_digest", "current_code_digest"]

#: Folders and suffixes of files that are caches of the package, not part of it.
_CACHE_DIRS = frozenset({"__pycache__"})
_CACHE_SUFFIXES = frozenset({".pyc", ".pyo", ".nbi", ".nbc"})


def _package_files(root: Path) -> list[Path]:
    """Every file under ``root`` (sources and bundled data), without interpreter and numba caches."""
    return sorted(
        path
        for path in root.rglob("*")
        if path.is_file()
        and path.suffix not in _CACHE_SUFFIXES
        and not _CACHE_DIRS.intersection(path.relative_to(root).parts)
    )


def _runtime_versions() -> list[str]:
    """``name==version`` for Python and each installed runtime dependency of the package.

    The dependencies are read from the installed package's metadata (extras left out); without
    metadata (the sources used from a checkout without installing) only Python's version is given.
    """
    versions = [f"python=={platform.python_version()}"]
    try:
        requirements = importlib.metadata.requires("centrality-vision") or []
    except importlib.metadata.PackageNotFoundError:
        requirements = []
    names = sorted(
        {
            re.match(r"[A-Za-z0-9._-]+", requirement).group(0).lower()
            for requirement in requirements
            if "extra" not in requirement.partition(";")[2]
        }
    )
    for name in names:
        try:
            versions.append(f"{name}=={importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(f"{name}==missing")
    return versions


def _stamps(files: list[Path]) -> tuple:
    """The path, size and modification time of each file and of each folder holding one (a
    folder's time changes when an entry is added or removed): what :func:`current_code_digest`
    checks before it reads every file again."""
    stamps = []
    for path in [*files, *sorted({path.parent for path in files})]:
        try:
            stat = path.stat()
        except OSError:
            stamps.append((path, None))
        else:
            stamps.append((path, stat.st_size, stat.st_mtime_ns))
    return tuple(stamps)


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """The first 16 hex digits of a SHA-256 over the package and what it runs on, read once per
    process: every file of the package (its Python sources and bundled data, each by its path
    inside the package and its bytes) and the versions of Python and of each runtime dependency.

    Examples
    --------
    >>> digest = code_digest()
    >>> len(digest), digest == code_digest()
    (16, True)
    """
    return _read_digest()


_read_at: list = []  # the files code_digest() read, and their stamps


def current_code_digest() -> str:
    """The digest of the package's files as they are now: :func:`code_digest` where no file of
    the package was added, removed, resized or modified since it was read (a check of the
    files' sizes and times, under a millisecond), else the digest read afresh.

    Examples
    --------
    >>> current_code_digest() == code_digest()
    True
    """
    digest = code_digest()
    if _read_at and _stamps(_read_at[0]) == _read_at[1]:
        return digest
    return _read_digest(remember=False)


def _read_digest(remember: bool = True) -> str:
    """The digest of the package's files as they are now (see :func:`code_digest`);
    ``remember``: keep the stamps for :func:`current_code_digest`."""
    root = Path(__file__).resolve().parent
    files = _package_files(root)
    stamps = _stamps(files)
    hasher = hashlib.sha256()
    for path in files:
        hasher.update(path.relative_to(root).as_posix().encode())
        hasher.update(b"\0")
        hasher.update(path.read_bytes())
        hasher.update(b"\0")
    for version in _runtime_versions():
        hasher.update(version.encode())
        hasher.update(b"\0")
    if remember:
        _read_at[:] = [files, stamps]
    return hasher.hexdigest()[:16]
