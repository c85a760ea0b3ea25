"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: turn_camera, turn_mount = seq.camera, vehicle.mount
assert recall_table[~planar_rows][0, 3] < 0.1  # a 1° pitch: no planar hypothesis fits...
assert np.all(recall_table[:, 4] < 0.01)  # ...yet every motion is found to 1 cm

# after: diag = [d for d in vo_full.diagnostics if d.ransac_inliers > 0]
assert np.median(share) < 1.0  # the general model is stricter than the gates
assert np.all(refined_in[[not d.fallback for d in diag]] >= CAR.min_inliers)

# after: odometry_only = vehicle.odometry_model.integrate(vehicle.odometry[1:])
assert final["fused"][0] < share * final["odometry only"][0]
assert final["VO only"][0] < share * final["odometry only"][0]

# after: n_pnp = len(seq) if REAL else 20  # the rendered sample only shows the timing
assert np.all(np.isfinite(pnp.camera_poses)) and len(pnp.milliseconds) == n_pnp
