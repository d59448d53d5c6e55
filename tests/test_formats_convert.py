"""Conversion between every pair of languages preserves poses (1e-6 mm); compensation of programs."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import TrajcompError, WriteError
from trajcomp.postprocess import FRAMELESS, compensate_program, convert_program
from trajcomp.robot import load_robot
from trajcomp.configuration import kuka_status_turn
from trajcomp.kinematics import fk
from trajcomp.transforms import matrix_to_pose, pose_to_matrix

DATA = Path(__file__).parent / "data" / "programs"
GOLDEN = {
    "csv": DATA / "csv" / "path.csv",
    "krl": DATA / "krl" / "weld.src",
    "rapid": DATA / "rapid" / "Welding.mod",
    "fanuc_ls": DATA / "fanuc" / "PICK_PLACE.LS",
    "urscript": DATA / "urscript" / "pick.script",
}
EXTENSION = {"csv": ".csv", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls", "urscript": ".script"}
TOOLS = {name: pose_to_matrix([1.0 * k, -2.0, 100.0 + k, 0.1, 0.2 * k, -0.3]) for k, name in enumerate("123", 1)}
FRAMES = {"1": pose_to_matrix([400.0, -150.0, 20.0, 0.5, 0.0, 0.0])}


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
    stack = program.cartesian_targets()
    seeded = program.with_targets(stack.index, joints=np.zeros((len(stack), 6)))  # configuration from joints
    converted = convert_program(seeded, to_format, robot=robot, tools=TOOLS, frames=FRAMES)
    out = tmp_path / f"converted{EXTENSION[to_format]}"
    formats.write(out, converted)
    again = formats.read(out)
    base = to_format in FRAMELESS
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


def _rigid_correct(offset, joints):
    """Stand-in compensation: command = target + offset (base frame); the joints are given (seed if any)."""
    calls = []

    def correct(T_base_tcp, T_flange_tool, q_seed):
        calls.append(len(T_base_tcp))
        command = T_base_tcp.copy()
        command[:, :3, 3] += offset
        return command, (np.tile(joints, (len(command), 1)) if q_seed is None else q_seed)

    correct.calls = calls
    return correct


def test_compensation_moves_each_target_by_the_offset_in_its_own_frame(tmp_path):
    robot = load_robot("abb_irb4600")
    program = formats.read(GOLDEN["rapid"])
    offset = np.array([0.3, -0.2, 0.1])
    q = np.radians([100, 10, -20, 30, -40, 200])
    correct = _rigid_correct(offset, q)
    new, report = compensate_program(program, correct, robot)
    assert correct.calls == [len(program.cartesian_targets())]  # one vectorized call
    stack, new_stack = program.cartesian_targets(), new.cartesian_targets()
    for frame, before, after in zip(stack.frame, stack.T, new_stack.T):
        R = program.frames[frame][:3, :3]
        np.testing.assert_allclose(after[:3, 3] - before[:3, 3], R.T @ offset, atol=1e-9)
    assert report.compensated == stack.names
    assert [line for line, _ in report.not_compensated] == [25, 26, 31]
    assert report.unused == ("pUnused",)
    assert report.joint_targets == ("jHome", "line 30")
    formats.write(tmp_path / "Welding.mod", new)
    again = formats.read(tmp_path / "Welding.mod")
    for i in stack.index:
        assert again.targets[i].config == (1, 0, 2, 1)  # confdata of q (100, 30, 200 deg; J5 < 0)
    for i in program.joint_targets()[0]:
        np.testing.assert_array_equal(again.targets[i].joints, program.targets[i].joints)


def test_joint_targets_compensated_on_request():
    robot = load_robot("abb_irb4600")
    program = formats.read(GOLDEN["rapid"])
    index, q = program.joint_targets()
    joints = np.radians([1, 2, 3, 4, 5, 6])
    new, report = compensate_program(program, _rigid_correct(np.zeros(3), joints), robot, joint_targets="compensate")
    for i in index:
        np.testing.assert_allclose(new.targets[i].joints, joints)  # the corrected joints replace them
        assert new.targets[i].edited
    assert report.joint_mode == "compensate"


def test_undefined_tool_is_an_error_not_a_guess(robot):
    program = formats.read(GOLDEN["krl"])
    with pytest.raises(TrajcompError, match=r"tool '1' is used but not defined.*--tool 1=x,y,z,a,b,c"):
        compensate_program(program, _rigid_correct(np.zeros(3), np.zeros(6)), robot)
