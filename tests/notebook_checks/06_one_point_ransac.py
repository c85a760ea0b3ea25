"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: many = synthetic_matches(camera, 3000, theta_true
assert ill_ratio > 10 and all(np.diff(band_median) < 0)  # worse the nearer, every band

# after: naive_sets = []
from vo_lib.comparison import Verdict

assert naive_rows[0, 2] < 0.5 and naive_rows[-1, 3] < 0.8
assert naive_cmp.verdict("the full estimator", "the naive one") is Verdict.BETTER

# after: GOOD_HYPOTHESIS = math.radians(0.05)
assert w_all < w_true and w_pool > w_all  # the effective ratio is below the true one; the pool lifts it

# after: def theta_support(values, variances, h, var_h):
# one match's own θ: within a few times the 0.08° typical of well-conditioned matches (section 4)
assert abs(theta_h - theta_true) < math.radians(0.25) and tried_theta <= hypotheses_needed(0.5)

# after: def weighted_mean(values, variances, mask):
assert var_theta_hat < var_h and abs(theta_hat - theta_true) < abs(theta_h - theta_true) + 1e-12

# after: def rho_per_match(wa, wb, theta):
assert abs(rho_hat - rho_true) < 0.1 * rho_true  # before the refinement of step 5

# after: rungs = list(LADDER)
from vo_lib.comparison import Verdict

assert ladder_theta.verdict(full, paper) is Verdict.BETTER
assert ladder_rho.verdict(full, paper) is Verdict.BETTER
assert ladder_theta.verdict(full, "+ adaptive N_h") is Verdict.BETTER  # the refinement is the step that pays
assert ladder_rho.verdict(full, "+ adaptive N_h") is Verdict.BETTER

# after: good_share = {"all": [], "pool": []}
from vo_lib.comparison import Verdict

assert pool_cmp.verdict("the pool", "all matches") is Verdict.BETTER

# after: ADAPTIVE_SEEDS = range(SEED + 3000, SEED + 3020)
assert max(adaptive_tried_ladder) == hypotheses_needed(0.5, CONFIDENCE) < hypotheses_needed(w_pool)
assert np.mean(adaptive_tried[True]) > np.mean(adaptive_tried[False])  # "does draw more"

# after: NEES_SEEDS = range(SEED + 4000, SEED + 4400)
assert tb[1] > band[1]  # over-confident: the whole seed interval above the band
assert sc[0] < tb[0] and np.median(gate_widening) < 0.05  # scaling helps; the gate hardly feels θ̂'s variance
assert orc[2] < tb[1]  # the cause: without the outliers among the supporters, far nearer the band
assert rf[1] > band[1]  # what leaves the estimator: the refined variance, over-confident too

# after: for seed in range(SEED, SEED + 60):
assert rows[:, 0].min() >= 0.95 and math.degrees(rows[:, 1].max()) <= 0.03
assert np.median(rows[:, 2]) <= 0.015 and rows[:, 2].max() <= 0.05

# after: real_rows = []
assert real_rows[:, 0].min() >= 0.9 and math.degrees(real_rows[:, 2].max()) <= 0.04

# after: methods = {
from vo_lib.comparison import Verdict

# what holds at every base seed tried: better than the rigid and essential estimators in θ, and
# never reliably worse than PnP, which minimises reprojection errors as our refinement does
rigid_and_essential = ("3-point rigid RANSAC", "5-point essential")
assert all(base_theta.verdict(ours, other) is Verdict.BETTER for other in rigid_and_essential)
assert base_theta.verdict(ours, "solvePnPRansac") is not Verdict.WORSE
