"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: crawler_speed, sample_rate, tight_radius = 0.3, 30.0, 1.0
assert crawler_excess < 1e-3 * encoder_step_sigma  # "negligible": a thousandth of the noise

# after: runs, steps = 3000, 300
assert P_eq9[1, 1] < 0.3 * mc_cov[1, 1]  # eq. 9 badly under-states the lateral uncertainty
assert np.all(lateral[99:, 2] < 0.2 * lateral[99:, 0])  # by a factor above 5 from the first metre on
