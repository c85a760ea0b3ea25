"""Figures, apart from the algorithms so that these run headless: ``run_figure``, the figure of one
run's outputs (the notebooks' figures are in ``vo_book``). Imports no wing.
"""
