"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: crawler_speed, sample_rate, tight_radius = 0.3, 30.0, 1.0
assert crawler_excess < 1e-3 * encoder_step_sigma  # "negligible": a thousandth of the noise

# after: runs, steps = 3000, 300
assert P_eq9[1, 1] < 0.3 * mc_cov[1, 1]  # eq. 9 badly under-states the lateral uncertainty
assert np.all(lateral[99:, 2] < 0.2 * lateral[99:, 0])  # by a factor above 5 from the first metre on

# after: study = dead_reckoning_seeds(
# a covariance to a few per cent, of the order of the cloud's own sampling error
assert np.median(relative) < 2.5 * np.median(sampling) and np.mean(relative < 0.05) >= 0.8
assert np.all(np.abs(spread / models - 1) < 0.1)  # the clouds spread as the full model says
assert runs == 3000 and odo.encoder_sigma == 0.01 and checkpoints == (100, 200, 300)  # as the text says
