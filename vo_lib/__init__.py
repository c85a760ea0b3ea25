"""vo_lib: the tested algorithms behind the vo-notebooks collection.

One folder per paper ([Zhao] ``stereo_vo``, [Yan 2020] ``line_slam``, [Yuan] ``lidar_tracking``)
on shared layers below them; imports run downwards only (import-linter contracts in
``pyproject.toml``). The package map, naming every module, is ``docs/layout.md`` (the tests check
that it does); each folder's ``__init__`` says which equations live where and where to start
reading. The notebooks' widgets and demonstrations are in ``vo_book``, beside this package.

Re-exported here, imported on first use: ``load_sequence`` (``data``), ``StereoCamera``
(``camera``), ``TrackOdometry`` (``models.track_odometry``), ``theta_from_pixels`` and
``rho_from_pixels`` (``stereo_vo.circular_motion``), ``one_point_ransac`` (``stereo_vo.ransac``),
``VoKalmanFilter`` (``stereo_vo.kalman``).
"""

import importlib
import os

__version__ = "0.1.0"

_EXPORTS = {"load_sequence": "data", "StereoCamera": "camera", "TrackOdometry": "models.track_odometry"}
_EXPORTS |= dict.fromkeys(("theta_from_pixels", "rho_from_pixels"), "stereo_vo.circular_motion")
_EXPORTS |= {"one_point_ransac": "stereo_vo.ransac", "VoKalmanFilter": "stereo_vo.kalman"}
__all__ = sorted(_EXPORTS)


def _same_blas_kernels_everywhere() -> None:
    """Have OpenBLAS (in NumPy and in OpenCV) use its Haswell kernels on any x86-64 CPU with AVX2.

    OpenBLAS picks its kernels by CPU, and kernels round differently; RANSAC's inlier counts and
    the trackers' thresholds turn those last bits into other poses, so a seed gave other figures
    on an AVX-512 CPU than on an AVX2 one. OpenBLAS reads ``OPENBLAS_CORETYPE`` when it loads:
    this works in a process that imports ``vo_lib`` before NumPy and OpenCV (the command line,
    the test session and the kernels it starts, and every notebook, whose first import it is), and
    a value the user set is kept.
    """
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as cpuinfo:
            avx2 = " avx2" in next((line for line in cpuinfo if line.startswith("flags")), "")
    except OSError:  # not Linux: OpenBLAS chooses
        return
    if avx2:
        os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")


_same_blas_kernels_everywhere()


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"vo_lib.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module 'vo_lib' has no attribute {name!r}")
