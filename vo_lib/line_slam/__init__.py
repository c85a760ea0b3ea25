"""[Yan 2020]: EKF-SLAM with line-segment landmarks seen by a simulated laser, whose visible part
is found by bisection instead of point by point.

``range_bearing``       range-bearing observation of a point and its inverse (eq. 8-12)
``line_landmarks``      wall segments of the shared world as "landmark feature points"
``line_observation``    the paper's observation of a segment (distance, start and end angles) and
                        the line measurement built from the visible part's end points
``segment_observers``   the visible part of a segment: closed form, point by point, bisection
``ekf_slam``            the filter: bicycle prediction (``vo_lib.models.bicycle``, eq. 4-7),
                        feature-point or line updates, Mahalanobis association (eq. 13), augmentation
``lap``                 the paper's simulation, one lap with the stated parameters (start here);
                        ``python -m vo_lib sweep lap`` runs its figures over many seeds
"""
