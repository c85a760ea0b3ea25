"""The compiled core of :func:`vo_lib.stereo_vo.features.best_matches` (Numba).

Choosing the nearest descriptor of each feature among its candidates, with the ratio test and the
mutual check, is a few passes over the candidate pairs. In NumPy it takes sorts and a scattered
minimum (``np.minimum.at``), milliseconds for the tens of thousands of pairs of a real frame; here
each pass is one loop. The rule, and the order of the result, are those documented in
``best_matches``; ties go to the earlier candidate, as in its stable sorts.
"""

from __future__ import annotations

import numpy as np

from vo_lib.compiled import jit as _jit

NONE = np.iinfo(np.int32).max


@_jit
def _nearest_two(ia, ib, dist, n_a, n_b):
    """Per ``a``: the nearest and second-nearest distance and the nearest ``b``; per ``b``: the
    nearest distance of any ``a``. Ties go to the earlier candidate."""
    best = np.full(n_a, NONE, np.int64)
    second = np.full(n_a, NONE, np.int64)
    best_b = np.full(n_a, -1, np.int64)
    nearest_for_b = np.full(n_b, NONE, np.int64)
    for k in range(len(ia)):
        a, b, d = ia[k], ib[k], np.int64(dist[k])
        if d < best[a]:
            second[a] = best[a]
            best[a] = d
            best_b[a] = b
        elif d < second[a]:
            second[a] = d
        if d < nearest_for_b[b]:
            nearest_for_b[b] = d
    return best, second, best_b, nearest_for_b


@_jit
def best_matches_core(ia, ib, dist, n_a, n_b, max_distance, ratio):
    best, second, best_b, nearest_for_b = _nearest_two(ia, ib, dist, n_a, n_b)
    keep = np.zeros(n_a, np.bool_)
    for a in range(n_a):
        if best_b[a] >= 0 and best[a] <= max_distance and best[a] < ratio * second[a]:
            keep[a] = best[a] <= nearest_for_b[best_b[a]]
    # one a per b: the nearest, ties to the smaller a; the result is ordered by b
    owner = np.full(n_b, -1, np.int64)
    for a in range(n_a):
        if keep[a]:
            b = best_b[a]
            if owner[b] < 0 or best[a] < best[owner[b]]:
                owner[b] = a
    owned = np.flatnonzero(owner >= 0)
    chosen = owner[owned]
    return chosen, owned, best[chosen]


# the steps below serve window_candidates and row_candidates


@_jit
def _row_windows(key, half, sorted_v):
    """Per ``i``, the range ``lo[i]:hi[i]`` of ``sorted_v`` within ``half[i]`` of ``key[i]`` (empty
    where ``key[i]`` is not finite), and the sum of their lengths: no more pairs than that can be
    found, so the pair arrays are allocated once, at that size."""
    n = key.shape[0]
    lo = np.zeros(n, np.int64)
    hi = np.zeros(n, np.int64)
    total = 0
    for i in range(n):
        if np.isfinite(key[i]):
            lo[i] = np.searchsorted(sorted_v, key[i] - half[i], side="left")
            hi[i] = max(lo[i], np.searchsorted(sorted_v, key[i] + half[i], side="right"))
            total += hi[i] - lo[i]
    return lo, hi, total


@_jit
def _hamming(des_a, i, des_b, j):
    """Hamming distance of descriptor rows ``des_a[i]`` and ``des_b[j]`` (uint64 words)."""
    h = 0
    for k in range(des_a.shape[1]):
        h += _popcount64(des_a[i, k] ^ des_b[j, k])
    return h


@_jit
def _popcount64(x):
    x = x - ((x >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (x * np.uint64(0x0101010101010101)) >> np.uint64(56)


@_jit
def window_candidates(predicted, radius, w_curr, order_v, sorted_v, des_prev, des_curr):
    """Pairs ``(i, j)`` whose current feature ``j`` lies within ``radius[i] = (ru, rv, rd)`` of
    previous feature ``i``'s predicted ``(u, v, d)``, with their Hamming distances.

    ``order_v`` sorts the current features by row and ``sorted_v`` holds their rows in that order;
    pairs come ordered by ``i``, then by row, as from ``features.window_pairs``."""
    n = predicted.shape[0]
    seen = np.empty(n, np.float64)  # the row, or nan where the prediction is not finite
    for i in range(n):
        u, v, d = predicted[i, 0], predicted[i, 1], predicted[i, 2]
        seen[i] = v if np.isfinite(u) and np.isfinite(v) and np.isfinite(d) else np.nan
    lo, hi, total = _row_windows(seen, radius[:, 1], sorted_v)
    sorted_u, sorted_d = w_curr[order_v, 0], w_curr[order_v, 2]  # read in sequence below
    ia = np.empty(total, np.int64)
    ib = np.empty(total, np.int64)
    dist = np.empty(total, np.int64)
    count = 0
    for i in range(n):
        u, d, ru, rd = predicted[i, 0], predicted[i, 2], radius[i, 0], radius[i, 2]
        for s in range(lo[i], hi[i]):
            if abs(sorted_u[s] - u) > ru or abs(sorted_d[s] - d) > rd:
                continue
            j = order_v[s]
            ia[count], ib[count], dist[count] = i, j, _hamming(des_prev, i, des_curr, j)
            count += 1
    return ia[:count], ib[:count], dist[:count]


@_jit
def sad_costs(left, right, ui, vi, di, half, search):
    """``costs[k + search, n]``: sum of absolute differences between the left patch of half-width
    ``half`` at ``(ui[n], vi[n])`` and the right patch at disparity ``di[n] + k``."""
    n = ui.shape[0]
    costs = np.zeros((2 * search + 1, n), np.int64)
    for m in range(n):
        for s in range(2 * search + 1):
            shift = di[m] + s - search
            total = 0
            for dv in range(-half, half + 1):
                row = vi[m] + dv
                for du in range(-half, half + 1):
                    col = ui[m] + du
                    total += abs(np.int64(left[row, col]) - np.int64(right[row, col - shift]))
            costs[s, m] = total
    return costs


@_jit
def row_candidates(
    left, left_level, right, right_level, order_v, sorted_v, row_tolerance, d_min, d_max, des_left, des_right
):
    """Stereo candidates: pairs ``(i, j)`` of a left and a right corner within ``row_tolerance``
    rows, with a disparity ``left_u - right_u`` in ``[d_min, d_max]`` and pyramid levels at most
    one apart, with their Hamming distances; ordered by ``i``, then by right row."""
    n = left.shape[0]
    lo, hi, total = _row_windows(left[:, 1], np.full(n, row_tolerance), sorted_v)
    sorted_u, sorted_level = right[order_v, 0], right_level[order_v]
    ia = np.empty(total, np.int64)
    ib = np.empty(total, np.int64)
    dist = np.empty(total, np.int64)
    count = 0
    for i in range(n):
        u, level = left[i, 0], left_level[i]
        for s in range(lo[i], hi[i]):
            d = u - sorted_u[s]
            if d < d_min or d > d_max or abs(level - sorted_level[s]) > 1:
                continue
            j = order_v[s]
            ia[count], ib[count], dist[count] = i, j, _hamming(des_left, i, des_right, j)
            count += 1
    return ia[:count], ib[:count], dist[:count]
