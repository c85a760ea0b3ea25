"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: print(f"cells of {CELL}x{CELL} px")
assert stats[real_name]["empty"] > 0.2  # a real frame leaves many cells without a corner

# after: ours, theirs, where = errors["pyramid (ORB)"]
assert len(ours) >= 100  # enough scored features for a median; the count is printed
assert np.median(ours) <= np.median(theirs)  # at least as accurate as SGBM at the same pixels
assert np.median(ours) <= np.median(errors["single scale (FAST)"][0])

# after: known = np.isfinite(moto_truth)
assert np.mean(on_edge[tail]) >= 0.8 and np.median(ours[~on_edge]) < 0.15

# after: counts["single scale"].append(len(single_fe.process(left, right)))
if REAL:
    assert np.median(counts["pyramid"]) > 2 * np.median(counts["single scale"])

# after: f"over the drive: climbed {V[-1, 2, 3]:.2f} m; pitch
if REAL:
    assert vehicle.mount[0, 3] > 0.5  # the camera is well ahead of the axis
    assert np.abs(step_ypr[:, 1]).max() > 0.1 and V[-1, 2, 3] > 0.5  # the body pitches, the road climbs
else:
    assert np.abs(step_ypr[:, 1:]).max() < 1e-6  # the rendered floor is flat

# after: gain, offset = np.polyfit(forward_accel, body_nose_up, 1)
if REAL:  # braking dips the nose: the fit has the sign and the correlation the sentence states
    assert gain > 0 and corr > 0.3

# after: for j, what in enumerate(("slope, bank and pitch (6-DoF vs planar)"
if REAL:
    assert np.percentile(gaps[:, 0], 90) > rigid_motion.INLIER_PIXELS

# after: f"the circular motion, {within['refined']:.0%} under the refined one
if REAL:
    assert within["refined"] > within["circular"]
else:  # the circular model is exact for the rendered crawler: nothing for the refinement to add
    assert abs(within["refined"] - within["circular"]) < 0.05
