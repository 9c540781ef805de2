"""Output helpers shared by the benchmark scripts (imported as ``_common`` from this folder)."""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

__all__ = ["table", "fmt_s", "load_line", "probreg_beta", "RESULTS", "scratch_dir"]

#: The committed results: only a script's full, documented run writes here by default.
RESULTS = Path(__file__).resolve().parent.parent / "results" / "benchmarks"


def scratch_dir():
    """Where smoke runs and partial analyses write unless told otherwise (not ``results/``).

    ``<temp>/centrality-vision-benchmarks``, created on first use: a ``--quick`` run or an
    analysis on a few pairs must not replace the committed tables of the full run.
    """
    path = Path(tempfile.gettempdir()) / "centrality-vision-benchmarks"
    path.mkdir(parents=True, exist_ok=True)
    return path


def table(headers, rows, align=None):
    """A plain-text table: left-aligned first column, right-aligned others unless ``align`` says."""
    cols = list(zip(*([headers] + rows))) if rows else [[h] for h in headers]
    widths = [max(len(str(x)) for x in col) for col in cols]
    align = align or ["<"] + [">"] * (len(headers) - 1)

    def line(r):
        return "  ".join(("{:%s%d}" % (a, w)).format(str(x)) for x, w, a in zip(r, widths, align))

    out = [line(headers), "  ".join("-" * w for w in widths)]
    out += [line(r) for r in rows]
    return "\n".join(out)


def fmt_s(result):
    """Median seconds of a measurement (``*`` after a single run), its status if it failed, ``-`` if absent."""
    if result is None:
        return "-"
    if result.status != "ok":
        return result.status
    s = result.median
    txt = "%.4f" % s if s < 10 else "%.2f" % s
    return txt + ("*" if len(result.times) == 1 else "")


def load_line(busy_note="timings are unreliable"):
    """The load average, with ``busy_note`` when more than half the cores are taken."""
    try:
        load = os.getloadavg()
    except OSError:
        return "load average: unknown"
    line = "load average (1, 5, 15 min): %.2f %.2f %.2f" % load
    if load[0] > 0.5 * (os.cpu_count() or 1):
        line += "  ! the machine is busy: " + busy_note
    return line


def probreg_beta(beta):
    """probreg's ``beta`` for CPD's kernel width ``beta``, read from probreg's own kernel.

    probreg 0.3.8's ``rbf_kernel(a, b, beta)`` is ``exp(-|d|^2 / (2 beta))`` (measured:
    ``-log G / |d|^2`` is ``1 / (2 beta)`` at beta 0.5, 1 and 2), so CPD's width ``beta`` is
    probreg's ``beta**2``. The two agree only at 1, where an earlier check of this suite was
    made; until it was corrected (2026-11-23), probreg ran with width ``sqrt(2)`` where the
    others had 2.
    """
    import numpy as np
    from probreg import math_utils

    g = float(np.asarray(math_utils.rbf_kernel(np.zeros((1, 2)), np.array([[1.0, 0.0]]), 2.0))[0, 0])
    if abs(g - math.exp(-1 / 4)) < 1e-6:
        return beta**2
    if abs(g - math.exp(-1 / 8)) < 1e-6:
        return beta
    raise RuntimeError(f"probreg's rbf_kernel at distance 1 and beta 2 is {g}: an unknown convention")
