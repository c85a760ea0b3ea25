"""[Yuan]: LIDAR pose tracking assisted by visual odometry (VOAPT).

``likelihood_field``      occupancy grid, likelihood field, scoring of sample poses (III.A)
``pose_tracking``         LBPT and VOAPT: score statistics and ``C_s`` (eq. 11-13), control
                          limits (eq. 14-16), PCA error direction (eq. 17-20), compensation with
                          the visual displacement (eq. 21-23)
``pnp_odometry``          the paper's visual odometer: ORB landmarks, PnP, local map (eq. 1-7)
``corridor_experiment``   the occluded corridor, LBPT against VOAPT (Table III); start here;
                          ``python -m vo_lib sweep corridor`` runs it over many seeds

The one wing that may import ``vo_lib.stereo_vo`` (``pnp_odometry`` uses [Zhao]'s stereo front
end), as the contract in ``pyproject.toml`` states.
"""
