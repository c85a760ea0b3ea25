"""Every compiled kernel sits beside its NumPy reference and gives the same result on random inputs.

Kernels are kept only where the NumPy version makes the whole frame more than 1.5x slower (the
stereo and temporal matching on real frames, the renderer's composite, the laser trackers' reading
of the likelihood field; ``bench kernels`` times the three). Each property test below draws
inputs with hypothesis and holds the kernel to its twin: exactly where the result is discrete
(inlier masks, counts), and to a stated tolerance where the two sum in different orders.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import vo_lib
from vo_lib.lidar_tracking import likelihood_field
from vo_lib.sim import composite, composite_plain
from vo_lib.stereo_vo import matching_core, matching_plain


def _import_all():
    for info in pkgutil.walk_packages(vo_lib.__path__, "vo_lib."):
        if ".cli" not in info.name:  # the command line compiles nothing; its imports are heavy
            importlib.import_module(info.name)


def _rng(seed):
    return np.random.default_rng(seed)


SEEDS = st.integers(0, 2**32 - 1)
RATIOS = [0.7, 0.8, 1.0]


@settings(max_examples=60, deadline=None)
@given(SEEDS, st.integers(1, 40), st.integers(1, 40), st.integers(0, 300), st.sampled_from(RATIOS))
def test_best_matches_equal_their_twin(seed, n_a, n_b, m, ratio):
    rng = _rng(seed)
    ia, ib = rng.integers(0, n_a, m), rng.integers(0, n_b, m)
    dist = rng.integers(0, 25, m)  # few distinct distances: many ties
    args = (ia, ib, dist, n_a, n_b, 18.0, ratio)
    assert_same_arrays(matching_core.best_matches_core(*args), matching_plain.best_matches(*args))


def assert_same_arrays(kernel_result, plain_result):
    """Exactly the same arrays, in the same order (pairs, indices, distances)."""
    for a, b in zip(kernel_result, plain_result, strict=True):
        assert np.array_equal(a, b)


def _features(rng, n, width=600.0, height=300.0):
    w = np.column_stack([rng.uniform(0, width, n), rng.uniform(0, height, n), rng.uniform(1, 60, n)])
    return w, rng.integers(0, 256, (n, 32), dtype=np.uint8).view(np.uint64)


@settings(max_examples=40, deadline=None)
@given(SEEDS, st.integers(0, 120), st.integers(1, 150), st.floats(1.0, 400.0))
def test_window_candidates_equal_their_twin(seed, n, m, max_radius):
    rng = _rng(seed)
    w_prev, des_prev = _features(rng, n)
    w_curr, des_curr = _features(rng, m)
    predicted = w_prev + rng.normal(0, 5, (n, 3))
    predicted[rng.random(n) < 0.1, rng.integers(0, 3)] = np.nan  # out of view
    radius = np.column_stack([rng.uniform(1.0, max_radius, (n, 2)), 2.0 + 0.3 * predicted[:, 2]])
    order = np.argsort(w_curr[:, 1], kind="stable")
    args = (predicted, radius, w_curr, order, w_curr[order, 1].copy(), des_prev, des_curr)
    assert_same_arrays(matching_core.window_candidates(*args), matching_plain.window_candidates(*args))


@settings(max_examples=40, deadline=None)
@given(SEEDS, st.integers(1, 120), st.integers(1, 150), st.floats(0.0, 3.0))
def test_row_candidates_equal_their_twin(seed, n, m, tolerance):
    rng = _rng(seed)
    left, des_left = _features(rng, n)
    right, des_right = _features(rng, m)
    right[:, 1] = np.round(right[:, 1] / 4) * 4  # shared rows
    left[:, 1] = np.round(left[:, 1] / 4) * 4
    levels_l, levels_r = rng.integers(0, 4, n), rng.integers(0, 4, m)
    order = np.argsort(right[:, 1], kind="stable")
    rows = right[order, 1].copy()
    args = (left, levels_l, right, levels_r, order, rows, tolerance, 0.5, 90.0, des_left, des_right)
    assert_same_arrays(matching_core.row_candidates(*args), matching_plain.row_candidates(*args))


@settings(max_examples=40, deadline=None)
@given(SEEDS, st.integers(0, 60), st.integers(1, 4), st.integers(0, 3))
def test_sad_costs_equal_their_twin(seed, n, half, search):
    rng = _rng(seed)
    left = rng.integers(0, 256, (60, 120), dtype=np.uint8)
    right = rng.integers(0, 256, (60, 120), dtype=np.uint8)
    vi = rng.integers(half, 60 - half, n)
    di = rng.integers(0, 30, n)
    ui = rng.integers(half + 30 + search, 120 - half - search, n)
    kernel = matching_core.sad_costs(left, right, ui, vi, di, half, search)
    assert np.array_equal(kernel, matching_plain.sad_costs(left, right, ui, vi, di, half, search))


@settings(max_examples=40, deadline=None)
@given(SEEDS, st.sampled_from([1.0, 0.7, 1.3]))
def test_draw_nearer_equals_its_twin(seed, shade):
    rng = _rng(seed)
    image = rng.integers(0, 256, (40, 50), dtype=np.uint8)
    inv_depth = rng.uniform(0, 0.5, (40, 50)).astype(np.float32)
    h, w = int(rng.integers(1, 30)), int(rng.integers(1, 40))
    y0, x0 = int(rng.integers(0, 40 - h)), int(rng.integers(0, 50 - w))
    warped = rng.integers(0, 256, (h, w), dtype=np.uint8)
    mask = (rng.random((h, w)) < 0.7).astype(np.uint8)
    plane = (float(rng.normal(0, 0.01)), float(rng.normal(0, 0.01)), float(rng.uniform(0, 0.5)))
    images = [image.copy(), image.copy()]
    depths = [inv_depth.copy(), inv_depth.copy()]
    composite.draw_nearer(images[0], depths[0], warped, mask, x0, y0, *plane, shade)
    composite_plain.draw_nearer(images[1], depths[1], warped, mask, x0, y0, *plane, shade)
    assert np.array_equal(images[0], images[1]) and np.array_equal(depths[0], depths[1])


@settings(max_examples=40, deadline=None)
@given(SEEDS, st.integers(1, 60), st.integers(1, 80))
def test_field_at_equals_its_twin(seed, n, k):
    rng = _rng(seed)
    rows, cols = int(rng.integers(1, 50)), int(rng.integers(1, 50))
    padded = np.pad(rng.random((rows, cols), dtype=np.float32), 1).ravel()
    heading = rng.uniform(-np.pi, np.pi, n)
    grid = (padded, rows, cols, *rng.normal(0, 1, 2), float(rng.choice([0.05, 0.1, 0.3])))
    poses = (rng.uniform(-1, 4, n), rng.uniform(-1, 4, n), np.cos(heading), np.sin(heading))
    points = (rng.normal(0, 2, k), rng.normal(0, 2, k))  # some off the grid
    kernel = likelihood_field.field_at(*grid, *poses, *points)
    assert np.array_equal(kernel, likelihood_field.field_at_plain(*grid, *poses, *points))


#: Kernel -> the property test holding it to its twin.
PROPERTY_TESTS = {
    "vo_lib.stereo_vo.matching_core.best_matches_core": test_best_matches_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.window_candidates": test_window_candidates_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.row_candidates": test_row_candidates_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.sad_costs": test_sad_costs_equal_their_twin,
    "vo_lib.sim.composite.draw_nearer": test_draw_nearer_equals_its_twin,
    "vo_lib.lidar_tracking.likelihood_field.field_at": test_field_at_equals_its_twin,
}


def test_every_compiled_kernel_has_a_property_test():
    from numba.core.registry import CPUDispatcher

    _import_all()
    kernels = {
        f"{name}.{attr}"
        for name, module in list(sys.modules.items())
        if name.startswith("vo_lib.")
        for attr, value in vars(module).items()
        if isinstance(value, CPUDispatcher) and not attr.startswith("_") and value.__module__ == name
    }
    assert kernels, "no compiled function found"
    assert sorted(kernels - set(PROPERTY_TESTS)) == [], "compiled kernels without a property test"
