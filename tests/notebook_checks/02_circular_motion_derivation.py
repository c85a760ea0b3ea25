"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: lean = np.degrees(
assert lean > 5.0  # the drawing's geometry is exact: a clear lean, not a rounding

# after: camera = StereoCamera.bumblebee2()
assert min(printed_errors) > 1.0  # metres: the printed sign returns about twice the depth
assert 1.8 < np.median(printed_over_depth) < 2.1
