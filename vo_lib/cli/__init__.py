"""The command line, ``python -m vo_lib COMMAND``: ``main`` parses and dispatches to ``run`` (run,
convert and generate), ``evaluate`` and ``sweep`` (``bench`` runs :mod:`vo_lib.bench`).

The top layer: it may import everything, nothing imports it.
"""
