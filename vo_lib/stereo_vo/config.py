"""The settings of the stereo VO pipeline, as one frozen structure, and its presets.

:data:`CRAWLER` is the paper's robot [Zhao], :data:`CAR` a car on a real road (KITTI),
:data:`HOVER` a drone or hand-held rig. Sweep a setting with
``dataclasses.replace(CRAWLER, key_distance=0.08)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from scipy.stats import chi2

from vo_lib.stereo_vo.frames import LOST_REFERENCE, Reason
from vo_lib.stereo_vo.ransac import RansacParams
from vo_lib.stereo_vo.rigid_motion import MIN_INLIERS

FRONT_ENDS = ("fast", "pyramid")
MOTIONS = ("planar", "full")


@dataclass(frozen=True)
class PipelineConfig:
    """Every choice of :class:`~vo_lib.stereo_vo.pipeline.StereoOdometry` that is a number or a name."""

    #: ``"fast"``: single-scale FAST corners; ``"pyramid"``: two scales, for a car's large image motion.
    front_end: str = "fast"
    #: ``"planar"``: circular motion (eq. 12-17); ``"full"``: then a 6-DoF refinement (``six_dof``).
    motion: str = "planar"
    ransac: RansacParams = field(default_factory=RansacParams)
    #: track the matched corners to sub-pixel positions in the current image (6-DoF motion only)
    subpixel_tracking: bool = False
    #: 6-DoF motion: 1-point RANSAC's planar hypotheses first, a general 3-point RANSAC where they
    #: keep too few matches; False: the general one alone (a body free in six degrees of freedom).
    planar_hypotheses: bool = True
    min_features: int = 20  #: stereo features a frame needs to be matched
    min_inliers: int = 15
    #: Of the temporal matches; a large moving object drags it down (6-DoF: the 1-point RANSAC's).
    min_inlier_ratio: float = 0.7
    #: The same on a frame's last attempt, matched without windows (None: ``min_inlier_ratio``).
    last_attempt_ratio: float | None = None
    prior_gate: float = float(chi2.ppf(0.9999, 2))  #: VO motion against the prediction (Mahalanobis^2)
    #: Consecutive frames the prior gate may reject before the vision is believed over the prediction:
    #: chosen on draws of the rendered ``outdoor_free_3`` drive, judged on held-out drives (notebook 08).
    max_contradictions: float = 2
    recent_frames: int = 15  #: good frames whose match and inlier counts make the recent medians
    #: Guided matching below this fraction of the recent median is retried ``retry_widening`` wider.
    retry_fraction: float = 0.8
    retry_widening: float = 4.0
    #: Keyframes: frames are measured against a reference until the motion since it is this large
    #: (metres of chord, radians), so that sub-pixel errors are small against it ...
    key_distance: float = 0.04
    key_angle: float = math.radians(1.5)
    #: ... or the inliers fall below this fraction of the first frame's against the reference.
    key_inlier_fraction: float = 0.75
    key_max_gap: int = 12  #: frame intervals (frames, unless frames were dropped)
    #: Factors applied element by element to the estimator's covariance before the filter: corners
    #: on whole pixels and sub-pixel motion make theta's spread about 1.2x and rho's 2.7x the
    #: least-squares figure on the rendered indoor samples (notebook 08); the diagonal only.
    vo_covariance_scale: tuple = ((1.5**2, 0.0), (0.0, 3.0**2))
    #: A frame whose inliers fall below this fraction of the recent median has lost part of its
    #: view to something moving (0: not checked) ...
    lost_view_fraction: float = 0.6
    #: ... unless the drop lasts this many frames: then it is the new normal (a changed scene).
    lost_view_patience: int = 15
    #: After this many frame intervals without a good frame (for one of ``restart_reasons``, or any
    #: when empty), the current frame becomes the reference.
    restart_gap: int = 90
    restart_reasons: frozenset[Reason] = frozenset()
    #: Counts measured right after frames without vision are not typical of the next ones.
    typical_counts_only: bool = True
    #: Sideways motion per metre travelled that the odometry cannot see (``kalman``).
    lateral_sigma: float = 0.0
    #: Uncertainty (x, y metres; yaw radians) added to the prediction while nothing predicts the
    #: motion; empty: none.
    unknown_motion_sigma: tuple = ()

    def __post_init__(self):
        for name, allowed in (("front_end", FRONT_ENDS), ("motion", MOTIONS)):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}; got {getattr(self, name)!r}")
        try:  # a misspelt reason would silently disable the restart rule: refuse it
            reasons = frozenset(Reason(r) for r in self.restart_reasons)
        except ValueError as exc:
            known = ", ".join(repr(r.value) for r in Reason if r is not Reason.NONE)
            raise ValueError(f"restart_reasons: {exc}; expected some of {known}") from None
        object.__setattr__(self, "restart_reasons", reasons)


#: The paper's crawler: single-scale FAST, planar model, track odometry.
CRAWLER = PipelineConfig()

#: A car on a real road: two-scale front end, turning-axis virtual camera, 6-DoF refinement.
CAR = PipelineConfig(
    front_end="pyramid",
    motion="full",
    ransac=RansacParams(pixel_sigma=1.0),
    min_inlier_ratio=0.5,
    recent_frames=10,
    retry_fraction=0.6,
    retry_widening=3.0,
    # a standing car keeps its reference, so that it does not drift while it waits
    key_distance=0.05,
    key_angle=math.radians(1.0),
    key_inlier_fraction=0.0,
    key_max_gap=10,
    # the residuals of real matches are neither independent nor Gaussian
    vo_covariance_scale=((2.0**2,) * 3,) * 3,
    lost_view_fraction=0.0,
    restart_gap=2,
    restart_reasons=LOST_REFERENCE,
    typical_counts_only=False,
    # a car's odometry frame is aligned with its direction of travel only to a fraction of a
    # degree; a tight value lets the odometry's zero sideways motion overrule the vision's
    # heading through their correlation. At 5 % the sideways motion is the vision's.
    lateral_sigma=0.05,
    unknown_motion_sigma=(10.0, 10.0, 1.0),
)

#: A camera free in six degrees of freedom without odometry (a drone, a hand-held rig): the car's
#: settings, but the constant-velocity prediction never vetoes the vision (a hovering body's turns
#: and stops break it), general 3-point hypotheses, a keyframe also at the crawler's inlier
#: fraction (pitch and roll turn the view away without yaw or chord), and a motion counts on as
#: few inliers as the refinement accepts, with no inlier ratio on the last attempt: in a fast
#: turn a motion measured on few matches beats the last one repeated.
HOVER = replace(
    CAR,
    prior_gate=math.inf,
    subpixel_tracking=True,
    planar_hypotheses=False,
    key_inlier_fraction=CRAWLER.key_inlier_fraction,
    min_inliers=MIN_INLIERS,
    last_attempt_ratio=0.0,
)

PRESETS = {"planar": CRAWLER, "full": CAR, "hover": HOVER}
