"""A RoboDK post processor that compensates every pose before the vendor post writes it.

RoboDK turns a station's program into robot code by calling a post
processor, a ``RobotPost`` class: ``setFrame`` / ``setTool`` with the active
reference frame and tool, then ``MoveJ(pose, joints, conf_RLF)``,
``MoveL(...)`` and ``MoveC(pose1, joints1, pose2, joints2, conf_RLF_1,
conf_RLF_2)`` with each target's pose (a ``robomath.Mat``, mm: the TCP in
the reference frame), its joints (deg) and its configuration flags
``[REAR, LOWERARM, FLIP]``. `compensated_post` wraps a vendor's class: each
pose is replaced by its compensated command, its joints by the command's
joints in the same posture, and its flags follow (a flag changes only when
a joint crosses its boundary, e.g. J5 through zero), before the vendor post
writes them. Everything else reaches the vendor post unchanged.

A post processor file in RoboDK's ``Posts`` folder, e.g.
``KUKA_KRC4_trajcomp.py``, selected as the robot's post processor::

    from trajcomp_robodk import compensated_post
    from KUKA_KRC4 import RobotPost as VendorPost

    RobotPost = compensated_post(VendorPost, model=r"C:/cells/kr6/model.yaml")

The joints RoboDK plans choose the posture (`trajcomp.Compensator`); they
must be the joints of the pose on the model's nominal robot with the active
tool and frame (1 mm, 1 deg), so a station whose robot, tool or frame
differs from the calibrated one is refused instead of compensated wrongly.
Joint moves without a pose (``MoveJ(None, joints)``) pass unchanged. Moves
are compensated in batches, a whole path in one vectorized call.
"""

import numpy as np

from trajcomp import __version__
from trajcomp.api import compensator
from trajcomp.errors import TrajcompError
from trajcomp.arm.ik import configuration_of
from trajcomp.arm.kinematics import fk
from trajcomp.arm.transforms import rotation_angle_between

HINT_POSITION = 1.0  # mm: largest distance between a pose and the nominal pose of its RoboDK joints
HINT_ROTATION = 1.0  # deg: largest rotation between them


def compensated_post(vendor_post, model, **options):
    """A RobotPost class that compensates each pose, then hands it to ``vendor_post``.

    Parameters
    ----------
    vendor_post : type
        The vendor's ``RobotPost`` class.
    model : str, Path, CompensationModel or Compensator
        The compensation model (a file is loaded once, here).
    **options
        `trajcomp.Compensator` options: ``mode``, ``outside``,
        ``max_joint_change`` (deg), ``max_correction`` (mm).

    Returns
    -------
    type
        A subclass of `CompensatedPost` that RoboDK instantiates like the vendor's.
    """
    return type(f"Compensated{vendor_post.__name__}", (CompensatedPost,),
                {"VENDOR_POST": vendor_post, "COMPENSATOR": compensator(model, **options)})


class CompensatedPost:
    """A RoboDK ``RobotPost`` wrapping the vendor's: moves compensated, everything else passed on.

    Built by `compensated_post`; constructed by RoboDK with the vendor
    post's arguments. Attributes other than its own (``PROG``, ``LOG``, ...)
    are the vendor post's.

    Moves with a pose are queued and compensated together, in one
    vectorized call, as soon as anything else reaches the post (a frame,
    tool, speed, message, the end of the program, an attribute): a long
    machining path costs milliseconds, not milliseconds per point. The
    vendor post receives every call in RoboDK's order.

    Raises
    ------
    TrajcompError
        A robot with external axes (its poses depend on them), a pose
        without joints or with joints that are not the pose's (at once), or
        any error of `trajcomp.Compensator.filter_targets` for a queued move
        (posture, implausible correction, unreachable; named ``MoveL #n``,
        the n-th move of the program); RoboDK then shows the message and
        writes no program.
    """

    VENDOR_POST = None
    COMPENSATOR = None
    _OWN = frozenset({"vendor", "tool", "frame", "queue", "count", "moves", "outside", "largest"})

    def __init__(self, *args, **kwargs):
        axes = kwargs.get("robot_axes", args[2] if len(args) > 2 else 6)
        if axes != 6:
            raise TrajcompError(f"trajcomp compensates 6-axis arms; this robot has {axes} axes (external axes "
                                "move the frame the poses are in)")
        self.vendor = self.VENDOR_POST(*args, **kwargs)
        self.tool = None  # T_flange_tool of setTool, mm (None: the calibrated TCP)
        self.frame = None  # T_base_frame of setFrame, mm (None: the robot base)
        self.queue = []  # moves waiting for compensation: (method, label, targets, T (k, 4, 4), hint (k, 6))
        self.count = 0  # moves with a pose so far
        self.moves, self.outside, self.largest = 0, 0, 0.0  # poses compensated, of them outside the grid, mm

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

    # ------------------------------------------------------- program frame

    def ProgStart(self, *args, **kwargs):
        self._flush()
        self.vendor.ProgStart(*args, **kwargs)
        self._comment(f"compensated by trajcomp {__version__}: robot {self.COMPENSATOR.robot.name}, "
                      f"mode {self.COMPENSATOR.mode}")

    def ProgFinish(self, *args, **kwargs):
        self._flush()
        summary = f"trajcomp: {self.moves} poses compensated, largest correction {self.largest:.3f} mm"
        if self.outside:
            summary += f"; {self.outside} outside the calibrated grid ({self.COMPENSATOR.outside} policy)"
        self._comment(summary)
        self.vendor.ProgFinish(*args, **kwargs)

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

    # --------------------------------------------------------------- moves

    def MoveJ(self, pose, joints, conf_RLF=None):
        if pose is None:  # a joint target: the joints are the program's
            self._flush()
            self.vendor.MoveJ(pose, joints, conf_RLF)
            return
        self._enqueue("MoveJ", [(pose, joints, conf_RLF)])

    def MoveL(self, pose, joints, conf_RLF=None):
        self._enqueue("MoveL", [(pose, joints, conf_RLF)])

    def MoveC(self, pose1, joints1, pose2, joints2, conf_RLF_1=None, conf_RLF_2=None):
        self._enqueue("MoveC", [(pose1, joints1, conf_RLF_1), (pose2, joints2, conf_RLF_2)])

    def _enqueue(self, method, targets):
        """Check a move's targets ``[(pose, joints, conf_RLF)]`` now; queue them for compensation."""
        label = f"{method} #{self.count + 1}"
        if any(joints is None for _, joints, _ in targets):
            raise TrajcompError(f"{label}: RoboDK gave a pose without joints; the posture to keep is unknown")
        T = np.array([_matrix(pose) for pose, _, _ in targets])
        hint = np.array([np.asarray(joints, dtype=float)[:6] for _, joints, _ in targets])
        self._check_hint(label, T, hint)
        self.queue.append((method, label, targets, T, hint))
        self.count += 1

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
            poses, joints, confs = zip(*commands)
            if method == "MoveC":
                self.vendor.MoveC(poses[0], joints[0], poses[1], joints[1], confs[0], confs[1])
            else:
                getattr(self.vendor, method)(poses[0], joints[0], confs[0])

    def _check_hint(self, label, T, hint):
        """Refuse joints that are not the pose's on the model's robot with the active tool and frame."""
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
