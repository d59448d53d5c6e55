"""The compensation core in pieces: chunks give the result of one piece and name failures alike; tool groups."""

import numpy as np
import pytest

import trajcomp.compensation.target_correction as compensation
from trajcomp.compensation.target_correction import compensate, program_corrector
from trajcomp.errors import IKError, ModelError
from trajcomp.arm.ik import IKResult
from trajcomp.calibration.measurement_plan import default_orientation
from trajcomp.compensation.program_rewrite import _compensation_warnings
from trajcomp.arm.transforms import abc_to_matrix
from virtual_cell import CORNER, SIDE, landing_error, virtual_cell


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    return virtual_cell(tmp_path_factory)


def targets_in_cube(robot, n, seed):
    """n TCP poses (n, 4, 4) inside the calibrated cube, tool orientation of home."""
    targets = np.tile(np.eye(4), (n, 1, 1))
    targets[:, :3, :3] = abc_to_matrix(default_orientation(robot))
    targets[:, :3, 3] = np.array([320.0, -80.0, 320.0]) + np.random.default_rng(seed).uniform(0, 460, (n, 3))
    return targets


def test_chunks_give_the_result_of_one_piece(cell, monkeypatch):
    targets = targets_in_cube(cell.robot, 40, 1)
    targets[9, :3, 3] = [550.0, 150.0, 250.0]  # below the cube: flagged outside, in the second chunk
    whole = compensate(cell.model, targets)
    monkeypatch.setattr(compensation, "CHUNK", 7)
    pieces = compensate(cell.model, targets)
    for name in ("T_command", "q", "correction", "residual", "outside"):
        np.testing.assert_array_equal(getattr(pieces, name), getattr(whole, name))
    assert pieces.outside.tolist() == [i == 9 for i in range(40)]
    assert landing_error(cell, np.degrees(pieces.q), targets)[~pieces.outside].max() < 0.05


def test_failures_in_chunks_are_named_as_in_one_piece(cell, monkeypatch):
    """The message names every failing target of the whole set with its count, not a chunk's."""
    targets = targets_in_cube(cell.robot, 30, 2)
    targets[[12, 23], :3, 3] = [[3000.0, 0.0, 500.0], [0.0, -2500.0, 900.0]]  # beyond the reach, chunks 2 and 4
    names = [f"prog.csv line {k + 2}" for k in range(30)]
    with pytest.raises(IKError) as whole:
        compensate(cell.model, targets, label="prog.csv", names=names)
    monkeypatch.setattr(compensation, "CHUNK", 6)
    with pytest.raises(IKError) as pieces:
        compensate(cell.model, targets, label="prog.csv", names=names)
    assert str(pieces.value) == str(whole.value)
    assert "2 of 30 targets" in str(whole.value)
    assert "prog.csv line 14: unreachable" in str(whole.value) and "prog.csv line 25" in str(whole.value)

    outside = targets_in_cube(cell.robot, 30, 3)
    outside[[8, 20], :3, 3] = [[550.0, 150.0, 250.0], [250.0, 100.0, 500.0]]
    with pytest.raises(ModelError, match=r"2 of 30 targets lie outside .*: target 8: outside the grid; target 20:"):
        compensate(cell.model, outside, outside="error")
    with pytest.raises(ModelError, match=r"prog.csv: 2 of 30 .*: prog.csv line 10: outside the grid; prog.csv line 22"):
        compensate(cell.model, outside, outside="error", label="prog.csv", names=names)


def test_program_corrector_compensates_each_tool_group_with_its_tool(cell):
    targets = targets_in_cube(cell.robot, 12, 4)
    gripper = np.eye(4)
    gripper[:3, 3] = [0.0, 30.0, 150.0]
    measured = cell.model.nominal.T_flange_tool
    on_gripper = np.arange(12) % 3 == 1
    tools = np.where(on_gripper[:, None, None], gripper, measured)
    seeds = compensate(cell.model, targets).q
    names = [f"line {k}" for k in range(12)]
    result = program_corrector(cell.model)(targets, tools, seeds, names)
    alone = {False: compensate(cell.model, targets[~on_gripper], seed=seeds[~on_gripper]),
             True: compensate(cell.model, targets[on_gripper], tool=gripper, seed=seeds[on_gripper])}
    for name in ("T_command", "q", "correction", "residual", "outside"):
        for group, reference in alone.items():
            np.testing.assert_array_equal(getattr(result, name)[on_gripper == group], getattr(reference, name))
    assert not np.allclose(result.q[on_gripper], seeds[on_gripper], atol=1e-3)  # the gripper's TCP moved the joints

    one_tool = program_corrector(cell.model, label="prog.csv")
    np.testing.assert_array_equal(one_tool(targets, np.broadcast_to(measured, (12, 4, 4)), seeds, names).q,
                                  compensate(cell.model, targets, seed=seeds).q)
    targets[5, :3, 3] = [3000.0, 0.0, 500.0]
    with pytest.raises(IKError, match=r"prog.csv: no IK solution for 1 of 12 targets \(line 5: unreachable\)"):
        one_tool(targets, np.broadcast_to(measured, (12, 4, 4)), seeds, names)


def test_targets_stop_iterating_once_they_land(cell, monkeypatch):
    targets = targets_in_cube(cell.robot, 40, 5)
    solved_rows = []
    solve = compensation._solve
    monkeypatch.setattr(compensation, "_solve", lambda *args: solved_rows.append(len(args[2])) or solve(*args))
    landed = compensate(cell.model, targets)
    assert solved_rows[0] == 40 and sum(solved_rows) < 3 * 40  # fewer rows than three full passes
    monkeypatch.setattr(compensation, "LANDED", 0.0)
    every_pass = compensate(cell.model, targets)
    assert landed.residual.max() < 1e-5
    np.testing.assert_allclose(landed.T_command[:, :3, 3], every_pass.T_command[:, :3, 3], rtol=0, atol=1e-5)


def test_a_failure_among_the_rows_of_a_later_pass_is_counted_among_all_targets():
    solved = IKResult(np.full((2, 6), np.nan), np.array([True, False]), np.zeros(2), np.zeros(2),
                      np.array(["", "unreachable"]))
    names = [f"line {k}" for k in range(5)]
    with pytest.raises(IKError, match=r"^p: no IK solution for 1 of 5 targets \(line 3: unreachable\)$"):
        compensation._of_all(solved, np.array([1, 3]), 5).raise_on_failure("p", names)


def test_targets_near_a_face_keep_the_grid_value_where_their_command_leaves_the_grid(cell):
    """Grid mode gave a target just inside a face no correction when its command left the grid (2 mm off)."""
    lower, upper = np.array(CORNER), np.array(CORNER) + SIDE
    centre = (lower + upper) / 2
    faces = np.repeat(centre[None], 6, axis=0)
    for axis in range(3):
        faces[2 * axis, axis], faces[2 * axis + 1, axis] = lower[axis] + 0.01, upper[axis] - 0.01
    targets = np.tile(np.eye(4), (6, 1, 1))
    targets[:, :3, :3] = abc_to_matrix(default_orientation(cell.robot))
    targets[:, :3, 3] = faces
    result = compensate(cell.model, targets, mode="grid")
    leaves = result.near_face
    assert leaves.any() and not leaves.all()  # the correction points out of the grid at some faces only
    command = result.T_command[:, :3, 3]
    assert np.array_equal(leaves, np.any((command < lower) | (command > upper), axis=1))
    assert not result.outside.any()  # the targets are inside: not flagged outside, and not refused
    np.testing.assert_array_equal(compensate(cell.model, targets, mode="grid", outside="error").near_face, leaves)
    landed = landing_error(cell, np.degrees(result.q), targets)
    as_planned = landing_error(cell, np.degrees(compensate(cell.model, targets, mode="none").q), targets)
    assert as_planned[leaves].min() > 1.5  # what zero correction there gave
    assert landed.max() < 0.25  # grid mode's accuracy mid-cell (idw8 over 100 mm cells), at every face
    assert np.linalg.norm(result.correction[leaves], axis=1).min() > 1.0  # really corrected


def test_near_face_and_other_tool_targets_are_named_in_the_program_warnings(cell):
    lower = np.array(CORNER)
    targets = np.tile(np.eye(4), (3, 1, 1))
    targets[:, :3, :3] = abc_to_matrix(default_orientation(cell.robot))
    targets[:, :3, 3] = [lower + [250, 250, 0.01], lower + [250, 250, 250], lower + [250, 0.01, 250]]
    gripper = np.eye(4)
    gripper[:3, 3] = [0.0, 30.0, 150.0]
    tools = np.stack([cell.model.nominal.T_flange_tool, gripper, cell.model.nominal.T_flange_tool])
    seeds = compensate(cell.model, targets).q
    correct = program_corrector(cell.model, mode="grid")
    result = correct(targets, tools, seeds, ["P1 (p.src:3)", "P2 (p.src:4)", "P3 (p.src:5)"])
    assert not cell.model.places_other_tools
    assert result.other_tool.tolist() == [False, True, False]
    warnings = _compensation_warnings(result, ["P1 (p.src:3)", "P2 (p.src:4)", "P3 (p.src:5)"])
    faces = [w for w in warnings if "near a face" in w]
    assert len(faces) == (1 if result.near_face.any() else 0)
    assert all(label in faces[0] for label, near in zip(["P1", "P2", "P3"], result.near_face) if near)
    assert any(w.startswith("1 targets use a tool other than the calibrated TCP") and w.endswith("P2 (p.src:4)")
               for w in warnings)


def test_a_target_at_the_edge_of_the_reach_is_refused_naming_the_reach(cell):
    """The elbow 0.5 deg from stretched: the real arm needs more reach than it has for the corrected command."""
    from trajcomp.arm.kinematics import fk

    stretched = fk(cell.robot, np.radians([[0.0, -90.0, 0.5, -90.0, -90.0, 0.0]]))
    with pytest.raises(IKError, match=r"target 0: not converged\); 1 of them at the edge of the arm's reach "
                                      r"\(the elbow 0\.50 deg from stretched\)"):
        compensate(cell.model, stretched)
    inside = fk(cell.robot, np.radians([[0.0, -90.0, 30.0, -90.0, -90.0, 0.0]]))
    assert compensate(cell.model, inside).q.shape == (1, 6)  # the elbow bent: reached as any target
