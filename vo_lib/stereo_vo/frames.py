"""What the pipeline records per frame: diagnostics, timings, and the result of a whole run."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np


@dataclass
class FrameDiagnostics:
    """What happened to one frame."""

    frame: int
    features: int = 0
    temporal_matches: int = 0
    inliers: int = 0
    inlier_ratio: float = 0.0
    ransac_inliers: int = 0  # 6-DoF motion: 1-point RANSAC's, before the refinement
    theta: float = float("nan")
    rho: float = float("nan")
    odometry: bool = False
    fallback: bool = False
    reason: str = ""


@dataclass
class FrameTimings:
    """Milliseconds per stage (the columns of the paper's Table 1, plus matching)."""

    stereo: float = 0.0
    prediction: float = 0.0
    matching: float = 0.0
    estimation: float = 0.0
    refinement: float = 0.0  # 6-DoF refinement (the car's preset only)
    kalman: float = 0.0
    total: float = 0.0


@dataclass
class PipelineResult:
    """One planar pose (and covariance) per frame, with diagnostics and timings; with the 6-DoF
    motion model also each frame's camera pose (``camera_poses``, in frame 0's camera)."""

    poses: np.ndarray
    covariances: np.ndarray
    diagnostics: list[FrameDiagnostics] = field(default_factory=list)
    timings: list[FrameTimings] = field(default_factory=list)
    camera_poses: np.ndarray | None = None

    @property
    def flagged(self) -> np.ndarray:
        """Indices of frames whose VO motion was not used."""
        return np.array([d.frame for d in self.diagnostics if d.fallback], dtype=int)

    def timing_table(self) -> dict[str, float]:
        """Median milliseconds of each stage over the frames after the first."""
        rows = self.timings[1:] or self.timings
        return {k: float(np.median([asdict(t)[k] for t in rows])) for k in asdict(rows[0])}
