"""[Zhao]: stereo visual odometry for a crawler robot, fused with its track odometry.

Read in the order a frame is processed (``pipeline`` strings the parts of ``parts`` together):

``features``          stereo front end: FAST corners, binary descriptors, row matching (III.A.1)
``pyramid_features``  the same at two scales, for the large image motion of a car
``circular_motion``   the planar circular-motion model, theta and rho from pixels (eq. 12-17)
``temporal``          frame-to-frame matching guided by the filter's prediction
``ransac``            1-point RANSAC with its gates and settings (eq. 18-21)
``refinement``        its last step: (theta, rho) by least squares on the inliers, eq. 21 whitened
``rigid_motion``      6-DoF motion refined on reprojection errors, SE(3) log and exp,
                      general 3-point RANSAC
``matching_plain``    candidate search and best matches in NumPy, the reference
``matching_core``     the same compiled (Numba), which the front end runs
``kalman``            the Kalman filter fusing track odometry (eq. 2-11, in
                      ``vo_lib.models.track_odometry``) with the visual motion
``parts``             the interfaces of the pipeline's parts (front end, motion model)
``planar_motion``     the paper's motion model as a part: prediction, matching, 1-point RANSAC
``six_dof``           a car's motion model as a part: turning-axis view, 6-DoF refinement
``vehicle``           what carries the camera: mount, odometry, which motion model fits
``config``            every setting of the pipeline, one frozen ``PipelineConfig``; the
                      ``CRAWLER`` and ``CAR`` presets
``frames``            what the pipeline records per frame, and a run's result
``pipeline``          the whole method, frame by frame (Fig. 3); start reading here
``run_report``        the tables of a run: time per stage, errors in 3-D, planar ones labelled
``baselines``         3-point rigid RANSAC, solvePnPRansac, 5-point essential matrix; a PnP
                      visual odometry to time the pipeline against on real data
``synthetic``         matches under a known circular motion, for exact checks
``paper_sets``        the paper's outdoor and spot-turn sets at full length, run once and stored

The command ``python -m vo_lib run`` runs ``pipeline`` on a sequence.
"""
