"""Compiled kernels for the entropy graphs (MWME, MSTME); see ``_entropy.py``.

The callers pass finite, positive distances (``_entropy._distance_matrix`` rescales the
points so that they are); still, no kernel indexes with a choice it failed to make: when
every candidate compares false (NaN weights), it raises instead of writing out of bounds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "order_cost",
    "mwme_exact",
    "mwme_greedy_starts",
    "mwme_greedy_order",
    "mwme_local",
    "mstme_greedy",
    "mstme_exchange",
]


@njit(cache=True, nogil=True)
def order_cost(dist, order, joining):
    """Total edge weight of the NHDD graph laid on the points in ``order``."""
    n = order.shape[0]
    cost = 0.0
    for k in range(1, n):
        if joining[k]:
            p = order[k]
            for i in range(k):
                cost += dist[p, order[i]]
    return cost


@njit(cache=True, nogil=True)
def mwme_exact(dist, joining):
    """Minimum-cost order by dynamic programming over subsets, O(2^n n) time and memory.

    dp[S] is the least cost of filling positions 0..|S|-1 with the points of S; adding p
    at position |S| costs the sum of its distances to S when that position joins, else 0.
    """
    n = dist.shape[0]
    full = 1 << n
    dp = np.full(full, np.inf)
    parent = np.full(full, -1, dtype=np.int8)
    sums = np.zeros((full, n))  # sums[S, p] = sum of dist[p, q] over q in S
    dp[0] = 0.0
    for s in range(1, full):
        low = s & -s
        lb = 0
        while (1 << lb) != low:
            lb += 1
        prev = s ^ low
        for p in range(n):
            sums[s, p] = sums[prev, p] + dist[p, lb]
    for s in range(full):
        base = dp[s]
        if base == np.inf:
            continue
        k = 0
        t = s
        while t:
            t &= t - 1
            k += 1
        if k == n:
            continue
        join = joining[k]
        for p in range(n):
            bit = 1 << p
            if s & bit:
                continue
            c = base + sums[s, p] if join else base
            if c < dp[s | bit]:
                dp[s | bit] = c
                parent[s | bit] = p
    order = np.empty(n, dtype=np.int64)
    s = full - 1
    for k in range(n - 1, -1, -1):
        p = parent[s]
        if p < 0:
            raise ValueError("mwme_exact: no finite-cost order (non-finite distances)")
        order[k] = p
        s ^= 1 << p
    return order, dp[full - 1]


# relative: values closer than this are ties, broken by the invariant key. Rounding in a
# sum of n distances is about n * 2e-16 of it; 1e-9 was far looser and, with one point a
# billion times farther than the others' spacing, made every difference among the others
# a tie, so the first index won and relabelling the points changed the matching
_TIE = 1e-12


@njit(cache=True, nogil=True, inline="always")
def _better(value, key, best_value, best_key):
    """``value`` beats ``best_value``, ties (to ``_TIE`` relative) going to the smaller ``key``."""
    tol = _TIE * max(abs(value), abs(best_value))
    if value < best_value - tol:
        return True
    if value <= best_value + tol and key < best_key - _TIE * abs(best_key):
        return True
    return False


@njit(cache=True, nogil=True)
def mwme_greedy_order(dist, joining, start, key):
    """The corrected n1graph greedy from one start point; returns (order, cost).

    A joining position takes the point with the least total distance to the points
    placed so far (it is joined to all of them); an isolated position takes the point
    nearest to the last one placed (the thesis' "edge to the last node" rule, used only
    to choose the point: the graph is always Algorithm 6.1's NHDD graph). Near-ties are
    broken by ``key`` (each point's total distance to all points), which, unlike point
    indices, does not change under similarity transforms and permutations.
    """
    n = dist.shape[0]
    order = np.empty(n, dtype=np.int64)
    used = np.zeros(n, dtype=np.bool_)
    acc = np.zeros(n)
    order[0] = start
    used[start] = True
    for q in range(n):
        acc[q] = dist[q, start]
    last = start
    cost = 0.0
    for k in range(1, n):
        best = -1
        best_value = np.inf
        for q in range(n):
            if used[q]:
                continue
            value = acc[q] if joining[k] else dist[q, last]
            if best < 0 or _better(value, key[q], best_value, key[best]):
                best_value = value
                best = q
        if best < 0:
            raise ValueError("mwme_greedy_order: no point left to place")
        if joining[k]:
            cost += acc[best]
        order[k] = best
        used[best] = True
        last = best
        for q in range(n):
            acc[q] += dist[q, best]
    return order, cost


@njit(cache=True, nogil=True)
def mwme_greedy_starts(dist, joining, first, stop, key):
    """Best (cost, start) of the greedy over start points ``first .. stop - 1``."""
    best_cost = np.inf
    best_start = -1
    for start in range(first, stop):
        _, cost = mwme_greedy_order(dist, joining, start, key)
        if best_start < 0 or _better(cost, key[start], best_cost, key[best_start]):
            best_cost = cost
            best_start = start
    return best_cost, best_start


@njit(cache=True, nogil=True)
def mwme_local(dist, joining, order, max_passes):
    """Improve ``order`` by exchanging the points of two positions while the cost drops.

    Positions a and b are adjacent iff the later one joins. Exchanging their points
    changes the cost by sum_k (A[a,k] - A[b,k]) (d(p_b, p_k) - d(p_a, p_k)), O(n) per pair.
    Returns (order, cost, passes).
    """
    n = order.shape[0]
    order = order.copy()
    tol = _TIE * dist.sum() / (n * n)  # relative to the mean distance
    passes = 0
    for _ in range(max_passes):
        passes += 1
        improved = False
        for a in range(n):
            for b in range(a + 1, n):
                pa = order[a]
                pb = order[b]
                delta = 0.0
                for k in range(n):
                    if k == a or k == b:
                        continue
                    adj_a = joining[max(a, k)]
                    adj_b = joining[max(b, k)]
                    if adj_a != adj_b:
                        pk = order[k]
                        change = dist[pb, pk] - dist[pa, pk]
                        delta += change if adj_a else -change
                if delta < -tol:
                    order[a] = pb
                    order[b] = pa
                    improved = True
        if not improved:
            break
    return order, order_cost(dist, order, joining), passes


@njit(cache=True, nogil=True)
def _plogp(count, n):
    if count <= 0:
        return 0.0
    p = count / n
    return -p * np.log2(p)


@njit(cache=True, nogil=True)
def _entropy(counts, n):
    h = 0.0
    for c in counts:
        h += _plogp(c, n)
    return h


@njit(cache=True, nogil=True)
def _entropy_after(counts, n, h, a, b):
    """Entropy after the degrees a and b (of two different nodes) each grow by one."""
    # Changes of counts: a -1, a+1 +1, b -1, b+1 +1 (they may coincide).
    idx = np.array([a, a + 1, b, b + 1])
    change = np.array([-1, 1, -1, 1])
    out = h
    seen = np.zeros(4, dtype=np.bool_)
    for i in range(4):
        if seen[i]:
            continue
        total = change[i]
        for j in range(i + 1, 4):
            if idx[j] == idx[i]:
                total += change[j]
                seen[j] = True
        c = counts[idx[i]]
        out += _plogp(c + total, n) - _plogp(c, n)
    return out


@njit(cache=True, nogil=True, inline="always")
def _move_degrees(degree, counts, a, b, step):
    """Add (step=1) or remove (step=-1) the edge a-b in the degree and count arrays."""
    for d in (degree[a], degree[b]):
        counts[d] -= 1
        counts[d + step] += 1
    degree[a] += step
    degree[b] += step


@njit(cache=True, nogil=True)
def mstme_greedy(weight, lam, key):
    """Algorithm 7.1: n-1 times add the cycle-free edge minimising w_e - lam H(T + e).

    The entropy change depends only on the degrees of the edge's two ends, so it is
    tabulated once per step for every pair of degrees; components are kept as labels
    (union by relabelling the smaller one). Ties (to ``_TIE`` relative) go to the edge
    of smaller ``key[u] + key[v]`` (an invariant key per node), so that the result
    depends on the row order only where both tie; then to the first edge (u, v), u < v,
    in row order. Returns the
    edge list (n-1, 2).
    """
    n = weight.shape[0]
    degree = np.zeros(n, dtype=np.int64)
    counts = np.zeros(n + 1, dtype=np.int64)
    counts[0] = n
    label = np.arange(n)
    size = np.ones(n, dtype=np.int64)
    edges = np.empty((n - 1, 2), dtype=np.int64)
    h = 0.0
    max_degree = 0
    for it in range(n - 1):
        table = np.empty((max_degree + 1, max_degree + 1))
        for a in range(max_degree + 1):
            for b in range(max_degree + 1):
                if counts[a] > 0 and counts[b] > 0 and (a != b or counts[a] > 1):
                    table[a, b] = -lam * _entropy_after(counts, n, h, a, b)
                else:
                    table[a, b] = 0.0
        best = np.inf
        best_key = np.inf
        bu = -1
        bv = -1
        for u in range(n):
            lu = label[u]
            du = degree[u]
            row = weight[u]
            for v in range(u + 1, n):
                if label[v] == lu:
                    continue
                score = row[v] + table[du, degree[v]]
                edge_key = key[u] + key[v]
                if score < np.inf and (bu < 0 or _better(score, edge_key, best, best_key)):
                    best = score
                    best_key = edge_key
                    bu = u
                    bv = v
        if bu < 0:
            raise ValueError("mstme_greedy: no edge with a finite score (non-finite weights)")
        edges[it, 0] = bu
        edges[it, 1] = bv
        _move_degrees(degree, counts, bu, bv, 1)
        max_degree = max(max_degree, degree[bu], degree[bv])
        h = _entropy(counts, n)
        keep, drop = label[bu], label[bv]
        if size[keep] < size[drop]:
            keep, drop = drop, keep
        for q in range(n):
            if label[q] == drop:
                label[q] = keep
        size[keep] += size[drop]
    return edges


@njit(cache=True, nogil=True)
def _tree_components(n, edges, skip):
    """Component label of every node in the tree without edge ``skip``."""
    adj_ptr = np.zeros(n + 1, dtype=np.int64)
    for e in range(edges.shape[0]):
        if e != skip:
            adj_ptr[edges[e, 0] + 1] += 1
            adj_ptr[edges[e, 1] + 1] += 1
    for i in range(n):
        adj_ptr[i + 1] += adj_ptr[i]
    fill = adj_ptr[:-1].copy()
    adj = np.empty(adj_ptr[n], dtype=np.int64)
    for e in range(edges.shape[0]):
        if e != skip:
            u, v = edges[e, 0], edges[e, 1]
            adj[fill[u]] = v
            fill[u] += 1
            adj[fill[v]] = u
            fill[v] += 1
    label = np.full(n, -1, dtype=np.int64)
    stack = np.empty(n, dtype=np.int64)
    start = edges[skip, 0]
    label[start] = 0
    stack[0] = start
    top = 1
    while top:
        top -= 1
        v = stack[top]
        for j in range(adj_ptr[v], adj_ptr[v + 1]):
            w = adj[j]
            if label[w] < 0:
                label[w] = 0
                stack[top] = w
                top += 1
    for i in range(n):
        if label[i] < 0:
            label[i] = 1
    return label


@njit(cache=True, nogil=True)
def mstme_exchange(weight, lam, edges, max_passes, key):
    """Local search by edge exchange: drop a tree edge, add the best edge across the cut.

    Accepts an exchange when it lowers W - lam H (by more than 1e-12); among equally good
    replacements the one of smaller ``key[u] + key[v]`` wins, as in :func:`mstme_greedy`.
    Stops after a pass without one. Returns (edges, passes, exchanges).
    """
    n = weight.shape[0]
    edges = edges.copy()
    degree = np.zeros(n, dtype=np.int64)
    for e in range(edges.shape[0]):
        degree[edges[e, 0]] += 1
        degree[edges[e, 1]] += 1
    counts = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        counts[degree[i]] += 1
    passes = 0
    exchanges = 0
    for _ in range(max_passes):
        passes += 1
        improved = False
        for e in range(edges.shape[0]):
            u0, v0 = edges[e, 0], edges[e, 1]
            label = _tree_components(n, edges, e)
            _move_degrees(degree, counts, u0, v0, -1)  # remove e
            h = _entropy(counts, n)
            base = weight[u0, v0] - lam * _entropy_after(counts, n, h, degree[u0], degree[v0])
            best = np.inf
            best_key = np.inf
            bu = -1
            bv = -1
            for u in range(n):
                if label[u] != 0:
                    continue
                for v in range(n):
                    if label[v] != 1:
                        continue
                    score = weight[u, v] - lam * _entropy_after(counts, n, h, degree[u], degree[v])
                    edge_key = key[u] + key[v]
                    if score < np.inf and (bu < 0 or _better(score, edge_key, best, best_key)):
                        best = score
                        best_key = edge_key
                        bu = u
                        bv = v
            if not best < base - 1e-12:  # no better replacement: the edge stays
                bu = u0
                bv = v0
            a, b = min(bu, bv), max(bu, bv)
            if a != min(u0, v0) or b != max(u0, v0):
                improved = True
                exchanges += 1
            edges[e, 0] = a
            edges[e, 1] = b
            _move_degrees(degree, counts, a, b, 1)
        if not improved:
            break
    return edges, passes, exchanges
