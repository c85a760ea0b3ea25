"""The command line, ``python -m vo_lib COMMAND`` (``main`` parses and dispatches; the benchmarks
that ``bench`` runs are in :mod:`vo_lib.bench`).

``main``    the parser: run, evaluate, convert, generate, bench, sweep
``run``     ``run`` (the stereo VO pipeline on a sequence, files written), ``evaluate``, ``convert``
``sweep``   a paper's statistic over many seeds, serially or on Dask

The top layer: it may import everything, nothing imports it.
"""
