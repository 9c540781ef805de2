"""What a stored result was computed with, so that it is never read back under other code.

Results kept on disk (the experiments' unit files, :class:`~centrality_vision.shapes.CentralityCache`
files) carry :func:`code_digest` in their key: a result computed by another version of the
package, or by the same version edited (a development install), has another key and is
recomputed, never reused.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

__all__ = ["code_digest"]


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """The first 16 hex digits of a SHA-256 over every Python source file of the package (each
    file's path inside the package and its bytes), read once per process.

    Examples
    --------
    >>> digest = code_digest()
    >>> len(digest), digest == code_digest()
    (16, True)
    """
    root = Path(__file__).resolve().parent
    hasher = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        hasher.update(path.relative_to(root).as_posix().encode())
        hasher.update(b"\0")
        hasher.update(path.read_bytes())
        hasher.update(b"\0")
    return hasher.hexdigest()[:16]
