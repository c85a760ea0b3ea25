"""Candidate search and best matches in plain NumPy: the reference of the compiled kernels of
:mod:`vo_lib.stereo_vo.matching_core`, which the front end runs because this version makes a
real frame more than 1.5x slower (``python -m vo_lib bench kernels``).

Each function has the arguments and results of the kernel it is the reference of. They use sorts, binary
searches and ``np.bitwise_count`` where the kernels loop; the results are the same, pair for pair
and in the same order (the tests hold them to it on random inputs).
"""

from __future__ import annotations

import numpy as np

from vo_lib.stereo_vo import matching_core as core
from vo_lib.stereo_vo.features import window_pairs


def _hamming(des_a, des_b, ia, ib):
    """Hamming distances of the descriptor pairs ``(des_a[ia], des_b[ib])`` (uint64 words)."""
    return np.bitwise_count(des_a[ia] ^ des_b[ib]).sum(axis=1, dtype=np.int64)


def best_matches(ia, ib, dist, n_a, n_b, max_distance, ratio):
    """The rule of :func:`vo_lib.stereo_vo.features.best_matches`, by sorts."""
    ia, ib, dist = np.asarray(ia, np.int64), np.asarray(ib, np.int64), np.asarray(dist, np.int64)
    if len(dist) == 0:
        empty = np.zeros(0, np.int64)
        return empty, empty, empty
    order = np.lexsort((dist, ia))  # by a, then by distance; ties keep the earlier candidate
    ia_s, ib_s, d_s = ia[order], ib[order], dist[order]
    starts = np.flatnonzero(np.r_[True, ia_s[1:] != ia_s[:-1]])
    best_a, best_b, best_d = ia_s[starts], ib_s[starts], d_s[starts]
    second = np.full(len(starts), core.NONE, dtype=np.int64)
    has_second = np.r_[starts[1:], len(ia_s)] - starts > 1
    second[has_second] = d_s[starts[has_second] + 1]
    keep = (best_d <= max_distance) & (best_d < ratio * second)
    best_a, best_b, best_d = best_a[keep], best_b[keep], best_d[keep]
    if len(best_b):
        # that a must be b's nearest over all candidates; a b claimed by several a keeps the nearest
        nearest_for_b = np.full(n_b, core.NONE, dtype=np.int64)
        np.minimum.at(nearest_for_b, ib, dist)
        keep = best_d <= nearest_for_b[best_b]
        best_a, best_b, best_d = best_a[keep], best_b[keep], best_d[keep]
        order = np.lexsort((best_d, best_b))
        sel = order[np.r_[True, best_b[order][1:] != best_b[order][:-1]]] if len(order) else order
        best_a, best_b, best_d = best_a[sel], best_b[sel], best_d[sel]
    return best_a, best_b, best_d


def window_candidates(predicted, radius, w_curr, order_v, sorted_v, des_prev, des_curr):
    """:func:`.matching_core.window_candidates`, by :func:`.window_pairs` on the rows."""
    seen = np.all(np.isfinite(predicted), axis=1)
    half = np.where(seen, radius[:, 1], -1.0)  # a window no row falls in
    v = np.where(seen, predicted[:, 1], 0.0)
    ia, ib = window_pairs(v, sorted_v, half)
    ib = order_v[ib]
    inside = np.abs(w_curr[ib, 0] - predicted[ia, 0]) <= radius[ia, 0]
    inside &= np.abs(w_curr[ib, 2] - predicted[ia, 2]) <= radius[ia, 2]
    ia, ib = ia[inside], ib[inside]
    return ia, ib, _hamming(des_prev, des_curr, ia, ib)


def row_candidates(
    left, left_level, right, right_level, order_v, sorted_v, row_tolerance, d_min, d_max, des_left, des_right
):
    """:func:`.matching_core.row_candidates`, by :func:`.window_pairs` on the rows."""
    half = np.full(len(left), float(row_tolerance))
    ia, ib = window_pairs(left[:, 1], sorted_v, half)
    ib = order_v[ib]
    d = left[ia, 0] - right[ib, 0]
    ok = (d >= d_min) & (d <= d_max) & (np.abs(left_level[ia] - right_level[ib]) <= 1)
    ia, ib = ia[ok], ib[ok]
    return ia, ib, _hamming(des_left, des_right, ia, ib)


def sad_costs(left, right, ui, vi, di, half, search):
    """:func:`.matching_core.sad_costs`, one disparity at a time over all patches."""
    du, dv = np.meshgrid(np.arange(-half, half + 1), np.arange(-half, half + 1))
    rows = vi[:, None] + dv.ravel()  # (n, patch pixels)
    cols = ui[:, None] + du.ravel()
    patch = left[rows, cols].astype(np.int64)
    costs = np.zeros((2 * search + 1, len(ui)), np.int64)
    for s in range(2 * search + 1):
        shifted = right[rows, cols - (di + s - search)[:, None]].astype(np.int64)
        costs[s] = np.abs(patch - shifted).sum(axis=1)
    return costs
