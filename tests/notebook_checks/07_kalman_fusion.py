"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: SEEDS = range(SEED, SEED + STUDY_SEEDS)
from vo_lib.comparison import Verdict

# the claims of the next cell's explanation, each over the seeds
assert heading_cmp["spot turn"].verdict("fused", "odometry") is Verdict.BETTER
assert position_cmp["indoor"].verdict("fused", "odometry") is Verdict.BETTER
assert heading_cmp["spot turn"].verdict("fused", "VO") is not Verdict.BETTER  # the slip's mean leaks in
assert all(abs(heading_cmp[c].difference("fused", "VO")[0]) < 0.05 for c in ("spot turn", "indoor"))
assert position_cmp["indoor, weak vision"].verdict("fused", "VO") is Verdict.BETTER
assert position_cmp["spot turn, weak vision"].verdict("fused", "VO") is Verdict.BETTER
assert heading_cmp["spot turn, weak vision"].verdict("fused", "VO") is Verdict.WORSE
assert heading_cmp["spot turn, VO outage"].verdict("fused", "VO") is Verdict.WORSE
assert fused_vo < 0.1  # "a few hundredths of a degree at most", as sampled, in every seed

# after: "The slip-calibrated filter against the plain one, in heading: "
from vo_lib.comparison import Verdict

assert heading_cmp["spot turn, weak vision"].verdict("calibrated", "fused") is Verdict.BETTER
assert heading_cmp["spot turn, VO outage"].verdict("calibrated", "fused") is Verdict.BETTER
assert position_cmp["indoor, weak vision"].verdict("calibrated", "fused") is Verdict.WORSE
assert position_cmp["indoor"].verdict("calibrated", "fused") is Verdict.WORSE
# the clause "more with weak vision" of the next cell
cost = {c: position_cmp[c].difference("calibrated", "fused")[0] for c in ("indoor", "indoor, weak vision")}
assert cost["indoor, weak vision"] > cost["indoor"]

# after: scale_sigma = {c: np.median([d["scale_sigma"] for d in draws[c].values()]) for c in CONDITIONS}
# the clause "about as much as the slip": indoors with weak vision the scale's σ reaches the 1 % slip
assert (
    0.5 * SAMPLES["indoor_free"].slip.mean
    < scale_sigma["indoor, weak vision"]
    < 2 * SAMPLES["indoor_free"].slip.mean
)
assert scale_sigma["spot turn, weak vision"] < 0.5 * SAMPLES["spot_turn"].slip.spot_turn_mean

# after: nees_rows = {}
assert nees_rows[("spot turn", "fused")][1] > 3  # the clause "over-confident" of the spot turn

# after: gap_run = run_drive("spot_turn", 400, seed=SEED, outage=set(range(200, 261)))
assert len(flagged) == 61 and yaw_sigma[260] > 5 * yaw_sigma[199]
# after the gap the growth all but stops
assert yaw_sigma[300] - yaw_sigma[260] < 0.1 * (yaw_sigma[260] - yaw_sigma[199])

# after: "constant velocity without the sideways row",
from vo_book.demo_fusion import STATED, STUDY_COMPARISONS

# every comparison section 4 states, and every NEES verdict, is one of the family its intervals
# were widened for
assert len(STATED) == STUDY_COMPARISONS and len(nees_rows) == STUDY_FAMILY - STUDY_COMPARISONS
