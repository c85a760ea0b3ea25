"""Seed 000: stereo visual odometry for a crawler robot, fused with its track odometry.

Read in the order a frame is processed (``pipeline`` strings them together):

``features``          stereo front end: FAST corners, binary descriptors, row matching (III.A.1)
``circular_motion``   the planar circular-motion model, theta and rho from pixels (eq. 12-17)
``temporal``          frame-to-frame matching guided by the filter's prediction
``ransac``            1-point RANSAC with its gates and refinement (eq. 18-21);
``ransac_core``       its compiled (Numba) core
``kalman``            the Kalman filter fusing track odometry (eq. 2-11, in
                      ``vo_lib.models.track_odometry``) with the visual motion
``pipeline``          the whole method, frame by frame (Fig. 3); start reading here
``baselines``         3-point rigid RANSAC, solvePnPRansac, 5-point essential matrix
``synthetic``         matches under a known circular motion, for exact checks

The command ``python -m vo_lib run`` runs ``pipeline`` on a sequence.
"""
