"""What the pipeline records per frame: why a frame's vision was not used, diagnostics, timings
(and the stopwatch that takes them), and the result of a whole run."""

from __future__ import annotations

import enum
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field

import numpy as np


class Reason(str, enum.Enum):
    """Why a frame's VO motion was not used (:attr:`NONE`: it was), as the diagnostics print it."""

    NONE = ""
    NO_REFERENCE = "no reference frame with features"
    FEW_FEATURES = "too few stereo features"
    FEW_MATCHES = "too few temporal matches"
    FEW_INLIERS = "too few inliers"
    LOW_INLIER_RATIO = "low inlier ratio"
    CONTRADICTS_PREDICTION = "motion contradicts the prediction"
    VIEW_LOST = "part of the view lost (occluder or moving object)"
    REPEATED = "the images of the frame before, repeated"

    def __str__(self) -> str:  # the sentence, on Python 3.10 too (no enum.StrEnum there)
        return self.value


#: Reasons that say the reference frame no longer shares enough of the view with this one.
LOST_REFERENCE = frozenset({Reason.FEW_MATCHES, Reason.FEW_INLIERS, Reason.LOW_INLIER_RATIO})


class Stopwatch:
    """Milliseconds per named stage: ``with watch("stereo"): ...`` adds the block's time to
    ``watch.ms["stereo"]``; :meth:`total` is the time since the watch was made."""

    def __init__(self) -> None:
        self.ms: dict[str, float] = {}
        self._start = time.perf_counter()

    @contextmanager
    def __call__(self, stage: str) -> Iterator[None]:
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.ms[stage] = self.ms.get(stage, 0.0) + (time.perf_counter() - t0) * 1e3

    def total(self) -> float:
        return (time.perf_counter() - self._start) * 1e3


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
    reason: Reason = Reason.NONE


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
