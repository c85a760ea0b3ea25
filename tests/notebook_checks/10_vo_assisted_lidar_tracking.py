"""This notebook's measured claims, checked in its kernel after the cells named (tests/test_notebooks.py)."""

# after: offsets = np.linspace(-0.6, 0.6, 61)
for x in (9.0, 11.0):
    assert np.ptp(profiles[x]) < 0.5  # flat: nothing fixes the position along the corridor
for x in (3.0, 16.0, 23.0):
    assert np.ptp(profiles[x]) > 10 and abs(offsets[np.argmax(profiles[x])]) <= 0.03
assert np.all(np.diff(flat_here) < 0.15)  # one stretch
assert flat_positions(without_umbrella(world), field, offsets).size == 0

# after: rendered, frame_iter = render_sample("corridor", 200)
assert max(final_200.values()) < 0.03  # both within 3 cm after 10 m

# after: vo, vo_seconds = corridor_visual_odometry()
assert max(largest_share.values()) < 0.6  # each axis's largest deviation well under the paper's (one run)
# "within centimetres": the end within 0.3 % of the distance driven
assert np.hypot(*(vo[-1, :2] - truth0[-1, :2])) < 0.003 * np.hypot(*(truth0[-1, :2] - truth0[0, :2]))

# after: frame_stats, raw_scores = {}, {}
normal_frame, occluded_frame = frame_stats.values()
assert normal_frame.v_max > 2 * occluded_frame.v_max
# the boxes are flat: quartiles at a few per cent of the occluded frame's maximum at most (one frame each)
assert max(st.v_uq for st in frame_stats.values()) < 0.05 * occluded_frame.v_max

# after: scales = {
assert all(abs(s["d_s"] / s["v_max"] - 1) < 1e-3 for s in post)  # D_s is V_max on our scale
assert aucs["raw score"]["d_s"] > 0.95 and aucs["raw score"]["d_s_printed"] < 0.5
ours = aucs["posterior × n (ours)"]
assert ours["v_max"] == ours["d_s"] == ours["d_s_printed"]
every_printed10 = [s["v_max"] for g in (normal_stats, occluded_stats) for s in g["printed eq. 10 × n"]]
assert max(every_printed10) < 1.25 and printed10["normal"] / printed10["occluded"] < 1.1
assert posterior_vmax["normal"] / posterior_vmax["occluded"] > 3
assert np.all(eq11_aucs < 0.5)  # the summary's "worse than chance": in every scan of these seeds

# after: temperature_rows = {}
assert np.isclose(temperature_rows[1.0][0], posterior_vmax["normal"])  # T = 1: the reading above

# after: truth_c, odo_c = corridor_drive(1000)
assert abs(cal.thresholds.d_s - cal.thresholds.v_max) < 1e-3 * cal.thresholds.v_max  # C_s: D_s repeats V_max
assert laser_share < 1 and vo_share < 0.2  # "smaller", and for the visual odometer "a fraction"

# after: dirs = np.array([s.direction for s in voapt.steps if s.direction is not None])
assert np.mean(np.abs(dirs[:, 0])) > 0.95

# after: result = run_experiment(range(20), vo)
from vo_lib.comparison import Verdict

# the summary's "severalfold", averaged over the seeds
assert mx["VOAPT"][0] <= 0.3 * mx["LBPT"][0] and mn["VOAPT"][0] <= 0.2 * mn["LBPT"][0]
assert result.flagged_when_lost() >= 0.9 and result.false_alarms() <= 0.1
assert all(c.verdict("VOAPT", "LBPT") is Verdict.BETTER for c in by_seed.values())
assert 0.5 < mx["LBPT"][0] / paper[("LBPT", 0)][0] < 2  # our LBPT fails about as badly as the paper's
assert mx["VOAPT"][0] > paper[("VOAPT", 0)][0] and credible_in_occlusion > 0.05
assert y_share < 0.5  # our largest Y, averaged over seeds, under half the paper's *mean* VOAPT Y
assert 0 < voapt_worse < len(result.seeds) / 2  # the mean lowered "in most seeds but not all"
