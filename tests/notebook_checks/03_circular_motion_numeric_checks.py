"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: worst_theta = worst_rho = 0.0
assert scene.height_above_floor(m.points).min() > -1e-9

# after: measured, model, normalised = np.array(measured), np.array(model), np.array(normalised)
# the table's first bin, near the camera's height, spreads over ten times as much as its last
assert measured[0] > 10 * measured[-1]

# after: results[(a, label)] = np.median(err)
for motion in ("arc 2°, 8 cm", "spot turn 2°"):
    # the printed bias grows with the offset, about in proportion: over 2 % of the 2° turn at 10 cm,
    # over 8 % at 30 cm, two and a half to three and a half times as much
    assert 0.02 * 2 < results[(0.1, motion)] < results[(0.3, motion)]
    assert 2.5 < results[(0.3, motion)] / results[(0.1, motion)] < 3.5 and results[(0.3, motion)] > 0.08 * 2
    # and is the same share of the turn for an arc and a spot turn
    assert abs(results[(0.3, motion)] / results[(0.3, "arc 2°, 8 cm")] - 1) < 0.1


# after: sigma_mc, sigma_model = theta_spread()
# "vary the depth: the spread of θ hardly moves": the first-order σθ (checked against the draws in
# the cell) of the same pixel and turn at 2 m and at 30 m
def _sigma_at(depth):
    w = np.array([[camera.cx + 100, camera.cy + 60, camera.fx * camera.baseline / depth]])
    w2 = camera.project(cm.apply_motion(camera.backproject(w), np.radians(2.0), 0.08))
    return cm.theta_standard_deviation(w, w2, camera, 0.5)[0]


assert abs(_sigma_at(30.0) / _sigma_at(2.0) - 1) < 0.1

# after: depth_ranges = [(1.0, 3.0), (1.5, 15.0), (5.0, 15.0), (20.0, 60.0)]
assert fraction[(0.3, 1.0)] > 4 * fraction[(0.3, 5.0)] > 4 * fraction[(0.3, 20.0)]
assert all(value > 0 for value in signed.values())  # over-estimated, never lost
assert all(abs(signed[key] / fraction[key] - 1) < 0.05 for key in signed)  # the same share as |error|

# after: OFFSET_SEEDS = range(SEED, SEED + 20)
assert max(abs(v) for v in spot_minus_arc[1:]) < 0.2 * np.median(offset_cmp.figures["the arc"])

# after: tilt_error[tilt] = row
assert min(tilt_error[2.0]) > 3.0 / 3  # more than a third of the true turn
assert tilt_error[5.0][0] > tilt_error[2.0][0] and tilt_error[5.0][1] > tilt_error[2.0][1]

# after: mount_pitch, mount_signed, levelled_error = {}, {}, {}
assert mount_pitch[0.0] < 1e-9 < mount_pitch[2.0] < mount_pitch[5.0] < mount_pitch[10.0]

# after: Y_GATE = float(np.sqrt(chi2.ppf(0.999, 2)))  # 99.9 % of planar frames pass
assert np.sum(planar_scores > Y_GATE) <= 1  # planar frames pass (a 99.9 % gate: one in 60 is chance) ...
assert np.all(np.array(scores[0.5]) > Y_GATE)  # ... every frame tilted by half a degree is
assert abs(fitted[0] - 2.0) < 0.2 and abs(fitted[1]) < 0.2
