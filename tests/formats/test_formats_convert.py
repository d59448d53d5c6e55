"""Conversion between every pair of languages preserves poses (1e-6 mm); compensation of programs."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.formats.capabilities import BaseFrameOnly
from trajcomp.errors import TrajcompError, WriteError
from trajcomp.compensation.program_rewrite import compensate_program, convert_program
from trajcomp.arm.robot import load_robot
from trajcomp.compensation.target_correction import CompensationResult
from trajcomp.formats.krl.configuration import encode as kuka_status_turn
from trajcomp.formats.rapid.configuration import encode as abb_confdata
from trajcomp.programs.frames import FrameTable
from trajcomp.arm.kinematics import fk
from trajcomp.arm.transforms import invert, matrix_to_pose, pose_to_matrix

DATA = Path(__file__).parents[1] / "data" / "programs"
GOLDEN = {
    "csv": DATA / "csv" / "path.csv",
    "krl": DATA / "krl" / "weld.src",
    "rapid": DATA / "rapid" / "Welding.mod",
    "fanuc_ls": DATA / "fanuc" / "PICK_PLACE.LS",
    "urscript": DATA / "urscript" / "pick.script",
}
EXTENSION = {"csv": ".csv", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls", "urscript": ".script"}
TOOLS = {name: pose_to_matrix([1.0 * k, -2.0, 100.0 + k, 0.1, 0.2 * k, -0.3]) for k, name in enumerate("123", 1)}
FRAMES = {"1": pose_to_matrix([400.0, -150.0, 20.0, 0.5, 0.0, 0.0]),
          "Plane_1": pose_to_matrix([300.0, 100.0, 5.0, 0.0, 0.0, 0.25])}


@pytest.fixture(scope="module")
def robot():
    return load_robot("kuka_kr6_r900")


def _positions(program, base):
    """Targets of the compensable motions in order (via, end): poses (base or own frame) or joints."""
    out = []
    frames = {**FRAMES, **program.frames}
    for motion in program.motions:
        for index in (motion.via, motion.target):
            if index is None:
                continue
            target = program.targets[index]
            if target.is_joint:
                out.append(("joints", target.joints))
            else:
                frame = target.frame if target.frame is not None else motion.frame
                T = frames[frame] @ target.pose if base and frame is not None else target.pose
                out.append(("pose", T))
    return out


@pytest.mark.parametrize("to_format", sorted(GOLDEN))
@pytest.mark.parametrize("from_format", sorted(GOLDEN))
def test_conversion_preserves_poses(from_format, to_format, robot, tmp_path):
    program = formats.read(GOLDEN[from_format])
    if from_format == to_format:  # its own language: the byte-preserving writer, every line kept
        same = tmp_path / Path(GOLDEN[from_format]).name
        formats.write(same, convert_program(program, to_format, robot=robot, tools=TOOLS, frames=FRAMES))
        assert same.read_bytes() == Path(GOLDEN[from_format]).read_bytes()
        return
    stack = program.cartesian_targets()
    seeded = program.with_targets(stack.index, joints=np.zeros((len(stack), 6)))  # configuration from joints
    converted = convert_program(seeded, to_format, robot=robot, tools=TOOLS, frames=FRAMES)
    out = tmp_path / f"converted{EXTENSION[to_format]}"
    axis = {"rapid": [250.5], "fanuc_ls": [150.0]}.get(from_format, [])  # pFixture's extax, P[6]'s E1
    if axis and formats.find_format(format=to_format).capability(BaseFrameOnly):
        with pytest.raises(WriteError, match=r"hold 0 external axes; target (pFixture|P\[6\]) \(line \d+\) gives E1 a value"):
            formats.write(out, converted)
        return
    formats.write(out, converted)
    again = formats.read(out)
    external = [t.external[0] for t in again.targets if t.external is not None]
    assert external == axis  # carried; KUKA's E1..E6 = 0 left out
    base = formats.find_format(format=to_format).capability(BaseFrameOnly) is not None
    before, after = _positions(program, base), _positions(again, base)
    assert [kind for kind, _ in before] == [kind for kind, _ in after]
    for (kind, a), (_, b) in zip(before, after):
        if kind == "pose":
            np.testing.assert_allclose(b[:3, 3], a[:3, 3], atol=1e-6)  # mm
            np.testing.assert_allclose(b[:3, :3], a[:3, :3], atol=1e-9)
        else:
            np.testing.assert_allclose(b, a, atol=1e-9)
    assert len(again.runtime_motions()) == 0


def test_conversion_needs_configuration_or_a_robot(tmp_path):
    program = formats.read(GOLDEN["csv"])
    with pytest.raises(WriteError, match="RAPID needs its confdata"):
        formats.write(tmp_path / "x.mod", convert_program(program, "rapid"))


def test_conversion_computes_configuration_with_the_robot(robot, tmp_path):
    q = np.radians([[0, -90, 90, 0, 45, 0], [20, -60, 100, -30, -40, 10], [-30, -100, 80, 10, 60, -20]])
    poses = matrix_to_pose(fk(robot, q))
    rows = [",".join(f"{v:.6f}" for v in (*p[:3], *np.degrees(p[3:]))) for p in poses]
    (tmp_path / "fk.csv").write_text("x,y,z,a,b,c\n" + "\n".join(rows) + "\n")
    converted = convert_program(formats.read(tmp_path / "fk.csv"), "krl", robot=robot)
    solved = np.array([t.joints for t in converted.targets])
    np.testing.assert_allclose(matrix_to_pose(fk(robot, solved)), poses, atol=1e-5)
    assert [t.config for t in converted.targets] == kuka_status_turn(robot, solved)
    formats.write(tmp_path / "fk.src", converted)
    assert [t.config for t in formats.read(tmp_path / "fk.src").targets] == kuka_status_turn(robot, solved)


def _rigid_correct(offset, joint_step=np.zeros(6)):
    """Stand-in compensation: command = target + offset (base frame); joints = seed + joint_step (rad)."""
    calls = []

    def correct(T_base_tcp, T_flange_tool, q_seed, names):
        calls.append(len(T_base_tcp))
        command = T_base_tcp.copy()
        command[:, :3, 3] += offset
        n = len(command)
        return CompensationResult(command, q_seed + joint_step, np.tile(offset, (n, 1)), np.zeros(n, bool), np.zeros(n))

    correct.calls = calls
    return correct


def _reachable(program, robot, q0=np.radians([100, 10, -20, 30, -40, 200])):
    """The program with every used Cartesian target moved to a pose the robot reaches, its confdata consistent.

    Welding.mod's own numbers are a parser test (one point sits inside the robot base); the
    targets become FK of joints near ``q0`` expressed in their own frames.
    """
    plan_index = [i for i in program.usage() if not program.targets[i].is_joint]
    table = FrameTable(program, robot)
    T_base_frame, T_tool, _ = table.targets_in_base(plan_index)
    q = q0 + np.radians(np.arange(len(plan_index)))[:, None] * np.array([1, 1, 1, 0, 0, 0])
    poses = invert(T_base_frame) @ fk(robot.replace(T_flange_tool=np.eye(4)), q) @ T_tool
    return program.with_targets(plan_index, poses=poses, configs=abb_confdata(robot, q))


def test_compensation_moves_each_target_by_the_offset_in_its_own_frame(tmp_path):
    robot = load_robot("abb_irb4600")
    program = _reachable(formats.read(GOLDEN["rapid"]), robot)
    offset = np.array([0.3, -0.2, 0.1])
    correct = _rigid_correct(offset)
    new, report = compensate_program(program, correct, robot)
    assert correct.calls == [len(program.cartesian_targets())]  # one vectorized call
    stack, new_stack = program.cartesian_targets(), new.cartesian_targets()
    for frame, before, after in zip(stack.frame, stack.T, new_stack.T):
        R = program.frames[frame][:3, :3]
        np.testing.assert_allclose(after[:3, 3] - before[:3, 3], R.T @ offset, atol=1e-9)
    assert sorted(report.labels) == sorted(program.where(i) for i in stack.index)
    assert [line for line, _, _ in report.not_compensated] == [25, 26, 31]
    assert report.unused == ("pUnused",)
    assert report.joint_targets == ("jHome", "line 30")
    assert report.declared == report.written  # the corrected joints are the planned ones: same confdata
    formats.write(tmp_path / "Welding.mod", new)
    again = formats.read(tmp_path / "Welding.mod")
    for i in stack.index:
        assert again.targets[i].config == program.targets[i].config
    for i in program.joint_targets()[0]:
        np.testing.assert_array_equal(again.targets[i].joints, program.targets[i].joints)


def test_joint_targets_compensated_on_request():
    robot = load_robot("abb_irb4600")
    program = _reachable(formats.read(GOLDEN["rapid"]), robot)
    index, q = program.joint_targets()
    step = np.radians([0.01, 0.02, 0.03, 0.04, 0.05, 0.06])
    new, report = compensate_program(program, _rigid_correct(np.zeros(3), step), robot, joint_targets="compensate")
    for i in index:
        np.testing.assert_allclose(new.targets[i].joints, program.targets[i].joints + step)  # corrected joints
        assert new.targets[i].edited
    assert report.joint_mode == "compensate"


def test_undefined_tool_is_an_error_not_a_guess(robot):
    program = formats.read(GOLDEN["krl"])
    with pytest.raises(TrajcompError, match=r"tool '1' is used but not defined.*--tool 1=x,y,z,a,b,c"):
        compensate_program(program, _rigid_correct(np.zeros(3)), robot)
