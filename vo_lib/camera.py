"""A rectified stereo camera: pixels plus disparity to 3-D points and back ([Zhao], eq. 13).

The left camera is the reference. The right camera sits ``baseline`` metres along the left
camera's +x axis, both share the intrinsics, and rows are aligned, so a point at depth ``z``
appears in both images on the same row with disparity ``d = u_left - u_right = fx * B / z``.
A calibrated pair that is not rectified becomes one through :func:`rectify_stereo` (OpenCV).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from vo_lib.geometry import as_match_array, rigid_matrix

#: The paper's rig, a Bumblebee2 stereo head: 12 cm baseline, about 66 degrees horizontal field of view.
BUMBLEBEE2_BASELINE = 0.12
BUMBLEBEE2_HFOV_DEG = 66.0


def _positive(name: str, value) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0; got {value!r}")
    return value


def _positive_rows(values: np.ndarray, message: str) -> np.ndarray:
    """``values``, once all are > 0; else ValueError, ``message`` formatted with the first bad row."""
    if np.any(values <= 0):
        bad = int(np.flatnonzero(values <= 0)[0])
        raise ValueError(message.format(bad, float(values[bad])))
    return values


@dataclass(frozen=True)
class StereoCamera:
    """Pinhole intrinsics shared by a rectified stereo pair, and its baseline.

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels, > 0.
    cx, cy : float
        Principal point ``(u0, v0)`` in pixels.
    baseline : float
        Distance between the optical centres in metres, > 0.
    width, height : int, optional
        Image size in pixels, used by :meth:`in_image` and by renderers.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    baseline: float
    width: int | None = None
    height: int | None = None

    def __post_init__(self):
        for name in ("fx", "fy", "cx", "cy", "baseline"):  # plain floats, whatever array type came in
            object.__setattr__(self, name, float(getattr(self, name)))
        _positive("fx (focal length in pixels)", self.fx)
        _positive("fy (focal length in pixels)", self.fy)
        _positive("baseline (metres)", self.baseline)
        for name in ("cx", "cy"):
            if not math.isfinite(value := getattr(self, name)):
                raise ValueError(f"{name} (principal point) must be finite; got {value!r}")
        for name in ("width", "height"):
            if (value := getattr(self, name)) is not None and (int(value) != value or value <= 0):
                raise ValueError(f"{name} must be a positive whole number of pixels; got {value!r}")

    @classmethod
    def bumblebee2(cls, width: int = 640, height: int = 480) -> StereoCamera:
        """A rig like the paper's Bumblebee2: 66 degrees horizontal field of view, 12 cm baseline,
        square pixels, principal point at the image centre."""
        f = (width / 2.0) / math.tan(math.radians(BUMBLEBEE2_HFOV_DEG) / 2.0)
        return cls(f, f, (width - 1) / 2.0, (height - 1) / 2.0, BUMBLEBEE2_BASELINE, width, height)

    @classmethod
    def from_projection_matrices(cls, P0, P1, width=None, height=None) -> StereoCamera:
        """Read a rectified pair from its 3x4 projection matrices (KITTI ``calib.txt`` layout):
        ``P1 = K [I | -B e_x]`` up to the translation of ``P0``, so ``B = (P0[0,3] - P1[0,3]) / fx``."""
        P0, P1 = (np.asarray(P, dtype=float).reshape(3, 4) for P in (P0, P1))
        fx = _positive("P0[0,0] (fx)", P0[0, 0])
        baseline = (P0[0, 3] - P1[0, 3]) / fx
        if not baseline > 0:
            raise ValueError(
                f"P1 must place the right camera at +x of the left (P1[0,3] < P0[0,3]); "
                f"got P0[0,3]={float(P0[0, 3]):g}, P1[0,3]={float(P1[0, 3]):g}"
            )
        return cls(fx, P0[1, 1], P0[0, 2], P0[1, 2], baseline, width, height)

    def scaled(self, width: int, height: int) -> StereoCamera:
        """The same optics sampled at another resolution (the paper's Table 1 resolutions)."""
        self._require_size("scaled()")
        sx, sy = width / self.width, height / self.height
        cx, cy = (self.cx + 0.5) * sx - 0.5, (self.cy + 0.5) * sy - 0.5
        return StereoCamera(self.fx * sx, self.fy * sy, cx, cy, self.baseline, width, height)

    def _require_size(self, what: str) -> None:
        if self.width is None or self.height is None:
            raise ValueError(f"{what} needs a camera with width and height")

    @property
    def K(self) -> np.ndarray:
        """3x3 intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def projection_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``(P0, P1)``: 3x4 projection matrices of the left and right cameras."""
        P0 = np.hstack([self.K, np.zeros((3, 1))])
        P1 = P0.copy()
        P1[0, 3] = -self.fx * self.baseline
        return P0, P1

    def project(self, points) -> np.ndarray:
        """Project left-camera points ``(N, 3)`` to ``w = (u, v, d)`` ``(N, 3)``.

        Raises
        ------
        ValueError
            If a point is not in front of the camera (``z <= 0``).
        """
        P = as_match_array("points", points)
        z = _positive_rows(P[:, 2], "points must lie in front of the camera (z > 0); row {} has z={}")
        u, v = self.cx + self.fx * P[:, 0] / z, self.cy + self.fy * P[:, 1] / z
        return np.column_stack([u, v, self.fx * self.baseline / z])

    def backproject(self, w) -> np.ndarray:
        """Points ``(N, 3)`` in the left camera frame from ``w = (u, v, d)`` ([Zhao], eq. 13).

        With ``fx == fy == f`` this is the paper's ``x = B(u-u0)/d, y = B(v-v0)/d, z = Bf/d``;
        with unequal focal lengths ``y`` carries the factor ``fx / fy``.

        Raises
        ------
        ValueError
            If a disparity is not > 0 (a point at infinity or behind the rig has no 3-D position).
        """
        w = as_match_array("w", w)
        d = _positive_rows(w[:, 2], "w[:, 2] (disparity) must be > 0 to back-project; row {} has d={}")
        scale = self.baseline / d
        x, y = scale * (w[:, 0] - self.cx), scale * (w[:, 1] - self.cy) * (self.fx / self.fy)
        return np.column_stack([x, y, scale * self.fx])

    def depth_from_disparity(self, d):
        """Depth ``z = fx * B / d`` of disparities ``d`` in pixels; ``d`` must be > 0."""
        d = np.asarray(d, dtype=float)
        if np.any(d <= 0):
            raise ValueError("d (disparity) must be > 0 to give a depth")
        return self.fx * self.baseline / d

    def in_image(self, w, margin: float = 0.0) -> np.ndarray:
        """Boolean mask of ``w`` rows whose left pixel lies ``margin`` pixels inside the image."""
        self._require_size("in_image()")
        u, v = np.asarray(w, dtype=float)[:, :2].T
        across = (u >= margin) & (u <= self.width - 1 - margin)
        return across & (v >= margin) & (v <= self.height - 1 - margin)


@dataclass(frozen=True)
class Rectification:
    """The undistort-and-rectify maps of a stereo pair, the rectified cameras' projection matrices
    and image ``size``, the rectified left camera's pose in the body frame (``T_body_rect``), and
    the share of each raw image that its rectified image shows (:func:`_sampled_share`)."""

    left_maps: tuple[np.ndarray, np.ndarray]
    right_maps: tuple[np.ndarray, np.ndarray]
    projections: tuple[np.ndarray, np.ndarray]
    size: tuple[int, int]
    T_body_rect: np.ndarray
    valid_shares: tuple[float, float]

    @cached_property
    def camera(self) -> StereoCamera:
        """The rectified rig; ``ValueError`` where the right camera is not to the right of the left."""
        return StereoCamera.from_projection_matrices(*self.projections, *self.size)

    def __call__(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Both images undistorted and rectified (bilinear)."""
        return (
            cv2.remap(left, *self.left_maps, cv2.INTER_LINEAR),
            cv2.remap(right, *self.right_maps, cv2.INTER_LINEAR),
        )


def rectify_stereo(
    left, right, size: tuple[int, int], T_right_left, T_body_left, fisheye: bool = False
) -> Rectification:
    """OpenCV's rectification of a calibrated pair (``stereoRectify`` with zero disparity at
    infinity, ``alpha = 0``: only valid pixels) and its maps. Fisheye lenses get ``cv2.fisheye``'s
    rotations and a pinhole view of the left lens's own focal length, centred: the lens's
    resolution at the centre, and only the view a pinhole image can show.

    Parameters
    ----------
    left, right : tuple
        Each camera's ``(K, distortion)``: 3x3 intrinsics and radial-tangential ``[k1, k2, p1, p2]``
        (equidistant ``[k1, k2, k3, k4]`` with ``fisheye``).
    size : tuple of int
        ``(width, height)`` of both cameras' images.
    T_right_left : array_like, 4x4
        The left camera's coordinates into the right camera's.
    T_body_left : array_like, 4x4
        The left camera's coordinates into the body's.
    fisheye : bool
        Both cameras follow the equidistant (Kannala-Brandt) model of ``cv2.fisheye``.
    """
    T_right_left = np.asarray(T_right_left, float)
    R, t = np.ascontiguousarray(T_right_left[:3, :3]), T_right_left[:3, 3:].copy()
    if fisheye:
        R1, R2, *_ = cv2.fisheye.stereoRectify(*left, *right, size, R, t, flags=cv2.CALIB_ZERO_DISPARITY)
        f = float(np.sqrt(left[0][0, 0] * left[0][1, 1]))  # the lens's focal length, kept
        P1 = np.array(
            [[f, 0.0, (size[0] - 1) / 2, 0.0], [0.0, f, (size[1] - 1) / 2, 0.0], [0.0, 0.0, 1.0, 0.0]]
        )
        P2 = P1.copy()
        P2[0, 3] = -f * float(np.linalg.norm(t))  # the right camera a baseline along x
    else:
        R1, R2, P1, P2, *_ = cv2.stereoRectify(
            *left, *right, size, R, t, flags=cv2.CALIB_ZERO_DISPARITY, alpha=0.0
        )
    opencv, cameras = cv2.fisheye if fisheye else cv2, ((*left, R1, P1), (*right, R2, P2))
    shares = [_sampled_share(opencv, *camera, size) for camera in cameras]
    maps = [tuple(opencv.initUndistortRectifyMap(*camera, size, cv2.CV_16SC2)) for camera in cameras]
    T_body_rect = T_body_left @ rigid_matrix(R1.T, 0.0)  # R1.T: rectified -> raw left camera
    return Rectification(*maps, (P1, P2), size, T_body_rect, tuple(shares))


def undistorted_share(K, dist, size: tuple[int, int], fisheye: bool = False) -> float:
    """The share of a raw image that one camera shows once undistorted alone to a centred pinhole
    view of valid pixels only (as :func:`_sampled_share`, and as rectification would): low for a
    calibration that is not of its images."""
    K, dist, R = np.asarray(K, float), np.asarray(dist, float), np.eye(3)
    if fisheye:
        new = cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(K, dist, size, R, balance=0.0)
    else:
        new, _ = cv2.getOptimalNewCameraMatrix(K, dist, size, 0.0, size, centerPrincipalPoint=True)
    P = np.hstack([new, np.zeros((3, 1))])
    return _sampled_share(cv2.fisheye if fisheye else cv2, K, dist, R, P, size)


def _sampled_share(opencv, K, dist, R_rect, P, size: tuple[int, int]) -> float:
    """The share of a raw image that its rectified image shows: the rectified pixels that fall
    inside it, times the part of it their bounding box spans (a sliver when the calibration is
    not of the images, or when its principal point sits by a corner)."""
    x, y = opencv.initUndistortRectifyMap(K, dist, R_rect, P, size, cv2.CV_32FC1)
    inside = (x >= 0) & (x <= size[0] - 1) & (y >= 0) & (y <= size[1] - 1)
    if not inside.any():
        return 0.0
    span = np.ptp(x[inside]) * np.ptp(y[inside]) / ((size[0] - 1) * (size[1] - 1))
    return float(inside.mean() * span)
