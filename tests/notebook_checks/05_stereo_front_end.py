"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: K = np.array([[camera.fx, 0, camera.cx], [0, camera.fy, camera.cy], [0, 0, 1]])
assert row_offset.min() > max(5, 3 * ROW_TOLERANCE)  # one degree moves the line by several pixels

# after: fast = cv2.FastFeatureDetector_create(40, True)
assert cells_covered(points[kept]) >= cells_covered(points[strongest])

# after: front = StereoFrontEnd(camera)
assert len(common) > 0.5 * len(keypoints)
assert np.median(same) < 0.5 * np.median(shuffled) and np.median(shuffled) > 100

# after: u_i, v_i = np.rint(features.w[:, 0]).astype(int), np.rint(features.w[:, 1]).astype(int)
assert stereo_median_err < 0.7 * np.median(np.abs(err_integer))
assert stereo_wrong < 0.02

# after: stats = matching_rows(drive, renderer, front, camera, mount, rng)
from vo_lib.comparison import Verdict

assert pair_share < 0.01  # a per cent at most: the sentence after this cell says a small share
assert correct_guided > 0.9 * correct_brute  # the printed correct matches per frame, within a tenth
assert wrong_verdict is Verdict.BETTER  # the window's reason in the sentence after this cell presumes it

# after: front_end = front_end_on(camera, left, right, true_disparity)
# a guard of the widget's default run: the lab's painted walls and tiled floor leave part of the
# view without corners, yet its default settings keep a few hundred matches
assert count > 250
