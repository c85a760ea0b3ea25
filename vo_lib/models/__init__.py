"""Motion models shared by the simulation and the estimators.

``track_odometry``   crawler track odometry and its covariance ([Zhao], eq. 2-11):
                     :class:`~vo_lib.models.track_odometry.TrackOdometry`
``bicycle``          the front-wheel-steered car of [Yan 2020] (eq. 4-5, Jacobians eq. 6-7) and
                     its waypoint-following steering
"""
