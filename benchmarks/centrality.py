#!/usr/bin/env python
"""Benchmark our exact centralities against networkx and compiled reference libraries.

One process, the same graphs for every library. Graphs are built once (seeded) from
our own builders (``centrality_vision.graphs.pixel_graph`` / ``delaunay_graph``), or,
if those cannot be imported, from ``skimage.graph.pixel_graph`` / ``scipy.spatial.Delaunay``.
Each library gets the same graph converted beforehand to its own graph type; the
conversion is NOT timed (it is printed on one line per library).

Everything is unweighted (hop distances), which is what we benchmark:

==============  ===========================================================================
library         calls
==============  ===========================================================================
ours            ``cen.betweenness/closeness/eigenvector/eccentricity(graph, weights=False)``;
                on pixel disks ``graph`` is the ``PixelGraph`` of ``pixel_graph``: betweenness
                walks the grid and needs one search per orbit of the disk's 8 symmetries
ours-csr        the same calls on the same adjacency as a plain ``csr_array`` (no grid walk,
                no symmetries): the like-for-like kernel comparison
networkx        ``betweenness_centrality(G, normalized=False)``, ``closeness_centrality``,
                ``eigenvector_centrality_numpy``, ``eccentricity``
networkit       ``centrality.Betweenness(G, normalized=False)``, ``centrality.Closeness(G,
                False, ClosenessVariant.STANDARD)``, ``centrality.EigenvectorCentrality``,
                ``distance.Eccentricity.getValue(G, v)`` for every node (no bulk function)
rustworkx       ``graph_betweenness_centrality(G, normalized=False)``, ``closeness_centrality``,
                ``eigenvector_centrality``, eccentricity = ``distance_matrix(G).max(axis=1)``
                (no eccentricity function; only where the dense n x n matrix fits)
igraph          ``betweenness(directed=False)``, ``closeness()``,
                ``eigenvector_centrality(scale=True)``, ``eccentricity()`` (GPL: benchmark only)
scipy           ``sparse.linalg.eigsh(A, k=1, which="LA")`` (eigenvector only)
==============  ===========================================================================

Each measurement is the median of ``--repeat`` runs (default 3; a single run when the
first run takes more than 20 s). The seconds are the library call only; turning the
returned dict/list into an ndarray is not timed.

Usage::

    python benchmarks/centrality.py --quick
    python benchmarks/centrality.py --only betweenness,closeness
    python benchmarks/centrality.py --graphs delaunay-1000,delaunay-5000 --repeat 5 --json out.json
    python benchmarks/centrality.py --with-slow-networkx       # many minutes
    python benchmarks/centrality.py --scale   # image scale: silhouettes of 100,000 pixels and
                                              # a 1-megapixel mask, weighted vs hop kernels,
                                              # sampling, eccentricity bounds, long thin eigenvector
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

CENTRALITIES = ("betweenness", "closeness", "eigenvector", "eccentricity")
LIBRARIES = ("ours", "ours-csr", "networkx", "networkit", "rustworkx", "igraph", "scipy")
COMPILED = ("networkit", "rustworkx", "igraph", "scipy")
SHORT = {
    "ours-csr": "ours-csr",
    "networkit": "nk",
    "rustworkx": "rx",
    "igraph": "ig",
    "scipy": "sp",
    "networkx": "nx",
    "ours": "ours",
}

# name -> (kind, target size)
GRAPHS = {
    "disk-2500": ("disk", 2500),
    "disk-10000": ("disk", 10000),
    "disk-40000": ("disk", 40000),
    "delaunay-1000": ("delaunay", 1000),
    "delaunay-5000": ("delaunay", 5000),
}
DEFAULT_GRAPHS = ("disk-10000", "disk-40000", "delaunay-1000", "delaunay-5000")
QUICK_GRAPHS = ("delaunay-1000", "disk-2500")

SLOW_NETWORKX_N = 6000  # networkx betweenness/closeness/eccentricity skipped above this n
SINGLE_RUN_S = 20.0  # a first run longer than this is not repeated
RX_DENSE_MAX_BYTES = 2 * 1024**3  # rustworkx eccentricity needs the dense n x n matrix


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--only", default=",".join(CENTRALITIES), help="comma list of centralities (default: %(default)s)")
    p.add_argument(
        "--graphs",
        default=None,
        help="comma list of graphs among %s (default: %s)" % (", ".join(GRAPHS), ",".join(DEFAULT_GRAPHS)),
    )
    p.add_argument("--libs", default=",".join(LIBRARIES), help="comma list of libraries (default: %(default)s)")
    p.add_argument("--repeat", type=int, default=3, help="runs per measurement, median reported")
    p.add_argument("--quick", action="store_true", help="smoke run: only %s" % ",".join(QUICK_GRAPHS))
    p.add_argument(
        "--with-slow-networkx",
        action="store_true",
        help="also run networkx betweenness/closeness/eccentricity on graphs with "
        "n > %d (many minutes)" % SLOW_NETWORKX_N,
    )
    p.add_argument(
        "--threads",
        type=int,
        default=2,
        help="threads for networkit, rustworkx (RAYON_NUM_THREADS) and ours "
        "(default: %(default)s; igraph and networkx are single-threaded)",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="also write the results as JSON")
    p.add_argument(
        "--scale",
        action="store_true",
        help="run the image-scale section instead (ours, with igraph for exact betweenness)",
    )
    p.add_argument(
        "--scale-exact",
        action="store_true",
        help="with --scale: also exact betweenness of the 100,000-pixel silhouette (minutes)",
    )
    p.add_argument(
        "--scale-plain",
        action="store_true",
        help="with --scale-exact: also the 100,000-pixel disk on the plain adjacency (minutes)",
    )
    p.add_argument(
        "--scale-sections",
        default="exact,closeness,approx,eccentricity,eigenvector",
        help="with --scale: comma list of sections (default: %(default)s)",
    )
    args = p.parse_args(argv)

    def split(s, allowed, what):
        items = [x.strip() for x in s.split(",") if x.strip()]
        bad = [x for x in items if x not in allowed]
        if bad:
            p.error("unknown %s: %s (choose from %s)" % (what, ", ".join(bad), ", ".join(allowed)))
        return items

    args.only = split(args.only, CENTRALITIES, "centrality")
    args.libs = split(args.libs, LIBRARIES, "library")
    if args.graphs is not None:
        args.graphs = split(args.graphs, tuple(GRAPHS), "graph")
    elif args.quick:
        args.graphs = list(QUICK_GRAPHS)
    else:
        args.graphs = list(DEFAULT_GRAPHS)
    if args.repeat < 1:
        p.error("--repeat must be >= 1")
    return args


# The thread pools of rustworkx (rayon) and numba read their environment variables at
# first use, so they are set before those libraries are imported.
_ARGS = parse_args() if __name__ == "__main__" else None
if _ARGS is not None:
    os.environ["RAYON_NUM_THREADS"] = str(_ARGS.threads)
    os.environ["NUMBA_NUM_THREADS"] = str(_ARGS.threads)

import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from _common import fmt_s, load_line, table  # noqa: E402


def _try_import(name):
    try:
        return __import__(name), None
    except Exception as exc:
        return None, "%s: %s" % (type(exc).__name__, exc)


nx, _nx_err = _try_import("networkx")
nk, _nk_err = _try_import("networkit")
rx, _rx_err = _try_import("rustworkx")
ig, _ig_err = _try_import("igraph")


def _import_ours():
    """(cen, pixel_graph, delaunay_graph, message); any of the first three may be None."""

    def attempt():
        cen = pix = dela = None
        msgs = []
        try:
            from centrality_vision import centrality as cen_mod

            for f in CENTRALITIES:
                getattr(cen_mod, f)
            cen = cen_mod
        except Exception as exc:
            msgs.append("centrality: %s: %s" % (type(exc).__name__, exc))
        try:
            from centrality_vision.graphs import delaunay_graph, pixel_graph

            pix, dela = pixel_graph, delaunay_graph
        except Exception as exc:
            msgs.append("graphs: %s: %s" % (type(exc).__name__, exc))
        return cen, pix, dela, msgs

    cen, pix, dela, msgs = attempt()
    if cen is None and pix is None and any("No module named 'centrality_vision'" in m for m in msgs):
        src = Path(__file__).resolve().parents[1] / "src"
        if src.is_dir():
            sys.path.insert(0, str(src))
            cen, pix, dela, msgs = attempt()
    return cen, pix, dela, "; ".join(msgs)


# --------------------------------------------------------------------------- graphs


def disk_mask(target):
    """Boolean disk whose pixel count is the closest achievable to ``target``."""
    r = int(math.ceil(math.sqrt(target / math.pi))) + 2
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    d2 = (x * x + y * y).ravel()
    vals, counts = np.unique(d2, return_counts=True)
    cum = np.cumsum(counts)
    k = int(np.argmin(np.abs(cum - target)))
    mask = (x * x + y * y) <= vals[k]
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    mask = mask[rows[0] - 1 : rows[-1] + 2, cols[0] - 1 : cols[-1] + 2]  # one background pixel border
    return mask, math.sqrt(vals[k])


def delaunay_points(n):
    return np.random.default_rng(0).random((n, 2))


def ref_pixel_graph(mask):
    from skimage.graph import pixel_graph as sk_pixel_graph

    g, nodes = sk_pixel_graph(mask, connectivity=2)
    return sp.csr_array(g), nodes


def ref_delaunay_graph(points):
    from scipy.spatial import Delaunay

    tri = Delaunay(points).simplices
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    w = np.linalg.norm(points[e[:, 0]] - points[e[:, 1]], axis=1)
    n = len(points)
    return sp.csr_array((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n))


@dataclass
class Graph:
    name: str
    csr: Any  # scipy.sparse.csr_array, as returned by the builder
    builder: str
    detail: str
    rows: np.ndarray = field(repr=False, default=None)  # undirected edge list, i < j
    cols: np.ndarray = field(repr=False, default=None)

    @property
    def n(self):
        return self.csr.shape[0]

    @property
    def m(self):
        return len(self.rows)


def build_graph(name, ours_pix, ours_dela):
    kind, target = GRAPHS[name]
    if kind == "disk":
        mask, radius = disk_mask(target)
        detail = "8-neighbour pixel disk, radius^2 = %g, mask %dx%d" % (radius**2, *mask.shape)
        builder = "skimage.graph.pixel_graph(connectivity=2)"
        csr = None
        if ours_pix is not None:
            try:
                csr, _ = ours_pix(mask, connectivity=8)
                builder = "centrality_vision.graphs.pixel_graph(connectivity=8)"
            except Exception as exc:
                print("  ! our pixel_graph failed (%s: %s); using skimage" % (type(exc).__name__, exc))
                csr = None
        if csr is None:
            csr, _ = ref_pixel_graph(mask)
    else:
        pts = delaunay_points(target)
        detail = "Delaunay of %d uniform points in [0,1)^2, default_rng(0)" % target
        builder = "scipy.spatial.Delaunay"
        csr = None
        if ours_dela is not None:
            try:
                csr = ours_dela(pts)
                builder = "centrality_vision.graphs.delaunay_graph"
            except Exception as exc:
                print("  ! our delaunay_graph failed (%s: %s); using scipy" % (type(exc).__name__, exc))
                csr = None
        if csr is None:
            csr = ref_delaunay_graph(pts)
    if not isinstance(csr, sp.csr_array):
        csr = sp.csr_array(csr)
    g = Graph(name, csr, builder, detail)
    upper = sp.triu(sp.coo_array(csr), k=1).tocoo()
    g.rows = np.asarray(upper.row, dtype=np.int64)
    g.cols = np.asarray(upper.col, dtype=np.int64)
    return g


def tiny_graph(ours_pix):
    mask, _ = disk_mask(30)
    if ours_pix is not None:
        try:
            return build_graph_from_mask(mask, ours_pix)
        except Exception:
            pass
    return build_graph_from_mask(mask, None)


def build_graph_from_mask(mask, pix):
    csr = pix(mask, connectivity=8)[0] if pix is not None else ref_pixel_graph(mask)[0]
    g = Graph("tiny", sp.csr_array(csr), "", "")
    upper = sp.triu(sp.coo_array(g.csr), k=1).tocoo()
    g.rows = np.asarray(upper.row, dtype=np.int64)
    g.cols = np.asarray(upper.col, dtype=np.int64)
    return g


# --------------------------------------------------------------------------- conversions


def to_networkx(g):
    G = nx.Graph()
    G.add_nodes_from(range(g.n))
    G.add_edges_from(zip(g.rows.tolist(), g.cols.tolist()))
    return G


def to_networkit(g):
    G = nk.Graph(g.n, weighted=False, directed=False)
    G.addEdges((g.rows.astype(np.uint64), g.cols.astype(np.uint64)))
    return G


def to_rustworkx(g):
    G = rx.PyGraph(multigraph=False)
    G.add_nodes_from(range(g.n))
    G.add_edges_from_no_data(list(zip(g.rows.tolist(), g.cols.tolist())))
    return G


def to_igraph(g):
    return ig.Graph(n=g.n, edges=np.column_stack([g.rows, g.cols]).tolist(), directed=False)


def to_scipy_unit(g):
    a = g.csr.copy()
    a.data = np.ones_like(a.data, dtype=np.float64)
    return a


CONVERTERS = {
    "ours": lambda g: g.csr,  # pixel graphs: our PixelGraph (grid walk, mask symmetries)
    "ours-csr": lambda g: sp.csr_array(g.csr),  # the same adjacency as a plain csr_array
    "networkx": to_networkx,
    "networkit": to_networkit,
    "rustworkx": to_rustworkx,
    "igraph": to_igraph,
    "scipy": to_scipy_unit,
}

# --------------------------------------------------------------------------- calls
# Each entry: (timed call on the converted graph -> native result,
#              untimed conversion native result -> ndarray aligned with node ids)


def _dict_to_array(n):
    return lambda d: np.fromiter((d[i] for i in range(n)), dtype=np.float64, count=n)


def _list_to_array(_n):
    return lambda x: np.asarray(x, dtype=np.float64)


def _nk_ecc(G):
    get = nk.distance.Eccentricity.getValue
    return [get(G, v)[1] for v in range(G.numberOfNodes())]


def _rx_ecc(G):
    return rx.distance_matrix(G).max(axis=1)


def _eigsh(A):
    from scipy.sparse.linalg import eigsh

    n = A.shape[0]
    _, vec = eigsh(A, k=1, which="LA", v0=np.full(n, 1.0 / math.sqrt(n)))
    return vec[:, 0]


def calls_for(lib, centrality, cen, n):
    """(callable, to_array) or None when the library has no such function."""
    d2a, l2a = _dict_to_array(n), _list_to_array(n)
    if lib in ("ours", "ours-csr"):
        f = getattr(cen, centrality)
        return (lambda G: f(G, weights=False)), l2a
    if lib == "networkx":
        return {
            "betweenness": (lambda G: nx.betweenness_centrality(G, normalized=False), d2a),
            "closeness": (lambda G: nx.closeness_centrality(G), d2a),
            "eigenvector": (lambda G: nx.eigenvector_centrality_numpy(G), d2a),
            "eccentricity": (lambda G: nx.eccentricity(G), d2a),
        }[centrality]
    if lib == "networkit":
        return {
            "betweenness": (lambda G: nk.centrality.Betweenness(G, normalized=False).run().scores(), l2a),
            "closeness": (
                lambda G: nk.centrality.Closeness(G, False, nk.centrality.ClosenessVariant.STANDARD).run().scores(),
                l2a,
            ),
            "eigenvector": (lambda G: nk.centrality.EigenvectorCentrality(G).run().scores(), l2a),
            "eccentricity": (_nk_ecc, l2a),
        }[centrality]
    if lib == "rustworkx":
        return {
            "betweenness": (lambda G: rx.graph_betweenness_centrality(G, normalized=False), d2a),
            "closeness": (lambda G: rx.closeness_centrality(G), d2a),
            "eigenvector": (lambda G: rx.eigenvector_centrality(G), d2a),
            "eccentricity": (_rx_ecc, l2a),
        }[centrality]
    if lib == "igraph":
        return {
            "betweenness": (lambda G: G.betweenness(directed=False), l2a),
            "closeness": (lambda G: G.closeness(), l2a),
            "eigenvector": (lambda G: G.eigenvector_centrality(scale=True), l2a),
            "eccentricity": (lambda G: G.eccentricity(), l2a),
        }[centrality]
    if lib == "scipy":
        if centrality == "eigenvector":
            return _eigsh, l2a
        return None
    raise ValueError(lib)


def to_our_convention(lib, centrality, values, n):
    """Rescale a library's values to ours (= networkx conventions)."""
    v = np.asarray(values, dtype=np.float64)
    if centrality == "betweenness" and lib == "networkit":
        v = v / 2.0  # networkit sums over ordered (s, t) pairs on undirected graphs
    if centrality == "eigenvector":
        v = np.abs(v)  # eigsh's sign is arbitrary
        mx = np.nanmax(v) if np.isfinite(v).any() else np.nan
        v = v / mx  # networkx / networkit: unit 2-norm; ours, igraph(scale=True): max 1
    return v


# --------------------------------------------------------------------------- measurement


@dataclass
class Cell:
    status: str  # ok | skipped | n/a | no-conv | error
    times: list = field(default_factory=list)
    note: str = ""
    values: Any = None  # ndarray in our convention
    nan: int = 0
    max_abs_diff: float = float("nan")
    max_rel_diff: float = float("nan")
    nan_mismatch: int = 0
    warnings: list = field(default_factory=list)

    @property
    def median(self):
        return statistics.median(self.times) if self.times else float("nan")


def _is_nonconvergence(exc):
    name = type(exc).__name__
    return "Converge" in name or "converge" in str(exc).lower()


def measure(fn, graph_obj, repeat):
    """Median-ready list of seconds and the last result; single run if the first is slow."""
    times = []
    result = None
    caught = []
    for i in range(repeat):
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            t0 = time.perf_counter()
            result = fn(graph_obj)
            times.append(time.perf_counter() - t0)
        caught.extend("%s: %s" % (x.category.__name__, x.message) for x in w)
        if i == 0 and times[0] > SINGLE_RUN_S:
            break
    return times, result, sorted(set(caught))


def run_cell(lib, centrality, g, conv, cen, repeat, with_slow_nx):
    if lib == "networkx" and centrality != "eigenvector" and g.n > SLOW_NETWORKX_N and not with_slow_nx:
        return Cell("skipped", note="n > %d (pass --with-slow-networkx)" % SLOW_NETWORKX_N)
    if lib == "rustworkx" and centrality == "eccentricity" and 8 * g.n * g.n > RX_DENSE_MAX_BYTES:
        return Cell(
            "n/a", note="needs a dense %d x %d distance matrix (%.1f GiB)" % (g.n, g.n, 8 * g.n * g.n / 1024**3)
        )
    spec = calls_for(lib, centrality, cen, g.n)
    if spec is None:
        return Cell("n/a", note="no such function")
    fn, to_array = spec
    try:
        times, result, caught = measure(fn, conv, repeat)
    except Exception as exc:
        status = "no-conv" if _is_nonconvergence(exc) else "error"
        return Cell(
            status, note="%s: %s" % (type(exc).__name__, str(exc).strip().splitlines()[0] if str(exc).strip() else "")
        )
    vals = to_our_convention(lib, centrality, to_array(result), g.n)
    return Cell("ok", times=times, values=vals, nan=int(np.isnan(vals).sum()), warnings=caught)


def compare(cells, ref_lib):
    ref = cells.get(ref_lib)
    if ref is None or ref.status != "ok":
        return
    r = ref.values
    scale = np.nanmax(np.abs(r)) if np.isfinite(r).any() else np.nan
    for c in cells.values():
        if c.status != "ok" or c.values is None:
            continue
        v = c.values
        both = np.isfinite(v) & np.isfinite(r)
        c.nan_mismatch = int((np.isnan(v) != np.isnan(r)).sum())
        if both.any():
            c.max_abs_diff = float(np.max(np.abs(v[both] - r[both])))
            c.max_rel_diff = float(c.max_abs_diff / scale) if scale else float("nan")


# --------------------------------------------------------------------------- output


def machine_info(threads):
    def ver(mod):
        return getattr(mod, "__version__", "?") if mod is not None else "not installed"

    import numba

    info = {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "threads": threads,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "networkx": ver(nx),
        "networkit": ver(nk),
        "rustworkx": ver(rx),
        "igraph": ver(ig),
    }
    try:
        import centrality_vision

        info["centrality_vision"] = centrality_vision.__version__
    except Exception:
        info["centrality_vision"] = "not importable"
    return info


def main(args):
    cen, ours_pix, ours_dela, ours_msg = _import_ours()
    avail = {
        "ours": cen is not None,
        "ours-csr": cen is not None,
        "networkx": nx is not None,
        "networkit": nk is not None,
        "rustworkx": rx is not None,
        "igraph": ig is not None,
        "scipy": True,
    }
    libs = [lib for lib in args.libs if avail[lib]]
    if nk is not None:
        nk.setNumberOfThreads(args.threads)
    if cen is not None:
        import centrality_vision

        centrality_vision.set_num_threads(args.threads)

    info = machine_info(args.threads)
    print("=" * 78)
    print("centrality benchmark (unweighted / hop distances)")
    print("machine: %s, %s, os.cpu_count() = %s" % (info["platform"], info["processor"], info["cpu_count"]))
    print("python %s | numpy %s | scipy %s | numba %s" % (info["python"], info["numpy"], info["scipy"], info["numba"]))
    print(
        "networkx %s | networkit %s | rustworkx %s | igraph %s | centrality_vision %s"
        % (info["networkx"], info["networkit"], info["rustworkx"], info["igraph"], info["centrality_vision"])
    )
    print(
        "threads: networkit %s, rustworkx RAYON_NUM_THREADS=%s, ours %s; networkx, igraph "
        "and scipy.eigsh single-threaded" % (args.threads, os.environ.get("RAYON_NUM_THREADS"), _our_threads())
    )
    if cen is None:
        print("ours: not available (%s)" % ours_msg)
    elif ours_msg:
        print("ours: partly available (%s)" % ours_msg)
    for lib, err in (("networkx", _nx_err), ("networkit", _nk_err), ("rustworkx", _rx_err), ("igraph", _ig_err)):
        if err and lib in args.libs:
            print("%s: not available (%s)" % (lib, err))
    print("repeat: %d (median; a single run, marked *, when the first run takes > %g s)" % (args.repeat, SINGLE_RUN_S))
    print(load_line("multi-threaded timings (networkit, rustworkx, ours) suffer most"))
    print("=" * 78)

    # graphs
    print("\ngraphs (built once, shared by all libraries):")
    graphs = []
    for name in args.graphs:
        t0 = time.perf_counter()
        g = build_graph(name, ours_pix, ours_dela)
        dt = time.perf_counter() - t0
        graphs.append(g)
        print("  %-14s n = %6d  edges = %7d  (%s; built by %s in %.3f s)" % (g.name, g.n, g.m, g.detail, g.builder, dt))

    # conversions (not timed)
    conv = {}
    conv_times = {}
    print("\nconversion to each library's graph type (NOT counted in the timings):")
    for lib in libs:
        parts = []
        for g in graphs:
            t0 = time.perf_counter()
            conv[lib, g.name] = CONVERTERS[lib](g)
            conv_times[lib, g.name] = time.perf_counter() - t0
            parts.append("%s %.3f s" % (g.name, conv_times[lib, g.name]))
        print("  %-10s %s" % (lib + ":", ", ".join(parts)))

    # warm-up
    tiny = tiny_graph(ours_pix)
    t0 = time.perf_counter()
    warm_msgs = []
    for lib in libs:
        G = CONVERTERS[lib](tiny)
        for c in args.only:
            spec = calls_for(lib, c, cen, tiny.n)
            if spec is None:
                continue
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    spec[0](G)
            except Exception as exc:
                if lib == "ours":
                    warm_msgs.append("%s: %s: %s" % (c, type(exc).__name__, exc))
    print(
        "\nwarm-up: every function called once on a tiny %d-node pixel disk before timing "
        "(numba JIT compilation of ours): %.2f s" % (tiny.n, time.perf_counter() - t0)
    )
    for m in warm_msgs:
        print("  ! ours warm-up failed: %s" % m)

    ref_lib = "ours" if "ours" in libs else ("networkx" if "networkx" in libs else None)
    results = {}
    for c in args.only:
        results[c] = {}
        for g in graphs:
            cells = {}
            for lib in libs:
                if lib == "scipy" and c != "eigenvector":
                    continue
                print("  running %-12s %-14s %-10s" % (c, g.name, lib), end="", flush=True)
                cell = run_cell(lib, c, g, conv[lib, g.name], cen, args.repeat, args.with_slow_networkx)
                cells[lib] = cell
                print(" %s" % (fmt_s(cell) if cell.status == "ok" else cell.status), flush=True)
            ref = ref_lib
            if ref is None or cells.get(ref) is None or cells[ref].status != "ok":
                # fall back to the first library that produced values (a compiled one first)
                ref = next(
                    (
                        lib
                        for lib in ("ours", "networkx", "igraph", "scipy", "rustworkx", "networkit")
                        if lib in cells and cells[lib].status == "ok"
                    ),
                    None,
                )
            compare(cells, ref)
            results[c][g.name] = (cells, ref)

    # tables
    print()
    for c in args.only:
        libs_c = [lib for lib in libs if not (lib == "scipy" and c != "eigenvector")]
        headers = (
            ["graph", "n", "edges"] + ["%s [s]" % lib for lib in libs_c] + ["ours/fastest-compiled", "networkx/ours"]
        )
        rows, agree_rows, notes = [], [], []
        for g in graphs:
            cells, ref = results[c][g.name]
            row = [g.name, g.n, g.m] + [fmt_s(cells.get(lib)) for lib in libs_c]
            ours = cells.get("ours")
            comp = [(cells[lib].median, lib) for lib in COMPILED if lib in cells and cells[lib].status == "ok"]
            best = min(comp) if comp else None
            if ours is not None and ours.status == "ok" and best is not None:
                row.append("%.2f (vs %s)" % (ours.median / best[0], SHORT[best[1]]))
            else:
                row.append("-" if best is None else "- (best %s %.4f)" % (SHORT[best[1]], best[0]))
            nxc = cells.get("networkx")
            if ours is not None and ours.status == "ok" and nxc is not None and nxc.status == "ok":
                row.append("%.1f" % (nxc.median / ours.median))
            else:
                row.append("-")
            rows.append(row)
            arow = [g.name, ref or "-"]
            for lib in libs_c:
                cell = cells.get(lib)
                if cell is None or cell.status != "ok":
                    arow.append(fmt_s(cell))
                    continue
                if lib == ref:
                    txt = "ref"
                elif math.isnan(cell.max_abs_diff):
                    txt = "nan"
                else:
                    txt = "%.1e" % cell.max_abs_diff
                txt += " nan=%d" % cell.nan
                if cell.nan_mismatch and lib != ref:
                    txt += " (%d differ)" % cell.nan_mismatch
                arow.append(txt)
            agree_rows.append(arow)
            for lib in libs_c:
                cell = cells.get(lib)
                if cell is None:
                    continue
                if cell.note and cell.status not in ("skipped",):
                    notes.append("%s/%s: %s: %s" % (g.name, lib, cell.status, cell.note))
                for w in cell.warnings:
                    notes.append("%s/%s: warning %s" % (g.name, lib, w[:200]))
        print("### %s  (seconds, median of %d; * = single run)" % (c, args.repeat))
        print(table(headers, rows))
        print("\nagreement with the reference (max |value - ref| after matching conventions; nan = NaN count):")
        print(table(["graph", "ref"] + libs_c, agree_rows))
        for note in dict.fromkeys(notes):
            print("  note: " + note)
        print()

    print(load_line("multi-threaded timings (networkit, rustworkx, ours) suffer most"))
    if args.json:
        out = {
            "machine": info,
            "args": {k: v for k, v in vars(args).items()},
            "ours_available": cen is not None,
            "ours_message": ours_msg,
            "graphs": {g.name: {"n": g.n, "edges": g.m, "builder": g.builder, "detail": g.detail} for g in graphs},
            "conversion_s": {lib: {g.name: conv_times[lib, g.name] for g in graphs} for lib in libs},
            "results": {},
        }
        for c, by_graph in results.items():
            out["results"][c] = {}
            for gname, (cells, ref) in by_graph.items():
                out["results"][c][gname] = {"reference": ref}
                for lib, cell in cells.items():
                    out["results"][c][gname][lib] = {
                        "status": cell.status,
                        "median_s": None if cell.status != "ok" else cell.median,
                        "times_s": cell.times,
                        "note": cell.note,
                        "nan_count": cell.nan if cell.status == "ok" else None,
                        "max_abs_diff": None if math.isnan(cell.max_abs_diff) else cell.max_abs_diff,
                        "max_rel_diff": None if math.isnan(cell.max_rel_diff) else cell.max_rel_diff,
                        "nan_mismatch": cell.nan_mismatch,
                        "warnings": cell.warnings,
                    }
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(out, indent=2))
        print("results written to %s" % args.json)
    return 0


def _our_threads():
    try:
        import centrality_vision

        return centrality_vision.get_num_threads()
    except Exception:
        return "?"


# --------------------------------------------------------------------------- image scale

MPEG7 = Path(os.environ.get("CV_DATA", "/work/shared/data")) / "mpeg7"


def silhouette_mask(name, target):
    """An MPEG-7 silhouette zoomed (nearest neighbour) to about ``target`` foreground pixels."""
    import imageio.v3 as iio
    from scipy import ndimage

    image = np.asarray(iio.imread(MPEG7 / ("%s.gif" % name)))
    mask = image.reshape(-1, *image.shape[-3:])[0, ..., 0] > 127 if image.ndim == 4 else image > 127
    if mask.ndim == 3:
        mask = mask[..., 0]
    zoom = math.sqrt(target / mask.sum())
    mask = ndimage.zoom(mask.astype(np.uint8), zoom, order=0).astype(bool)
    labels, count = ndimage.label(mask, structure=np.ones((3, 3)))
    if count > 1:  # keep the largest 8-connected part
        mask = labels == np.argmax(np.bincount(labels.ravel())[1:]) + 1
    return np.pad(mask, 1)


def _timed(fn, *args, **kwargs):
    start = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - start


def _best_of(repeat, fn, *args, **kwargs):
    """``(result, median seconds)`` of ``repeat`` calls."""
    runs = [_timed(fn, *args, **kwargs) for _ in range(repeat)]
    return runs[0][0], float(np.median([t for _, t in runs]))


def scale_main(args):
    """Image-scale measurements of ours (one process, same graphs); ratios are the point."""
    import centrality_vision
    from centrality_vision import centrality as cen
    from centrality_vision.centrality import _kernels
    from centrality_vision.graphs import pixel_graph

    centrality_vision.set_num_threads(args.threads)
    print("=" * 78)
    print("centrality benchmark: image scale (ours; igraph for exact betweenness)")
    info = machine_info(args.threads)
    print(
        "machine: %s, os.cpu_count() = %s, threads (ours) = %d; numba %s, igraph %s"
        % (info["platform"], info["cpu_count"], args.threads, info["numba"], info["igraph"])
    )
    print(load_line("every timing is inflated; compare the ratios measured side by side"))
    print("=" * 78)
    graphs = {}
    disk, _ = disk_mask(10000)
    graphs["disk-10000"] = disk
    graphs["disk-100k"] = disk_mask(100_000)[0]
    graphs["silhouette-100k"] = silhouette_mask("horse-1", 100_000)
    graphs["mask-1M"] = silhouette_mask("elephant-1", 1_000_000)
    built = {}
    for name, mask in graphs.items():
        (g, _), t = _timed(pixel_graph, mask)
        built[name] = g
        print(
            "  %-16s n = %8d  edges = %8d  mask %dx%d  (pixel_graph, 8-neighbour, %.2f s)"
            % (name, g.shape[0], g.nnz // 2, *mask.shape, t)
        )
    tiny, _ = pixel_graph(disk_mask(30)[0])
    for f in (cen.betweenness, cen.closeness, cen.eccentricity):  # compile
        f(tiny)
        f(tiny, weights=True)
    cen.betweenness(tiny, epsilon=0.5, seed=0)
    cen.harmonic(tiny, epsilon=0.5, seed=0)
    cen.eccentricity(tiny, method="bounds")

    def eps(edges, seconds):
        return "%.3g" % (edges / seconds) if seconds > 0 else "-"

    sections = set(args.scale_sections.split(","))

    # 1. Exact betweenness, ours vs igraph.
    if "exact" in sections:
        _scale_exact(args, built, cen, eps)
    if "closeness" in sections:
        _scale_closeness(built, cen, _kernels)
    if "approx" in sections:
        _scale_approx(built, cen, eps)
    if "eccentricity" in sections:
        _scale_eccentricity(built, cen)
    if "eigenvector" in sections:
        _scale_eigenvector(built, cen, pixel_graph)
    print()
    print(load_line("every timing is inflated; compare the ratios measured side by side"))
    return 0


def _scale_exact(args, built, cen, eps):
    print("\n### exact betweenness (hop counts); edges/s = n * edges / seconds")
    rows = []
    names = ["disk-10000"] + (["disk-100k", "silhouette-100k"] if args.scale_exact else [])
    for name in names:
        g = built[name]
        n, m = g.shape[0], g.nnz // 2
        (ours, info), t_ours = _timed(cen.betweenness, g, return_info=True)
        row = [name, n, m, "%.2f" % t_ours, eps(n * m, t_ours), "%d / %d" % (info["searches"], info["symmetries"])]
        if name == "disk-10000" or (name == "disk-100k" and args.scale_plain):
            plain, t_plain = _timed(cen.betweenness, sp.csr_array(g))
            row += ["%.2f" % t_plain, "%.2f" % (t_plain / t_ours), "%.1e" % (np.abs(plain - ours).max() / plain.max())]
        else:
            row += ["-", "-", "-"]
        if ig is not None and name == "disk-10000":
            upper = sp.triu(g, k=1).tocoo()
            G = ig.Graph(n=n, edges=np.column_stack([upper.row, upper.col]).tolist())
            ref, t_ig = _timed(G.betweenness, directed=False)
            row += ["%.2f" % t_ig, "%.2f" % (t_ig / t_ours), "%.1e" % np.abs(np.asarray(ref) - ours).max()]
        else:
            row += ["-", "-", "-"]
        rows.append(row)
    print(
        table(
            [
                "graph",
                "n",
                "edges",
                "ours [s]",
                "ours edges/s",
                "searches / maps",
                "csr [s]",
                "csr/ours",
                "rel diff",
                "igraph [s]",
                "igraph/ours",
                "max |diff|",
            ],
            rows,
        )
    )
    print(
        "  ours: the PixelGraph (grid walk; one search per orbit of the mask's mirror/rotation maps);"
        " csr: the same adjacency as a plain csr_array (adjacency lists, every node a source)"
    )


def _plain_fifo(grid, lo, hi):
    """The FIFO-queue search per source that the octile kernel replaced."""
    from centrality_vision.centrality._grid import fifo_stats

    return fifo_stats(grid, grid.raster[lo:hi])


def _scale_closeness(built, cen, _kernels):
    """Weighted (1, sqrt 2) versus hop-count closeness on pixel graphs."""
    from centrality_vision._parallel import run_chunks
    from centrality_vision.centrality._grid import _Grid

    print("\n### closeness on pixel graphs: by length (1, sqrt 2) versus hop counts, same process")
    rows = []
    graphs = {"disk-10000": built["disk-10000"]}
    try:  # Kimia-99 silhouettes at twice their size (about 2,000-21,000 pixels)
        from skimage.transform import rescale

        from centrality_vision.datasets import load_kimia99
        from centrality_vision.graphs import pixel_graph

        kimia = load_kimia99()
        for shape in ("dog1", "hand", "f16", "fish14"):
            mask = rescale(kimia.image(shape).astype(float), 2, order=0) > 0.5
            graphs["kimia-%s-x2" % shape] = pixel_graph(mask, connectivity=8)[0]
            if shape == "dog1":  # rectangular pixels: three lengths (1, 1.5, sqrt 3.25)
                graphs["dog1-x2-1:1.5"] = pixel_graph(mask, connectivity=8, spacing=(1.0, 1.5))[0]
    except Exception as exc:  # the data is optional here
        print("  ! Kimia-99 silhouettes unavailable (%s: %s)" % (type(exc).__name__, exc))
    for name, g in graphs.items():
        n, m = g.shape[0], g.nnz // 2
        grid = _Grid(g)
        # interleaved: hops, by length, harmonic by length, the plain FIFO search it replaces
        times = {"hops": [], "length": [], "harmonic": [], "fifo": []}
        for _ in range(3):
            _, t = _timed(cen.closeness, g)
            times["hops"].append(t)
            length, t = _timed(cen.closeness, g, weights=True)
            times["length"].append(t)
            _, t = _timed(cen.harmonic, g, weights=True)
            times["harmonic"].append(t)
            _, t = _timed(run_chunks, partial(_plain_fifo, grid), n)
            times["fifo"].append(t)
        t_hop, t_len, t_har, t_fifo = (float(np.median(times[k])) for k in ("hops", "length", "harmonic", "fifo"))
        prep = cen._api._prepare(g)
        sources = np.arange(n, dtype=np.int64)
        heap, t_heap = _timed(_kernels.dijkstra_stats, prep.indptr, prep.indices, prep.data, sources)
        heap_close = prep.unpermute((n - 1) / heap[0])
        rows.append(
            [
                name,
                n,
                m,
                "%.3f" % t_hop,
                "%.3f" % t_len,
                "%.2f" % (t_len / t_hop),
                "%.3f" % t_har,
                "%.2f" % (t_har / t_hop),
                "%.2f" % t_fifo,
                "%.1f" % (t_fifo / t_len),
                "%.2f" % t_heap,
                "%.1e" % np.abs(length - heap_close).max(),
            ]
        )
    print(
        table(
            [
                "graph",
                "n",
                "edges",
                "hops [s]",
                "length [s]",
                "length/hops",
                "harmonic [s]",
                "harmonic/hops",
                "plain FIFO [s]",
                "FIFO/length",
                "heap [s]",
                "length vs heap |diff|",
            ],
            rows,
        )
    )
    print(
        "  hops: bit-parallel search, 64 sources at a time. length: cen.closeness(weights=True), octile-visible\n"
        "  pixels in closed form and a search only for the hidden ones; harmonic: the same plus one difference\n"
        "  of prefix sums per run of seen pixels; plain FIFO: one exact FIFO-queue search per source (the kernel the\n"
        "  octile one replaced), same threads; heap: the Dijkstra kernel of general graphs, one thread, all\n"
        "  sources, for the |diff| check. Medians of 3 interleaved runs."
    )


def _scale_approx(built, cen, eps):
    print("\n### approximate betweenness, epsilon = 0.01 (normalised), delta = 0.1, seed = 0")
    rows = []
    for name in ("disk-10000", "disk-100k", "silhouette-100k", "mask-1M"):
        g = built[name]
        n, m = g.shape[0], g.nnz // 2
        (approx, infod), t = _timed(cen.betweenness, g, normalized=True, epsilon=0.01, seed=0, return_info=True)
        err = "-"
        if name.startswith("disk"):  # exact values known (the disk's symmetries: 13 s at 100k)
            err = "%.4f" % np.abs(approx - cen.betweenness(g, normalized=True)).max()
        rows.append(
            [
                name,
                n,
                m,
                "%.1f" % t,
                infod["samples"],
                "%.1f%%" % (100.0 * infod.get("counted", 0) / max(infod["samples"], 1)),
                "%.4f" % infod["bound"],
                err,
                eps(infod["visited"] * 2 * m / n, t),
            ]
        )
    print(
        table(
            ["graph", "n", "edges", "seconds", "samples", "counted", "guaranteed error", "observed error", "edges/s"],
            rows,
        )
    )
    print(
        "  counted: pairs whose paths were counted column by column (distance as on the open grid), not searched;\n"
        "  edges/s: (pixels visited + cells counted) x mean degree / seconds"
    )


def _scale_eccentricity(built, cen):
    """One search per node versus Takes-Kosters bounds."""
    print("\n### eccentricity: all searches versus Takes-Kosters bounds (exact both)")
    rows = []
    for name, weighted in (
        ("disk-10000", False),
        ("disk-10000", True),
        ("silhouette-100k", False),
        ("silhouette-100k", True),
    ):
        g = built[name]
        (b, ib), t_b = _timed(cen.eccentricity, g, weights=weighted, method="bounds", return_info=True)
        if name == "disk-10000" or not weighted:
            (a, ia), t_a = _timed(cen.eccentricity, g, weights=weighted, method="all", return_info=True)
            diff = "%.1e" % np.abs(a - b).max()
            row_a = ["%.2f" % t_a, ia["searches"]]
        else:
            diff, row_a = "-", ["(skipped)", g.shape[0]]
        rows.append([name, "length" if weighted else "hops", g.shape[0], *row_a, "%.2f" % t_b, ib["searches"], diff])
    print(
        table(
            ["graph", "distance", "n", "all [s]", "all searches", "bounds [s]", "bounds searches", "max |diff|"], rows
        )
    )
    print("  'all' by hops counts 64-source groups of the bit-parallel search")


def _scale_eigenvector(built, cen, pixel_graph):
    print("\n### eigenvector on long thin graphs (issue before: path 27.7 s, strip 92 s)")
    rows = []
    path = sp.diags_array([np.ones(9999), np.ones(9999)], offsets=[-1, 1], format="csr")
    strip, _ = pixel_graph(np.ones((3, 10000), dtype=bool))
    for name, g in (("path-10000", path), ("strip-3x10000", strip), ("disk-10000", built["disk-10000"])):
        v, t = _timed(cen.eigenvector, g)
        rows.append([name, g.shape[0], "%.3f" % t])
    print(table(["graph", "n", "ours [s]"], rows))


if __name__ == "__main__":
    try:
        sys.exit(scale_main(_ARGS) if _ARGS.scale else main(_ARGS))
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception:
        traceback.print_exc()
        sys.exit(1)
