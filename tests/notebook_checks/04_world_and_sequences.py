"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: err = np.abs(measured - true_disparity)
assert np.median(err) < 0.25 and np.mean(err < 0.5) > 0.9

# after: scanner = LaserScanner(range_sigma=0.0, max_range=30.0)  # longer than 10 m: no wall is cut off
# the image centre and the beam straight ahead can differ by the wall under half a pixel (the
# pixel's centre is not the optical axis); that physical bound is the margin, not the measured gap
assert abs(scan.ranges[ahead] - depth[row, col]) < 0.5 * pixel_width

# after: odometry = TrackOdometry()
# the sizes the printed sentence reports: the spot turn's heading ten degrees or more off, the
# corridor drive a metre or more off
assert spot_heading_error >= 10.0
assert corridor_error >= 1.0

# after: spot, spot_believed = drives["spot_turn"]
assert 1.03 < over_count < 1.10  # the mean spot-turn slip, 6 %

# after: ROAD_FRAME = 60
assert 0.35 <= road_stats.empty_cells <= 0.75 and 0.3 <= road_stats.low_gradient <= 0.6
