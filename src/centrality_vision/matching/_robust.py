"""Robust canonical matching: local MWME signatures, consensus over similarity hypotheses, refinement.

The thesis' MWME matching (ch. 6) labels every point by its degree in one global
minimum-weight maximum-entropy graph, so every point's position changes every label; its
conclusion proposes matching local regions of maximal entropy instead. This module does so:

1. **Local signatures.** Each point and its ``k`` nearest neighbours get their own MWME
   graph (exact, ``k + 1 <= 20`` points). The neighbourhood is expressed in a local frame
   (origin: the point; unit: the mean distance to its neighbours; axis: the principal axis
   of the neighbourhood, both signs tried), and every neighbour carries its MWME degree as
   a third coordinate. Two points are alike when these labelled neighbourhoods overlap
   (a symmetric chamfer distance): invariant to rotation, translation and scale, and,
   being a nearest-point comparison, indifferent to where exactly along an outline the
   points were sampled.
2. **Consensus.** Each of the ``n_candidates`` most alike fixed points of a moving point
   gives, through the two local frames, one full similarity hypothesis (scale = ratio of
   the local units, rotation = difference of the axes, translation = the pair). Every
   hypothesis is scored on all points (truncated quadratic: a moved point within
   ``tau`` of a fixed point counts ``1 - d^2 / tau^2``), which is a RANSAC whose
   minimal sample is one pair; outliers and missing parts only lower the score of the
   true hypothesis, they cannot raise a wrong one.
3. **Refinement.** The best hypotheses are refined by trimmed nearest-neighbour
   similarity fits (pairs within ``tau``), the best refined pose optionally by
   similarity CPD with an outlier weight (:class:`~centrality_vision.registration.RigidCPD`)
   started from it, whose pose is kept unless it loses a quarter of the consensus (a
   collapse); then each moving point takes its nearest fixed point within ``tau``,
   else -1.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..graphs import mwme_degrees
from ._common import assign_nearest, fit_pairs

__all__ = ["local_signatures", "robust_pose"]

DEGREE_WEIGHT = 0.5  # how much a neighbour's MWME degree (divided by k) counts beside its position


def _sampling_step(points: np.ndarray) -> float:
    dist, _ = cKDTree(points).query(points, k=2)
    return float(np.median(dist[:, 1]))


def local_signatures(points: np.ndarray, k: int) -> dict:
    """Local frames and MWME-labelled neighbourhoods of every point (2D).

    Returns ``units`` (n,), ``axes`` (n, 2) unit vectors, and ``shapes`` (n, 2, k + 1, 3):
    for each of the two signs of the axis, the neighbourhood (the point first) in the
    local frame with the MWME degree / k as third coordinate.
    """
    n = points.shape[0]
    _, index = cKDTree(points).query(points, k=k + 1)
    hood = points[index]  # (n, k+1, 2), the point itself first
    rel = hood - points[:, None, :]
    units = np.linalg.norm(rel[:, 1:], axis=2).mean(axis=1)
    centred = hood - hood.mean(axis=1, keepdims=True)
    _, vecs = np.linalg.eigh(np.einsum("nki,nkj->nij", centred, centred))
    axes = vecs[:, :, -1]
    degrees = mwme_degrees(hood)
    shapes = np.empty((n, 2, k + 1, 3))
    for s, sign in enumerate((1.0, -1.0)):
        a = axes * sign
        x = (rel * a[:, None, :]).sum(axis=2)
        y = rel[..., 1] * a[:, None, 0] - rel[..., 0] * a[:, None, 1]
        shapes[:, s, :, 0] = x / units[:, None]
        shapes[:, s, :, 1] = y / units[:, None]
        shapes[:, s, :, 2] = DEGREE_WEIGHT * degrees / k
    radii = np.sort(np.linalg.norm(rel[:, 1:], axis=2), axis=1) / units[:, None]
    return {"units": units, "axes": axes, "shapes": shapes, "radii": radii}


#: Above this many fixed points, each moving point compares its signature only with the
#: ``PREFILTER`` fixed points of most similar sorted neighbour distances (a k-d tree query)
#: instead of all: O(m L k^2) instead of O(m f k^2).
PREFILTER_ABOVE = 256
PREFILTER = 64
#: At most this many hypotheses (the most alike pairs) are scored.
MAX_HYPOTHESES = 3000
#: ``refine="cpd"`` keeps CPD's pose unless it brings fewer points into agreement than this
#: share of the consensus pose it started from. Measured on the fish and on random sets with
#: noise up to 0.03 of their extent: CPD's polish costs at most 7% of the consensus with
#: outlier weights up to 0.9; a collapse (w = 0.99 shrinks the set onto a few points) costs
#: 30-95%.
CPD_KEEPS = 0.75


def _chamfer(block: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Symmetric chamfer distance of ``block`` (b, 2, K, 3) against ``others``, shared
    (L, K, 3) or one row per block row (b, L, K, 3): shape (b, 2, L)."""
    if others.ndim == 3:
        cross = np.einsum("bski,fli->bsfkl", block, others, optimize=True)
        sq_o = (others**2).sum(axis=2)[None, None, :, None, :]
    else:
        cross = np.einsum("bski,bfli->bsfkl", block, others, optimize=True)
        sq_o = (others**2).sum(axis=3)[:, None, :, None, :]
    sq = (block**2).sum(axis=3)[:, :, None, :, None] + sq_o - 2.0 * cross  # (b, 2, L, K, K) squared distances
    np.maximum(sq, 0.0, out=sq)
    return 0.5 * (np.sqrt(sq.min(axis=4)).mean(axis=3) + np.sqrt(sq.min(axis=3)).mean(axis=3))


def _candidates(sig_m: dict, sig_f: dict, c: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The ``c`` most alike fixed points of every moving point: ``(pairs_m, pairs_f, signs,
    distances)``, with the sign of the moving axis (0: +, 1: -) that makes them alike."""
    from scipy.spatial import cKDTree

    shapes_m, shapes_f = sig_m["shapes"], sig_f["shapes"][:, 0]  # fixed frame: + sign only
    m, f, size = shapes_m.shape[0], shapes_f.shape[0], shapes_f.shape[1]
    if f > PREFILTER_ABOVE:
        _, pool = cKDTree(sig_f["radii"]).query(sig_m["radii"], k=PREFILTER)
    else:
        pool = np.broadcast_to(np.arange(f), (m, f))
    width = pool.shape[1]
    chunk = max(1, 4_000_000 // (2 * width * size * size))  # about 32 MB of temporaries per block
    dist = np.empty((m, width))
    sign = np.empty((m, width), dtype=np.int64)
    for lo in range(0, m, chunk):
        block = shapes_m[lo : lo + chunk]
        others = shapes_f if f <= PREFILTER_ABOVE else shapes_f[pool[lo : lo + chunk]]
        chamfer = _chamfer(block, others)
        sign[lo : lo + chunk] = chamfer.argmin(axis=1)
        dist[lo : lo + chunk] = chamfer.min(axis=1)
    c = min(c, width)
    top = np.argpartition(dist, c - 1, axis=1)[:, :c]
    rows = np.repeat(np.arange(m), c)
    cols = top.ravel()
    return rows, pool[rows, cols], sign[rows, cols], dist[rows, cols]


def _hypotheses(moving, fixed, sig_m, sig_f, pairs_m, pairs_f, signs, *, scale: bool, unit_ratio: float):
    """Similarity ``(R, t, s)`` per candidate pair from the two local frames (arrays)."""
    axes_m = sig_m["axes"][pairs_m] * np.where(signs == 0, 1.0, -1.0)[:, None]
    axes_f = sig_f["axes"][pairs_f]
    angle = np.arctan2(axes_f[:, 1], axes_f[:, 0]) - np.arctan2(axes_m[:, 1], axes_m[:, 0])
    c, s_ = np.cos(angle), np.sin(angle)
    rot = np.stack([np.stack([c, -s_], axis=1), np.stack([s_, c], axis=1)], axis=1)  # (H, 2, 2)
    s = sig_f["units"][pairs_f] / sig_m["units"][pairs_m] if scale else np.full(pairs_m.size, unit_ratio)
    t = fixed[pairs_f] - s[:, None] * np.einsum("hij,hj->hi", rot, moving[pairs_m])
    return rot, t, s


def _distinct_score(d: np.ndarray, j: np.ndarray, n_fixed: int, tau: float) -> np.ndarray:
    """Truncated quadratic score ``1 - d^2 / tau^2`` summed over distinct fixed points (each
    fixed point counts once, with its best moved point), rows of ``d``/``j`` one hypothesis
    each. Counting fixed points, not moved ones, keeps a hypothesis that shrinks the whole
    moving set onto a few fixed points from scoring high."""
    h = d.shape[0]
    weight = np.where(np.isfinite(d), 1.0 - (d / tau) ** 2, 0.0)
    best = np.zeros((h, n_fixed + 1))  # column n_fixed: misses (cKDTree's index for "none")
    np.maximum.at(best, (np.repeat(np.arange(h), d.shape[1]), j.ravel()), weight.ravel())
    return best[:, :n_fixed].sum(axis=1)


def _score(moving, fixed_tree, rot, t, s, tau, chunk: int = 256) -> np.ndarray:
    """Consensus score (see :func:`_distinct_score`) of every hypothesis on all moving points."""
    n_fixed = fixed_tree.n
    scores = np.empty(rot.shape[0])
    for lo in range(0, rot.shape[0], chunk):
        moved = (
            s[lo : lo + chunk, None, None] * np.einsum("hij,nj->hni", rot[lo : lo + chunk], moving)
            + t[lo : lo + chunk, None, :]
        )
        d, j = fixed_tree.query(moved.reshape(-1, 2), distance_upper_bound=tau)
        scores[lo : lo + chunk] = _distinct_score(d.reshape(moved.shape[:2]), j.reshape(moved.shape[:2]), n_fixed, tau)
    return scores


def _unique_pairs(d: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Indices of moved points that are the nearest (of those within reach) to their fixed point."""
    ok = np.flatnonzero(np.isfinite(d))
    order = ok[np.argsort(d[ok], kind="stable")]
    _, first = np.unique(j[order], return_index=True)
    return order[first]


def _trimmed_refine(moving, fixed, fixed_tree, rot, t, s, tau, *, scale: bool, unit_ratio: float, n_iter: int = 30):
    """Alternate one-to-one nearest pairs within ``tau`` and a least-squares similarity on them."""
    for _ in range(n_iter):
        moved = s * moving @ rot.T + t
        d, j = fixed_tree.query(moved, distance_upper_bound=tau)
        keep = _unique_pairs(d, j)
        if keep.size < 3:
            break
        r2, t2, s2 = fit_pairs(moving[keep], fixed[j[keep]], scale=scale)
        if not scale:
            s2 = unit_ratio
            t2 = fixed[j[keep]].mean(axis=0) - s2 * r2 @ moving[keep].mean(axis=0)
        done = np.allclose(r2, rot, atol=1e-12) and abs(s2 - s) <= 1e-12 * s and np.allclose(t2, t, atol=1e-12)
        rot, t, s = r2, t2, s2
        if done:
            break
    return rot, t, s, _pose_score(moving, fixed_tree, rot, t, s, tau)


def _pose_score(moving, fixed_tree, rot, t, s, tau) -> float:
    """Consensus score (see :func:`_distinct_score`) of one pose."""
    d, j = fixed_tree.query(s * moving @ rot.T + t, distance_upper_bound=tau)
    return float(_distinct_score(d[None], j[None], fixed_tree.n, tau)[0])


def _axis_angle(points: np.ndarray) -> float:
    """The angle of the principal axis of 2D points (modulo pi), which turns with them."""
    d = points - points.mean(axis=0)
    xx, yy, xy = (d[:, 0] ** 2).mean(), (d[:, 1] ** 2).mean(), (d[:, 0] * d[:, 1]).mean()
    return 0.5 * float(np.arctan2(2 * xy, xx - yy))


def _global_hypotheses(moving, fixed, *, scale: bool, unit_ratio: float, n_angles: int = 36):
    """Poses that align the centroids and RMS radii at ``n_angles`` rotations: right when
    both sets are whole outlines, whatever their local noise (the local signatures' blind spot).

    The rotations start from the turn that aligns the sets' principal axes, so that they turn
    with the data: at fixed angles, which poses came closest (and so won) depended on how
    ``moving`` was turned."""
    offset = _axis_angle(fixed) - _axis_angle(moving)
    angle = offset + 2 * np.pi * np.arange(n_angles) / n_angles
    c, s_ = np.cos(angle), np.sin(angle)
    rot = np.stack([np.stack([c, -s_], axis=1), np.stack([s_, c], axis=1)], axis=1)
    cm, cf = moving.mean(axis=0), fixed.mean(axis=0)
    ratio = (
        np.sqrt(((fixed - cf) ** 2).sum(axis=1).mean() / ((moving - cm) ** 2).sum(axis=1).mean())
        if scale
        else unit_ratio
    )
    s = np.full(n_angles, ratio)
    t = cf - s[:, None] * np.einsum("hij,j->hi", rot, cm)
    return rot, t, s


def robust_pose(
    moving: np.ndarray,
    fixed: np.ndarray,
    *,
    n_neighbors: int,
    n_candidates: int,
    refine: str,
    scale: bool,
    unit_ratio: float,
    w: float,
):
    """Pose and correspondence of normalised 2D sets; see the module docstring.

    ``unit_ratio`` is the scale that means 1 in the caller's units (used when ``scale`` is
    False). Returns ``(rotation, translation, s, correspondence, info)``.
    """
    k = min(n_neighbors, moving.shape[0] - 1, fixed.shape[0] - 1)
    sig_m, sig_f = local_signatures(moving, k), local_signatures(fixed, k)
    pairs_m, pairs_f, signs, alike = _candidates(sig_m, sig_f, n_candidates)
    if pairs_m.size > MAX_HYPOTHESES:
        keep = np.sort(np.argsort(alike, kind="stable")[:MAX_HYPOTHESES])
        pairs_m, pairs_f, signs = pairs_m[keep], pairs_f[keep], signs[keep]
    rot, t, s = _hypotheses(moving, fixed, sig_m, sig_f, pairs_m, pairs_f, signs, scale=scale, unit_ratio=unit_ratio)
    g_rot, g_t, g_s = _global_hypotheses(moving, fixed, scale=scale, unit_ratio=unit_ratio)
    rot, t, s = np.concatenate([rot, g_rot]), np.concatenate([t, g_t]), np.concatenate([s, g_s])
    fixed_tree = cKDTree(fixed)
    tau = 2.0 * _sampling_step(fixed)
    scores = _score(moving, fixed_tree, rot, t, s, tau)
    # Refine the best few distinct hypotheses; the best refined one wins (ties: lower index).
    order = np.argsort(-scores, kind="stable")[:8]
    best = None
    for h in order:
        r2, t2, s2, score = _trimmed_refine(
            moving, fixed, fixed_tree, rot[h], t[h], s[h], tau, scale=scale, unit_ratio=unit_ratio
        )
        if best is None or score > best[3] + 1e-9:
            best = (r2, t2, s2, score)
    rot_b, t_b, s_b, score_b = best
    info = {"hypotheses": int(rot.shape[0]), "consensus": float(scores.max()), "refined_consensus": score_b, "tau": tau}
    if not scale:
        # what a similarity would have found: a rigid fit of sets that differ in scale pairs
        # unrelated points within reach of each other (a copy scaled 1.5 and rotated 30
        # degrees: 29 of 40 points matched, every pair wrong, the rotation 127 degrees off)
        rot_s, t_s, s_s = _hypotheses(moving, fixed, sig_m, sig_f, pairs_m, pairs_f, signs, scale=True, unit_ratio=1.0)
        h = int(np.argmax(_score(moving, fixed_tree, rot_s, t_s, s_s, tau)))
        _, _, s_sim, score_sim = _trimmed_refine(
            moving, fixed, fixed_tree, rot_s[h], t_s[h], s_s[h], tau, scale=True, unit_ratio=unit_ratio
        )
        info.update(similarity_scale=float(s_sim / unit_ratio), similarity_consensus=score_sim)
    if refine == "cpd":
        rot_c, t_c, s_c = _cpd_refine(moving, fixed, rot_b, t_b, s_b, scale=scale, w=w)
        info["cpd_consensus"] = _pose_score(moving, fixed_tree, rot_c, t_c, s_c, tau)
        info["cpd_kept"] = info["cpd_consensus"] >= CPD_KEEPS * score_b
        if info["cpd_kept"]:
            rot_b, t_b, s_b = rot_c, t_c, s_c
    correspondence = assign_nearest(s_b * moving @ rot_b.T + t_b, fixed_tree, tau)
    return rot_b, t_b, s_b, correspondence, info


def _cpd_refine(moving, fixed, rot, t, s, *, scale: bool, w: float):
    """Similarity (or rigid) CPD from the consensus pose; returns the composed pose."""
    from ..registration import RigidCPD

    start = s * moving @ rot.T + t
    reg = RigidCPD(scale=scale, w=w, max_iter=100, tol=1e-6).fit(start, fixed)
    tr = reg.transform_
    r2 = np.asarray(tr.rotation) @ rot
    s2 = float(tr.scale) * s
    t2 = float(tr.scale) * np.asarray(tr.rotation) @ t + np.asarray(tr.translation)
    return r2, t2, s2
