"""Apply corrected poses to robot programs, and convert programs between languages.

`compensate_program` takes every target a program's motions use to the base
frame with its tool, asks a ``correct`` callable (the compensation core)
once for all of them, brings the commands back to each target's own frame
and writes them into the program with configuration data recomputed from the
corrected joints. `convert_program` re-expresses a program in another
language.

Frames: a target's pose is T_frame_tcp in its user frame (KUKA base, ABB
work object, FANUC user frame). Frame values are T_world_frame and tool
values T_flange_tool (mm); the base is placed in the world by the robot's
``T_world_base``. A frame or tool the program uses must be defined in the
program or supplied by the caller; a missing one is an error, never a guess.
Frame ``None`` is the base, tool ``None`` the robot description's tool.
"""

import dataclasses

import numpy as np

from trajcomp.configuration import configuration_for
from trajcomp.errors import IKError, TrajcompError
from trajcomp.ik import ik
from trajcomp.kinematics import fk
from trajcomp.program import Program
from trajcomp.transforms import invert

FRAMELESS = frozenset({"csv", "urscript"})  # languages whose poses are always in the base frame


@dataclasses.dataclass(frozen=True)
class ProgramReport:
    """What a compensation or conversion did to a program.

    Attributes
    ----------
    compensated : tuple of str
        Labels of the Cartesian targets given new numbers.
    joint_targets : tuple of str
        Labels of joint targets, and whether they were kept or compensated.
    not_compensated : tuple of (int, str)
        Line and text of motions whose position is computed at run time or
        refers to a point the program does not define: passed through.
    unused : tuple of str
        Targets no motion uses: left as written.
    joint_mode : str
        ``"keep"`` or ``"compensate"``.
    """

    compensated: tuple
    joint_targets: tuple
    not_compensated: tuple
    unused: tuple
    joint_mode: str = "keep"

    def lines(self):
        """Human-readable summary lines."""
        out = [f"compensated targets: {len(self.compensated)}"]
        verb = "compensated" if self.joint_mode == "compensate" else "kept as written"
        if self.joint_targets:
            out.append(f"joint targets {verb}: {', '.join(self.joint_targets)}")
        for line, text in self.not_compensated:
            out.append(f"not compensated (computed at run time or undefined), line {line}: {text}")
        if self.unused:
            out.append(f"unused points left as written: {', '.join(self.unused)}")
        return out


def _frame_table(program, robot, tools, frames):
    """Lookup functions name -> T_flange_tool and name -> T_base_frame, with located errors."""
    tool_values = {**(tools or {}), **program.tools}
    frame_values = {**(frames or {}), **program.frames}
    T_base_world = invert(robot.T_world_base) if robot is not None else np.eye(4)
    default_tool = robot.T_flange_tool if robot is not None else np.eye(4)

    def lookup(values, name, what, option):
        if name not in values:
            raise TrajcompError(
                f"{program.name}: {what} {name!r} is used but not defined in the program; "
                f"give its value (e.g. {option} {name}=x,y,z,a,b,c in mm and deg)"
            )
        return values[name]

    def tool(name):
        return default_tool if name is None else lookup(tool_values, name, "tool", "--tool")

    def frame(name):
        return np.eye(4) if name is None else T_base_world @ lookup(frame_values, name, "frame", "--frame")

    return tool, frame


def compensate_program(program, correct, robot, *, tools=None, frames=None, joint_targets="keep"):
    """A program whose targets are replaced by their compensated commands.

    Parameters
    ----------
    program : Program
    correct : callable
        ``correct(T_base_tcp (N, 4, 4), T_flange_tool (N, 4, 4), q_seed (N, 6)
        or None) -> (T_base_tcp_command (N, 4, 4), q (N, 6))``: the
        nominal-model TCP pose that makes the real arm land on each target,
        and its joints (rad). Called once, for all targets.
    robot : Robot
        The nominal robot (configuration data, joint-target poses, base
        placement and default tool).
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Values of tools (T_flange_tool) and user frames (T_world_frame), mm,
        that the program uses but does not define.
    joint_targets : {"keep", "compensate"}
        ``"compensate"`` treats each joint target as the nominal pose FK(q)
        stands for and replaces it with the corrected joints.

    Returns
    -------
    (Program, ProgramReport)

    Raises
    ------
    TrajcompError
        A tool or frame used but not defined, or a target used with two
        different tools or frames.
    """
    if joint_targets not in ("keep", "compensate"):
        raise ValueError(f"joint_targets must be 'keep' or 'compensate', got {joint_targets!r}")
    tool_of, frame_of = _frame_table(program, robot, tools, frames)
    usage = program.usage()
    stack = program.cartesian_targets()
    T_base_frame = np.array([frame_of(f) for f in stack.frame]).reshape(-1, 4, 4)
    T_tool = [tool_of(t) for t in stack.tool]
    T_target = [T_base_frame @ stack.T]
    seeds = [program.targets[i].joints for i in stack.index]
    joint_index, q_joint = program.joint_targets()
    if joint_targets == "compensate" and len(joint_index):
        joint_tools = [tool_of(usage[i][0]) for i in joint_index]
        T_target.append(fk(robot, q_joint, tcp=False) @ np.array(joint_tools))
        T_tool += joint_tools
        seeds += list(q_joint)
    T_target = np.concatenate(T_target)
    edited = program
    if len(T_target):
        seed = None if any(s is None for s in seeds) else np.array(seeds)
        T_command, q = correct(T_target, np.array(T_tool), seed)
        n = len(stack)
        poses = invert(T_base_frame) @ T_command[:n]
        edited = edited.with_targets(
            stack.index, poses=poses, joints=q[:n], configs=configuration_for(program.format, robot, q[:n])
        )
        if n < len(T_target):
            edited = edited.with_targets(joint_index, joints=q[n:])
    report = ProgramReport(
        compensated=stack.names,
        joint_targets=tuple(program.targets[i].label for i in joint_index),
        not_compensated=tuple((m.line, m.text) for m in program.runtime_motions()),
        unused=tuple(t.label for t in program.unused_targets()),
        joint_mode=joint_targets,
    )
    return edited, report


def nominal_joints(robot, T_base_tcp, T_flange_tool, seed=None, labels=None):
    """Joints (N, 6), rad, that put each tool (N, 4, 4) on its pose (N, 4, 4) with the nominal robot.

    Parameters
    ----------
    labels : sequence of str, optional
        Target names for the error message.

    Raises
    ------
    IKError
        Poses without solution, named with their reason.
    """
    T_base_tcp = np.asarray(T_base_tcp, dtype=float)
    labels = labels or [f"target {k}" for k in range(len(T_base_tcp))]
    q = np.empty((len(T_base_tcp), 6))
    reason = np.empty(len(T_base_tcp), dtype=object)
    flat = np.round(np.asarray(T_flange_tool, dtype=float).reshape(len(T_base_tcp), 16), 12)
    tools, group = np.unique(flat, axis=0, return_inverse=True)
    for k, tool in enumerate(tools):
        rows = np.flatnonzero(group.ravel() == k)
        solved = ik(robot.replace(T_flange_tool=tool.reshape(4, 4)), T_base_tcp[rows],
                    seed=None if seed is None else seed[rows])
        q[rows], reason[rows] = solved.q, solved.reason
    failed = [f"{labels[k]}: {reason[k]}" for k in np.flatnonzero(reason != "")]
    if failed:
        raise IKError(f"robot {robot.name}: no joint solution for {len(failed)} targets ({'; '.join(failed[:5])})")
    return q


def convert_program(program, to_format, *, robot=None, tools=None, frames=None):
    """The program re-expressed for another language (written fresh, not patched).

    Poses keep their frames where the language has user frames; for CSV and
    URScript they are moved to the base frame (the frames' values must then
    be known). Configuration data are computed from each target's joints,
    or from nominal IK when the joints are unknown and a robot is given.

    Parameters
    ----------
    program : Program
    to_format : str
        Registry name of the language.
    robot : Robot, optional
        Needed for configuration data (KRL S/T, RAPID confdata, FANUC CONFIG)
        of Cartesian targets without known joints.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Values the program uses but does not define.

    Returns
    -------
    Program
        With no sources: writers generate the text.
    """
    tool_of, frame_of = _frame_table(program, robot, tools, frames)
    usage = program.usage()
    targets = list(program.targets)
    motions = program.motions
    if to_format in FRAMELESS:
        for i, (_, frame) in usage.items():
            if targets[i].pose is not None and frame is not None:
                targets[i] = dataclasses.replace(targets[i], pose=frame_of(frame) @ targets[i].pose, frame=None)
        motions = tuple(dataclasses.replace(m, frame=None) for m in motions)
    cartesian = [i for i in sorted(usage) if not targets[i].is_joint]
    needs_config = to_format in ("krl", "rapid", "fanuc_ls")
    unknown = [i for i in cartesian if targets[i].joints is None]
    if robot is not None and unknown and (needs_config or to_format in FRAMELESS):
        T = np.array([frame_of(usage[i][1]) @ program.targets[i].pose for i in unknown])
        tools_T = np.array([tool_of(usage[i][0]) for i in unknown])
        q = nominal_joints(robot, T, tools_T, labels=[f"{program.name} {targets[i].label}" for i in unknown])
        for i, joints in zip(unknown, q):
            targets[i] = dataclasses.replace(targets[i], joints=joints)
    for i in range(len(targets)):
        known = targets[i].joints is not None and not targets[i].is_joint and robot is not None and needs_config
        config = configuration_for(to_format, robot, targets[i].joints[None])[0] if known else ()
        targets[i] = dataclasses.replace(targets[i], config=config, spans={}, edited=False)
    return Program(
        format=to_format,
        name=program.name,
        items=motions,
        targets=tuple(targets),
        tools={**(tools or {}), **program.tools},
        frames={**(frames or {}), **program.frames},
    )
