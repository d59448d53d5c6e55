"""RoboDK post processors whose programs come out compensated, as ``trajcomp compensate`` writes them.

RoboDK turns a station's program into robot code by calling a post
processor, a ``RobotPost`` class: ``setFrame`` / ``setTool`` with the active
reference frame and tool, then ``MoveJ(pose, joints, conf_RLF)``,
``MoveL(...)`` and ``MoveC(pose1, joints1, pose2, joints2, conf_RLF_1,
conf_RLF_2)`` with each target's pose (a ``robomath.Mat``, mm: the TCP in
the reference frame), its joints (deg) and its configuration flags
``[REAR, LOWERARM, FLIP]``, and at last ``ProgSave(folder, progname, ...)``,
where the post writes its files and prints ``SAVED: <path>`` for each.
`compensated_post` wraps a vendor's class in one of two ways:

- The program path, where trajcomp reads the language the vendor post
  writes (its ``PROG_EXT``: ``src``, ``mod``, ``ls``, ``script``...; see
  ``trajcomp formats``): the vendor post writes the program as RoboDK
  planned it, then at ``ProgSave`` each file it saved in such a language is
  compensated in place by the pipeline of ``trajcomp compensate``
  (`trajcomp.Compensator.filter_program`: compensate, joint targets
  included by default, re-time, write, judge), its report written beside it
  (``<program>.html`` and ``<program>.json``). The bytes and the verdict are
  those of ``trajcomp compensate <program> --model <model> --joint-targets
  compensate --in-place -o <program> --report <program>``. The verdict and
  the files written are printed, as RoboDK shows a post's output, and added
  to the post's ``LOG``.
- The target path, for a language trajcomp does not read: each pose is
  replaced by its compensated command, its joints by the command's joints in
  the same posture and its flags follow (a flag changes only when a joint
  crosses its boundary, e.g. J5 through zero), before the vendor post writes
  it. Such a program is not re-timed and gets no verdict; a comment at its
  start says so.

A post processor file in RoboDK's ``Posts`` folder, e.g.
``KUKA_KRC4_trajcomp.py``, selected as the robot's post processor::

    from trajcomp_robodk import compensated_post
    from KUKA_KRC4 import RobotPost as VendorPost

    RobotPost = compensated_post(VendorPost, model=r"C:/cells/kr6/model.yaml")

Either way the joints RoboDK plans must be the joints of the pose on the
model's nominal robot with the active tool and frame (1 mm, 1 deg), so a
station whose robot, tool or frame differs from the calibrated one is
refused instead of compensated wrongly; robots with external axes are
refused.
"""

import contextlib
import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from trajcomp import __version__, formats
from trajcomp.api import compensator
from trajcomp.arm.ik import configuration_of
from trajcomp.arm.kinematics import fk
from trajcomp.arm.transforms import rotation_angle_between
from trajcomp.errors import TrajcompError

HINT_POSITION = 1.0  # mm: largest distance between a pose and the nominal pose of its RoboDK joints
HINT_ROTATION = 1.0  # deg: largest rotation between them
SAVED = "SAVED:"  # how a post tells RoboDK the path of a file it wrote (one printed line each)
UNCOMPENSATED = ".uncompensated"  # suffix a refused program is moved to


def compensated_post(vendor_post, model, *, joint_targets="compensate", retime="auto", criteria=None, json_only=False,
                     tools=None, frames=None, **options):
    """A RobotPost class that compensates what ``vendor_post`` writes.

    Parameters
    ----------
    vendor_post : type
        The vendor's ``RobotPost`` class.
    model : str, Path, CompensationModel or Compensator
        The compensation model (a file is loaded once, here).
    joint_targets : {"compensate", "keep"}
        Program path: joint-space targets a post writes for ``MoveJ``
        (KRL ``PTP {AXIS: ..}``, RAPID ``MoveAbsJ``, URScript ``movej``)
        compensated as the pose RoboDK gave (default), or kept
        (``trajcomp compensate --joint-targets``).
    retime : {"auto", "toppra", "ruckig", "none"}
        Program path: re-timing (``trajcomp compensate --retime``).
    criteria : trajcomp.report.Criteria, optional
        Program path: the verdict's criteria; default the command line's.
    json_only : bool
        Program path: only the report's JSON beside the program, no page
        (``--json-only``; the page's plots take seconds).
    tools, frames : Mapping[str, array_like (4, 4) or (6,)], optional
        Program path: tools (T_flange_tool) and user frames (T_world_frame),
        mm / deg, that the written program uses but does not define, e.g. a
        FANUC ``UFRAME_NUM=3`` (``--tool`` / ``--frame``).
    **options
        `trajcomp.Compensator` options: ``mode``, ``outside``,
        ``max_joint_change`` (deg), ``max_correction`` (mm).

    Returns
    -------
    type
        A subclass of `ProgramPost` when trajcomp reads the language of
        ``vendor_post.PROG_EXT``, else of `TargetPost`; RoboDK instantiates
        it like the vendor's.
    """
    comp = compensator(model, **options)
    attributes = {"VENDOR_POST": vendor_post, "COMPENSATOR": comp}
    if _language(vendor_post) is None:
        return type(f"Compensated{vendor_post.__name__}", (TargetPost,), attributes)
    settings = {"joint_targets": joint_targets, "retime": retime, "criteria": criteria, "json_only": json_only,
                "tools": tools, "frames": frames}
    return type(f"Compensated{vendor_post.__name__}", (ProgramPost,), {**attributes, "SETTINGS": settings})


class CompensatedPost:
    """A RoboDK ``RobotPost`` wrapping the vendor's, with the station check; see `ProgramPost`, `TargetPost`.

    Constructed by RoboDK with the vendor post's arguments. Attributes
    other than its own (``PROG``, ``LOG``, ...) are the vendor post's.

    Raises
    ------
    TrajcompError
        A robot with external axes (its poses depend on them), a pose
        without joints or with joints that are not the pose's on the model's
        robot with the active tool and frame (named ``MoveL #n``, the n-th
        move with a pose); RoboDK then shows the message and writes no
        program.
    """

    VENDOR_POST = None
    COMPENSATOR = None
    _OWN = frozenset({"vendor", "tool", "frame", "count", "queue", "moves", "outside", "largest", "runs"})

    def __init__(self, *args, **kwargs):
        axes = kwargs.get("robot_axes", args[2] if len(args) > 2 else 6)
        if axes != 6:
            raise TrajcompError(f"trajcomp compensates 6-axis arms; this robot has {axes} axes (external axes "
                                "move the frame the poses are in)")
        self.vendor = self.VENDOR_POST(*args, **kwargs)
        self.tool = None  # T_flange_tool of setTool, mm (None: the calibrated TCP)
        self.frame = None  # T_base_frame of setFrame, mm (None: the robot base)
        self.count = 0  # moves with a pose so far

    def __getattr__(self, name):
        if "vendor" not in self.__dict__:
            raise AttributeError(name)
        self._flush()
        return getattr(self.vendor, name)

    def __setattr__(self, name, value):
        if name in self._OWN:
            object.__setattr__(self, name, value)
        else:
            self._flush()
            setattr(self.vendor, name, value)

    def setFrame(self, pose, *args, **kwargs):
        """The reference frame of the following poses, in the robot base frame."""
        self._flush()
        self.frame = _matrix(pose)
        self.vendor.setFrame(pose, *args, **kwargs)

    def setTool(self, pose, *args, **kwargs):
        """The TCP of the following poses, in the flange frame."""
        self._flush()
        self.tool = _matrix(pose)
        self.vendor.setTool(pose, *args, **kwargs)

    def MoveJ(self, pose, joints, conf_RLF=None):
        if pose is None:  # a joint target: the joints are the program's
            self._flush()
            self.vendor.MoveJ(pose, joints, conf_RLF)
            return
        self._move("MoveJ", [(pose, joints, conf_RLF)])

    def MoveL(self, pose, joints, conf_RLF=None):
        self._move("MoveL", [(pose, joints, conf_RLF)])

    def MoveC(self, pose1, joints1, pose2, joints2, conf_RLF_1=None, conf_RLF_2=None):
        self._move("MoveC", [(pose1, joints1, conf_RLF_1), (pose2, joints2, conf_RLF_2)])

    def _checked(self, method, targets):
        """Check a move's targets ``[(pose, joints, conf_RLF)]``: its label, T (k, 4, 4) mm and joints (k, 6) deg."""
        label = f"{method} #{self.count + 1}"
        if any(joints is None for _, joints, _ in targets):
            raise TrajcompError(f"{label}: RoboDK gave a pose without joints; the posture to keep is unknown")
        T = np.array([_matrix(pose) for pose, _, _ in targets])
        hint = np.array([np.asarray(joints, dtype=float)[:6] for _, joints, _ in targets])
        robot = self.COMPENSATOR.robot
        tool = robot.T_flange_tool if self.tool is None else self.tool
        frame = np.eye(4) if self.frame is None else self.frame
        planned = fk(robot.replace(T_flange_tool=tool), np.radians(hint))
        wanted = frame @ T
        distance = np.linalg.norm(planned[:, :3, 3] - wanted[:, :3, 3], axis=1)
        angle = np.degrees(rotation_angle_between(planned[:, :3, :3], wanted[:, :3, :3]))
        bad = np.flatnonzero((distance > HINT_POSITION) | (angle > HINT_ROTATION))
        if bad.size:
            k = bad[0]
            raise TrajcompError(
                f"{label}: the joints RoboDK gives ({np.round(hint[k], 3).tolist()} deg) put the tool "
                f"{distance[k]:.3f} mm and {angle[k]:.3f} deg from the pose on robot {robot.name} of the model: "
                "the station's robot, tool or reference frame is not the calibrated one"
            )
        self.count += 1
        return label, T, hint

    def _flush(self):
        """Hand queued moves to the vendor post (the target path queues them)."""

    def _move(self, method, targets):
        raise NotImplementedError


class ProgramPost(CompensatedPost):
    """The program path: the vendor post writes the planned program, ``ProgSave`` compensates its files.

    Moves are checked (`CompensatedPost`) and reach the vendor post as
    RoboDK gave them; at ``ProgSave`` every file the vendor post reports
    (``SAVED: <path>``) in a language trajcomp reads is compensated in place
    by `trajcomp.Compensator.filter_program` with the class's settings, the
    report beside it; other files are left as written and named. ``runs``
    holds each file's `ProgramRun` (``.written``, ``.passed``,
    ``.compliance``).

    Raises
    ------
    TrajcompError
        As `CompensatedPost`, and at ``ProgSave`` any error of
        ``filter_program`` (posture, implausible correction, unreachable,
        unreadable program: ``trajcomp compensate`` would exit 2): the
        program files not compensated are moved to ``<file>.uncompensated``
        so that no controller loads them by their name.
    """

    SETTINGS = None

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.runs = []

    def _move(self, method, targets):
        self._checked(method, targets)
        getattr(self.vendor, method)(*_arguments(method, targets))

    def ProgSave(self, folder, progname, ask_user=False, show_result=False):
        """The vendor post writes its files; each one trajcomp reads is compensated in place, verdict shown."""
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            self.vendor.ProgSave(folder, progname, ask_user, False)
        print(printed.getvalue(), end="")
        saved = [Path(line[len(SAVED):].strip()) for line in printed.getvalue().splitlines()
                 if line.startswith(SAVED)]
        programs = [path for path in saved if _language(path) is not None]
        lines = [f"trajcomp: {path} is not in a language trajcomp reads: left as written"
                 for path in saved if path not in programs]
        for k, path in enumerate(programs):
            try:
                run = self.COMPENSATOR.filter_program(path, path, in_place=True, report=path, **self.SETTINGS)
            except TrajcompError as exc:
                for left in programs[k:]:
                    os.replace(left, f"{left}{UNCOMPENSATED}")
                kept = ", ".join(f"{left}{UNCOMPENSATED}" for left in programs[k:])
                raise TrajcompError(f"{exc}; the program as RoboDK planned it is kept as {kept}, not compensated") \
                    from exc
            self.runs.append(run)
            lines += [f"trajcomp {__version__}: {path}", *run.result.lines]
            if run.result.message:
                lines.append(f"trajcomp: {run.result.message}")
        for line in lines:
            print(line)
        _log(self.vendor, lines)
        if show_result:
            _show(show_result, programs, self.vendor)


class TargetPost(CompensatedPost):
    """The target path: each pose is compensated before the vendor post writes it (language trajcomp does not read).

    Moves with a pose are queued and compensated together, in one
    vectorized call, as soon as anything else reaches the post (a frame,
    tool, speed, message, the end of the program, an attribute): a long
    machining path costs milliseconds, not milliseconds per point. The
    vendor post receives every call in RoboDK's order. The program gets a
    comment at its start saying that it is compensated pose by pose, not
    re-timed or judged, and one at its end counting the poses compensated.

    Raises
    ------
    TrajcompError
        As `CompensatedPost`, and any error of
        `trajcomp.Compensator.filter_targets` for a queued move (posture,
        implausible correction, unreachable; named ``MoveL #n``).
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.queue = []  # moves waiting for compensation: (method, label, targets, T (k, 4, 4), hint (k, 6))
        self.moves, self.outside, self.largest = 0, 0, 0.0  # poses compensated, of them outside the grid, mm

    def ProgStart(self, *args, **kwargs):
        self._flush()
        self.vendor.ProgStart(*args, **kwargs)
        extension = getattr(self.VENDOR_POST, "PROG_EXT", None)
        self._comment(f"compensated pose by pose by trajcomp {__version__}: robot {self.COMPENSATOR.robot.name}, "
                      f"mode {self.COMPENSATOR.mode}; trajcomp does not read "
                      f"{'.' + extension if extension else 'this post'}'s programs, so this one is not re-timed "
                      "and has no verdict")

    def ProgFinish(self, *args, **kwargs):
        self._flush()
        summary = f"trajcomp: {self.moves} poses compensated, largest correction {self.largest:.3f} mm"
        if self.outside:
            summary += f"; {self.outside} outside the calibrated grid ({self.COMPENSATOR.outside} policy)"
        self._comment(summary)
        self.vendor.ProgFinish(*args, **kwargs)

    def _move(self, method, targets):
        label, T, hint = self._checked(method, targets)
        self.queue.append((method, label, targets, T, hint))

    def _flush(self):
        """Compensate the queued moves in one call and hand them to the vendor post, in order."""
        queue, self.queue = self.queue, []
        if not queue:
            return
        comp = self.COMPENSATOR
        hint = np.concatenate([q[4] for q in queue])
        names = [label + ("" if len(targets) == 1 else (" via", " end")[k])
                 for _, label, targets, _, _ in queue for k in range(len(targets))]
        result = comp.filter_targets(np.concatenate([q[3] for q in queue]), tool=self.tool, frame=self.frame,
                                     joints_hint=hint, names=names)
        self.moves += len(hint)
        self.outside += int(result.outside_grid.sum())
        self.largest = max(self.largest, float(np.linalg.norm(result.correction[:, :3], axis=1).max()))
        row = 0
        for method, _, targets, _, _ in queue:
            commands = []
            for pose, joints, conf in targets:
                commands.append((_like(pose, result.poses[row]), _like(joints, result.joints[row]),
                                 conf_after(comp.robot, conf, hint[row], result.joints[row])))
                row += 1
            getattr(self.vendor, method)(*_arguments(method, commands))

    def _comment(self, text):
        run_message = getattr(self.vendor, "RunMessage", None)
        if run_message is not None:
            run_message(text, True)


def conf_after(robot, conf_RLF, q_before, q_after):
    """RoboDK configuration flags ``[REAR, LOWERARM, FLIP]`` of corrected joints.

    A flag changes where trajcomp's matching flag of the arm configuration
    (shoulder back, elbow down, wrist negative; `trajcomp.arm.ik.Configuration`)
    differs between the planned and the corrected joints, whatever polarity
    a brand gives it.

    Parameters
    ----------
    robot : Robot
    conf_RLF : sequence of 3 int, or None
    q_before, q_after : array_like, shape (6,)
        Planned and corrected joints, deg.

    Returns
    -------
    list or tuple of int, or None
        The flags (a tuple stays a tuple; None stays None).
    """
    if conf_RLF is None:
        return None
    before, after = (configuration_of(robot, np.radians(q)).index for q in (q_before, q_after))
    changed = before ^ after  # bits: 4 shoulder, 2 elbow, 1 wrist
    flags = [int(flag) ^ ((changed >> shift) & 1) for flag, shift in zip(conf_RLF, (2, 1, 0))]
    return type(conf_RLF)(flags) if isinstance(conf_RLF, (list, tuple)) else flags


def _language(post_or_path):
    """The `trajcomp.formats.Format` of a file, or of a post's ``PROG_EXT``; None if trajcomp does not read it."""
    if isinstance(post_or_path, Path):
        suffix = post_or_path.suffix
    else:
        extension = getattr(post_or_path, "PROG_EXT", None)
        if not extension:
            return None
        suffix = "." + str(extension).lstrip(".")
    try:
        return formats.find_format(Path(f"program{suffix}"))
    except TrajcompError:
        return None


def _arguments(method, targets):
    """The vendor call's arguments for a move's targets ``[(pose, joints, conf_RLF)]``."""
    if method == "MoveC":
        (pose1, joints1, conf1), (pose2, joints2, conf2) = targets
        return pose1, joints1, pose2, joints2, conf1, conf2
    return targets[0]


def _log(vendor, lines):
    """Add ``lines`` to the post's log (RoboDK shows a post's ``LOG`` once the program is generated)."""
    add = getattr(vendor, "addlog", None)
    for line in lines:
        if add is not None:
            add(line)
        else:
            vendor.LOG = getattr(vendor, "LOG", "") + line + "\n"


def _show(show_result, paths, vendor):
    """Open the programs as RoboDK posts do: with the given program (str or argument list), else the default one.

    The post's log follows in RoboDK's message box where the vendor
    module has one (``mbox``).
    """
    for path in paths:
        if isinstance(show_result, str):
            subprocess.Popen([show_result, str(path)])
        elif isinstance(show_result, list):
            subprocess.Popen([*show_result, str(path)])
        else:
            os.startfile(path)
    mbox = getattr(sys.modules.get(type(vendor).__module__), "mbox", None)
    if mbox is not None and getattr(vendor, "LOG", ""):
        mbox("Program generation LOG:\n\n" + vendor.LOG)


def _matrix(pose):
    """T (4, 4) of a RoboDK pose (``robomath.Mat``, rows in ``.rows``) or any 4x4 array."""
    return np.array(getattr(pose, "rows", pose), dtype=float)


def _like(original, values):
    """``values`` in the type of ``original``: a ``Mat`` of rows, a list or tuple, else an array."""
    values = np.asarray(values, dtype=float)
    if hasattr(original, "rows"):
        return type(original)(values.tolist())
    if isinstance(original, (list, tuple)):
        return type(original)(values.tolist() + list(original[len(values):]))
    return values
