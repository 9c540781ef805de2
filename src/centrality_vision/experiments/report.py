"""Run every experiment and write one Markdown report with all tables, figures and explanations.

``centrality-vision reproduce all [--quick] [--seeds N] --out DIR`` calls :func:`run_all`:
each experiment of :data:`~centrality_vision.experiments.REGISTRY` writes its files under
``DIR/<name>/`` (its resumable runner files included), and ``DIR/report.md`` gathers every
table (ours beside the thesis), links every figure, and carries under each experiment the
paragraph its module's ``explain(result)`` writes from the numbers just computed. The report
opens with an index from every figure and table in the thesis' lists to our file, or to the
reason there is none. No sentence of the report that states a measured fact is fixed text.
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import time
from collections.abc import Iterable, Mapping
from importlib import import_module
from pathlib import Path

from . import REGISTRY, RUNNER_EXPERIMENTS, experiment_argv
from ._common import make_out_folder, outputs_of

__all__ = ["run_all", "write_report", "figure_index", "THESIS_FIGURES", "RUNNER_EXPERIMENTS"]

_DIAGRAM = "a drawing that explains a notion; no data behind it"
#: The thesis' lists of figures and tables: number -> (title, why we have no file, or None when data stand behind it).
THESIS_FIGURES = {
    "fig. 1.1": ("Scene Understanding", _DIAGRAM),
    "fig. 1.2": ("Example of Image Registration", "an introductory picture of two fish; figs. 5.3-5.8 register them"),
    "fig. 1.3": ("Example of Image Segmentation", "a photograph; segmentation is not part of this work"),
    "fig. 1.4": ("Example of Classification", "a photograph of tea bags"),
    "fig. 1.5": (
        "Graph Representation of a Shape",
        "an introductory drawing; fig. 4.2 shows the pixel graphs' centralities",
    ),
    "fig. 2.1": ("The seven bridges of Königsberg", _DIAGRAM),
    "fig. 2.2": ("A directed graph", _DIAGRAM),
    "fig. 2.3": ("Induced subgraphs", _DIAGRAM),
    "fig. 2.4": ("The Minimum Spanning Tree", _DIAGRAM),
    "fig. 2.5": ("Data structures for Graph Representation", _DIAGRAM),
    "fig. 2.6": ("Representing images as graphs", _DIAGRAM),
    "fig. 2.7": ("Distance between two cities", _DIAGRAM),
    "fig. 2.8": ("Triangle Inequality", _DIAGRAM),
    "fig. 2.9": ("Relaxation of the metric axioms", _DIAGRAM),
    "fig. 2.10": ("Metric Balls", _DIAGRAM),
    "fig. 2.11": ("Geodesics in a Graph", _DIAGRAM),
    "fig. 2.12": ("A toy example for graph centralities", None),
    "fig. 3.1": ("Rigid transformation", _DIAGRAM),
    "fig. 3.2": ("Similarity Transformation", _DIAGRAM),
    "fig. 3.3": ("Affine transformation", _DIAGRAM),
    "fig. 4.1": ("Images from the Kimia 99 Database", None),
    "fig. 4.2": ("Centrality distribution of graphs", None),
    "fig. 4.3": ("Comparison of betweenness centrality histograms", None),
    "fig. 4.4": ("Comparison of closeness centrality histograms", None),
    "fig. 4.5": ("Comparison of degree centrality histograms", None),
    "fig. 4.6": ("Comparison of eigenvector centrality histograms", None),
    "fig. 4.7": ("Binary Comparison of Centrality Values", _DIAGRAM),
    "fig. 4.8": ("Confusion Matrices for the Centrality-based Learning", None),
    "fig. 5.1": ("Centrality of a Delaunay Triangulation", None),
    "fig. 5.2": ("Histogram of Closeness Centrality", None),
    "fig. 5.3": ("Convergence of the registration under similarity transformation", None),
    "fig. 5.4": ("Registration under similarity transformation", None),
    "fig. 5.5": ("Registration under affine transformation", None),
    "fig. 5.6": ("Convergence of the registration under affine registration", None),
    "fig. 5.7": ("Registration under non-rigid transformation", None),
    "fig. 5.8": ("Convergence of the registration under nonrigid transformation", None),
    "fig. 5.9": (
        "Stability of Delaunay Triangulation",
        "a hand-drawn six-point example; fig. 7.4 measures Delaunay's stability",
    ),
    "fig. 5.10": ("Sample point-sets of 495 database used", None),
    "fig. 6.1": ("Data graphs of a point-set", None),
    "fig. 6.2": ("The Near Homogeneous Degree Distribution (NHDD) condition", _DIAGRAM),
    "fig. 6.3": ("N1graph Optimization", None),
    "fig. 6.4": ("Registration of point-sets under Similarity Transformation", None),
    "fig. 7.1": ("Minimum Spanning Tree of Maximum Entropy", None),
    "fig. 7.2": ("Data graphs connected using the MSTME", None),
    "fig. 7.3": ("Noise added to the point-set", None),
    "fig. 7.4": ("Comparison of the stability of the fish dataset", None),
    "fig. 7.5": ("Examples of data-graphs with noise equal to 3ε", None),
    "Table 2.1": ("Centrality values for a toy example", None),
    "Table 4.1": ("Classification results using different centrality measures", None),
    "Table 5.1": ("Average on the registration of 495 datasets", None),
    "Table 5.2": ("Standard Deviation of the registration of 495 datasets", None),
    "Table 5.3": ("Percentage of convergence on 495 point-sets under Rigid transformation", None),
    "Table 6.1": ("The table storing the cost during optimization", None),
}


def _owner(label: str):
    return next((e.name for e in REGISTRY.values() if label in e.reproduces), None)


def _files_for(outputs: Mapping[str, list[Path]], label: str) -> list[Path]:
    """Our files for a thesis figure or table: ``fig-<n>.png`` (or ``fig-<n>-*.png``) among the
    run's files; otherwise the figures (tables: text files) of the experiment that reproduces it."""
    kind, number = label.split()
    if kind == "fig.":
        stem = f"fig-{number}"
        exact = sorted(
            path
            for files in outputs.values()
            for path in files
            if path.suffix == ".png" and (_plain_stem(path) == stem or _plain_stem(path).startswith(stem + "-"))
        )
        if exact:
            return exact
    owner = _owner(label)
    return [path for path in outputs.get(owner, []) if path.suffix == (".png" if kind == "fig." else ".txt")]


def _plain_stem(path: Path) -> str:
    return path.stem.removesuffix("-quick")


def figure_index(out, outputs: Mapping[str, list[Path]]) -> list[str]:
    """Markdown lines: every figure and table of the thesis' lists -> our file among
    ``outputs`` (``{experiment: the files its run wrote}``), or why there is none."""
    out = Path(out)
    lines = ["| thesis | title | ours |", "|---|---|---|"]
    for label, (title, reason) in THESIS_FIGURES.items():
        if reason is not None:
            cell = f"none: {reason}"
        else:
            files = _files_for(outputs, label)
            cell = ", ".join(f"[{p.relative_to(out).as_posix()}]({p.relative_to(out).as_posix()})" for p in files)
            if not files:
                owner = _owner(label)
                cell = "**missing**: not written by this run" + (f" (`reproduce {owner}` draws it)" if owner else "")
        lines.append(f"| {label} | {title} | {cell} |")
    return lines


def run_all(
    out,
    *,
    quick: bool = False,
    seed: int = 0,
    seeds: int | None = None,
    only=None,
    scheduler: str | None = None,
    workers: int | None = None,
) -> Path:
    """Run the experiments (``only``: a subset of names) and write ``out/report.md``.

    ``seeds``: how many seeds each experiment checks its claims over (default 20, or 3 with
    ``quick``); an int for all, or ``{name: n}`` per experiment (missing names: the default).
    An experiment that cannot run here (fig-5.5 without the GPL face data) is reported as not
    run, with its reason, and the others go on.
    """
    names = list(REGISTRY) if only is None else _check_only(only)
    per_name = _check_seeds(seeds, names)
    # every option checked (by experiment_argv) before anything is written
    argvs = {
        name: experiment_argv(
            name, Path(out) / name, quick=quick, seed=seed, seeds=per_name[name], scheduler=scheduler, workers=workers
        )
        for name in names
    }
    out = make_out_folder(out)
    _check_report_place(out / "report.md")
    timings, skipped = {}, {}
    for name in names:
        module = import_module(f"{__package__}.{REGISTRY[name].module}")
        argv = argvs[name]
        if name == "fig-4.2":  # the same noisy copies as Table 4.1: one cache of centralities for both
            argv += ["--cache", str(out / "table-4.1" / "cache")]
        started = time.perf_counter()
        print(f"== {name}", file=sys.stderr)
        buffer = io.StringIO()
        try:
            with contextlib.redirect_stdout(buffer):
                code = module.main(argv)
        except FileNotFoundError as error:
            skipped[name] = str(error)
            print(f"   not run: {error}", file=sys.stderr)
            continue
        if code:
            raise RuntimeError(f"experiment {name} failed with exit code {code}")
        timings[name] = time.perf_counter() - started
    return write_report(out, names, quick=quick, seed=seed, seeds=seeds, timings=timings, skipped=skipped)


def _check_report_place(report: Path) -> None:
    """Before any experiment runs: ``report`` can be written (it was found out only after every
    experiment had run, as a bare OS error)."""
    import os
    import tempfile

    from ..exceptions import InputError

    if report.is_dir() or (report.exists() and not report.is_file()):
        raise InputError(f"`out`: {report} is a folder, not a file; the report is written there.")
    try:
        with tempfile.TemporaryFile(dir=report.parent):
            pass
    except OSError as exc:
        raise InputError(f"`out`: cannot write {report}: {report.parent} refuses new files ({exc.strerror}).") from None
    if report.exists() and not os.access(report, os.W_OK):
        raise InputError(f"`out`: cannot write {report}: the file is read-only.")


def _check_only(only) -> list[str]:
    from ..exceptions import InputError

    if isinstance(only, (str, bytes)) or not isinstance(only, Iterable):
        raise TypeError(f"`only` must be a list of experiment names; got {only!r}.")
    names = list(only)
    unknown = [name for name in names if not isinstance(name, str) or name not in REGISTRY]
    if unknown or not names:
        raise InputError(f"`only` must name experiments among {', '.join(REGISTRY)}; got {only!r}.")
    return list(dict.fromkeys(names))


def _check_seeds(seeds, names) -> dict:
    """``{name: seeds for that experiment}`` from an int, None or ``{name: n}``."""
    from ..exceptions import InputError

    if not isinstance(seeds, Mapping):
        return dict.fromkeys(names, seeds)
    unknown = [name for name in seeds if name not in REGISTRY]
    if unknown:
        raise InputError(f"`seeds` must map experiment names among {', '.join(REGISTRY)} to ints; got {unknown!r}.")
    return {name: seeds.get(name) for name in names}


def _result(files: list[Path], name: str):
    """The result record among a run's files (``<name>.json`` or ``<name>-quick.json``)."""
    records = [path for path in files if path.suffix == ".json" and _plain_stem(path) == name]
    return json.loads(records[0].read_text()) if records else None


def _explanation(name: str, result) -> str | None:
    module = import_module(f"{__package__}.{REGISTRY[name].module}")
    explain = getattr(module, "explain", None)
    if explain is None or result is None:
        return None
    return explain(result)


def _evidence(out: Path, word: str) -> list[Path]:
    return sorted(p for p in (out / "benchmarks").glob(f"*{word}*") if p.is_file())


def write_report(out, names, *, quick: bool, seed: int, seeds: int | None = None, timings=None, skipped=None) -> Path:
    """``out/report.md`` from the ``.txt`` tables, ``.json`` results and ``.png`` figures that the
    last quick (or full, by ``quick``) run of each experiment wrote under ``out/<name>/``: the files
    listed by :func:`~._common.run_outputs`, never others left in the folder."""
    out = Path(out)
    skipped = skipped or {}
    outputs = {name: outputs_of(out / name, name, quick=quick) or [] for name in names if name not in skipped}
    from .. import __version__

    if isinstance(seeds, Mapping):
        command = f"run_all(quick={quick}, seed={seed}, seeds={seeds})"
    else:
        command = f"centrality-vision reproduce all{' --quick' if quick else ''} --seed {seed}" + (
            f" --seeds {seeds}" if seeds else ""
        )
    results = {name: _result(files, name) for name, files in outputs.items()}
    from .._provenance import code_digest

    provenance = f"code digest `{code_digest()}`, written {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    if timings:
        # (units an earlier, interrupted run finished are read back, not timed again)
        provenance += f"; this run took {sum(timings.values()) / 60:.1f} min"
    checked = []
    for name, result in results.items():
        if isinstance(result, dict) and result.get("seeds"):
            checked.append(f"{name} {len(result['seeds'])}")
    lines = [
        "# centrality-vision: the thesis' experiments",
        "",
        f"Generated by `{command}` (centrality-vision {__version__}; {provenance}). Each table prints our value "
        "beside the thesis' "
        "value. Each claim of the thesis is checked on every seed (or every image, point or set where the thesis "
        "speaks "
        'of a data set) and printed as "holds in k of n" with a 95% Wilson interval, beside the thesis\' words. The '
        "paragraph under each heading is written by the experiment from the numbers of this run."
        + (" **Quick mode**: small sizes and few seeds, for a first look and for the tests." if quick else ""),
        "",
        "Seeds over which the claims were checked: " + (", ".join(checked) if checked else "none") + ".",
        "",
        "## Index of the thesis' figures and tables",
        "",
        *figure_index(out, outputs),
        "",
    ]
    for name in names:
        entry = REGISTRY[name]
        lines.append(f"## {name}: {entry.title}")
        lines.append("")
        lines.append(
            f"Reproduces {', '.join(entry.reproduces)}."
            + (f" _{timings[name]:.1f} s._" if timings and name in timings else "")
        )
        lines.append("")
        if name in skipped:
            lines += [f"**Not run here.** {skipped[name]}", ""]
            continue
        if not outputs[name]:
            lines += [f"**Not run here.** No {'quick' if quick else 'full'} run of {name} finished in `{name}/`.", ""]
            continue
        text = _explanation(name, results[name])
        if text:
            lines += [f"**What the numbers show.** {text}", ""]
        if name == "table-4.1":
            evidence = _evidence(out, "eigen")
            if evidence:
                lines += [
                    "Evidence on the eigenvector collapse: "
                    + ", ".join(f"[{p.relative_to(out).as_posix()}]({p.relative_to(out).as_posix()})" for p in evidence)
                    + ".",
                    "",
                ]
        for table in (path for path in outputs[name] if path.suffix == ".txt"):
            lines += ["```text", table.read_text().rstrip(), "```", ""]
        for figure in (path for path in outputs[name] if path.suffix == ".png"):
            lines.append(f"![{figure.stem}]({figure.relative_to(out).as_posix()})")
            lines.append("")
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path
