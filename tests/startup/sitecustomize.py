"""Run at the start of every Python process of the test session (the session puts this folder on
``PYTHONPATH``): once the process imports ``vo_lib.sim.frame_store``, its ``FOLDER`` is the
session's frame store, named by the environment variable ``VO_LIB_FRAME_STORE``. Nothing is
imported before the process asks for it, and a process outside the session is left alone."""

import importlib.abc
import importlib.machinery
import os
import sys

STORE = os.environ.get("VO_LIB_FRAME_STORE")
MODULE = "vo_lib.sim.frame_store"


class _SetFolder(importlib.abc.MetaPathFinder):
    """Finds nothing itself: wraps the loader of the frame store module to set its folder."""

    def find_spec(self, name, path, target=None):
        if name != MODULE:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        exec_module = spec.loader.exec_module

        def exec_and_set(module):
            exec_module(module)
            module.FOLDER = module.Path(STORE)

        spec.loader.exec_module = exec_and_set
        return spec


if STORE:
    sys.meta_path.insert(0, _SetFolder())
