"""[Zhao]: stereo visual odometry for a crawler robot, fused with its track odometry.

Start reading at ``pipeline``, the whole method frame by frame (Fig. 3), whose docstring names
the parts in the order a frame meets them; the package map of docs/layout.md lists every module
in that order. The command ``python -m vo_lib run`` runs ``pipeline`` on a sequence.
"""
