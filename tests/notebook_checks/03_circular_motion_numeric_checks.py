"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: worst_theta = worst_rho = 0.0
assert scene.height_above_floor(m.points).min() > -1e-9

# after: noise = 0.5
assert measured[0] > 10 * measured[-1]  # near the camera's height, an order of magnitude worse

# after: print(" mount ahead [m]   motion        median |θ error| [deg]   spread across matches [deg]")
for motion in ("arc 2°, 8 cm", "spot turn 2°"):
    # the bias grows with the offset, about in proportion: several percent of the turn for 10 cm,
    # about a tenth for 30 cm in this scene
    assert 0.02 * 2 < results[(0.1, motion)] < results[(0.3, motion)]
    assert 2.5 < results[(0.3, motion)] / results[(0.1, motion)] < 3.5 and results[(0.3, motion)] > 0.08 * 2
    # and is the same share of the turn for an arc and a spot turn
    assert abs(results[(0.3, motion)] / results[(0.3, "arc 2°, 8 cm")] - 1) < 0.1

# after: depth_ranges = [(1.0, 3.0), (1.5, 15.0), (5.0, 15.0), (20.0, 60.0)]
assert fraction[(0.3, 1.0)] > 4 * fraction[(0.3, 5.0)] > 4 * fraction[(0.3, 20.0)]
assert all(value > 0 for value in signed.values())  # over-estimated, never lost
assert all(abs(signed[key] / fraction[key] - 1) < 0.05 for key in signed)  # the same share as |error|

# after: OFFSET_SEEDS = range(SEED, SEED + 10)
assert max(abs(v) for v in spot_minus_arc[1:]) < 0.2 * np.median(offset_cmp.figures["the arc"])

# after: print(" tilt [deg]   median |θ error| [deg]: pitch   roll")
assert min(tilt_error[2.0]) > 3.0 / 3  # more than a third of the true turn
assert tilt_error[5.0][0] > tilt_error[2.0][0] and tilt_error[5.0][1] > tilt_error[2.0][1]

# after: mount_pitch, mount_signed, levelled_error = {}, {}, {}
assert mount_pitch[0.0] < 1e-9 < mount_pitch[2.0] < mount_pitch[5.0] < mount_pitch[10.0]

# after: Y_GATE = float(np.sqrt(chi2.ppf(0.999, 2)))  # 99.9 % of planar frames pass
assert np.all(planar_scores <= Y_GATE)  # no planar frame flagged ...
assert np.all(np.array(scores[0.5]) > Y_GATE)  # ... every frame tilted by half a degree is
assert abs(fitted[0] - 2.0) < 0.2 and abs(fitted[1]) < 0.2
