"""vo_lib: the tested algorithms behind the vo-notebooks collection.

Modules follow the flow of data, world -> sensors -> front end -> estimators -> evaluation ->
plotting; each does one job and cites the paper equations it implements.

``geometry``         frames, planar poses, angle wrapping (the conventions)
``camera``           rectified stereo camera, pixels + disparity <-> points (seed 000, eq. 13)
``odometry``         crawler track odometry and its covariance (seed 000, eq. 2-11)
``circular_motion``  planar circular-motion model (seed 000, eq. 12-17)
``synthetic``        matches with known truth, for checks
``textures``, ``world``   corner-rich textures; floor plans of segments shared by every sensor
``render``           rectified stereo pairs with ground-truth depth
``laser``            2-D laser scanner
``trajectories``     crawler drives with track slip
``sequence``, ``samples``, ``data``   KITTI-layout I/O, the named samples, load_sequence
``features``         stereo front end (FAST, ORB descriptors, row matching)
``temporal``         frame-to-frame matching guided by the filter's prediction
``ransac``           1-point RANSAC (seed 000, eq. 18-21)
``ransac_core``      its compiled core (Numba)
``baselines``        3-point rigid RANSAC, solvePnPRansac, 5-point essential matrix
``kalman``           odometry + VO Kalman filter on filterpy
``pipeline``         the whole stereo VO of seed 000, frame by frame
``evaluation``       ATE, RPE, KITTI segment errors, the paper's statistics
``run``, ``bench``   the command line: run, evaluate, generate, bench
``disturbances``     blank, noisy and occluded frames
``bicycle``, ``range_bearing``   seed 002's car (eq. 4-7) and laser observation (eq. 8-12)
``line_landmarks``, ``segment_observers``   walls as feature points; their visible parts
``ekf_slam``, ``line_slam``   EKF-SLAM with Mahalanobis association (eq. 13); the paper's lap
``likelihood_field``, ``pose_tracking``   laser scoring; LBPT and VOAPT (seed 004, eq. 8-23)
``pnp_odometry``     seed 004's visual odometer (eq. 1-7)
``corridor_experiment``   the occluded corridor, LBPT against VOAPT (Table III)
``plotting``         figures for the notebooks
``widgets``          interactive wrappers for the notebooks
"""

__version__ = "0.1.0"
