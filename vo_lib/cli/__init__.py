"""The command line, ``python -m vo_lib COMMAND`` (``main`` parses and dispatches).

``main``          the parser: run, evaluate, generate, bench, sweep, evaluate-all
``run``           ``run`` (the stereo VO pipeline on a sequence, files written) and ``evaluate``
``report``        the run's tables: time per stage, errors in 3-D and planar
``bench``         benchmarks, one module per wing
``sweep``         a grid of experiments, serially or on Dask, rows kept on disk by their parameters
``tasks``         where a sweep's tasks run: this process, a Dask LocalCluster or a scheduler
``experiments``   the papers' statistics as sweeps (``sweep corridor|lap|nees|table1``)
``evaluate_all``  ``evaluate-all``: the pipeline on every sequence under a folder

The top layer: it may import everything, nothing imports it.
"""
