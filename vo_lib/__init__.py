"""vo_lib: the tested algorithms behind the vo-notebooks collection.

Modules follow the flow of data, world -> sensors -> front end -> estimators -> evaluation ->
plotting; each does one job and cites the paper equations it implements.

``geometry``         frames, planar poses, angle wrapping (the conventions)
``camera``           rectified stereo camera, pixels + disparity <-> points (seed 000, eq. 13)
``odometry``         crawler track odometry and its covariance (seed 000, eq. 2-11)
``circular_motion``  planar circular-motion model (seed 000, eq. 12-17)
``synthetic``        matches with known truth, for checks
``plotting``         figures for the notebooks
``widgets``          interactive wrappers for the notebooks
"""

__version__ = "0.1.0"
