"""vo_book: the notebooks' helper modules, apart from the library they teach.

Widgets, demonstration drives, per-notebook tables and figures: what a notebook imports in one
line so that its story cells show the algorithm and its result. It imports ``vo_lib``; ``vo_lib``
never imports it (an import-linter contract in ``pyproject.toml``). Installed with ``vo_lib``, so
the student edition and the grader find it as the notebooks do.

``widgets``        interactive wrappers of a pure function ``f(**params)``
``prose``          sentences written by the code, so a computed figure reaches the prose
``plotting``       the figures the notebooks share: paths, worlds, ellipses, the papers' diagrams
``demo_drive``     notebook 01's drive-it-yourself widget: dead reckoning against slipping truth
``nb01``           notebook 01's Monte Carlo of dead reckoning over seeds, and its figures
``nb03``, ``demo_circular``   notebook 03: figures, the local exponent of σ_θ; scene draws, the θ widget
``nb04``, ``demo_worlds``     notebook 04: figures; image, depth and scan at a pose
``nb05``, ``demo_front_end``  notebook 05: grid-cell count, figures; the front-end widget on one pair
``nb06``, ``demo_one_point``  notebook 06: outlier-mix match sets, the RANSAC trial, tables, figures
``nb07``, ``demo_fusion``     notebook 07: figures; the seed drives, with the seed study stored
                              (``demo_fusion.json``)
``nb08``, ``demo_pipeline``   notebook 08: figures; the sample runs, the stored paper sets' tables
``nb09``           notebook 09's matrix comparison, finite differences, timings and figures
``nb10``, ``demo_corridor``   notebook 10: figures; score profiles, box statistics and ROC area
``nb11``           notebooks 11 and 12: figures and small measurements
``demo_real``      notebook 12's chain of the circular and 6-DoF readings
"""
