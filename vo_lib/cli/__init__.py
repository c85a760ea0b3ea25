"""The command line, ``python -m vo_lib COMMAND`` (``main`` parses and dispatches).

``main``    the parser: run, evaluate, generate, bench
``run``     ``run`` (the stereo VO pipeline on a sequence, files written) and ``evaluate``
``bench``   benchmarks, one module per wing

The top layer: it may import everything, nothing imports it.
"""
