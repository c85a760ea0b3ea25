"""Figures and widgets for the notebooks, apart from the algorithms so that these run headless.

``plotting``   figures the notebooks share; nothing here computes results
``widgets``    interactive wrappers around plain ``f(**params)`` functions
``prose``      sentences written by the code (Markdown that prints as text in a script)
``run_figure`` the figure of one run's outputs
``nb06``       tables and figures of notebook 06 (1-point RANSAC), out of its story cells

Imports no wing: a figure takes arrays and results, not estimators.
"""
