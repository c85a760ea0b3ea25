"""Figures, apart from the algorithms so that these run headless.

``run_figure`` the figure of one run's outputs

The notebooks' figures, widgets and tables are in ``vo_book``.

Imports no wing: a figure takes arrays and results, not estimators.
"""
