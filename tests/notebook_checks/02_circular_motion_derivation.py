"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: fig, axes = new_axes(2, width=5.5, height=4.5)
assert lean > 5.0  # the drawing's geometry is exact: a clear lean, not a rounding
