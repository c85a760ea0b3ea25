import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vo_lib.evaluation import ate, ate_planar, key_position_errors, kitti_segment_errors, rpe, umeyama
from vo_lib.formats.groundtruth import read_trajectory
from vo_lib.formats.poses import write_kitti_poses, write_tum


def random_trajectory(rng, n=200):
    T = np.tile(np.eye(4), (n, 1, 1))
    yaw = np.cumsum(rng.normal(0, 0.02, n))
    T[:, :3, :3] = Rotation.from_euler("zyx", np.column_stack([yaw, rng.normal(0, 0.01, (n, 2))])).as_matrix()
    T[:, :3, 3] = np.cumsum(rng.normal(0, 0.1, (n, 3)) + [0.5, 0, 0], axis=0)
    return T


def perturb(rng, T):
    E = T.copy()
    E[:, :3, 3] += rng.normal(0, 0.05, (len(T), 3))
    E[:, :3, :3] = Rotation.from_rotvec(rng.normal(0, 0.01, (len(T), 3))).as_matrix() @ T[:, :3, :3]
    return E


def evo_trajectory(T):
    from evo.core.trajectory import PoseTrajectory3D

    return PoseTrajectory3D(poses_se3=list(T), timestamps=np.arange(len(T), dtype=float))


def test_ate_equals_evo(rng):
    from evo.core import metrics

    gt, est = random_trajectory(rng), None
    est = perturb(rng, gt)
    moved = est.copy()
    moved[:, :3, 3] = est[:, :3, 3] @ Rotation.from_euler("z", 0.7).as_matrix().T + [3, -2, 1]
    ours, _ = ate(gt, moved)
    traj_ref, traj_est = evo_trajectory(gt), evo_trajectory(moved)
    traj_est.align(traj_ref)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((traj_ref, traj_est))
    stats = ape.get_all_statistics()
    assert ours.rmse == pytest.approx(stats["rmse"], abs=1e-9)
    assert ours.max == pytest.approx(stats["max"], abs=1e-9)
    assert ours.median == pytest.approx(stats["median"], abs=1e-9)


@pytest.mark.parametrize("delta", [1, 10])
@pytest.mark.parametrize("rotation", [False, True])
def test_rpe_equals_evo(rng, delta, rotation):
    from evo.core import metrics

    gt = random_trajectory(rng)
    est = perturb(rng, gt)
    ours, _ = rpe(gt, est, delta=delta, rotation=rotation)
    relation = metrics.PoseRelation.rotation_angle_deg if rotation else metrics.PoseRelation.translation_part
    m = metrics.RPE(relation, delta=delta, delta_unit=metrics.Unit.frames, all_pairs=False)
    m.process_data((evo_trajectory(gt), evo_trajectory(est)))
    stats = m.get_all_statistics()
    assert ours.rmse == pytest.approx(stats["rmse"], abs=1e-9)
    assert ours.mean == pytest.approx(stats["mean"], abs=1e-9)


def test_perfect_estimate_has_zero_errors(rng):
    gt = random_trajectory(rng, 120)
    assert ate(gt, gt)[0].max < 1e-9 and rpe(gt, gt)[0].max < 1e-9
    seg = kitti_segment_errors(gt, gt, lengths=(5, 10), step=5)
    assert set(seg) == {5, 10} and all(v[0] < 1e-9 and v[1] < 1e-6 for v in seg.values())


def test_kitti_segments_scale_error():
    n = 101
    gt = np.tile(np.eye(4), (n, 1, 1))
    gt[:, 0, 3] = np.linspace(0, 10, n)  # 10 m straight
    est = gt.copy()
    est[:, 0, 3] *= 1.02  # 2 % too long
    seg = kitti_segment_errors(gt, est, lengths=(2, 5, 20))
    assert seg[2][0] == pytest.approx(2.0, rel=1e-6) and seg[5][0] == pytest.approx(2.0, rel=1e-6)
    assert 20 not in seg  # no segment that long


def test_planar_ate_and_key_positions():
    g = np.column_stack([np.linspace(0, 5, 50), np.zeros(50), np.zeros(50)])
    e = g.copy()
    e[:, 1] += 0.01
    e[:, 2] += np.radians(0.5)
    assert ate_planar(g, e, align=False)[0].mean == pytest.approx(0.01)
    assert ate_planar(g, e)[0].max < 1e-9
    stats = key_position_errors(g, e, [10, 20, 30])
    assert stats["y_mm"] == pytest.approx((10.0, 0.0)) and stats["theta_deg"] == pytest.approx((0.5, 0.0))


def test_umeyama_recovers_similarity(rng):
    src = rng.normal(size=(30, 3))
    R = Rotation.from_euler("xyz", [0.3, -0.2, 1.0]).as_matrix()
    R2, t2, s2 = umeyama(src, 2.5 * src @ R.T + [1, 2, 3], with_scale=True)
    np.testing.assert_allclose(R2, R, atol=1e-12)
    assert s2 == pytest.approx(2.5) and t2 == pytest.approx([1, 2, 3])


def test_files_round_trip(tmp_path, rng):
    T = random_trajectory(rng, 10)
    write_kitti_poses(tmp_path / "a.txt", T)
    write_tum(tmp_path / "a.tum", np.arange(10) * 0.1, T)
    _, k = read_trajectory(tmp_path / "a.txt")
    times, t = read_trajectory(tmp_path / "a.tum")
    np.testing.assert_allclose(k, T, atol=1e-8)
    np.testing.assert_allclose(t, T, atol=1e-8)
    assert times[3] == pytest.approx(0.3)
    (tmp_path / "bad.txt").write_text("1 2 3\n")
    with pytest.raises(
        ValueError, match=r"bad.txt, line 1: expected 12 numbers \(KITTI\), 8 \(TUM: .*\) or 4 .*, got 3"
    ):
        read_trajectory(tmp_path / "bad.txt")
    with pytest.raises(ValueError, match="ground truth has 10 poses but the estimate has 9"):
        ate(T, T[:9])


def test_rotation_angle_is_stable_at_every_angle(rng):
    """The angle equals scipy's rotation magnitude from 1e-9 rad to pi, where arccos of the trace
    loses half the digits near 0."""
    from vo_lib.evaluation import rotation_angle

    angles = np.concatenate([[1e-9, 1e-7, 1e-5, 1e-3], rng.uniform(0, np.pi, 50), [np.pi - 1e-7]])
    axes = rng.normal(size=(len(angles), 3))
    rotvec = angles[:, None] * axes / np.linalg.norm(axes, axis=1, keepdims=True)
    R = Rotation.from_rotvec(rotvec).as_matrix()
    np.testing.assert_allclose(rotation_angle(R), angles, rtol=1e-6, atol=1e-15)
    tiny = Rotation.from_rotvec([1e-9, 0, 0]).as_matrix()
    floor = np.arccos(np.clip((np.trace(tiny) - 1) / 2, -1, 1))  # the formula it replaces
    assert abs(rotation_angle(tiny) - 1e-9) < 1e-15 < abs(floor - 1e-9)


def drifted(rng, T, off=1.7e-5):
    """Poses whose rotations are off SO(3) by ``off``, as a long product of estimates drifts."""
    D = T.copy()
    D[:, :3, :3] += rng.normal(0, off, (len(T), 3, 3))
    return D


def test_a_trajectory_against_itself_in_the_other_format_has_no_error(tmp_path, rng):
    """KITTI and TUM files of one estimate (rotations not quite orthonormal) evaluate to at most
    1e-6 deg of rotation error against each other, both ways, as RPE and as segment errors."""
    T = drifted(rng, random_trajectory(rng, 120))
    write_kitti_poses(tmp_path / "poses.txt", T)
    write_tum(tmp_path / "trajectory.tum", np.arange(len(T)) / 10, T)
    _, K = read_trajectory(tmp_path / "poses.txt")
    _, Q = read_trajectory(tmp_path / "trajectory.tum")
    figures = {}
    for name, (a, b) in {"kitti-tum": (K, Q), "tum-kitti": (Q, K)}.items():
        r = rpe(a, b, rotation=True)[0]
        seg = kitti_segment_errors(a, b, (5, 10, 20))
        assert seg, "no segment fits"
        figures[name] = (r.max, max(s[1] for s in seg.values()))
        assert r.max <= 1e-6 and max(s[1] * length for length, s in seg.items()) <= 1e-6, figures
    np.testing.assert_allclose(figures["kitti-tum"], figures["tum-kitti"], atol=1e-9)
    rotations = K[:, :3, :3]
    np.testing.assert_allclose(
        rotations.transpose(0, 2, 1) @ rotations, np.broadcast_to(np.eye(3), rotations.shape), atol=3e-9
    )


def test_evaluate_prints_no_rotation_error_for_a_run_against_its_own_files(tmp_path, rng, capsys):
    from vo_lib.cli.main import main

    T = drifted(rng, random_trajectory(rng, 60))
    write_kitti_poses(tmp_path / "poses.txt", T)
    write_tum(tmp_path / "trajectory.tum", np.arange(len(T)) / 10, T)
    outputs = []
    for gt, est in (("poses.txt", "trajectory.tum"), ("trajectory.tum", "poses.txt")):
        args = ["evaluate", "--gt", str(tmp_path / gt), "--est", str(tmp_path / est), "--segments", "5"]
        assert main(args) == 0
        out = capsys.readouterr().out.splitlines()
        outputs.append([line for line in out if not line.startswith("--")])  # the notes on the files
    assert outputs[0] == outputs[1]  # the notes: a timestamped truth outside a recording, paired one to one
    outputs[0] = "\n".join(outputs[0])
    rows = {line[:62].strip(): line[62:].strip() for line in outputs[0].splitlines()}
    assert rows["RPE RMSE, 1 frame: rotation [deg]"] == "0.0000"
    assert rows["final rotation error, 3-D [deg]"] == "0.000"
    assert rows["KITTI rotation (5 m, 5 segments) [deg/100 m]"] == "0.000"


def test_evaluate_says_when_the_rpe_steps_span_unpaired_poses(tmp_path, rng, capsys):
    """A truth at half the estimate's rate pairs every second pose: the RPE's steps then span two."""
    from vo_lib.cli.main import main

    T = drifted(rng, random_trajectory(rng, 60))
    times = np.arange(len(T)) / 10
    write_tum(tmp_path / "est.tum", times, T)
    for name, every, note in (("full.tum", 1, False), ("half.tum", 2, True)):
        write_tum(tmp_path / name, times[::every], T[::every])
        assert main(["evaluate", "--gt", str(tmp_path / name), "--est", str(tmp_path / "est.tum")]) == 0
        out = capsys.readouterr().out
        assert ("29 of 29 span more than one estimated pose" in out) is note, out


def test_final_error_is_the_planar_end_point_against_the_planar_distance():
    from vo_lib.evaluation import final_error

    truth = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 4.0, np.pi / 2]])
    est = np.array([[0.0, 0.0, 0.0], [3.0, 0.1, 0.0], [3.3, 4.4, np.pi / 2 + np.radians(179.0) * 2]])
    final = final_error(truth, est)
    assert final.distance_m == pytest.approx(7.0)
    assert final.position_m == pytest.approx(0.5) and final.percent == pytest.approx(100 * 0.5 / 7.0)
    assert final.heading_deg == pytest.approx(2.0)  # 358 deg of turn is 2 deg off, wrapped
    assert np.isnan(final_error(truth[:1].repeat(2, axis=0), est[:2]).percent)


def test_sim3_ate_equals_evo_and_recovers_the_scale(rng):
    from evo.core import metrics

    from vo_lib.evaluation import Alignment

    gt = random_trajectory(rng)
    est = perturb(rng, gt)
    est[:, :3, 3] = 0.8 * est[:, :3, 3] @ Rotation.from_euler("zyx", [0.4, 0.1, -0.2]).as_matrix().T + [
        1,
        2,
        3,
    ]
    ours, _ = ate(gt, est, alignment=Alignment.SIM3)
    traj_ref, traj_est = evo_trajectory(gt), evo_trajectory(est)
    traj_est.align(traj_ref, correct_scale=True)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((traj_ref, traj_est))
    assert ours.rmse == pytest.approx(ape.get_all_statistics()["rmse"], abs=1e-6)
    assert ours.rmse < ate(gt, est)[0].rmse  # the scale is worth aligning
    assert str(Alignment.SIM3) == "Sim(3)"


def test_final_error_3d_counts_height_and_equals_evo_at_the_last_pose(rng):
    from evo.core import metrics

    from vo_lib.evaluation import final_error_3d, path_lengths

    gt = random_trajectory(rng)
    est = perturb(rng, gt)
    est[0] = gt[0]
    final = final_error_3d(gt, est)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((evo_trajectory(gt), evo_trajectory(est)))  # no alignment: both start at the truth
    assert final.position_m == pytest.approx(ape.error[-1], abs=1e-6)
    rot = metrics.APE(metrics.PoseRelation.rotation_angle_deg)
    rot.process_data((evo_trajectory(gt), evo_trajectory(est)))
    assert final.rotation_deg == pytest.approx(rot.error[-1], abs=1e-6)
    assert final.distance_m == pytest.approx(path_lengths(gt)[-1])
    climb = gt.copy()
    climb[:, 2, 3] += np.linspace(0, 2.0, len(gt))  # height drift alone
    assert final_error_3d(gt, climb).position_m == pytest.approx(2.0, abs=1e-9)


def test_kitti_errors_equal_evo_on_the_same_segments(rng):
    from evo.core import metrics

    from vo_lib.evaluation import kitti_errors, segment_lengths, segment_pairs

    gt = random_trajectory(rng, 300)
    gt[:, :3, 3] *= 0.05  # about 8 m: shorter than KITTI's segments
    est = perturb(rng, gt)
    lengths = segment_lengths(gt)
    total = np.sum(np.linalg.norm(np.diff(gt[:, :3, 3], axis=0), axis=1))
    assert len(lengths) == 8 and lengths[-1] == pytest.approx(0.8 * total, rel=0.05)
    ours = kitti_errors(gt, est)
    t_err, r_err = [], []
    for length in lengths:
        for first, last in segment_pairs(gt, length):
            for relation, out in (
                (metrics.PoseRelation.translation_part, t_err),
                (metrics.PoseRelation.rotation_angle_deg, r_err),
            ):
                m = metrics.RPE(relation, delta=1, delta_unit=metrics.Unit.frames)
                m.process_data((evo_trajectory(gt[[first, last]]), evo_trajectory(est[[first, last]])))
                out.append(m.error[0] / length)
    assert ours.count == len(t_err) > 0
    assert ours.translation_pct == pytest.approx(100 * np.mean(t_err), abs=1e-6)
    assert ours.rotation_deg_per_100m == pytest.approx(100 * np.mean(r_err), abs=1e-6)
    assert ours.label().endswith(" m")


def test_kitti_errors_use_the_benchmark_lengths_when_the_path_allows():
    from vo_lib.evaluation import KITTI_LENGTHS, segment_lengths

    T = np.tile(np.eye(4), (901, 1, 1))
    T[:, 0, 3] = np.arange(901.0)  # 900 m straight
    assert segment_lengths(T) == KITTI_LENGTHS
    T[:, 0, 3] = np.arange(901.0) / 3  # 300 m: 100 and 200 m fit
    assert segment_lengths(T) == (100.0, 200.0)


@pytest.mark.parametrize(("offset", "max_diff"), [(0.0, 0.01), (0.136, 0.025), (-0.05, 0.002)])
def test_association_equals_evo(rng, offset, max_diff):
    """As ``evo_ape --t_offset OFFSET --t_max_diff MAX_DIFF``: the offset is added to the estimate's times."""
    from evo.core import sync
    from evo.core.trajectory import PoseTrajectory3D

    from vo_lib.evaluation import associate

    truth_t = np.cumsum(rng.uniform(0.004, 0.006, 400))
    query_t = np.sort(rng.uniform(truth_t[0] - 0.05, truth_t[-1] + 0.05, 60))
    i_q, i_t = associate(query_t + offset, truth_t, max_diff)
    assert len(i_q) > 10
    eye = [np.eye(4)]
    a = PoseTrajectory3D(poses_se3=eye * len(query_t), timestamps=query_t)
    b = PoseTrajectory3D(poses_se3=eye * len(truth_t), timestamps=truth_t)
    b2, a2 = sync.associate_trajectories(b, a, max_diff=max_diff, offset_2=offset)
    assert np.allclose(a2.timestamps, query_t[i_q]) and np.allclose(b2.timestamps, truth_t[i_t])


def test_rows_read_at_once_equal_rows_read_one_by_one_and_a_bad_row_is_named(tmp_path, rng):
    """The fast whole-file read gives what ``float`` gives row by row; a row it cannot read (an
    inline comment, a missing number) falls back to the row-by-row read, which names the line."""
    from vo_lib.formats.poses import TrajectoryError, read_rows

    T = random_trajectory(rng, 40)
    write_kitti_poses(tmp_path / "poses.txt", T)
    text = (tmp_path / "poses.txt").read_text()
    a, lines, comma = read_rows(tmp_path / "poses.txt")
    by_row = [[float(v) for v in line.split()] for line in text.splitlines() if line.strip()]
    assert np.array_equal(a, by_row) and lines == list(range(1, 41)) and not comma
    rows = text.splitlines()
    bad_rows = {
        rows[5] + " # a comment": "line 6: not a row of numbers",
        rows[5].rsplit(" ", 1)[0]: "line 6: expected 12 numbers like line 1, got 11",
    }
    for bad, message in bad_rows.items():
        (tmp_path / "bad.txt").write_text("\n".join(rows[:5] + [bad] + rows[6:]) + "\n")
        with pytest.raises(TrajectoryError, match=message):
            read_rows(tmp_path / "bad.txt")
    # a CSV whose header line lacks the '#' is read as with it; a first row of NaN is still refused
    csv = [f"{1403636583783555584 + 5 * 10**7 * k},1,2,3" for k in range(4)]
    for header in ("#timestamp [ns],p_x,p_y,p_z", "timestamp [ns],p_x,p_y,p_z"):
        (tmp_path / "gt.csv").write_text("\n".join([header, *csv]) + "\n")
        a, lines, comma = read_rows(tmp_path / "gt.csv")
        assert a.shape == (4, 4) and lines == [2, 3, 4, 5] and comma
    (tmp_path / "nan.txt").write_text("nan 1 2 3\n1 1 2 3\n")
    with pytest.raises(TrajectoryError, match="line 1: holds a NaN"):
        read_rows(tmp_path / "nan.txt")


def test_evaluate_refuses_or_says_undefined_what_it_cannot_measure(tmp_path, rng, capsys):
    """Figures that do not exist are not printed as numbers: a truth that stands still has no
    percentage and no Sim(3) scale, and no segment fits it; files read the wrong way are refused."""
    from vo_lib.cli.main import main

    T = random_trajectory(rng, 50)
    times = np.arange(len(T)) / 10
    write_tum(tmp_path / "est.tum", times, T)
    still = np.tile(np.eye(4), (len(T), 1, 1))
    write_tum(tmp_path / "still.tum", times, still)
    assert main(["evaluate", "--gt", str(tmp_path / "still.tum"), "--est", str(tmp_path / "est.tum")]) == 0
    rows = {line[:62].strip(): line[62:].strip() for line in capsys.readouterr().out.splitlines()}
    assert (
        rows["of distance travelled [%]"] == "undefined" and rows["KITTI segment errors"] == "no segment fits"
    )
    assert rows["ATE (Sim(3) alignment, scale undefined): rmse [m]"] == "undefined"
    # positions only, of a tracker that stands still: no Sim(3) scale either
    (tmp_path / "still.txt").write_text("".join(f"{t!r} 1 2 3\n" for t in times.tolist()))
    assert main(["evaluate", "--gt", str(tmp_path / "still.txt"), "--est", str(tmp_path / "est.tum")]) == 0
    out = capsys.readouterr().out
    assert (
        "ATE (Sim(3) alignment, scale undefined, positions only): rmse undefined m, max undefined" in out
        and "nan" not in out
    )
    # a quaternion that is no rotation is refused, not normalised into one nobody measured
    lines = (tmp_path / "est.tum").read_text().splitlines()
    values = lines[7].split()
    lines[7] = " ".join(values[:4] + [repr(1.3 * float(v)) for v in values[4:]])
    (tmp_path / "bad.tum").write_text("\n".join(lines) + "\n")
    assert main(["evaluate", "--gt", str(tmp_path / "bad.tum"), "--est", str(tmp_path / "est.tum")]) == 2
    assert (
        "bad.tum, line 8: the quaternion's norm is 1.3; expected a unit quaternion" in capsys.readouterr().err
    )
    # a ground truth in millimetres is read as metres, and evaluate says it looks like millimetres
    (tmp_path / "mm.txt").write_text(
        "".join(f"{t!r} {1000 * k} {2000 * k} 0\n" for k, t in enumerate(times.tolist()))
    )
    assert main(["evaluate", "--gt", str(tmp_path / "mm.txt"), "--est", str(tmp_path / "est.tum")]) == 0
    assert "is one of them in millimetres?" in capsys.readouterr().out
    # a TUM estimate whose header orders the quaternion w x y z; a CSV whose times are seconds
    text = (tmp_path / "est.tum").read_text()
    (tmp_path / "wxyz.tum").write_text("# timestamp tx ty tz qw qx qy qz\n" + text)
    (tmp_path / "seconds.csv").write_text(text.replace(" ", ","))
    rows = [line.split(" ", 1) for line in text.splitlines()]  # a TUM file in nanoseconds
    csv = [f"{1403636583783555584 + 5 * 10**7 * k},1,2,3" for k in range(5)]  # EuRoC's positions
    csv[2], csv[3] = csv[3], csv[2]
    (tmp_path / "order.csv").write_text("\r".join(csv) + "\r")  # old-Mac line ends, too
    (tmp_path / "ns.tum").write_text(
        "".join(f"{round(float(t) * 1e9) + 10**18} {rest}\n" for t, rest in rows)
    )
    kitti = "".join(
        ",".join(["0.9999972", "0", "0.0023", "0.1", "0", "1", "0", "0", "-0.0023", "0", "0.9999972", "0"])
        + "\n"
        for _ in range(3)
    )
    (tmp_path / "kitti.csv").write_text(kitti)  # KITTI poses, with commas
    # ... and a longer drive's, whose later rows read as quaternions off the unit norm: the first bad
    # line is named (its time, with the hint), not a later quaternion
    drive = [[1.0, 0, 0, 0.1, 0, 1, 0, y, 0, 0, 1, 0] for y in (0.0, 0.0, 0.5)]
    drive[1][0] = 0.99995
    (tmp_path / "kitti_drive.csv").write_text("".join(",".join(map(str, r)) + "\n" for r in drive))
    (tmp_path / "tum.csv").write_text("# timestamp tx ty tz qx qy qz qw\n" + text.replace(" ", ","))
    refused = {
        ("--gt", "kitti.csv", "--est", "est.tum"): "as KITTI poses? they are separated by spaces, not commas",
        ("--gt", "kitti_drive.csv", "--est", "est.tum"): "line 2: timestamp 0.99995 comes before",
        (
            "--gt",
            "tum.csv",
            "--est",
            "est.tum",
        ): "a TUM file? its numbers are separated by spaces, not commas",
        ("--gt", "est.tum", "--est", "wxyz.tum"): "line 1: the header orders the quaternion w x y z",
        # TUM's numbers with commas, and no header
        ("--gt", "seconds.csv", "--est", "est.tum"): "line 2: the times step by 0.1",
        ("--gt", "est.tum", "--est", "seconds.csv"): "microsecond; a TUM file? its numbers are separated",
        ("--gt", "order.csv", "--est", "est.tum"): (
            "line 4: timestamp 1403636583883555584 comes before the one on line 3 (1403636583933555584)"
        ),
        # a TUM file in nanoseconds is read so (with a notice), then refused: not on est.tum's clock
        ("--gt", "ns.tum", "--est", "est.tum"): "read as nanoseconds",
        ("--gt", "est.tum", "--est", "ns.tum"): "both must use one clock",
    }
    for (a, gt, b, est), message in refused.items():
        assert main(["evaluate", a, str(tmp_path / gt), b, str(tmp_path / est)]) == 2
        assert message in capsys.readouterr().err


def test_association_keeps_a_pair_exactly_max_diff_apart_as_evo_and_old_mac_lines_read(tmp_path, rng):
    from vo_lib.cli.main import _segments
    from vo_lib.evaluation import associate
    from vo_lib.formats.groundtruth import read_trajectory

    assert associate([0.01, 0.5], [0.0, 0.52, 1.0])[0].tolist() == [0]
    assert _segments("5,1,3,1") == (1.0, 3.0, 5.0)  # each length once, in order, as the label says
    T = random_trajectory(rng, 5)
    write_kitti_poses(tmp_path / "lf.txt", T)
    (tmp_path / "cr.txt").write_bytes((tmp_path / "lf.txt").read_bytes().replace(b"\n", b"\r"))
    assert np.array_equal(read_trajectory(tmp_path / "cr.txt")[1], read_trajectory(tmp_path / "lf.txt")[1])


def test_tum_and_euroc_ground_truth_read_as_evo_reads_them(tmp_path, rng):
    """A TUM file (t x y z qx qy qz qw) and an EuRoC CSV (t[ns], x, y, z, qw, qx, qy, qz) give
    evo's times and poses, and a position-only file evo's positions."""
    from evo.tools import file_interface

    from vo_lib.formats.groundtruth import read_groundtruth

    T = random_trajectory(rng, 50)
    seconds = 1403636579.0 + 0.05 * np.arange(50) + rng.uniform(0, 1e-3, 50)
    xyz, q_xyzw = T[:, :3, 3], Rotation.from_matrix(T[:, :3, :3]).as_quat()
    tum, csv, positions = tmp_path / "truth.tum", tmp_path / "data.csv", tmp_path / "prism.txt"
    np.savetxt(tum, np.column_stack([seconds, xyz, q_xyzw]), fmt="%.9f")
    header = (
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"
    )
    nanoseconds = np.round(seconds * 1e9).astype(np.int64)
    rows = [
        f"{ns}," + ",".join(f"{v:.9f}" for v in (*p, q[3], *q[:3]))
        for ns, p, q in zip(nanoseconds, xyz, q_xyzw, strict=True)
    ]
    csv.write_text("\n".join([header, *rows]) + "\n")
    np.savetxt(positions, np.column_stack([seconds, xyz]), fmt="%.9f")
    for path, evo_traj in (
        (tum, file_interface.read_tum_trajectory_file(str(tum))),
        (csv, file_interface.read_euroc_csv_trajectory(str(csv))),
    ):
        ours = read_groundtruth(path)
        assert np.allclose(ours.times, evo_traj.timestamps, rtol=0, atol=1e-6), path.name
        assert np.allclose(ours.poses, np.array(evo_traj.poses_se3), rtol=0, atol=1e-6), path.name
    only = read_groundtruth(positions)
    assert only.poses is None and np.allclose(only.positions, xyz, atol=1e-6)


def test_position_only_ate_equals_evo_on_the_carried_point(rng):
    """ATE against positions only (a prism 0.1 m beside the camera) is evo's APE of the point
    carried along the estimate, after the same SE(3) alignment."""
    from evo.core import metrics
    from evo.core.trajectory import PosePath3D

    from vo_lib.evaluation import ate_positions, carried_point

    gt = random_trajectory(rng, 120)
    lever_arm = np.array([0.1, -0.05, 0.02])
    prism = carried_point(gt, lever_arm)
    est = perturb(rng, gt)
    ours, _ = ate_positions(prism, est, lever_arm)

    def points(p):
        return PosePath3D(positions_xyz=p, orientations_quat_wxyz=np.tile([1.0, 0, 0, 0], (len(p), 1)))

    traj_est = points(carried_point(est, lever_arm))
    traj_est.align(points(prism), correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((points(prism), traj_est))
    assert abs(ours.rmse - ape.get_statistic(metrics.StatisticsType.rmse)) < 1e-6
