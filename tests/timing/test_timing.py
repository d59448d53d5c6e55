"""Re-timing under joint limits: each known pitfall, checked on what is written.

Limits and times are checked independently of the timing code's own
numbers: a program CSV with joints is re-timed through the CLI, read back
with the csv module, and its ``t`` column and joints are differentiated
(finite differences); the TCP speed comes from forward kinematics of the
written joints. Point-to-point times are compared with the closed-form
trapezoid and jerk-limited profiles.
"""

import csv
import dataclasses

import numpy as np
import pytest
import ruckig

from tests.timing.test_timing_dense import random_lines
from trajcomp.cli import main
from trajcomp.errors import TimingError
from trajcomp.arm.ik import Configuration, configuration_of, ik
from trajcomp.arm.kinematics import fk
from trajcomp.programs.items import JOINT, LINEAR
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, retime
from trajcomp.timing.toppra_run import ConstantAcceleration
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc
import trajcomp.timing.retiming as retime_module

UR10 = load_robot("ur10")
KUKA = load_robot("kuka_kr6_r900")
FD_TOLERANCE = 0.02  # finite differences of a written 1 us-resolution timing, 10 ms apart


def helix(robot, n, turns=4, radius=60.0, rise=-80.0):
    """TCP poses (n, 4, 4) of a helix below the robot's home pose, and their joints (n, 6)."""
    angle = np.linspace(0.0, 2.0 * np.pi * turns, n)
    T = np.tile(fk(robot, robot.home), (n, 1, 1))
    T[:, 0, 3] += radius * (np.cos(angle) - 1.0)
    T[:, 1, 3] += radius * np.sin(angle)
    T[:, 2, 3] += np.linspace(0.0, rise, n)
    return T, ik(robot, T, seed=robot.home).raise_on_failure().q


def write_joint_program(path, q, motion="LIN", speed="", zone="1"):
    """A program CSV of joint rows (deg); ``zone`` (mm) one value or one per row ("" = exact stop)."""
    zones = [zone] * len(q) if isinstance(zone, str) else zone
    rows = ["j1,j2,j3,j4,j5,j6,motion,speed,zone"]
    rows += [",".join(f"{v:.9f}" for v in np.degrees(row)) + f",{motion},{speed},{z}" for row, z in zip(q, zones)]
    path.write_text("\n".join(rows) + "\n")


def retimed_csv(tmp_path, q, robot="ur10", **columns):
    """Re-time a joint program through the CLI; the written (t (N,), joints (N, 6) rad)."""
    source, output = tmp_path / "path.csv", tmp_path / "timed.csv"
    write_joint_program(source, q, **columns)
    assert main(["retime", str(source), "-o", str(output), "--robot", robot]) == 0
    with output.open() as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    joints = np.radians([[float(r[f"j{i}"]) for i in range(1, 7)] for r in rows])
    return t, joints


def finite_differences(t, q):
    """Average velocity of each interval (N-1, 6) and acceleration between interval midpoints (N-2, 6)."""
    dt = np.diff(t)
    keep = dt > 0
    v = np.diff(q, axis=0)[keep] / dt[keep, None]
    middle = (t[:-1] + t[1:])[keep] / 2.0
    return v, np.diff(v, axis=0) / np.diff(middle)[:, None]


def test_a_cam_helix_is_written_within_the_joint_limits_and_near_them(tmp_path):
    _, q = helix(UR10, 1200)
    t, written = retimed_csv(tmp_path, q)
    np.testing.assert_allclose(written, q, atol=1e-9)  # the timing never moves a waypoint
    assert np.all(np.diff(t) > 0)
    v, a = finite_differences(t, written)
    assert np.all(np.abs(v).max(axis=0) <= UR10.v_max * 1.01)
    assert np.all(np.abs(a).max(axis=0) <= UR10.a_max * (1.0 + FD_TOLERANCE))
    assert np.max(np.abs(a).max(axis=0) / UR10.a_max) > 0.95  # time-optimal: a limit is reached


def test_the_written_path_never_runs_faster_than_programmed(tmp_path):
    T, q = helix(UR10, 800)
    t, written = retimed_csv(tmp_path, q, speed="50")
    position = fk(UR10, written)[:, :3, 3]
    step = np.linalg.norm(np.diff(position, axis=0), axis=1)
    assert np.max(step / np.diff(t)) <= 50.0 * 1.01
    length = step.sum()  # the helix at 50 mm/s takes its length / speed, plus the ramps at both ends
    assert length / 50.0 <= t[-1] <= length / 50.0 * 1.02


def test_toppra_alone_overshoots_between_grid_points_and_the_dense_check_sees_it():
    """The pitfall: spline parametrizer and automatic grid exceed the acceleration limit between grid points."""
    import toppra
    import toppra.algorithm
    import toppra.constraint

    _, q = helix(UR10, 1500)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]
    constraints = [toppra.constraint.JointVelocityConstraint(UR10.v_max),
                   toppra.constraint.JointAccelerationConstraint(UR10.a_max)]
    naive = toppra.algorithm.TOPPRA(constraints, toppra.SplineInterpolator(s, q), solver_wrapper="seidel")
    trajectory = naive.compute_trajectory()
    sampled = trajectory(np.arange(0.0, trajectory.duration, 1e-3), 2)
    assert np.max(np.abs(sampled) / UR10.a_max) > 1.05
    ours = retime(Moves.from_joints(q, UR10), UR10)
    _, _, qdd = ours.at(np.arange(0.0, ours.cycle_time, 1e-3))
    assert np.max(np.abs(qdd) / UR10.a_max) <= 1.01
    assert ours.within_limits


def test_sharp_blended_corners_meet_the_limits_in_the_dense_check(tmp_path):
    """The demo's program (7 lines at 250 mm/s with 1 mm zones across the cube): the first TOPP-RA
    timing overshoots J1-J6 accelerations by up to 85 % inside the blends; the lowered limits must
    bring every sample within 1 % (the command exits 0, not 1)."""
    rows = ["x,y,z,a,b,c,motion,speed,zone", "604.785,57.915,366.389,90,0,180,PTP,,"] + [
        f"{x},{y},{z},90,0,180,LIN,250,1" for x, y, z in [
            (356.611, 275.308, 715.102), (592.654, 241.799, 567.450), (724.029, 276.341, 351.095),
            (692.962, -36.566, 641.862), (420.262, 295.272, 566.584), (469.885, 119.075, 361.328),
            (399.713, 218.250, 608.876)]]
    (tmp_path / "corners.csv").write_text("\n".join(rows) + "\n")
    assert main(["retime", str(tmp_path / "corners.csv"), "-o", str(tmp_path / "out.csv"), "--robot", "ur10"]) == 0


def test_an_overshoot_refines_the_grid_where_it_happens_not_the_whole_run(tmp_path, monkeypatch):
    """11 lines with 1 mm zones whose first timing overshoots the acceleration limits in the blends by 2 %
    (2x when the fit cut the corners): the grid is refined there (no uniform slow-down, 11.44 s); without
    refinement (the last resort) the whole timing runs uniformly slower by what the overshoot needs (11.54 s).
    Both written within the limits."""
    rows = ["x,y,z,a,b,c,motion,speed,zone", "672.486,76.581,409.615,90,0,180,PTP,,1"] + [
        f"{x},{y},{z},90,0,180,LIN,250,1" for x, y, z in [
            (629.405, 129.418, 669.576), (444.207, 77.914, 669.952), (552.827, 152.554, 444.478),
            (355.815, 323.290, 384.330), (687.971, 97.152, 730.409), (509.770, 324.577, 572.464),
            (446.054, 246.569, 619.756), (623.682, 135.530, 438.755), (606.376, -7.164, 626.889),
            (604.155, 100.605, 669.409), (427.610, 106.184, 669.174)]]
    (tmp_path / "blends.csv").write_text("\n".join(rows) + "\n")
    stretched = []
    original = ConstantAcceleration.stretched
    monkeypatch.setattr(ConstantAcceleration, "stretched",
                        lambda law, factor: stretched.append(factor) or original(law, factor))
    cycle, default = {}, retime_module._REFINEMENTS
    for refinements in (default, 0):
        monkeypatch.setattr(retime_module, "_REFINEMENTS", refinements)
        assert main(["retime", str(tmp_path / "blends.csv"), "-o", str(tmp_path / "out.csv"), "--robot", "ur10"]) == 0
        with (tmp_path / "out.csv").open() as f:
            cycle[refinements] = float(list(csv.DictReader(f))[-1]["t"])
    assert len(stretched) == 1 and 1.005 < stretched[0] < 1.02  # sqrt of the 2 % acceleration overshoot, once
    assert cycle[0] > 1.005 * cycle[default]


def test_a_stretched_law_runs_the_same_path_slower():
    law = ConstantAcceleration.from_speeds(np.array([0.0, 0.5, 1.5, 2.0]), np.array([0.0, 1.0, 2.0, 0.0]))
    slow = law.stretched(2.0)
    assert slow.duration == pytest.approx(2.0 * law.duration)
    t = np.linspace(0.0, law.duration, 37)
    s, sd, sdd = law(t)
    s2, sd2, sdd2 = slow(2.0 * t)
    np.testing.assert_allclose(s2, s, atol=1e-12)
    np.testing.assert_allclose(sd2, sd / 2.0, atol=1e-12)
    np.testing.assert_allclose(sdd2, sdd / 4.0, atol=1e-12)


def test_a_re_timed_program_can_be_re_timed_again(tmp_path):
    """The output has a t column: timing it again rewrites that column (it raised a NameError once)."""
    (tmp_path / "p.csv").write_text("x,y,z,a,b,c,motion,speed,zone\n600,100,500,90,0,180,PTP,,\n"
                                    "650,100,500,90,0,180,LIN,100,\n650,150,500,90,0,180,LIN,100,\n")
    assert main(["retime", str(tmp_path / "p.csv"), "-o", str(tmp_path / "once.csv"), "--robot", "ur10"]) == 0
    assert main(["retime", str(tmp_path / "once.csv"), "-o", str(tmp_path / "twice.csv"), "--robot", "ur10"]) == 0
    assert (tmp_path / "twice.csv").read_text() == (tmp_path / "once.csv").read_text()


def test_duplicated_and_zero_length_waypoints_take_no_time(tmp_path):
    _, q = helix(UR10, 300, turns=1)
    doubled = np.insert(np.repeat(q, 2, axis=0), 100, q[50], axis=0)  # every row twice, row 50 three times
    t, written = retimed_csv(tmp_path, doubled)
    clean = retime(Moves.from_joints(q, UR10, zone=1.0), UR10)
    assert np.all(np.isfinite(t))
    repeated = np.r_[False, np.all(written[1:] == written[:-1], axis=1)]
    assert repeated.sum() == 301
    np.testing.assert_allclose(t[repeated], t[np.flatnonzero(repeated) - 1], atol=1e-6)  # reached at once
    assert t[-1] == pytest.approx(clean.cycle_time, rel=1e-3)


def rounded_like_a_program(T):
    """Poses (N, 4, 4) with positions to 0.001 mm and A, B, C to 0.0001 deg, as a program writes them."""
    out = T.copy()
    out[:, :3, 3] = np.round(T[:, :3, 3], 3)
    out[:, :3, :3] = abc_to_matrix(np.radians(np.round(np.degrees(matrix_to_abc(T[:, :3, :3])), 4)))
    return out


def test_ik_noise_of_rounded_poses_does_not_make_toppra_crawl():
    T, q = helix(UR10, 6000)
    noisy = ik(UR10, rounded_like_a_program(T), seed=q).raise_on_failure().q
    clean = retime(Moves.from_joints(q, UR10), UR10)
    smoothed = retime(Moves.from_joints(noisy, UR10), UR10)
    interpolated = retime(Moves.from_joints(noisy, UR10), UR10, tolerance=1e-9)
    assert smoothed.cycle_time == pytest.approx(clean.cycle_time, rel=0.01)
    assert interpolated.cycle_time > 1.5 * clean.cycle_time  # the pitfall: the spline through the noise
    assert smoothed.within_limits
    # the smoothed path passes each compensated waypoint within the stated tolerance (0.005 mm)
    path_q, _, _ = smoothed.at(smoothed.t)
    miss = np.linalg.norm(fk(UR10, path_q)[:, :3, 3] - fk(UR10, noisy)[:, :3, 3], axis=1)
    assert miss.max() <= 0.005 * 1.05



def test_a_sample_the_finest_knots_miss_pulls_the_fit_and_only_there():
    """A CAM path at 0.01 mm spacing, rounded as written, with one waypoint's J1 off by 1e-5 rad (about 5 um at
    the TCP, a step of the compensation): the fit keeps every waypoint within tolerance without crawling."""
    n = 3000
    angle = np.linspace(0.0, 0.2 * np.pi * n / 3000, n)
    T = np.tile(fk(UR10, UR10.home), (n, 1, 1))
    T[:, 0, 3] += 60.0 * (np.cos(angle) - 1.0)
    T[:, 1, 3] += 60.0 * np.sin(angle)
    T[:, 2, 3] += np.linspace(0.0, -0.002 * n, n)
    q = ik(UR10, rounded_like_a_program(T), seed=UR10.home).raise_on_failure().q
    off = q.copy()
    off[n // 2, 0] += 1e-5
    plain = retime(Moves.from_joints(q, UR10, tcp_speed=50.0, zone=1.0), UR10)
    pulled = retime(Moves.from_joints(off, UR10, tcp_speed=50.0, zone=1.0), UR10)
    assert pulled.cycle_time == pytest.approx(plain.cycle_time, rel=0.01)  # interpolating the noise: 2.2 times
    assert pulled.within_limits
    path_q, _, _ = pulled.at(pulled.t)
    miss = np.linalg.norm(fk(UR10, path_q)[:, :3, 3] - fk(UR10, off)[:, :3, 3], axis=1)
    assert miss.max() <= 0.005 * 1.05

def near_singular_line(offset):
    """Joints at both ends of an 80 mm LIN of the KUKA passing ``offset`` mm from a wrist singularity (A5 = 0).

    Both ends in the same configuration (a LIN keeps it), the one whose A4
    swing stays inside the A4 limits.
    """
    q_singular = np.radians([10.0, -80.0, 100.0, 0.0, 0.0, 20.0])
    ends = np.tile(fk(KUKA, q_singular), (2, 1, 1))
    ends[:, :3, 3] += offset * np.array([0.0, 0.0, 1.0]) + np.outer([-40.0, 40.0], [0.0, 1.0, 0.0])
    arm = configuration_of(KUKA, q_singular + np.radians([0.0, 0.0, 0.0, 0.0, 5.0, 0.0]))
    return ik(KUKA, ends, config=Configuration(arm.shoulder, arm.elbow, "positive"), seed=q_singular).q


def test_a_line_near_a_wrist_singularity_slows_down_within_the_limits():
    q = near_singular_line(0.5)
    result = retime(Moves.from_joints(q, KUKA, tcp_speed=250.0), KUKA)
    times = np.arange(0.0, result.cycle_time, 1e-3)
    sampled, _, _ = result.at(times)
    velocity = np.diff(sampled, axis=0) / 1e-3  # finite differences of the sampled joints
    assert np.all(np.abs(velocity).max(axis=0) <= KUKA.v_max * 1.01)
    swing = np.abs(np.diff(sampled[:, 3])).sum()  # A4 swings by about half a turn near the singular point
    assert swing > np.radians(150.0)
    assert result.cycle_time >= swing / KUKA.v_max[3]  # the swing alone at full A4 speed
    assert result.within_limits


def test_a_line_through_a_wrist_singularity_is_refused_with_its_waypoint_and_joints():
    q = near_singular_line(1e-7)
    moves = Moves.from_joints(q, KUKA, labels=["P1 (weld.dat:3)", "P2 (weld.dat:4)"])
    with pytest.raises(TimingError, match=r"P2 \(weld.dat:4\) passes through a singularity.*J4 and J6"):
        retime(moves, KUKA)


def test_a_path_crossing_the_wrist_singularity_in_joint_space_is_timed(tmp_path):
    q = np.tile(np.radians([0.0, -80.0, 90.0, -90.0, 0.0, 0.0]), (400, 1))
    q[:, 4] = np.linspace(np.radians(-20.0), np.radians(20.0), 400)  # J5 through zero, J4 and J6 still
    q[:, 0] = np.linspace(0.0, np.radians(10.0), 400)
    t, written = retimed_csv(tmp_path, q, motion="PTP")  # blended joint motions: a joint-space path
    v, a = finite_differences(t, written)
    assert np.all(np.abs(v).max(axis=0) <= UR10.v_max * 1.01)
    assert np.all(np.abs(a).max(axis=0) <= UR10.a_max * (1.0 + FD_TOLERANCE))
    assert np.max(np.abs(v).max(axis=0) / UR10.v_max) > 0.99  # J5 at full speed through the singularity


def test_start_and_end_at_rest_and_at_an_exact_stop(tmp_path):
    _, q = helix(UR10, 600, turns=2)
    t, _ = retimed_csv(tmp_path, q)
    v, _ = finite_differences(t, q)
    # from rest, with at most the acceleration limit, the first and last intervals are slow
    assert np.all(np.abs(v[0]) <= 0.5 * UR10.a_max * (t[1] - t[0]) * 1.01)
    assert np.all(np.abs(v[-1]) <= 0.5 * UR10.a_max * (t[-1] - t[-2]) * 1.01)
    zones = ["1"] * 600
    zones[300] = ""  # an exact stop at row 300
    t_stop, _ = retimed_csv(tmp_path, q, zone=zones)
    v_stop, _ = finite_differences(t_stop, q)
    for interval in (299, 300):  # into and out of the stop
        assert np.all(np.abs(v_stop[interval]) <= 0.5 * UR10.a_max * np.diff(t_stop)[interval] * 1.01)
    assert t_stop[-1] > t[-1]  # stopping costs time


def test_a_linear_motion_beyond_a_joint_limit_names_waypoint_line_and_joint():
    ends = np.tile(fk(UR10, UR10.home), (2, 1, 1))
    ends[:, 0, 3] = -250.0
    ends[:, 1, 3] = [-500.0, 500.0]  # a line passing the base: J3 bends most half-way
    q = ik(UR10, ends, seed=UR10.home).raise_on_failure().q
    middle = np.tile(fk(UR10, UR10.home), (1, 1, 1))
    middle[:, 0, 3], middle[:, 1, 3] = -250.0, 0.0
    q_middle = ik(UR10, middle, seed=UR10.home).raise_on_failure().q[0]
    limit = 0.5 * (max(abs(q[0, 2]), abs(q[1, 2])) + abs(q_middle[2]))  # between the ends' and the middle's
    tight = UR10.replace(q_max=np.where(np.arange(6) == 2, limit, UR10.q_max),
                         q_min=np.where(np.arange(6) == 2, -limit, UR10.q_min))
    moves = Moves.from_joints(q, tight, labels=["p1 (cell.script:4)", "p2 (cell.script:5)"])
    with pytest.raises(TimingError, match=r"motion to p2 \(cell.script:5\) at \d+ % of its way: J3 would reach"):
        retime(moves, tight)


def test_a_zero_speed_names_the_line(tmp_path, capsys):
    _, q = helix(UR10, 5, turns=0.1)
    write_joint_program(tmp_path / "path.csv", q, speed="0")
    assert main(["retime", str(tmp_path / "path.csv"), "-o", str(tmp_path / "out.csv"), "--robot", "ur10"]) == 2
    assert "line 2: motion to path.csv:2 asks speed 0 mm/s" in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()


def s_curve_time(distance, v, a, j):
    """Rest-to-rest time of the jerk-limited profile reaching v and a (distance long enough): d/v + v/a + a/j."""
    return distance / v + v / a + a / j


def test_a_point_to_point_motion_takes_the_closed_form_time_and_its_jerk_is_limited(monkeypatch):
    calls = []
    calculate = ruckig.Ruckig.calculate

    def recorded(self, query, trajectory):
        calls.append((query.degrees_of_freedom, len(query.intermediate_positions)))
        return calculate(self, query, trajectory)

    monkeypatch.setattr(ruckig.Ruckig, "calculate", recorded)
    start = UR10.home
    end = start + np.radians([120.0, 60.0, 0.0, 0.0, 0.0, 0.0])  # J1 leads: 120 deg at 120 deg/s
    result = retime(Moves.from_joints(np.array([start, end]), UR10, kind=JOINT), UR10)
    assert result.segments[0].kind == "ruckig"
    assert calls == [(1, 0)]  # one degree of freedom (the joint line), never intermediate waypoints
    expected = s_curve_time(np.radians(120.0), UR10.v_max[0], UR10.a_max[0], UR10.j_max[0])
    assert result.cycle_time == pytest.approx(expected, rel=1e-6)
    times = np.arange(0.0, result.cycle_time, 1e-3)
    q, _, qdd = result.at(times)
    jerk = np.abs(np.diff(qdd, axis=0)) / 1e-3
    assert np.all(jerk.max(axis=0) <= UR10.j_max * 1.01)
    assert result.segments[0].jerk_limited and np.all(result.peak_jerk <= UR10.j_max * 1.01)
    assert result.peak_jerk[0] > 0.9 * UR10.j_max[0]  # measured: the leading joint reaches its jerk limit
    share = (q - start)[:, :2] / (end - start)[:2]  # phase-synchronized: on the straight joint line
    np.testing.assert_allclose(share[:, 0], share[:, 1], atol=1e-9)


def test_without_a_jerk_limit_a_point_to_point_motion_is_a_trapezoid():
    end = KUKA.home + np.radians([0.0, 0.0, 90.0, 0.0, 0.0, 0.0])
    result = retime(Moves.from_joints(np.array([KUKA.home, end]), KUKA, kind=JOINT), KUKA)
    v, a = KUKA.v_max[2], KUKA.a_max[2]
    assert result.cycle_time == pytest.approx(np.radians(90.0) / v + v / a, rel=1e-6)
    assert np.all(np.isnan(result.peak_jerk))  # not bounded, not measured: no number
    assert not result.segments[0].jerk_limited
    assert result.lines_of_text()[8].startswith("jerk: not bounded in 1 of 1 segments")


def test_programmed_joint_speed_and_time_are_honoured():
    end = UR10.home + np.radians([90.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    moves = Moves.from_joints(np.array([UR10.home, end]), UR10, kind=JOINT)
    half = Moves(**{**moves.__dict__, "velocity": moves.velocity * 0.5})
    slow = retime(half, UR10)
    _, qd, _ = slow.at(np.arange(0.0, slow.cycle_time, 1e-3))
    assert np.abs(qd[:, 0]).max() <= 0.5 * UR10.v_max[0] * 1.001
    timed = Moves(**{**moves.__dict__, "min_duration": np.array([0.0, 3.0])})
    assert retime(timed, UR10).cycle_time == pytest.approx(3.0, rel=1e-6)


@pytest.mark.parametrize("stop", [True, False])
def test_a_programmed_time_is_taken_at_least_in_a_blended_run_and_between_stops(stop):
    """Random lines with a joint motion among them, each motion with a time (RAPID \\T, FANUC sec): each takes it
    at least, to 1e-5 (a joint motion in a blended run took 0.269 s for \\T:=8; a line's TCP length summed from
    linearized steps made \\T:=8 7.976 s)."""
    rng = np.random.default_rng(4)
    q = random_lines(7, 2)
    kind = np.array([LINEAR] * 7, dtype=object)
    kind[3] = JOINT
    times = np.r_[0.0, rng.choice([0.5, 1.0, 2.0, 8.0], 6)]
    moves = dataclasses.replace(Moves.from_joints(q, UR10, kind=kind, stop=stop, zone=0.0 if stop else 5.0),
                                min_duration=times)
    result = retime(moves, UR10)
    assert np.all(result.durations[1:] >= times[1:] * (1.0 - 1e-5)) and result.within_limits


def test_every_method_keeps_the_limits_and_toppra_is_fastest():
    T, q = helix(UR10, 200, turns=1)
    kinds = [JOINT] * 2 + [LINEAR] * 198
    stops = np.arange(200) == 1  # a joint motion from rest to rest, then a blended helix
    results = {m: retime(Moves.from_joints(q, UR10, kind=kinds, zone=2.0, stop=stops), UR10, method=m)
               for m in ("auto", "toppra", "ruckig")}
    assert all(r.within_limits for r in results.values())
    assert results["toppra"].cycle_time <= results["auto"].cycle_time * (1 + 1e-6)
    assert results["auto"].cycle_time <= results["ruckig"].cycle_time * (1 + 1e-6)
    assert [s.kind for s in results["auto"].segments] == ["ruckig", "toppra"]


def test_a_task_s_timing_error_names_the_file_of_the_motion(tmp_path):
    """In a task joined from several files, a line number alone would point into the wrong file."""
    from trajcomp import formats
    from trajcomp.jobs.retime import planned
    from trajcomp.compensation.posture import planned_joints
    from trajcomp.timing import moves_from_program

    for name, speed, y in (("a", "0.2", 0), ("b", "0", 100)):
        (tmp_path / f"{name}.src").write_text(f"DEF {name}()\n$VEL.CP={speed}\nPTP {{A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0}}\n"
                                              f"LIN {{X 600,Y {y},Z 600,A 0,B 90,C 0}}\nEND\n")
    program = formats.read_task([tmp_path / "a.src", tmp_path / "b.src"])
    robot = load_robot("kuka_kr6_r900")
    plan = planned_joints(program, robot)
    with pytest.raises(TimingError, match=r"^b\.src:4: motion to b\.src:4 asks speed 0 mm/s"):
        moves_from_program(program, robot, planned(program, plan.index, plan.q))
