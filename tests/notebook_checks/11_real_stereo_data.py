"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: print(f"cells of {CELL}x{CELL} px")
assert stats[real_name]["empty"] > 0.2  # a real frame leaves many cells without a corner

# after: h, w = moto_left.shape
assert len(ours) >= 100  # enough scored features for a median; the count is printed
assert np.median(ours) <= np.median(theirs)  # at least as accurate as SGBM at the same pixels
assert np.median(ours) <= np.median(errors["single scale (FAST)"][0])

# after: known = np.isfinite(moto_truth)
assert np.mean(on_edge[tail]) >= 0.8 and np.median(ours[~on_edge]) < 0.15
