"""Shared fixtures: the rig, a seeded generator, and a kernel that runs this very interpreter."""

from __future__ import annotations

import json
import os
import pathlib
import sys

import numpy as np
import pytest

from vo_lib.camera import StereoCamera

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: Real sequences beside the repository (CI has them); the notebooks find them through
#: ``VO_LIB_REALDATA``, which the test kernel gets when the folder exists and it is not set.
REALDATA = ROOT.parent / "shared" / "realdata"
NOTEBOOK_KERNEL = "python3"  # the kernel every notebook names (tests/test_kernel_name.py)


@pytest.fixture
def camera() -> StereoCamera:
    return StereoCamera.bumblebee2()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def kernel_dir(tmp_path_factory) -> pathlib.Path:
    """A kernelspec folder whose only kernel, named ``python3`` as the notebooks name it, starts
    ``sys.executable``: the tests' own environment, whatever kernels the user has registered."""
    kernels = tmp_path_factory.mktemp("jupyter") / "kernels"
    spec = kernels / NOTEBOOK_KERNEL
    spec.mkdir(parents=True)
    kernel = {
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "vo-notebooks (tests)",
        "language": "python",
    }
    if "VO_LIB_REALDATA" not in os.environ and REALDATA.is_dir():
        kernel["env"] = {"VO_LIB_REALDATA": str(REALDATA)}
    spec.joinpath("kernel.json").write_text(json.dumps(kernel))
    return kernels
