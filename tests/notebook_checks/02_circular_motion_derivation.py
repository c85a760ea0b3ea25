"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: lean = np.degrees(
assert lean > 5.0  # the drawing's geometry is exact: a clear lean, not a rounding
