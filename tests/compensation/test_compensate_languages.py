"""Every robot language, compensated through the CLI, lands on its targets as the CSV path does.

For each language a small program is written (by this test, in the
language's own units, conventions and typical precision) with targets inside
a calibration cube of its robot, some in the base frame and some in a user
frame / work object, all on a tool with a non-identity TCP. That tool is the
one the calibration measured (the robot YAML's ``tool``), as on a real cell
where the tracker target sits on the production tool: a program naming it
by its own number or name, with its own numbers, gets the identified TCP. A
composite model is calibrated on the robot's virtual copy; ``trajcomp
compensate`` corrects the program; the corrected file is read back and
turned into the joints the controller would run: from the joints the file
carries (URScript ``Waypoint_q`` / ``qnear``, CSV ``j1..j6``, checked
against the pose), or from nominal IK of the written pose on the branch and
turns its written configuration data (KUKA S/T, ABB confdata, FANUC CONFIG)
select. Those joints run on the virtual robot; the TCP must land within
0.05 mm, with the error the same targets get through a program CSV, while
the original program misses by more than 0.5 mm.

The expected targets are computed here from the numbers written, with
scipy's rotations (not trajcomp's conversions).
"""

import dataclasses
import itertools
import warnings
from importlib import resources

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajcomp import formats
from trajcomp.calibration.calibrate import calibrate
from trajcomp.cli import main
from trajcomp.compensation.target_correction import compensate
from trajcomp.formats.configuration import BOUNDARY_TOLERANCE, configuration_data, configuration_for, declared_windows
from trajcomp.arm.ik import configuration_of, ik, ik_all
from trajcomp.arm.kinematics import fk
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import save_model
from trajcomp.calibration.orientations import spread_orientations
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot

LANDED = 0.05  # mm, largest landing error of a compensated target
MISSED = 0.2  # mm, smallest landing error of an uncompensated target
SAME_AS_CSV = 0.003  # mm, largest difference to the CSV path's landing error (written precision)

# robot: calibration cube corner and side (mm), grid step; 216 points each
CUBES = {
    "kuka_kr6_r900": ((350.0, -150.0, 250.0), 300.0, 60.0),
    "abb_irb4600": ((1000.0, -300.0, 700.0), 600.0, 120.0),
    "fanuc_lrmate200id": ((320.0, -100.0, 300.0), 200.0, 40.0),
    "ur10": ((300.0, -100.0, 300.0), 500.0, 100.0),
    "ur5": ((200.0, -100.0, 200.0), 300.0, 60.0),
}
LANGUAGES = {"krl": "kuka_kr6_r900", "rapid": "abb_irb4600", "fanuc_ls": "fanuc_lrmate200id",
             "urscript": "ur10", "csv": "ur5"}
# Targets as fractions of the cube: (fraction, motion, in the user frame)
PLAN = [
    ((0.50, 0.50, 0.50), "ptp", False),
    ((0.21, 0.33, 0.71), "lin", False),
    ((0.62, 0.18, 0.41), "via", False),
    ((0.83, 0.64, 0.27), "circ", False),
    ((0.31, 0.72, 0.63), "lin", True),
    ((0.72, 0.43, 0.22), "ptp", True),
]
# The measured TCP, T_flange_tool: x, y, z mm, A, B, C deg. Half a turn about z keeps
# every language's numbers exact (ABB quaternion [0, 0, 0, 1]). On the flange axis: with
# a lateral offset (8, -6, 60) the UR10's composite model is no better than its DH model
# (0.055 mm mean on the virtual UR10, CSV path included), a calibration matter.
TOOL = (0.0, 0.0, 60.0, 180.0, 0.0, 0.0)
FRAME_ANGLE = 30.0  # deg about z: the user frame, placed at the cube corner


def matrix(position, rotation):
    T = np.eye(4)
    T[:3, :3] = rotation.as_matrix()
    T[:3, 3] = position
    return T


def xyzabc(values):
    """T from x, y, z (mm) and KUKA A, B, C (deg): intrinsic Z-Y'-X''."""
    return matrix(values[:3], Rotation.from_euler("ZYX", values[3:], degrees=True))


def abc_of(T):
    """KUKA A, B, C (deg) of T."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # B = 90 deg (KUKA tool down): scipy warns and sets C = 0
        return Rotation.from_matrix(T[:3, :3]).as_euler("ZYX", degrees=True)


def fixed(values, places):
    return ",".join(f"{v:.{places}f}" for v in values)


@dataclasses.dataclass
class Point:
    """One target of a test program, as the test means it."""

    T_base: np.ndarray  # where the TCP must land, base frame, mm (from the numbers written)
    T_frame: np.ndarray  # what the program states: the pose in its frame
    framed: bool  # in the user frame
    motion: str
    config: tuple = ()  # configuration data of the original program (nominal IK)
    q: np.ndarray = None  # nominal joints of the original program


@dataclasses.dataclass
class Case:
    """A program in one language for one robot, with the value of its user frame."""

    language: str
    robot: object
    points: list
    frame: np.ndarray  # T_base_frame of the user frame, from the numbers written
    files: dict = dataclasses.field(default_factory=dict)  # name -> text
    options: list = dataclasses.field(default_factory=list)  # CLI --tool / --frame


# ------------------------------------------------------------- the programs


def declared_joints(robot, T_base, posture):
    """Nominal joints (6,) of a target in a posture: ``"home"`` (nearest home) or ``"flipped"``.

    ``"flipped"`` is a valid non-default posture: the home solution's wrist
    flipped (J4 + 180, J5 negated, J6 + 180 deg; where that branch cannot
    reach, the elbow flipped instead) and J6 one turn further where its
    limits allow.
    """
    solved = ik(robot, T_base[None], seed=robot.home)
    assert solved.success[0], solved.reason
    if posture == "home":
        return solved.q[0]
    q_branches, valid = ik_all(robot, T_base[None], seed=robot.home)
    home_branch = configuration_of(robot, solved.q[0]).index
    branch = next(home_branch ^ flip for flip in (1, 2, 3) if valid[0, home_branch ^ flip])
    q = q_branches[0, branch].copy()
    for turn in (2 * np.pi, -2 * np.pi):
        if robot.q_min[5] <= q[5] + turn <= robot.q_max[5]:
            q[5] += turn
            break
    return q


def build_points(language, robot, frame, written, posture):
    """Targets of PLAN; ``written(T) -> T`` is the pose the program's rounded numbers state."""
    corner, side, _ = CUBES[robot.name]
    rotation = Rotation.from_euler("ZYX", default_orientation(robot))  # the orientation measured
    points = []
    for fraction, motion, framed in PLAN:
        position = np.asarray(corner) + side * np.asarray(fraction) + np.array([0.1234, -0.4321, 0.2468])
        T_wanted = matrix(position, rotation)
        T_frame = written(np.linalg.inv(frame) @ T_wanted if framed else T_wanted)
        T_base = frame @ T_frame if framed else T_frame
        q = declared_joints(robot, T_base, posture)
        config = configuration_for(configuration_data(language), robot, q[None])
        points.append(Point(T_base, T_frame, framed, motion, tuple(config[0]) if config else (), q))
    return points


def krl_case(robot, posture):
    """KUKA KRL: .dat points (E6POS with S, T), inline E6POS, CIRC; tool and base 1 given on the command line."""
    corner = CUBES[robot.name][0]
    frame_values = (*corner, FRAME_ANGLE, 0.0, 0.0)
    frame = xyzabc(frame_values)

    def written(T):  # X, Y, Z with 3 decimals, A, B, C with 4 (as KUKA's editors write)
        return xyzabc(np.concatenate([np.round(T[:3, 3], 3), np.round(abc_of(T), 4)]))

    points = build_points("krl", robot, frame, written, posture)

    def e6pos(p):
        xyz, abc = p.T_frame[:3, 3], abc_of(p.T_frame)
        return (f"{{X {xyz[0]:.3f},Y {xyz[1]:.3f},Z {xyz[2]:.3f},A {abc[0]:.4f},B {abc[1]:.4f},C {abc[2]:.4f},"
                f"S {p.config[0]},T {p.config[1]},E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}")

    dat = ["&ACCESS RVP", "&REL 1", "DEFDAT  e2e"]
    dat += [f"DECL E6POS XP{k + 1}={e6pos(p)}" for k, p in enumerate(points[:-1])]
    dat += ["ENDDAT"]
    src = [
        "&ACCESS RVP", "&REL 1", "DEF e2e( )",
        "  BAS(#TOOL,1)", "  BAS(#BASE,0)",
        "  BAS(#VEL_PTP,50)", "  PTP XP1 C_DIS",
        "  $VEL.CP=0.1", "  $APO.CDIS=5", "  LIN XP2 C_DIS",
        "  CIRC XP3, XP4",
        "  BAS(#BASE,1)",
        "  LIN XP5",
        f"  PTP {e6pos(points[-1])}",
        "END",
    ]
    files = {"e2e.src": "\r\n".join(src) + "\r\n", "e2e.dat": "\r\n".join(dat) + "\r\n"}
    options = ["--tool", "1=" + fixed(TOOL, 3), "--base", "1=" + fixed(frame_values, 3)]
    return Case("krl", robot, points, frame, files, options)


def _quat(T):
    """ABB quaternion [q1 = w, q2, q3, q4] of T's rotation, q1 >= 0."""
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    return np.array([w, x, y, z]) * (1 if w >= 0 else -1)


def _from_quat(position, q):
    return matrix(position, Rotation.from_quat([q[1], q[2], q[3], q[0]]))


def rapid_case(robot, posture):
    """ABB RAPID: robtarget declarations and an inline robtarget, MoveC, tooldata and wobjdata in the module."""
    corner = CUBES[robot.name][0]
    tool_q = np.round(_quat(xyzabc(TOOL)), 6)
    assert np.allclose(_from_quat(TOOL[:3], tool_q), xyzabc(TOOL), atol=1e-12)
    frame_q = np.round(_quat(xyzabc((0, 0, 0, FRAME_ANGLE, 0, 0))), 6)
    frame = _from_quat(corner, frame_q)  # as written: quaternion with 6 decimals

    def written(T):  # mm with 2 decimals, quaternion with 6 (as RobotStudio writes)
        return _from_quat(np.round(T[:3, 3], 2), np.round(_quat(T), 6))

    points = build_points("rapid", robot, frame, written, posture)

    def robtarget(p):
        xyz, q = p.T_frame[:3, 3], _quat(p.T_frame)
        return (f"[[{fixed(xyz, 2)}],[{fixed(q, 6)}],[{','.join(str(c) for c in p.config)}],"
                "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")

    lines = [
        "MODULE E2E",
        f"  PERS tooldata tGun := [TRUE,[[{fixed(TOOL[:3], 1)}],[{fixed(tool_q, 6)}]],"
        "[1.5,[0,0,50],[1,0,0,0],0,0,0]];",
        f"  PERS wobjdata wTable := [FALSE,TRUE,\"\",[[{fixed(corner, 1)}],[{fixed(frame_q, 6)}]],"
        "[[0,0,0],[1,0,0,0]]];",
    ]
    lines += [f"  CONST robtarget p{10 * (k + 1)} := {robtarget(p)};" for k, p in enumerate(points[:-1])]
    lines += [
        "",
        "  PROC main()",
        "    MoveJ p10, v1000, z10, tGun;",
        "    MoveL p20, v200, z5, tGun;",
        "    MoveC p30, p40, v100, fine, tGun;",
        "    MoveL p50, v100, z5, tGun\\WObj:=wTable;",
        f"    MoveJ {robtarget(points[-1])}, v500, fine, tGun\\WObj:=wTable;",
        "  ENDPROC",
        "ENDMODULE",
    ]
    return Case("rapid", robot, points, frame, {"E2E.mod": "\r\n".join(lines) + "\r\n"})


def fanuc_case(robot, posture):
    """FANUC .LS: /POS entries with UF/UT/CONFIG, a C motion; user frame and tool 1 given on the command line."""
    corner = CUBES[robot.name][0]
    frame_values = (*corner, FRAME_ANGLE, 0.0, 0.0)  # W = P = 0, R = 30
    frame = xyzabc(frame_values)

    def wpr(T):
        return Rotation.from_matrix(T[:3, :3]).as_euler("xyz", degrees=True)  # fixed X-Y-Z: W, P, R

    def written(T):  # mm and deg with 3 decimals (as the controller writes)
        return matrix(np.round(T[:3, 3], 3), Rotation.from_euler("xyz", np.round(wpr(T), 3), degrees=True))

    points = build_points("fanuc_ls", robot, frame, written, posture)

    def position(k, p):
        x, y, z = p.T_frame[:3, 3]
        w, pp, r = wpr(p.T_frame)
        f, u, t, t1, t4, t6 = p.config
        return (f"P[{k}]{{\n   GP1:\n\tUF : {1 if p.framed else 0}, UT : 1,\t\t"
                f"CONFIG : '{f} {u} {t}, {t1}, {t4}, {t6}',\n"
                f"\tX = {x:.3f}  mm,\tY = {y:.3f}  mm,\tZ = {z:.3f}  mm,\n"
                f"\tW = {w:.3f} deg,\tP = {pp:.3f} deg,\tR = {r:.3f} deg\n}};")

    mn = [
        "   1:  UFRAME_NUM=0 ;", "   2:  UTOOL_NUM=1 ;",
        "   3:J P[1] 50% CNT50    ;",
        "   4:L P[2] 200mm/sec CNT20    ;",
        "   5:C P[3]    ", "    :  P[4] 100mm/sec FINE    ;",
        "   6:  UFRAME_NUM=1 ;",
        "   7:L P[5] 100mm/sec FINE    ;",
        "   8:J P[6] 30% FINE    ;",
    ]
    text = (["/PROG  E2E", "/ATTR", "OWNER\t\t= MNEDITOR;", "LINE_COUNT\t= 8;", "/MN"] + mn + ["/POS"]
            + [position(k + 1, p) for k, p in enumerate(points)] + ["/END"])
    options = ["--tool", "1=" + fixed(TOOL, 3), "--uframe", "1=" + fixed(frame_values, 3)]
    return Case("fanuc_ls", robot, points, frame, {"E2E.LS": "\n".join(text) + "\n"}, options)


def urscript_case(robot, posture):
    """URScript: set_tcp, PolyScope Waypoint_p/_q pairs, get_inverse_kin with qnear, movec (no user frames)."""
    tcp = np.concatenate([np.asarray(TOOL[:3]) / 1000.0, Rotation.from_matrix(xyzabc(TOOL)[:3, :3]).as_rotvec()])

    def vector(T):
        return np.concatenate([T[:3, 3] / 1000.0, Rotation.from_matrix(T[:3, :3]).as_rotvec()])

    def written(T):  # metres and rad with 10 decimals
        v = np.round(vector(T), 10)
        return matrix(v[:3] * 1000.0, Rotation.from_rotvec(v[3:]))

    points = build_points("urscript", robot, np.eye(4), written, posture)
    for p in points:
        p.framed = False  # URScript poses are in the base frame

    def pose(point):
        return "p[" + ", ".join(f"{v:.10f}" for v in vector(point.T_frame)) + "]"

    def joints(point):
        return "[" + ", ".join(f"{v:.10f}" for v in point.q) + "]"

    lines = ["def e2e():", "  set_tcp(p[" + ", ".join(f"{v:.9f}" for v in tcp) + "])"]
    for k in (1, 2, 3, 4):
        lines += [f"  global Waypoint_{k}_p={pose(points[k])}", f"  global Waypoint_{k}_q={joints(points[k])}"]
    lines += [
        f"  movej(get_inverse_kin({pose(points[0])}, qnear={joints(points[0])}), a=1.4, v=1.05)",
        "  movel(Waypoint_1_p, a=1.2, v=0.25, r=0.005)",
        "  movec(Waypoint_2_p, Waypoint_3_p, a=1.2, v=0.1, r=0, mode=0)",
        "  movel(Waypoint_4_p, a=1.2, v=0.25)",
        # a plain pose: the controller moves on in the posture of the previous target
        f"  movel({pose(points[5])}, a=1.2, v=0.25)" if posture != "home"
        else f"  movej(get_inverse_kin({pose(points[5])}, qnear={joints(points[5])}), a=1.4, v=1.05)",
        "end",
        "e2e()",
    ]
    return Case("urscript", robot, points, np.eye(4), {"e2e.script": "\n".join(lines) + "\n"})


def csv_case(robot, posture):
    """Program CSV: base frame, the robot's TCP (a CSV states neither user frames nor tools)."""

    def written(T):
        return xyzabc(np.concatenate([np.round(T[:3, 3], 3), np.round(abc_of(T), 4)]))

    points = [p for p in build_points("csv", robot, np.eye(4), written, posture) if not p.framed]
    text = csv_text(points, 3, 4, joints=posture != "home")  # the default posture needs no joints
    return Case("csv", robot, points, np.eye(4), {"e2e.csv": text})


def csv_text(points, places, angle_places, joints=False):
    """A program CSV of the points' base-frame poses, with their joints j1..j6 (deg) if asked."""
    rows = ["x,y,z,a,b,c,motion,speed" + (",j1,j2,j3,j4,j5,j6" if joints else "")]
    for p in points:
        motion = "PTP" if p.motion == "ptp" else "LIN"
        row = f"{fixed(p.T_base[:3, 3], places)},{fixed(abc_of(p.T_base), angle_places)},{motion},100"
        rows.append(row + ("," + fixed(np.degrees(p.q), 6) if joints else ""))
    return "\n".join(rows) + "\n"


BUILDERS = {"krl": krl_case, "rapid": rapid_case, "fanuc_ls": fanuc_case, "urscript": urscript_case, "csv": csv_case}


# --------------------------------------------- calibration, running, landing


@pytest.fixture(scope="module")
def cells(tmp_path_factory):
    """``cell(name, posture) -> (robot, virtual robot, model, model file)``: the robot with TOOL as its TCP.

    Calibrated once per posture, measured in that posture: a model identified in one arm
    posture does not predict the errors of another (gear and compliance errors follow
    the joints), as a real cell calibrates the posture its programs run in.
    """
    made = {}

    def cell(name, posture="home"):
        if (name, posture) not in made:
            folder = tmp_path_factory.mktemp(name)
            yaml_text = resources.files("trajcomp.arm.robots").joinpath(f"{name}.yaml").read_text(encoding="utf-8")
            robot_file = folder / f"{name}_tool.yaml"
            robot_file.write_text(yaml_text + f"tool: [{fixed(TOOL, 1)}]\n")
            robot = load_robot(robot_file)
            corner, side, step = CUBES[name]
            virtual = VirtualRobot.create(robot, "paper", seed=1)
            plan = plan_grid(robot, corner, side, step, one_posture=False)  # re-solved in `posture` below
            assert plan.reachable.all(), name
            joints = np.array([declared_joints(robot, T, posture) for T in fk(robot, plan.joints)])
            rng = np.random.default_rng(11)
            meas = Measurements(joints=joints, position=plan.position, measured=virtual.measure(joints, rng),
                                lines=np.arange(len(joints)) + 2, path=f"{name}.csv")
            model = calibrate(robot, meas, robot_ref=str(robot_file), method="composite", grid_step=step, folds=3)
            save_model(folder / "model.yaml", model)
            made[name, posture] = (robot, virtual, model, folder / "model.yaml")
        return made[name, posture]

    return cell


def compensate_cli(program, model_path, output, options=()):
    """Compensate without re-timing (its speed fields are tested in test_timing_languages.py)."""
    command = ["compensate", str(program), "--model", str(model_path), *options, "--retime", "none"]
    assert main([*command, "-o", str(output)]) == 0
    return formats.read(output)


def controller_joints(case, program):
    """Joints (N, 6) rad the controller runs for the motion targets of a program read back from file."""
    robot = case.robot
    used = [i for m in program.motions for i in (m.via, m.target) if i is not None]
    out = [robot.home]
    for index, point in zip(used, case.points, strict=True):
        target = program.targets[index]
        T_base = case.frame @ target.pose if point.framed else target.pose
        if target.joints is not None:  # URScript Waypoint_q / qnear, CSV j1..j6: they must be the pose's joints
            assert np.linalg.norm(fk(robot, target.joints)[:3, 3] - T_base[:3, 3]) < 2e-3, target.label
            out.append(target.joints)
        elif target.config:
            out.append(joints_of_configuration(case.language, robot, T_base, target.config))
        else:  # a pose alone: the controller's IK, nearest the joints it is at
            solved = ik(robot, T_base[None], seed=out[-1])
            assert solved.success[0], (case.language, target.label, solved.reason)
            out.append(solved.q[0])
    return np.array(out[1:])


def joints_of_configuration(language, robot, T_base, config):
    """The nominal IK solution (branch and joint turns) the controller runs for configuration data ``config``.

    As a controller reads them: the branch the flags name, each joint in the window its code names
    or within BOUNDARY_TOLERANCE of it (a joint on a boundary satisfies both codes); of two
    candidates on a boundary, the one further inside its window.
    """
    q_branches, valid = ik_all(robot, T_base[None])
    turns = 2 * np.pi * np.array(list(itertools.product((-1, 0, 1), repeat=6)))
    candidates = (q_branches[0][valid[0]][:, None, :] + turns[None]).reshape(-1, 6)
    candidates = candidates[robot.within_limits(candidates)]
    data = configuration_data(language)
    branch, lower, upper = declared_windows(data, [config])
    flags = [declared_windows(data, [c])[0][0] for c in configuration_for(data, robot, candidates)]
    outside = np.maximum(lower - candidates, candidates - upper).max(axis=1)
    match = np.flatnonzero((np.array(flags) == branch[0]) & (outside <= BOUNDARY_TOLERANCE))
    assert len(match) in (1, 2), f"{language}: {len(match)} solutions have configuration {config}"
    return candidates[match[np.argmin(outside[match])]]


def landing_errors(points, virtual, q):
    """|reached - target| (N,) mm of the measured TCP on the virtual robot."""
    reached = virtual.reached_poses(np.asarray(q).reshape(-1, 6))[:, :3, 3]
    return np.linalg.norm(reached - np.array([p.T_base[:3, 3] for p in points]).reshape(-1, 3), axis=1)


# ------------------------------------------------------------------- tests


@pytest.fixture(scope="module", params=list(itertools.product(sorted(LANGUAGES), ("home", "flipped"))),
                ids="-".join)
def run(request, cells, tmp_path_factory):
    """One language's program, in one posture, compensated through the CLI and run on the virtual robot."""
    language, posture = request.param
    robot, virtual, _, model_path = cells(LANGUAGES[language], posture)
    case = BUILDERS[language](robot, posture)
    folder = tmp_path_factory.mktemp(language)
    for name, text in case.files.items():
        (folder / name).write_bytes(text.encode("utf-8"))
    program = folder / next(iter(case.files))
    (folder / "out").mkdir()
    original = formats.read(program)
    corrected = compensate_cli(program, model_path, folder / "out" / program.name, case.options)
    # the same targets through a program CSV (base frame, written with 6 decimals)
    (folder / "reference.csv").write_text(csv_text(case.points, 6, 9, joints=True))
    reference = compensate_cli(folder / "reference.csv", model_path, folder / "out" / "reference.csv")
    plain = dataclasses.replace(case, language="csv", frame=np.eye(4),
                                points=[dataclasses.replace(p, framed=False) for p in case.points])
    return {
        "case": case,
        "original": original,
        "corrected": corrected,
        "q_before": controller_joints(case, original),
        "q_after": controller_joints(case, corrected),
        "before": landing_errors(case.points, virtual, controller_joints(case, original)),
        "after": landing_errors(case.points, virtual, controller_joints(case, corrected)),
        "csv": landing_errors(case.points, virtual, controller_joints(plain, reference)),
    }


def test_the_original_program_misses_its_targets(run):
    assert run["before"].min() > MISSED, run["before"]


def test_the_compensated_program_lands_on_its_targets(run):
    assert run["after"].max() < LANDED, run["after"]


def test_it_lands_as_well_as_the_csv_path(run):
    np.testing.assert_allclose(run["after"], run["csv"], atol=SAME_AS_CSV)


# Joints whose sign, quadrant or turn the language's configuration data encode, and the
# boundaries of those codes (deg): KUKA T = signs, ABB cf1/cf4/cf6 = 90-deg quadrants,
# FANUC turn numbers change at odd multiples of 180 deg.
CODE_BOUNDARIES = {"krl": ((0, 1, 2, 3, 4, 5), 360.0, 0.0), "rapid": ((0, 3, 5), 90.0, 0.0),
                   "fanuc_ls": ((0, 3, 5), 360.0, 180.0)}


def on_a_code_boundary(language, q, margin=0.5):
    """True where a joint of q (N, 6) rad lies within ``margin`` deg of a boundary of its configuration code."""
    if language not in CODE_BOUNDARIES:
        return np.zeros(len(q), dtype=bool)
    joints, period, shift = CODE_BOUNDARIES[language]
    offset = np.mod(np.degrees(q[:, joints]) - shift + period / 2, period) - period / 2
    return np.any(np.abs(offset) < margin, axis=1)


def test_the_declared_posture_is_the_one_written_and_run(run):
    """Every point runs in the posture it declared (joints within 1 deg), with its configuration data.

    The data are the declared ones, except where a joint sits on a boundary of its code
    (J4 = 0 exactly, a turn at 180 deg) and the correction moves it across by a hair: the
    data then describe the corrected joints, the same posture.
    """
    case, original, corrected = run["case"], run["original"], run["corrected"]
    used = [i for m in original.motions for i in (m.via, m.target) if i is not None]
    declared = [original.targets[i].joints is not None or bool(original.targets[i].config) for i in used]
    np.testing.assert_allclose(run["q_before"][declared], np.array([p.q for p in case.points])[declared], atol=1e-6)
    assert np.abs(run["q_after"] - run["q_before"]).max() < np.radians(1.0)
    changed = np.array([corrected.targets[i].config != original.targets[i].config for i in used])
    assert not np.any(changed & ~on_a_code_boundary(case.language, run["q_before"]))


def test_only_numbers_change(run):
    """Same lines and statements: the corrected files differ from the originals in target numbers only."""
    original, corrected = run["original"], run["corrected"]
    if run["case"].language == "csv":
        pytest.skip("a program CSV gains j1..j6 columns (docs/conventions.md)")
    for before, after in zip(original.sources, corrected.sources, strict=True):
        assert len(before.text.splitlines()) == len(after.text.splitlines())
        for a, b in zip(before.text.splitlines(), after.text.splitlines()):
            if "CONFIG" in a:  # FANUC flags are letters
                continue
            assert _skeleton(a) == _skeleton(b), (a, b)
    assert [type(i) for i in original.items] == [type(i) for i in corrected.items]


def _skeleton(line):
    return "".join(ch for ch in line if not (ch.isdigit() or ch in ".-+"))


def test_a_tool_other_than_the_measured_tcp_lands(cells):
    """A model that locates the flange places other tools; one that does not says so.

    Position measurements of one TCP in one orientation cannot tell the
    flange's pose from the TCP's offset (d6 vs tool z, wrist angles vs tool
    lever), and a point on the last axis never shows that axis' direction:
    such models name the reason. A tracker target beside the tool, measured
    with the tool tilted about two axes, locates the flange; program tools
    (taken as exact on the flange) then land, in postures around the
    measured ones, at orientations up to the plan's tilt.
    """
    robot, virtual, single, _ = cells("ur10", "home")
    assert not single.places_other_tools and "orientations" in single.other_tools_reason
    corner, side, step = CUBES["ur10"]
    orientations = spread_orientations(default_orientation(robot), 5, np.radians(30))

    def tilted_calibration(target):
        probe = robot.replace(T_flange_tool=target)
        plan = plan_grid(probe, corner, side, step, orientations)
        q = plan.joints[plan.reachable]  # a few far-corner targets are out of reach when tilted
        meas = Measurements(joints=q, position=plan.position[plan.reachable], lines=np.arange(len(q)) + 2,
                            measured=measure(target, q), path="ur10-tilted.csv")
        return calibrate(probe, meas, method="composite", folds=0), q

    def measure(tool, q):
        """The cell's arm measured at a point ``tool`` on its flange (the tool carries the payload)."""
        reached = virtual.reached_joints(q)
        seen = fk(virtual.true_robot.replace(T_flange_tool=tool), reached)[:, :3, 3]
        return seen + np.random.default_rng(11).normal(0.0, virtual.profile.noise_sigma, seen.shape)

    on_axis, _ = tilted_calibration(robot.T_flange_tool)
    assert not on_axis.places_other_tools and "axis" in on_axis.other_tools_reason
    model, q_measured = tilted_calibration(xyzabc((40.0, -30.0, 60.0, 0.0, 0.0, 0.0)))
    assert model.places_other_tools, model.other_tools_reason
    rng = np.random.default_rng(4)
    postures = q_measured[rng.choice(len(q_measured), 20)] + np.radians(rng.uniform(-3.0, 3.0, (20, 6)))
    for other in (robot.T_flange_tool, xyzabc((0.0, 0.0, 150.0, 0.0, 0.0, 0.0))):
        targets = fk(robot.replace(T_flange_tool=other), postures)
        landed = {}
        for name, calibrated in (("located", model), ("single", single)):
            q = compensate(calibrated, targets, tool=other, seed=postures).q
            reached = fk(virtual.true_robot.replace(T_flange_tool=other), virtual.reached_joints(q))[:, :3, 3]
            landed[name] = np.linalg.norm(reached - targets[:, :3, 3], axis=1).max()
        assert landed["located"] < LANDED < landed["single"], landed
