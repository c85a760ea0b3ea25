"""Shared fixtures: the rig, a seeded generator, and a kernel that runs this very interpreter."""

from __future__ import annotations

import json
import os
import pathlib
import pickle
import shutil
import sys
import tempfile
import time

# vo_lib first: it chooses OpenBLAS's kernels before NumPy loads them (vo_lib/__init__.py)
import vo_lib  # noqa: F401

# isort: split
import numpy as np
import pytest

from vo_lib.camera import StereoCamera

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: Real sequences beside the repository (CI has them); the notebooks find them through
#: ``VO_LIB_REALDATA``, which the test kernel gets when the folder exists and it is not set.
REALDATA = ROOT.parent / "shared" / "realdata"
NOTEBOOK_KERNEL = "python3"  # the kernel every notebook names (tests/test_kernel_name.py)
#: Debian's Chromium and the flags the browser tests start it with: headless, and no attempt to
#: reach the network, which this machine does not have.
CHROMIUM = pathlib.Path("/usr/bin/chromium")
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def jupyter_command(app: str, port: int, token: str) -> list[str]:
    """``jupyter APP`` (lab or server) on 127.0.0.1:``port`` with ``token``, for a browser or a
    client of the tests: no browser of its own, root allowed (CI containers), no port retries."""
    return [
        sys.executable,
        "-m",
        "jupyter",
        app,
        "--no-browser",
        "--allow-root",  # CI containers run as root; harmless otherwise
        "--ip=127.0.0.1",
        f"--port={port}",
        "--port-retries=0",
        f"--IdentityProvider.token={token}",
    ]


def stop_server(proc, log) -> None:
    """Terminate a server a test started (killed if it does not stop in 30 s) and close its log."""
    import subprocess

    proc.terminate()
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=30)
    log.close()


#: The session's frame store, named to every process the session starts; tests/startup/sitecustomize.py
#: (on their PYTHONPATH) sets vo_lib.sim.frame_store.FOLDER from it.
FRAME_STORE = "VO_LIB_FRAME_STORE"
STARTUP = str(pathlib.Path(__file__).with_name("startup"))


def pytest_configure(config):
    """One frame store for the session, made before the workers start: they, the notebook kernels
    and the command-line runs they start inherit it, so each frame of a sample that several tests
    render is rendered once (``vo_lib.sim.frame_store``)."""
    if not os.environ.get(FRAME_STORE):  # else a worker (it inherits the store), or the caller's
        config.frame_store = tempfile.mkdtemp(prefix="vo_lib_frames_")
        os.environ[FRAME_STORE] = config.frame_store
    paths = list(filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep)))
    if STARTUP not in paths:
        os.environ["PYTHONPATH"] = os.pathsep.join([STARTUP, *paths])
    from vo_lib.sim import frame_store

    frame_store.FOLDER = pathlib.Path(os.environ[FRAME_STORE])  # this process too


def pytest_unconfigure(config):
    folder = getattr(config, "frame_store", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)
        os.environ.pop(FRAME_STORE, None)


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


#: How long a worker waits for another to compute a shared result before computing it itself.
SHARED_WAIT_S = 900.0


@pytest.fixture(scope="session")
def shared(tmp_path_factory):
    """``shared(name, compute)``: the result of ``compute()``, computed once per test session.

    The test workers (pytest-xdist) share a temporary folder: the first worker to ask computes
    the result and pickles it there (written under a temporary name, then renamed), and the
    others wait for it and read it. ``compute`` may take a folder inside that shared one to write
    into: ``shared(name, compute, folder=True)`` calls ``compute(folder)``.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the folder every worker's temporary folder is in

    def get(name: str, compute, folder: bool = False):
        result, lock = base / f"shared-{name}.pickle", base / f"shared-{name}.lock"
        deadline = time.monotonic() + SHARED_WAIT_S
        while not result.exists():
            try:
                os.close(os.open(lock, os.O_CREAT | os.O_EXCL))  # exactly one worker gets it
            except FileExistsError:
                if time.monotonic() < deadline:
                    time.sleep(0.2)
                    continue
            try:
                if folder:
                    (base / f"shared-{name}").mkdir(exist_ok=True)
                value = compute(base / f"shared-{name}") if folder else compute()
            except BaseException:
                lock.unlink(missing_ok=True)  # a waiting worker tries, and fails, on its own
                raise
            partial = result.with_suffix(f".{os.getpid()}.partial")
            partial.write_bytes(pickle.dumps(value))
            partial.replace(result)
            return value
        return pickle.loads(result.read_bytes())

    return get
