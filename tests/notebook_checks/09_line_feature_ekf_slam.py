"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: gaps = judge("H", num_H, H, printed_H, subs_h)
# the printed landmark columns of the bearing row lie along the line of sight, the derived ones across it
assert sp.simplify(H[1, 3] * printed_H[1, 3] + H[1, 4] * printed_H[1, 4]) == 0
assert sp.simplify(H[1, 3] ** 2 + H[1, 4] ** 2) != 0

# after: ekf, z, true_index = association_example()
from vo_lib.line_slam.ekf_slam import GATE_ASSOCIATE, GATE_AUGMENT

assert ekf.associate([z], "euclidean")[0] != true_index == ekf.associate([z], "mahalanobis")[0]
assert abs(cov[0, 1]) < 1e-9 * cov[1, 1]
assert abs(offsets["B"][0]) / sigma_along > 5 and abs(offsets["A"][1]) / sigma_across < 1
assert GATE_ASSOCIATE < d2_printed["A"] < GATE_AUGMENT < d2_printed["B"]

# after: off_view = total = 0
assert off_view / total > 0.1

# after: world_x = paper_world(extended=True)
assert np.all((50 < rights_true) & (rights_true < 60))
assert 0.7 < metre_on - on_waypoint < 1.3
assert max(abs(v - right_true) for v in by_wheelbase.values()) < 0.05

# after: table1_bisection = [8.871066, 8.612084, 9.639981, 9.142181, 8.560958, 8.760142]
assert lap_ratio < 0.5 * paper_ratio  # outside the paper's range, as the text after this cell says

# after: LAP_SEEDS = range(SEED, SEED + 20)
from vo_lib.comparison import Verdict

assert slam_vs_dr.verdict("EKF-SLAM", "dead reckoning") is Verdict.BETTER

# after: laps_line = [simulate_lap(seed=s, scenario=LineSlamScenario(observation="line")) for s in LAP_SEEDS]
from vo_lib.comparison import Verdict

assert (
    over_seeds(lambda i: {"line": line_err[i], "dr": dr_err[i]}, range(len(laps))).verdict("line", "dr")
    is Verdict.BETTER
)
