"""Compiled kernels (numba) for the shortest-path centralities.

All kernels take a CSR adjacency as ``indptr`` (int64), ``indices`` (int32) and
``data`` (float64 edge lengths) and a chunk of source nodes, run serially and release
the GIL; :mod:`._parallel` runs chunks on a pool of threads and adds their parts. (numba's
own ``prange`` was 8x slower when another process shared the cores, because OpenMP
threads spin at its barriers; plain threads leave scheduling to the OS.)

Exactness, the point of writing these ourselves:

- Shortest-path counts overflow float64 on long thin shapes (a 5 x 1200 pixel strip has
  more than 1e308 shortest paths between its ends), where other libraries return NaN.
  Every source is first run with plain float64 counts; a source whose counts overflow is
  run again with counts kept as logarithms, which cannot overflow. The ratios
  ``sigma[v] / sigma[w]`` that betweenness needs are the same either way.
- With edge lengths, equal path lengths must tie exactly: on 8-neighbour pixel graphs
  (lengths 1 and sqrt 2) floating-point sums of the same length differ in the last bits,
  and a library that compares them with ``==`` drops shortest paths. Two lengths tie here
  when they differ by at most ``TIE_RTOL`` times their size, which is far above rounding
  error (about 1e-13 after 1,000 hops) and far below the smallest gap between distinct
  lengths ``a + b sqrt 2`` of any image of up to a million pixels (about 1e-7 relative).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["TIE_RTOL", "dijkstra_stats", "multi_source_stats", "compact_groups", "brandes"]

TIE_RTOL = 1e-10
_OVERFLOW = 1e300
NO_GRID = (np.empty(0, dtype=np.int64), np.empty(0, dtype=np.bool_))  # offs, foreground: adjacency lists


@njit(cache=True, nogil=True, inline="always")
def _heap_push(heap_d, heap_v, size, d, v):
    i = size
    heap_d[i] = d
    heap_v[i] = v
    while i > 0:
        parent = (i - 1) >> 1
        if heap_d[parent] <= heap_d[i]:
            break
        heap_d[parent], heap_d[i] = heap_d[i], heap_d[parent]
        heap_v[parent], heap_v[i] = heap_v[i], heap_v[parent]
        i = parent
    return size + 1


@njit(cache=True, nogil=True, inline="always")
def _heap_pop(heap_d, heap_v, size):
    d = heap_d[0]
    v = heap_v[0]
    size -= 1
    heap_d[0] = heap_d[size]
    heap_v[0] = heap_v[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and heap_d[left + 1] < heap_d[left]:
            child = left + 1
        if heap_d[i] <= heap_d[child]:
            break
        heap_d[child], heap_d[i] = heap_d[i], heap_d[child]
        heap_v[child], heap_v[i] = heap_v[i], heap_v[child]
        i = child
    return d, v, size


@njit(cache=True, nogil=True, inline="always")
def _before(heap_d, heap_z, a, b):
    """Whether heap entry ``a`` comes before ``b``: by distance, then by zero-length edges."""
    return heap_d[a] < heap_d[b] or (heap_d[a] == heap_d[b] and heap_z[a] < heap_z[b])


@njit(cache=True, nogil=True, inline="always")
def _heap2_push(heap_d, heap_z, heap_v, size, d, z, v):
    """:func:`_heap_push` keyed by ``(d, z)`` in lexicographic order."""
    i = size
    heap_d[i] = d
    heap_z[i] = z
    heap_v[i] = v
    while i > 0:
        parent = (i - 1) >> 1
        if not _before(heap_d, heap_z, i, parent):
            break
        heap_d[parent], heap_d[i] = heap_d[i], heap_d[parent]
        heap_z[parent], heap_z[i] = heap_z[i], heap_z[parent]
        heap_v[parent], heap_v[i] = heap_v[i], heap_v[parent]
        i = parent
    return size + 1


@njit(cache=True, nogil=True, inline="always")
def _heap2_pop(heap_d, heap_z, heap_v, size):
    """:func:`_heap_pop` keyed by ``(d, z)``; returns ``(d, z, v, size)``."""
    d = heap_d[0]
    z = heap_z[0]
    v = heap_v[0]
    size -= 1
    heap_d[0] = heap_d[size]
    heap_z[0] = heap_z[size]
    heap_v[0] = heap_v[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and _before(heap_d, heap_z, left + 1, left):
            child = left + 1
        if not _before(heap_d, heap_z, child, i):
            break
        heap_d[child], heap_d[i] = heap_d[i], heap_d[child]
        heap_z[child], heap_z[i] = heap_z[i], heap_z[child]
        heap_v[child], heap_v[i] = heap_v[i], heap_v[child]
        i = child
    return d, z, v, size


@njit(cache=True, nogil=True, inline="always")
def _push(heap_d, heap_z, heap_v, size, d, z, v, keyed_z):
    """Push onto the ``(d, z)`` heap, or onto the ``d`` heap when not ``keyed_z``."""
    if keyed_z:
        return _heap2_push(heap_d, heap_z, heap_v, size, d, z, v)
    return _heap_push(heap_d, heap_v, size, d, v)


@njit(cache=True, nogil=True, inline="always")
def _pop(heap_d, heap_z, heap_v, size, keyed_z):
    """Pop from the heap :func:`_push` fills; ``z`` is 0 when not ``keyed_z``."""
    if keyed_z:
        return _heap2_pop(heap_d, heap_z, heap_v, size)
    d, v, size = _heap_pop(heap_d, heap_v, size)
    return d, 0, v, size


@njit(cache=True, nogil=True)
def _bfs(indptr, indices, s, hops, order):
    """Breadth-first search from ``s``; fills ``hops`` (must be -1) and ``order``; returns count."""
    hops[s] = 0
    order[0] = s
    head = 0
    tail = 1
    while head < tail:
        v = order[head]
        head += 1
        nxt = hops[v] + 1
        for j in range(indptr[v], indptr[v + 1]):
            w = indices[j]
            if hops[w] < 0:
                hops[w] = nxt
                order[tail] = w
                tail += 1
    return tail


@njit(cache=True, nogil=True)
def _dijkstra(indptr, indices, data, s, dist, done, order, heap_d, heap_v):
    """Dijkstra from ``s``; fills ``dist`` (must be inf), ``done`` and ``order``; returns count."""
    dist[s] = 0.0
    size = _heap_push(heap_d, heap_v, 0, 0.0, s)
    count = 0
    while size > 0:
        d, v, size = _heap_pop(heap_d, heap_v, size)
        if done[v]:
            continue
        done[v] = True
        order[count] = v
        count += 1
        for j in range(indptr[v], indptr[v + 1]):
            w = indices[j]
            if done[w]:
                continue
            nd = d + data[j]
            if nd < dist[w]:
                dist[w] = nd
                size = _heap_push(heap_d, heap_v, size, nd, w)
    return count


@njit(cache=True, nogil=True)
def _dijkstra_workspace(n, n_arcs):
    """Work arrays of :func:`_dijkstra`: distances (inf), done flags and a lazy heap."""
    return np.full(n, np.inf), np.zeros(n, dtype=np.bool_), np.empty(n_arcs + 1), np.empty(n_arcs + 1, dtype=np.int64)


@njit(cache=True, nogil=True)
def dijkstra_stats(indptr, indices, data, sources):
    """Per source, by edge length: sum of distances, sum of inverse distances, largest
    distance, reached count (the source included).

    Serial; the caller runs chunks of sources on several threads (the GIL is released).
    Hop distances go through :func:`multi_source_stats` instead.
    """
    n = indptr.shape[0] - 1
    k = sources.shape[0]
    total = np.zeros(k)
    inverse = np.zeros(k)
    largest = np.zeros(k)
    reached = np.zeros(k, dtype=np.int64)
    order = np.empty(n, dtype=np.int64)
    dist, done, heap_d, heap_v = _dijkstra_workspace(n, indices.shape[0])
    for i in range(k):
        count = _dijkstra(indptr, indices, data, sources[i], dist, done, order, heap_d, heap_v)
        t = 0.0
        h = 0.0
        for q in range(1, count):
            d = dist[order[q]]
            t += d
            if d > 0.0:  # a node at distance 0 (zero-length edges) adds nothing, as in networkx
                h += 1.0 / d
        largest[i] = dist[order[count - 1]]
        for q in range(count):
            dist[order[q]] = np.inf
            done[order[q]] = False
        total[i] = t
        inverse[i] = h
        reached[i] = count
    return total, inverse, largest, reached


_M1 = np.uint64(0x5555555555555555)
_M2 = np.uint64(0x3333333333333333)
_M4 = np.uint64(0x0F0F0F0F0F0F0F0F)
_H01 = np.uint64(0x0101010101010101)


@njit(cache=True, nogil=True, inline="always")
def _popcount(x):
    x = x - ((x >> np.uint64(1)) & _M1)
    x = (x & _M2) + ((x >> np.uint64(2)) & _M2)
    x = (x + (x >> np.uint64(4))) & _M4
    return np.int64((x * _H01) >> np.uint64(56))


@njit(cache=True)
def compact_groups(indptr, indices, size):
    """Split the nodes into groups of at most ``size`` that are close in the graph.

    Greedy: from the first node not yet grouped, a breadth-first search over ungrouped
    nodes takes the next ``size`` nodes. Returns ``(members, group_ptr)`` in CSR style.
    Groups of nearby sources keep the bit-parallel search below short.
    """
    n = indptr.shape[0] - 1
    # Seeds are taken in breadth-first order of the whole graph, so that the sweep moves
    # through it coherently and leaves few scattered leftovers for the last groups.
    sweep = np.empty(n, dtype=np.int64)
    hops = np.full(n, -1, dtype=np.int64)
    filled = 0
    for root in range(n):
        if hops[root] < 0:
            filled += _bfs(indptr, indices, root, hops, sweep[filled:])
    taken = np.zeros(n, dtype=np.bool_)
    members = np.empty(n, dtype=np.int64)
    group_ptr = np.zeros(n + 1, dtype=np.int64)
    n_groups = 0
    pos = 0
    for start in sweep:
        if taken[start]:
            continue
        taken[start] = True
        members[pos] = start
        head = pos
        tail = pos + 1
        while head < tail and tail - pos < size:
            v = members[head]
            head += 1
            for j in range(indptr[v], indptr[v + 1]):
                w = indices[j]
                if not taken[w] and tail - pos < size:
                    taken[w] = True
                    members[tail] = w
                    tail += 1
        pos = tail
        n_groups += 1
        group_ptr[n_groups] = pos
    return members, group_ptr[: n_groups + 1]


@njit(cache=True, nogil=True)
def multi_source_stats(indptr, indices, members, group_ptr, first_group, stop_group):
    """Hop-distance sums over the sources of groups ``first_group .. stop_group - 1``.

    Bit-parallel breadth-first search (Then et al., VLDB 2015): the (at most 64) sources
    of a group advance together, one bit each. For undirected graphs d(s, w) = d(w, s),
    so the sums collected at node ``w`` over all sources are ``w``'s own. Returns per
    node: sum of distances, sum of inverse distances, largest distance and number of
    sources that reach it (itself included). Serial; the caller splits the groups
    between threads and adds the parts.
    """
    n = indptr.shape[0] - 1
    tot = np.zeros(n)
    inv = np.zeros(n)
    big = np.zeros(n)
    rea = np.zeros(n, dtype=np.int64)
    zero = np.uint64(0)
    seen = np.zeros(n, dtype=np.uint64)
    frontier = np.zeros(n, dtype=np.uint64)
    nxt = np.zeros(n, dtype=np.uint64)
    active = np.empty(n, dtype=np.int64)
    touched = np.empty(n, dtype=np.int64)
    visited = np.empty(n, dtype=np.int64)
    for g in range(first_group, stop_group):
        n_active = 0
        n_visited = 0
        for q in range(group_ptr[g], group_ptr[g + 1]):
            s = members[q]
            bit = np.uint64(1) << np.uint64(q - group_ptr[g])
            seen[s] = bit
            frontier[s] = bit
            active[n_active] = s
            n_active += 1
            visited[n_visited] = s
            n_visited += 1
            rea[s] += 1
        level = 0
        while n_active > 0:
            level += 1
            n_touched = 0
            for a in range(n_active):
                v = active[a]
                f = frontier[v]
                for j in range(indptr[v], indptr[v + 1]):
                    w = indices[j]
                    if f & ~seen[w] == zero:
                        continue
                    if nxt[w] == zero:
                        touched[n_touched] = w
                        n_touched += 1
                    nxt[w] |= f
                frontier[v] = zero
            n_active = 0
            for t in range(n_touched):
                w = touched[t]
                new = nxt[w] & ~seen[w]
                nxt[w] = zero
                if seen[w] == zero:
                    visited[n_visited] = w
                    n_visited += 1
                seen[w] |= new
                frontier[w] = new
                active[n_active] = w
                n_active += 1
                cnt = _popcount(new)
                tot[w] += cnt * level
                inv[w] += cnt / level
                rea[w] += cnt
                if level > big[w]:
                    big[w] = level
        for q in range(n_visited):
            seen[visited[q]] = zero
    return tot, inv, big, rea


# Breadth-first kernels walk either adjacency lists or, with ``grid``, a padded pixel raster
# whose neighbours are ``v + offs[k]`` (see :mod:`._grid`); ``_span`` gives the loop range
# and ``_neighbour`` the node, so one kernel serves both (the branch is loop-invariant).


@njit(cache=True, nogil=True, inline="always")
def _span(indptr, offs, grid, v):
    if grid:
        return 0, offs.shape[0]
    return indptr[v], indptr[v + 1]


@njit(cache=True, nogil=True, inline="always")
def _neighbour(indices, offs, grid, v, j):
    return v + offs[j] if grid else indices[j]


@njit(cache=True, nogil=True)
def _brandes_source_bfs(indptr, indices, offs, grid, s, hops, order, sigma, coef, bc, weight, succ, first):
    """One source of Brandes' algorithm with float64 path counts, adding ``weight`` times
    its dependencies to ``bc``; False (and nothing added) if the counts overflow.

    The forward pass records the successors of the ``q``-th settled node in
    ``succ[first[q]:first[q + 1]]`` (``succ`` as long as the arcs), so the backward pass
    reads only arcs of the shortest-path DAG, in order (1.4-1.6x faster than re-scanning
    every neighbour's hop count).

    Every node index is unsigned: ``order``, ``succ`` and ``first`` are uint64 arrays and
    ``offs`` (the grid mode's neighbour offsets, negative ones wrapped) uint64, so no array
    access pays numba's negative-index wraparound (1.27x faster on a 1,000-node Delaunay
    graph).
    """
    zero = np.uint64(0)
    one = np.uint64(1)
    hops[s] = 0
    sigma[s] = 1.0
    order[0] = s
    head = zero
    tail = one
    m = zero
    ok = True
    n_offs = np.uint64(offs.shape[0])
    while head < tail:
        v = order[head]
        first[head] = m
        head += one
        nxt = hops[v] + 1
        sv = sigma[v]  # final: every predecessor was settled before v
        if sv > _OVERFLOW:
            ok = False
        lo = zero if grid else np.uint64(indptr[v])
        hi = n_offs if grid else np.uint64(indptr[v + one])
        for j in range(lo, hi):
            w = v + offs[j] if grid else np.uint64(indices[j])
            hw = hops[w]
            if hw < 0:
                hops[w] = nxt
                sigma[w] = sv
                order[tail] = w
                tail += one
                succ[m] = w
                m += one
            elif hw == nxt:
                sigma[w] += sv
                succ[m] = w
                m += one
    first[tail] = m
    if ok:
        # coef[w] = (1 + delta[w]) / sigma[w]; delta[v] = sigma[v] * sum of coef over successors.
        # A successor comes later in ``order``, so its coef is written (for this source)
        # before it is read: coef needs no reset; the backward pass reads no hop count, so
        # the hop counts are reset on the way.
        q = tail - one
        while q > zero:
            v = order[q]
            acc = 0.0
            for a in range(first[q], first[q + one]):
                acc += coef[succ[a]]
            delta_v = acc * sigma[v]
            bc[v] += weight * delta_v
            coef[v] = (1.0 + delta_v) / sigma[v]
            hops[v] = -1
            q -= one
        hops[s] = -1
    else:
        for q in range(tail):
            hops[order[q]] = -1
    return ok


@njit(cache=True, nogil=True)
def _brandes_source_bfs_log(indptr, indices, offs, grid, s, hops, order, lsigma, delta, bc, weight):
    """One source of Brandes' algorithm with path counts kept as logarithms (cannot overflow)."""
    hops[s] = 0
    lsigma[s] = 0.0
    order[0] = s
    head = 0
    tail = 1
    while head < tail:
        v = order[head]
        head += 1
        nxt = hops[v] + 1
        sv = lsigma[v]
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            hw = hops[w]
            if hw < 0:
                hops[w] = nxt
                lsigma[w] = sv
                order[tail] = w
                tail += 1
            elif hw == nxt:
                a = lsigma[w]
                lsigma[w] = max(a, sv) + np.log1p(np.exp(-abs(a - sv)))
    for q in range(tail):
        delta[order[q]] = 0.0
    for q in range(tail - 1, 0, -1):
        v = order[q]
        nxt = hops[v] + 1
        acc = 0.0
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if hops[w] == nxt:
                acc += np.exp(lsigma[v] - lsigma[w]) * (1.0 + delta[w])
        delta[v] = acc
        bc[v] += weight * acc
    for q in range(tail):
        hops[order[q]] = -1
        delta[order[q]] = 0.0


@njit(cache=True, nogil=True)
def _dijkstra_counts(
    indptr, indices, data, s, dist, zeros, done, order, heap_d, heap_z, heap_v, sigma, use_log, rtol, has_zero
):
    """Forward pass of Brandes' algorithm by length: Dijkstra from ``s`` counting shortest
    paths (``sigma``, as logarithms when ``use_log``), lengths tying within ``rtol``.

    Among paths of tied length only those with the fewest zero-length edges count
    (``zeros``): a zero-length edge is as if infinitesimally long, which keeps the
    shortest-path DAG acyclic and independent of the order the search settles nodes at
    equal distance. Without zero-length edges (``has_zero`` False) every count is 0 and
    the heap is keyed by distance alone, which is faster. Returns the number of nodes
    settled (in ``order``) and whether a plain count passed ``_OVERFLOW``.
    """
    dist[s] = 0.0
    zeros[s] = 0
    sigma[s] = 0.0 if use_log else 1.0
    size = _push(heap_d, heap_z, heap_v, 0, 0.0, 0, s, has_zero)
    count = 0
    overflow = False
    while size > 0:
        d, z, v, size = _pop(heap_d, heap_z, heap_v, size, has_zero)
        if done[v] or z != zeros[v]:  # settled, or an entry a tie with fewer zeros replaced
            continue
        done[v] = True
        order[count] = v
        count += 1
        sv = sigma[v]
        if not use_log and sv > _OVERFLOW:
            overflow = True
        for j in range(indptr[v], indptr[v + 1]):
            w = indices[j]
            if done[w]:
                continue
            nd = d + data[j]
            nz = z + (data[j] == 0.0)
            dw = dist[w]
            tie = dw < np.inf and nd <= dw + rtol * dw
            if dw == np.inf or nd < dw - rtol * dw or (tie and nz < zeros[w]):
                dist[w] = nd
                zeros[w] = nz
                sigma[w] = sv
                size = _push(heap_d, heap_z, heap_v, size, nd, nz, w, has_zero)
            elif tie and nz == zeros[w]:
                if use_log:
                    a = sigma[w]
                    sigma[w] = max(a, sv) + np.log1p(np.exp(-abs(a - sv)))
                else:
                    sigma[w] += sv
    return count, overflow


@njit(cache=True, nogil=True, inline="always")
def _on_dag(dv, zv, length, dw, zw, later, rtol):
    """Whether arc v -> w (``length`` long; w settled ``later``) is on the shortest-path DAG
    that :func:`_dijkstra_counts` counted: d(v) + length = d(w) within ``rtol``, and
    zeros(v) + [length = 0] = zeros(w)."""
    return dw < np.inf and later and abs(dv + length - dw) <= rtol * dw and zv + (length == 0.0) == zw


@njit(cache=True, nogil=True)
def _brandes_source_dijkstra(
    indptr,
    indices,
    data,
    s,
    dist,
    zeros,
    done,
    order,
    heap_d,
    heap_z,
    heap_v,
    sigma,
    delta,
    bc,
    use_log,
    rtol,
    rank,
    has_zero,
):
    count, overflow = _dijkstra_counts(
        indptr, indices, data, s, dist, zeros, done, order, heap_d, heap_z, heap_v, sigma, use_log, rtol, has_zero
    )
    ok = not overflow
    if ok:
        for q in range(count):
            delta[order[q]] = 0.0
            rank[order[q]] = q
        for q in range(count - 1, 0, -1):
            v = order[q]
            acc = 0.0
            for j in range(indptr[v], indptr[v + 1]):
                w = indices[j]
                if _on_dag(dist[v], zeros[v], data[j], dist[w], zeros[w], rank[w] > q, rtol):
                    if use_log:
                        acc += np.exp(sigma[v] - sigma[w]) * (1.0 + delta[w])
                    else:
                        acc += (1.0 + delta[w]) / sigma[w]
            delta[v] = acc if use_log else acc * sigma[v]
            bc[v] += delta[v]
    for q in range(count):
        dist[order[q]] = np.inf
        done[order[q]] = False
    return ok


@njit(cache=True, nogil=True)
def brandes(indptr, indices, data, sources, weighted, rtol, force_log):
    """Betweenness summed over ``sources`` (ordered pairs: halve for undirected graphs).

    Returns the per-node sums and the number of sources that needed log-space counts.
    Serial; the caller runs chunks of sources on several threads and adds the parts.
    """
    n = indptr.shape[0] - 1
    bc = np.zeros(n)
    n_log = 0
    order = np.empty(n, dtype=np.int64)
    sigma = np.empty(n)
    delta = np.zeros(n)
    hops = np.full(n, -1, dtype=np.int64)
    rank = np.empty(n, dtype=np.int64)
    dist, done, heap_d, heap_v = _dijkstra_workspace(n, indices.shape[0] if weighted else 0)
    zeros = np.zeros(n, dtype=np.int64)
    heap_z = np.empty(heap_v.shape[0], dtype=np.int64)
    has_zero = weighted and data.shape[0] > 0 and data.min() == 0.0
    no_offs = np.empty(0, dtype=np.int64)
    # the hop-count search's node indices, unsigned (see _brandes_source_bfs)
    order_u = np.empty(0 if weighted else n, dtype=np.uint64)
    no_offs_u = np.empty(0, dtype=np.uint64)
    succ = np.empty(0 if weighted else indices.shape[0], dtype=np.uint64)
    first = np.empty(0 if weighted else n + 1, dtype=np.uint64)
    for i in range(sources.shape[0]):
        s = sources[i]
        ok = False
        if weighted:
            # plain counts first; where they overflow, the source again in log space (which
            # cannot overflow, so the loop ends)
            use_log = force_log
            while not _brandes_source_dijkstra(
                indptr,
                indices,
                data,
                s,
                dist,
                zeros,
                done,
                order,
                heap_d,
                heap_z,
                heap_v,
                sigma,
                delta,
                bc,
                use_log,
                rtol,
                rank,
                has_zero,
            ):
                use_log = True
            n_log += use_log
        else:
            if not force_log:
                ok = _brandes_source_bfs(
                    indptr, indices, no_offs_u, False, np.uint64(s), hops, order_u, sigma, delta, bc, 1.0, succ, first
                )
            if not ok:
                n_log += 1
                _brandes_source_bfs_log(indptr, indices, no_offs, False, s, hops, order, sigma, delta, bc, 1.0)
    return bc, n_log


# --- few distinct edge lengths: Dijkstra with one FIFO queue per length ---------------------
#
# On pixel graphs every edge is 1 or sqrt 2 long (nD: a few more with ``spacing``). With K
# distinct lengths, Dijkstra needs no heap: the nodes reached over edges of length L_k are
# appended to queue k in settling order, so each queue is sorted, and the next node to settle
# is the smallest of the K queue heads (O(m + nK) per source instead of O(m log n)). A
# distance is kept as its integer counts of each length, and its value is recomputed from
# them, so it carries no accumulated rounding: two lengths a + b sqrt 2 tie exactly when
# their counts agree, and differ by far more than ``TIE_RTOL`` otherwise.


def length_classes(data, max_classes=8):
    """``(kind, lengths)`` when the arc lengths take at most ``max_classes`` distinct values,
    all positive; ``kind[j]`` is the class of arc ``j``. Else None.

    Classes are exact values: lengths that differ only in their last bits are two classes
    (the search then ties paths by ``TIE_RTOL``, as the general one does). Merging lengths
    within a tolerance rounded distances to a class's smallest length, and tied paths the
    general search keeps apart, so that a component's results depended on whether the rest
    of the graph had few lengths.
    """
    if data.size == 0 or data.min() <= 0:
        return None
    lengths, kind = np.unique(data, return_inverse=True)
    if lengths.size > max_classes:
        return None
    return kind.astype(np.int8), lengths.astype(np.float64)


@njit(cache=True, nogil=True)
def _class_workspace(n, kind, n_classes, repeat=1):
    """Integer length counts, distances, flags and one FIFO queue per class, each as long
    as the arcs of its class (``repeat`` times ``kind``: the grid mode's per-pixel offsets)."""
    counts = np.zeros((n, n_classes), dtype=np.int32)
    dist = np.full(n, np.inf)
    done = np.zeros(n, dtype=np.bool_)
    qstart = np.zeros(n_classes + 1, dtype=np.int64)
    for j in range(kind.shape[0]):
        qstart[kind[j] + 1] += repeat
    for k in range(n_classes):
        qstart[k + 1] += qstart[k]
    qnode = np.empty(qstart[n_classes], dtype=np.int64)
    return counts, dist, done, qstart, qnode


@njit(cache=True, nogil=True)
def _walk_workspace(indptr, kind, n_classes, offs, foreground):
    """``(n, grid, workspace)`` for adjacency lists, or for the grid mode when ``offs`` is
    not empty: one node per raster pixel, background pixels flagged as settled forever."""
    grid = offs.shape[0] > 0
    if not grid:
        n = indptr.shape[0] - 1
        return n, grid, _class_workspace(n, kind, n_classes, 1)
    n = foreground.shape[0]
    n_pixels = np.count_nonzero(foreground)
    counts, dist, done, qstart, qnode = _class_workspace(n, kind, n_classes, n_pixels)
    for i in range(n):
        done[i] = not foreground[i]
    return n, grid, (counts, dist, done, qstart, qnode)


@njit(cache=True, nogil=True)
def _class_search(
    indptr,
    indices,
    offs,
    grid,
    kind,
    lengths,
    s,
    counts,
    dist,
    done,
    order,
    qstart,
    qnode,
    qhead,
    qtail,
    cand,
    sigma,
    count_paths,
    use_log,
    rtol,
):
    """Dijkstra from ``s`` with one FIFO queue per length class; returns the count settled.

    Fills ``dist`` (must be inf), ``done``, ``counts`` and ``order``; with ``count_paths``
    also the shortest-path counts ``sigma`` (as logarithms with ``use_log``) and returns
    a negative count when plain counts pass the overflow threshold.
    """
    n_classes = lengths.shape[0]
    for k in range(n_classes):
        qhead[k] = qstart[k]
        qtail[k] = qstart[k]
        counts[s, k] = 0
    dist[s] = 0.0
    sv = 0.0
    if count_paths:
        sigma[s] = 0.0 if use_log else 1.0
    v = s
    count = 0
    overflow = False
    while v >= 0:
        done[v] = True
        order[count] = v
        count += 1
        if count_paths:
            sv = sigma[v]
            if not use_log and sv > _OVERFLOW:
                overflow = True
        # The K candidate distances, each recomputed from integer counts (no drift).
        for c in range(n_classes):
            nd = 0.0
            for k in range(n_classes):
                nd += (counts[v, k] + (1 if k == c else 0)) * lengths[k]
            cand[c] = nd
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            if done[w]:
                continue
            c = kind[j]
            nd = cand[c]
            dw = dist[w]
            if nd < dw - rtol * dw or dw == np.inf:
                dist[w] = nd
                for k in range(n_classes):
                    counts[w, k] = counts[v, k]
                counts[w, c] += 1
                if count_paths:
                    sigma[w] = sv
                qnode[qtail[c]] = w
                qtail[c] += 1
            elif count_paths and nd <= dw + rtol * dw:
                if use_log:
                    a = sigma[w]
                    if a >= sv:
                        sigma[w] = a + np.log1p(np.exp(sv - a))
                    else:
                        sigma[w] = sv + np.log1p(np.exp(a - sv))
                else:
                    sigma[w] += sv
        # Next: the unsettled queue head of smallest (current) distance. Each queue is
        # sorted by the distance at push time, and a head's current distance is at most
        # that, so the smallest head is the smallest unsettled tentative distance.
        v = -1
        bd = np.inf
        for k in range(n_classes):
            h = qhead[k]
            while h < qtail[k] and done[qnode[h]]:
                h += 1
            qhead[k] = h
            if h < qtail[k] and dist[qnode[h]] < bd:
                bd = dist[qnode[h]]
                v = k
        if v >= 0:
            h = qhead[v]
            qhead[v] = h + 1
            v = qnode[h]
    if overflow:
        return -count
    return count


@njit(cache=True, nogil=True)
def class_stats(indptr, indices, kind, lengths, sources, offs, foreground):
    """As :func:`dijkstra_stats`, by the FIFO-queue search of few-length graphs.

    Grid mode when ``offs`` is not empty: nodes are the pixels of the padded raster
    ``foreground`` (see :mod:`._grid`), ``kind`` the class of each offset.
    """
    n, grid, (counts, dist, done, qstart, qnode) = _walk_workspace(indptr, kind, lengths.shape[0], offs, foreground)
    k = sources.shape[0]
    total = np.zeros(k)
    inverse = np.zeros(k)
    largest = np.zeros(k)
    reached = np.zeros(k, dtype=np.int64)
    order = np.empty(n, dtype=np.int64)
    qhead = np.empty(lengths.shape[0], dtype=np.int64)
    qtail = np.empty(lengths.shape[0], dtype=np.int64)
    cand = np.empty(lengths.shape[0])
    sigma = np.empty(0)
    for i in range(k):
        count = _class_search(
            indptr,
            indices,
            offs,
            grid,
            kind,
            lengths,
            sources[i],
            counts,
            dist,
            done,
            order,
            qstart,
            qnode,
            qhead,
            qtail,
            cand,
            sigma,
            False,
            False,
            0.0,
        )
        t = 0.0
        h = 0.0
        for q in range(1, count):
            d = dist[order[q]]
            t += d
            h += 1.0 / d
        largest[i] = dist[order[count - 1]]
        for q in range(count):
            dist[order[q]] = np.inf
            done[order[q]] = False
        total[i] = t
        inverse[i] = h
        reached[i] = count
    return total, inverse, largest, reached


@njit(cache=True, nogil=True)
def class_brandes(indptr, indices, kind, lengths, sources, rtol, force_log, edge_values, offs, foreground, weights):
    """As :func:`brandes` with edge lengths, by the FIFO-queue search of few-length graphs,
    adding ``weights[i]`` times the dependencies of ``sources[i]``.

    With ``edge_values`` also returns the per-arc dependencies (edge betweenness parts).
    Grid mode as in :func:`class_stats`.
    """
    n, grid, (counts, dist, done, qstart, qnode) = _walk_workspace(indptr, kind, lengths.shape[0], offs, foreground)
    bc = np.zeros(n)
    eb = np.zeros(indices.shape[0] if edge_values else 0)
    n_log = 0
    order = np.empty(n, dtype=np.int64)
    sigma = np.empty(n)
    delta = np.zeros(n)
    qhead = np.empty(lengths.shape[0], dtype=np.int64)
    qtail = np.empty(lengths.shape[0], dtype=np.int64)
    cand = np.empty(lengths.shape[0])
    for i in range(sources.shape[0]):
        s = sources[i]
        use_log = force_log
        while True:
            count = _class_search(
                indptr,
                indices,
                offs,
                grid,
                kind,
                lengths,
                s,
                counts,
                dist,
                done,
                order,
                qstart,
                qnode,
                qhead,
                qtail,
                cand,
                sigma,
                True,
                use_log,
                rtol,
            )
            if count > 0:
                break
            for q in range(-count):  # overflow: run this source again in log space
                dist[order[q]] = np.inf
                done[order[q]] = False
            use_log = True
        if use_log:
            n_log += 1
        _accumulate(
            indptr,
            indices,
            offs,
            grid,
            lengths,
            kind,
            order,
            count,
            dist,
            sigma,
            delta,
            bc,
            eb,
            use_log,
            rtol,
            edge_values,
            weights[i],
        )
        for q in range(count):
            dist[order[q]] = np.inf
            done[order[q]] = False
    return bc, n_log, eb


@njit(cache=True, nogil=True)
def _accumulate(
    indptr,
    indices,
    offs,
    grid,
    lengths,
    kind,
    order,
    count,
    dist,
    sigma,
    delta,
    bc,
    eb,
    use_log,
    rtol,
    edge_values,
    weight,
):
    """Brandes' backward pass over a few-length search (successor: d(v) + len = d(w))."""
    for q in range(count):
        delta[order[q]] = 0.0
    for q in range(count - 1, -1, -1):
        v = order[q]
        dv = dist[v]
        acc = 0.0
        lo, hi = _span(indptr, offs, grid, v)
        for j in range(lo, hi):
            w = _neighbour(indices, offs, grid, v, j)
            dw = dist[w]
            if dw > dv and dw < np.inf and abs(dv + lengths[kind[j]] - dw) <= rtol * dw:
                if use_log:
                    part = np.exp(sigma[v] - sigma[w]) * (1.0 + delta[w])
                else:
                    part = sigma[v] * ((1.0 + delta[w]) / sigma[w])
                acc += part
                if edge_values:
                    eb[j] += part
        if q > 0:
            delta[v] = acc
            bc[v] += weight * acc


@njit(cache=True, nogil=True)
def distances_from(indptr, indices, data, kind, lengths, s, weighted):
    """Distances from ``s`` to every node (inf where unreachable): hops, or lengths by the
    FIFO-queue search when ``kind`` is not empty, else by Dijkstra with a heap."""
    n = indptr.shape[0] - 1
    out = np.full(n, np.inf)
    order = np.empty(n, dtype=np.int64)
    if not weighted:
        hops = np.full(n, -1, dtype=np.int64)
        count = _bfs(indptr, indices, s, hops, order)
        for q in range(count):
            out[order[q]] = hops[order[q]]
        return out
    if kind.shape[0] > 0:
        no_offs = np.empty(0, dtype=np.int64)
        counts, dist, done, qstart, qnode = _class_workspace(n, kind, lengths.shape[0])
        qhead = np.empty(lengths.shape[0], dtype=np.int64)
        qtail = np.empty(lengths.shape[0], dtype=np.int64)
        cand = np.empty(lengths.shape[0])
        _class_search(
            indptr,
            indices,
            no_offs,
            False,
            kind,
            lengths,
            s,
            counts,
            dist,
            done,
            order,
            qstart,
            qnode,
            qhead,
            qtail,
            cand,
            np.empty(0),
            False,
            False,
            0.0,
        )
        return dist
    dist, done, heap_d, heap_v = _dijkstra_workspace(n, indices.shape[0])
    _dijkstra(indptr, indices, data, s, dist, done, order, heap_d, heap_v)
    return dist


@njit(cache=True, nogil=True)
def brandes_edges(indptr, indices, data, sources, rtol):
    """Per-arc dependencies summed over ``sources`` (edge betweenness over ordered pairs).

    Path counts are kept as logarithms, so they cannot overflow. For hop counts pass
    ``data`` of ones. Ties and zero-length edges as in :func:`_dijkstra_counts`.
    """
    has_zero = data.shape[0] > 0 and data.min() == 0.0
    n = indptr.shape[0] - 1
    eb = np.zeros(indices.shape[0])
    order = np.empty(n, dtype=np.int64)
    lsigma = np.empty(n)
    delta = np.zeros(n)
    rank = np.empty(n, dtype=np.int64)
    dist, done, heap_d, heap_v = _dijkstra_workspace(n, indices.shape[0])
    zeros = np.zeros(n, dtype=np.int64)
    heap_z = np.empty(heap_v.shape[0], dtype=np.int64)
    for i in range(sources.shape[0]):
        s = sources[i]
        count, _ = _dijkstra_counts(
            indptr, indices, data, s, dist, zeros, done, order, heap_d, heap_z, heap_v, lsigma, True, rtol, has_zero
        )
        for q in range(count):
            delta[order[q]] = 0.0
            rank[order[q]] = q
        for q in range(count - 1, -1, -1):
            v = order[q]
            acc = 0.0
            for j in range(indptr[v], indptr[v + 1]):
                w = indices[j]
                if _on_dag(dist[v], zeros[v], data[j], dist[w], zeros[w], rank[w] > q, rtol):
                    part = np.exp(lsigma[v] - lsigma[w]) * (1.0 + delta[w])
                    eb[j] += part
                    acc += part
            delta[v] = acc
        for q in range(count):
            dist[order[q]] = np.inf
            done[order[q]] = False
    return eb


@njit(cache=True, nogil=True)
def eccentricity_bounds(indptr, indices, data, kind, lengths, weighted, budget, rtol):
    """Takes-Kosters: exact eccentricities from few searches; returns (values, searches, done).

    After a search from ``v`` (eccentricity ``e``), every node ``w`` it reaches satisfies
    ``max(d, e - d) <= ecc(w) <= e + d`` with ``d = d(v, w)``. Searches start alternately
    from the open node of largest upper bound and of smallest lower bound (ties: largest
    degree) until every node's bounds meet, or ``budget`` searches (``done`` False).
    """
    n = indptr.shape[0] - 1
    lower = np.zeros(n)
    upper = np.full(n, np.inf)
    is_open = np.ones(n, dtype=np.bool_)
    ecc = np.zeros(n)
    n_open = n
    searches = 0
    pick_upper = True
    while n_open > 0:
        if budget >= 0 and searches >= budget:
            return ecc, searches, False
        v = -1
        for w in range(n):
            if not is_open[w]:
                continue
            if v < 0:
                v = w
                continue
            if pick_upper:
                better = upper[w] > upper[v] or (
                    upper[w] == upper[v] and indptr[w + 1] - indptr[w] > indptr[v + 1] - indptr[v]
                )
            else:
                better = lower[w] < lower[v] or (
                    lower[w] == lower[v] and indptr[w + 1] - indptr[w] > indptr[v + 1] - indptr[v]
                )
            if better:
                v = w
        pick_upper = not pick_upper
        d = distances_from(indptr, indices, data, kind, lengths, v, weighted)
        searches += 1
        e = 0.0
        for w in range(n):
            if d[w] < np.inf and d[w] > e:
                e = d[w]
        ecc[v] = e
        is_open[v] = False
        n_open -= 1
        for w in range(n):
            dw = d[w]
            if dw == np.inf or not is_open[w]:
                continue
            lo = max(dw, e - dw)
            if lo > lower[w]:
                lower[w] = lo
            if e + dw < upper[w]:
                upper[w] = e + dw
            if upper[w] - lower[w] <= rtol * upper[w]:
                ecc[w] = lower[w] if weighted else upper[w]
                is_open[w] = False
                n_open -= 1
    return ecc, searches, True
