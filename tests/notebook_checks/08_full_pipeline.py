"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: lab = SAMPLES["indoor_linear"]
# sub-pixel motion, the premise of keyframes: the bound is the pixel itself, not a margin
assert disparity_change < 1.0 and below_pixel > 0.5

# after: result, truth, _ = run("indoor_linear", 60
# a clean, well-textured start: no frame needs the fallback, and the pose stays on the truth
assert len(result.flagged) == 0 and end_error < 0.01 * travelled_60
assert {"stereo", "matching", "estimation", "kalman"} <= set(result.timing_table())

# after: n_table = frames_for("indoor_linear", 40, FULL)
# the painted lab does not fill the cap: every step down in resolution loses features
counts = np.array([t["features"] for t in measured.values()])
assert np.all(np.diff(counts) < 0) and counts[-1] < 0.6 * counts[0]

# after: n_lin = SAMPLES["indoor_linear"].frames  # forward and back needs the whole drive
assert relative <= 0.01  # a bound of our own, a fifth of the paper's 5 % (both printed)

# after: n_out = frames_for("outdoor_linear", 200, FULL)
assert relative_o < 0.05  # our own target: the paper's indoor bound

# after: n_spot = frames_for("spot_turn", 300, FULL)
# the encoders count the slip as turning; vision, alone or fused, ends far closer
assert spot_errors["fused"][-1] < spot_errors["odometry"][-1] / 2
assert spot_errors["vision"][-1] < spot_errors["odometry"][-1] / 2

# after: stored = paper_sets.load()["sets"]
# the sentences after this cell: in RMS both sets lie below the paper's; odometry alone far above both
assert all(rms_of(stored, n, "theta_deg") < rms_of(stored, n, "theta_deg", "paper") for n in spot_sets)
odometry_over_paper = [
    rms_of(stored, n, "theta_deg", "odometry") / rms_of(stored, n, "theta_deg", "paper") for n in spot_sets
]
# "far above": at least three times the paper's
assert min(odometry_over_paper) > 3
assert flag_share["spot_turn"] > flag_share["spot_turn_2"]  # the clause "yet the second ..."
assert rms_of(stored, "spot_turn_2", "theta_deg") > rms_of(stored, "spot_turn", "theta_deg")

# after: free_sets = ("indoor_free", "outdoor_free", "outdoor_free_2", "outdoor_free_3", "outdoor_linear")
# each clause of the sentences above
assert indoor_rms.count(" / ") == 3  # the sentence gives all three figures, fused and odometry alone
assert all(ratio[("indoor_free", q)] > 1 for q in QUANTITIES)

# after: study = paper_sets.load()["contradictions"]
from vo_lib.comparison import Verdict

assert heading_cmp.verdict(believed, "never believes") is Verdict.BETTER  # the setting's reason

# after: fusion = paper_sets.load()["fusion"]
# the held-out verdict on the setting names every drive once, and the preset is the setting judged
named = [n for names in outcome.values() for n in names]
assert set(named) == set(fusion["sets"])
assert study["limit"] == CRAWLER.max_contradictions

# after: key_theta, key_rho = math.radians(1.5), 0.04
assert abs(slip_bias[5.0]) > 3 * abs(slip_bias[1.0]) > 0  # grows with the sideslip
assert 1.0 < np.median(sideslip_deg) < 10.0
