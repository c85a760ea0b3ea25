"""Every compiled kernel has a plain NumPy twin that gives the same result on random inputs.

The twins are what ``VO_LIB_PLAIN=1`` runs (``vo_lib.compiled``). Each property test below draws
inputs with hypothesis and holds the kernel to its twin: exactly where the result is discrete
(inlier masks, counts), and to a stated tolerance where the two sum in different orders.
"""

from __future__ import annotations

import importlib
import math
import pkgutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import vo_lib
from vo_lib import compiled
from vo_lib.camera import StereoCamera
from vo_lib.sim import composite, composite_plain
from vo_lib.stereo_vo import matching_core, matching_plain, ransac_core, ransac_plain, rigid_core, rigid_plain
from vo_lib.stereo_vo.ransac import camera_terms, hypothesis_draws, one_point_ransac
from vo_lib.stereo_vo.rigid_motion import rotation_matrix
from vo_lib.stereo_vo.synthetic import synthetic_matches

CAMERA = StereoCamera(fx=450.0, fy=460.0, cx=320.0, cy=240.0, baseline=0.12, width=640, height=480)
#: Tolerance of quantities the kernel and its twin sum in different orders (relative).
RTOL = 1e-9
SLOW = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _import_all():
    for info in pkgutil.walk_packages(vo_lib.__path__, "vo_lib."):
        if ".cli" not in info.name:  # the command line compiles nothing; its imports are heavy
            importlib.import_module(info.name)


@st.composite
def match_sets(draw):
    """Matches under a random circular motion, with outliers and noise, and random settings."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n = draw(st.integers(0, 150))
    theta = math.radians(draw(st.floats(-6, 6)))
    rho = draw(st.floats(-0.05, 0.2))
    m = synthetic_matches(
        CAMERA,
        n,
        theta,
        rho,
        rng,
        noise_px=draw(st.floats(0, 1.5)),
        outlier_ratio=draw(st.floats(0, 0.8)),
    )
    a, b = m.w_prev.copy(), m.w_curr.copy()
    if n and draw(st.booleans()):  # a few matches with no disparity
        bad = rng.random(n) < 0.1
        a[bad, 2] = 0.0
    params = ransac_core.RansacParams(
        pixel_sigma=draw(st.floats(0.2, 1.5)),
        gate_sigmas=draw(st.floats(1.5, 4.0)),
        max_hypotheses=draw(st.integers(5, 200)),
        refine=draw(st.booleans()),
        initial_inlier_ratio=draw(st.floats(0.1, 0.9)),
    )
    prior = (np.array([theta + 1e-3, 1e-5]), np.array([rho + 2e-3, 1e-4]))
    no_prior = (np.array([np.nan, np.nan]), np.array([np.nan, np.nan]))
    prior_theta, prior_rho = prior if draw(st.booleans()) else no_prior
    draws = hypothesis_draws(rng, params.max_hypotheses)
    return a, b, prior_theta, prior_rho, draws, params


@SLOW
@given(match_sets())
def test_one_point_core_equals_its_twin(case):
    a, b, prior_theta, prior_rho, draws, params = case
    args = (a, b, camera_terms(CAMERA), prior_theta, prior_rho, draws, params)
    kernel = ransac_core.one_point_core(*args)
    plain = ransac_plain.one_point(*args)
    status, theta, rho, cov, inliers, *counts = kernel
    assert plain[0] == status
    assert np.array_equal(plain[4], inliers)
    assert [int(c) for c in plain[5:]] == [int(c) for c in counts]
    assert np.allclose(plain[1:3], (theta, rho), rtol=RTOL, atol=1e-12, equal_nan=True)
    # covariances to 1e-6 relative; noise-free matches leave residuals of rounding size, whose
    # covariance (below 1e-15) is rounding noise in both
    assert np.allclose(plain[3], cov, rtol=1e-6, atol=1e-15, equal_nan=True)


@SLOW
@given(st.integers(0, 2**32 - 1), st.integers(3, 80), st.integers(1, 4))
def test_gauss_newton_and_covariance_equal_their_twins(seed, n, iterations):
    rng = np.random.default_rng(seed)
    m = synthetic_matches(
        CAMERA, n, math.radians(rng.uniform(-5, 5)), rng.uniform(0.02, 0.15), rng, noise_px=0.5
    )
    P, Q = CAMERA.backproject(m.w_prev), CAMERA.backproject(m.w_curr)
    start = (rng.normal(0, 0.02), rng.uniform(0.0, 0.2))
    args = (P, Q, m.w_prev, m.w_curr, *start, camera_terms(CAMERA), iterations)
    kernel, plain = ransac_core.gauss_newton(*args), ransac_plain.gauss_newton(*args)
    assert np.allclose(plain, kernel, rtol=1e-7, atol=1e-12)
    cov_k = ransac_core.covariance(*kernel[2:], 6 * n)
    cov_p = ransac_plain.covariance(*kernel[2:], 6 * n)
    assert np.allclose(cov_p, cov_k, rtol=1e-7, atol=0)


def test_the_switch_runs_the_plain_twin(monkeypatch, rng):
    m = synthetic_matches(CAMERA, 120, 0.03, 0.08, rng, noise_px=0.5, outlier_ratio=0.3)
    calls = []
    original = ransac_plain.one_point

    def spy(*args):
        calls.append(1)
        return original(*args)

    monkeypatch.setattr(ransac_plain, "one_point", spy)
    compiled_run = one_point_ransac(m.w_prev, m.w_curr, CAMERA, rng=5)
    assert calls == []
    monkeypatch.setenv("VO_LIB_PLAIN", "1")
    plain_run = one_point_ransac(m.w_prev, m.w_curr, CAMERA, rng=5)
    assert calls == [1]
    assert np.array_equal(plain_run.inliers, compiled_run.inliers)
    assert plain_run.theta == pytest.approx(compiled_run.theta, rel=RTOL)
    monkeypatch.setenv("VO_LIB_PLAIN", "0")
    one_point_ransac(m.w_prev, m.w_curr, CAMERA, rng=5, plain=True)  # the argument wins
    assert calls == [1, 1]


def _rng(seed):
    return np.random.default_rng(seed)


SEEDS = st.integers(0, 2**32 - 1)
RATIOS = [0.7, 0.8, 1.0]


@settings(max_examples=60, deadline=None)
@given(
    SEEDS, st.integers(1, 40), st.integers(1, 40), st.integers(0, 300), st.booleans(), st.sampled_from(RATIOS)
)
def test_best_matches_equal_their_twin(seed, n_a, n_b, m, mutual, ratio):
    rng = _rng(seed)
    ia, ib = rng.integers(0, n_a, m), rng.integers(0, n_b, m)
    dist = rng.integers(0, 25, m)  # few distinct distances: many ties
    args = (ia, ib, dist, n_a, n_b, 18.0, ratio, mutual)
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
@given(SEEDS, st.integers(1, 200), st.sampled_from([0.5, 2.0, np.inf]))
def test_normal_equations_equal_their_twin(seed, n, huber):
    rng = _rng(seed)
    P = np.column_stack([rng.uniform(-10, 10, n), rng.uniform(-2, 2, n), rng.uniform(3, 40, n)])
    R, t = rotation_matrix(rng.normal(0, 0.02, 3)), rng.normal(0, 0.3, 3)
    fx, fy, cx, cy, fb = 700.0, 710.0, 600.0, 180.0, 700.0 * 0.54
    Q = P @ R.T + t
    w = np.column_stack([fx * Q[:, 0] / Q[:, 2] + cx, fy * Q[:, 1] / Q[:, 2] + cy, fb / Q[:, 2]])
    w += rng.normal(0, 1.0, w.shape)
    args = (P, w, np.eye(3), np.zeros(3), fx, fy, cx, cy, fb, huber)
    kernel, plain = rigid_core.normal_equations(*args), rigid_plain.normal_equations(*args)
    for a, b in zip(kernel, plain, strict=True):  # sums in another order: to 1e-9
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)


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


def test_the_switch_runs_every_twin(monkeypatch):
    monkeypatch.setenv("VO_LIB_PLAIN", "1")
    for kernel in (matching_core.sad_costs, rigid_core.normal_equations, composite.draw_nearer):
        assert compiled.choose(kernel) is compiled.twin_of(kernel)
        assert compiled.choose(kernel, plain=False) is kernel


#: Kernel -> the property test holding it to its twin.
PROPERTY_TESTS = {
    "vo_lib.stereo_vo.ransac_core.one_point_core": test_one_point_core_equals_its_twin,
    "vo_lib.stereo_vo.ransac_core.gauss_newton": test_gauss_newton_and_covariance_equal_their_twins,
    "vo_lib.stereo_vo.ransac_core.covariance": test_gauss_newton_and_covariance_equal_their_twins,
    "vo_lib.stereo_vo.matching_core.best_matches_core": test_best_matches_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.window_candidates": test_window_candidates_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.row_candidates": test_row_candidates_equal_their_twin,
    "vo_lib.stereo_vo.matching_core.sad_costs": test_sad_costs_equal_their_twin,
    "vo_lib.stereo_vo.rigid_core.normal_equations": test_normal_equations_equal_their_twin,
    "vo_lib.sim.composite.draw_nearer": test_draw_nearer_equals_its_twin,
}


def test_every_compiled_function_has_a_twin_and_a_property_test():
    _import_all()
    ours = {name for name in compiled.COMPILED if name.startswith("vo_lib.")}  # not those tests compile
    kernels = ours - set(compiled.STEPS)
    assert kernels, "no compiled function found"
    assert set(compiled.STEPS.values()) <= kernels, "a step names a kernel that does not exist"
    assert sorted(kernels - set(compiled.TWINS)) == [], "compiled kernels without a plain twin"
    for name in kernels:
        assert callable(compiled.twin_of(compiled.COMPILED[name])), name
    assert sorted(kernels - set(PROPERTY_TESTS)) == [], "compiled kernels without a property test"
