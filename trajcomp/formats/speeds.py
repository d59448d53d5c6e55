"""A motion's speed field as its controller runs it, and the same speed carried into another language, never faster.

Each language states a motion's speed in its own units (its
`trajcomp.formats.capabilities.SpeedUnits`): a percentage of every axis's speed (KRL PTP, FANUC J),
the speed of the leading axis (UR movej, rad/s), a TCP speed (mm/s; for a
joint motion, RAPID MoveJ and program CSV, the TCP's speed along the
joint path), an orientation speed (FANUC L ``deg/sec``, rad/s; RAPID's
v_ori, `trajcomp.programs.items.Motion.orientation_speed`), or the motion's
total time (s). They compare through one number, the motion's cruise rate
c: the motion's path parameter runs from 0 to 1, accelerating at the rate
the slowest joint allows (a = min_j a_max_j / |dq_j|), cruising at c, then
braking (a trapezoid; the controller's own ramps). A field that makes c no
larger runs every joint and the TCP no faster, and takes no less time:

- ``%`` p: c = min_j p/100 v_max_j / |dq_j|; the leading axis's v (rad/s):
  c = v / max_j |dq_j|;
- a TCP speed v: c = v / L along a line or circle of L mm, v / max |dp/ds|
  along a joint motion's path; an orientation speed w: w / max |dphi/ds|;
- a time T: the cruise of the trapezoid that takes T,
  c = (a T - sqrt(a^2 T^2 - 4 a)) / 2;
- no field (FANUC ``max_speed``, a CSV row without speed): the arm's
  limits, c = min_j v_max_j / |dq_j|.

`convert_speeds` writes each motion of a program in the units of another
language: the same unit is kept exactly; a percentage and a leading-axis
speed convert with the robot's velocity limits alone (no faster for any
motion); anything else through the motion's geometry (`MotionGeometry`,
its start must be known) and rounded at the written resolution by the
writer (speeds down, times up). A speed that cannot be carried over (set
at run time, a motion whose start is unknown, no robot) is written as the
language's slowest (``SLOWEST``) and listed in the motion's ``speed_why``.
"""

import dataclasses

import numpy as np

from trajcomp.arm.kinematics import fk, fk_and_jacobian
from trajcomp.arm.transforms import rotation_angle_between
from trajcomp.programs.items import JOINT, LINEAR

SAMPLES = 65  # points of a joint motion's path where its TCP and orientation rates are evaluated
# a joint motion's sampled peak |dp/ds| raised by this much where a TCP speed is read (its true peak lies between
# samples, never below them): the rate read is never above the controller's; written, the sampled peak itself
RATE_MARGIN = 1.01
SLOWEST = {"%": 1.0, "rad/s": np.radians(1.0), "mm/s": 1.0}  # the slowest reading written where none is known


@dataclasses.dataclass(frozen=True)
class MotionGeometry:
    """What each motion of a program moves, for those whose start and end joints are known.

    Attributes
    ----------
    known : ndarray of bool, shape (M,)
        Over the program's M motions: the motion's start and end joints are
        known (the others have NaN below).
    dq : ndarray, shape (M, 6)
        Joint change, rad.
    length : ndarray, shape (M,)
        TCP path length of a linear or circular motion, mm; for a joint
        motion the peak TCP rate max |dp/ds| along its joint path
        (`SAMPLES` points: at most the true peak).
    turn : ndarray, shape (M,)
        Reorientation of a linear or circular motion, rad; for a joint
        motion the peak orientation rate max |dphi/ds| (likewise).
    """

    known: np.ndarray
    dq: np.ndarray
    length: np.ndarray
    turn: np.ndarray

    @classmethod
    def of(cls, program, robot, moves):
        """The geometry of ``program``'s motions from their `trajcomp.timing.moves.Moves` (timed waypoints)."""
        m = len(program.motion_table())
        known = np.zeros(m, dtype=bool)
        dq, length, turn = np.full((m, 6), np.nan), np.full(m, np.nan), np.full(m, np.nan)
        steps = np.flatnonzero(~moves.start)
        known[moves.motion[steps]], dq[moves.motion[steps]] = True, moves.q[steps] - moves.q[steps - 1]
        lines = steps[moves.kind[steps] == LINEAR]
        for tool_index in np.unique(moves.tool[lines]).tolist():  # the lines of each tool, at once
            k = lines[moves.tool[lines] == tool_index]
            tool = robot.replace(T_flange_tool=moves.tools[tool_index])
            start, end = fk(tool, moves.q[k - 1]), fk(tool, moves.q[k])
            length[moves.motion[k]] = np.linalg.norm(end[:, :3, 3] - start[:, :3, 3], axis=1)
            turn[moves.motion[k]] = rotation_angle_between(start[:, :3, :3], end[:, :3, :3])
        for k in steps[moves.kind[steps] != LINEAR].tolist():
            index = int(moves.motion[k])
            tool = robot.replace(T_flange_tool=moves.tools[moves.tool[k]])
            q_a, q_b = moves.q[k - 1], moves.q[k]
            if moves.kind[k] == JOINT:
                length[index], turn[index] = _joint_path_rates(tool, q_a, q_b)
                continue
            T, _ = fk_and_jacobian(tool, np.array([q_a, moves.via[k], q_b]))  # a circle
            length[index] = arc_length(T[:, :3, 3])
            turn[index] = rotation_angle_between(T[0, :3, :3], T[-1, :3, :3])
        return cls(known, dq, length, turn)


def _joint_path_rates(robot, q_a, q_b):
    """Sampled peaks (`SAMPLES` points) of the TCP rate |dp/ds| (mm) and the orientation rate |dphi/ds| (rad)
    along the joint line from q_a to q_b (6,)."""
    s = np.linspace(0.0, 1.0, SAMPLES)[:, None]
    _, J = fk_and_jacobian(robot, q_a + s * (q_b - q_a))
    rates = np.einsum("nij,j->ni", J, q_b - q_a)
    return np.linalg.norm(rates[:, :3], axis=1).max(), np.linalg.norm(rates[:, 3:], axis=1).max()


def orientation_time(kind, q_a, q_b, orientation_speed, robot):
    """The least time (s) a controller bounding the reorientation by ``orientation_speed`` (rad/s) takes.

    The motion from q_a to q_b (6,) turns the tool by the angle between
    its end orientations (a line or circle), or at the peak rate of its
    joint line (a joint motion, raised by `RATE_MARGIN`); it cruises at the
    rate that keeps that speed, between the ramps of `path_acceleration`:
    the time a controller given this time (RAPID ``\\T``) needs to turn no
    faster. The tool does not matter: a rotation's angle is the flange's.
    """
    q_a, q_b = np.asarray(q_a, dtype=float), np.asarray(q_b, dtype=float)
    if not np.any(q_b - q_a):
        return 0.0
    if kind == JOINT:
        turn = RATE_MARGIN * _joint_path_rates(robot, q_a, q_b)[1]
    else:
        T, _ = fk_and_jacobian(robot, np.array([q_a, q_b]), tcp=False)
        turn = rotation_angle_between(T[0, :3, :3], T[1, :3, :3])
    if not turn > 0:
        return 0.0
    return _trapezoid_time(orientation_speed / turn, path_acceleration(q_b - q_a, robot))


def _trapezoid_time(rate, acceleration):
    """Time (s) of the path parameter's trapezoid from 0 to 1 cruising at ``rate`` (1/s), ramps at ``acceleration``."""
    if rate >= np.sqrt(acceleration):  # no cruise: accelerating then braking
        return 2.0 / np.sqrt(acceleration)
    return 1.0 / rate + rate / acceleration


def arc_length(points):
    """Length (mm) of the line through 2 points (2, 3), or of the circle's arc from the first through the second
    to the third (3, 3): the via point sees the chord at the angle pi - theta / 2 (theta the arc's central angle)."""
    if len(points) == 2:
        return float(np.linalg.norm(points[1] - points[0]))
    to_start, to_end = points[0] - points[1], points[2] - points[1]
    at_via = np.arctan2(np.linalg.norm(np.cross(to_start, to_end)), np.dot(to_start, to_end))
    if np.pi - at_via < 1e-9 or not at_via > 1e-9:  # the via point on the chord, or on an end: a line
        return float(np.linalg.norm(to_start) + np.linalg.norm(to_end))
    radius = np.linalg.norm(points[2] - points[0]) / (2.0 * np.sin(at_via))
    return float(radius * (2.0 * np.pi - 2.0 * at_via))


def cruise_rate(kind, speed, unit, orientation_speed, geometry, index, robot, acceleration=None, share=None):
    """The cruise rate c (1/s) at which motion ``index`` runs under its speed field (see the module).

    A programmed ``acceleration`` below the arm's (UR ``a=``, KRL
    ``$ACC.CP``) or a ``share`` of the arm's (KRL ``$ACC_AXIS``, RAPID
    ``AccSet``, FANUC ``ACC``) makes the motion take longer than its cruise
    rate's trapezoid at the arm's ramps: c is then the rate whose
    trapezoid at the arm's ramps takes that longer time, so that a field
    stating c in any unit is no faster in its cruise nor in its time.

    Parameters
    ----------
    kind : str
        The motion's kind (`trajcomp.programs.items`).
    speed : float or None
        Its speed in ``unit``; None for the arm's limits.
    unit : str
        ``"%"``, ``"rad/s"``, ``"mm/s"`` or ``"s"``.
    orientation_speed : float or None
        An orientation speed bounding it too (RAPID v_ori), rad/s.
    geometry : MotionGeometry
    index : int
        The motion's index; its geometry must be known.
    robot : Robot
    acceleration : float, optional
        Of the leading axis (rad/s^2) of a joint motion, of the TCP (mm/s^2) of another.
    share : float, optional
        Of the arm's acceleration limits, (0, 1].

    Returns
    -------
    float
    """
    dq = np.abs(geometry.dq[index])
    moving = dq > 0
    if not moving.any():
        return np.inf
    limit = np.min(robot.v_max[moving] / dq[moving])
    margin = RATE_MARGIN if kind == JOINT else 1.0
    rates = [limit]
    if speed is not None and unit == "%":
        rates.append(speed / 100.0 * limit)
    elif speed is not None and unit == "rad/s" and kind == JOINT:
        rates.append(speed / dq.max())
    elif speed is not None and unit == "rad/s":
        rates.append(_per(speed, margin * geometry.turn[index]))
    elif speed is not None and unit == "mm/s":
        rates.append(_per(speed, margin * geometry.length[index]))
    elif speed is not None and unit == "s":
        rates.append(_rate_of_time(speed, path_acceleration(dq, robot)))
    if orientation_speed is not None:
        rates.append(_per(orientation_speed, margin * geometry.turn[index]))
    rate = float(min(rates))
    extent = dq.max() if kind == JOINT else geometry.length[index]
    ramps = path_acceleration(dq, robot)
    programmed = ramps * (1.0 if share is None else min(share, 1.0))
    if acceleration is not None and extent > 0:
        programmed = min(programmed, acceleration / extent)
    if programmed < ramps:
        rate = _rate_of_time(_trapezoid_time(rate, programmed), ramps)
    return rate


def _rate_of_time(duration, acceleration):
    """The cruise rate (1/s) of the path parameter's trapezoid from 0 to 1 that takes ``duration`` s with ramps at
    ``acceleration`` (1/s^2); the ramps alone where no cruise is that slow."""
    root = (acceleration * duration) ** 2 - 4.0 * acceleration
    return np.sqrt(acceleration) if root <= 0 else 0.5 * (acceleration * duration - np.sqrt(root))


def _per(speed, extent):
    return np.inf if not extent > 0 else speed / extent


def path_acceleration(dq, robot):
    """The path parameter's acceleration (1/s^2) when the joint that limits it accelerates at its limit."""
    dq = np.abs(dq)
    moving = dq > 0
    return float(np.min(robot.a_max[moving] / dq[moving]))


def field_of_rate(kind, rate, unit, geometry, index, robot):
    """The value in ``unit`` (%, rad/s, mm/s or s) at which motion ``index`` runs at cruise rate ``rate`` (1/s).

    The inverse of `cruise_rate` for one unit (a percentage at most 100);
    None where the unit cannot state it (a TCP speed of a motion whose TCP
    does not move).
    """
    dq = np.abs(geometry.dq[index])
    if unit == "%":
        return min(100.0 * rate * np.max(dq / robot.v_max), 100.0)
    if unit == "rad/s":
        extent = dq.max() if kind == JOINT else geometry.turn[index]
    elif unit == "mm/s":
        extent = geometry.length[index]
    else:
        return _trapezoid_time(rate, path_acceleration(dq, robot))
    return rate * extent if extent > 0 else None


def convert_speeds(motions, units, robot=None, geometry=None, language="", orientation=False):
    """``motions`` with their speeds in ``units``, each no faster than as read (see the module).

    Parameters
    ----------
    motions : Sequence[Motion]
        A program's motions.
    units : Mapping[str, Mapping[str, float]]
        Per motion kind, the units the language states and the smallest
        value it writes in each (its `SpeedUnits`), the one to convert
        into first. A speed below a unit's smallest value is stated in the
        next unit.
    robot : Robot, optional
        Its velocity limits convert a percentage to a leading-axis speed and back.
    geometry : MotionGeometry, optional
        Of the program's motions, with ``robot``: every other conversion.
    language : str
        The language's name, for the listing.
    orientation : bool
        The language states an orientation speed beside a TCP speed (its
        `OrientationSpeed`: RAPID's speeddata v_ori).

    Returns
    -------
    tuple of Motion
        Motions whose speed could not be carried over have the language's
        slowest speed (`SLOWEST`, or its smallest value if larger, in the
        first of its units there) and say why in ``speed_why``.
    """
    out = []
    for index, motion in enumerate(motions):
        stated = units[motion.kind]
        if motion.target is None:
            out.append(motion)
            continue
        speed, unit, why = _converted(motion, index, stated, robot, geometry, orientation)
        bound = motion.orientation_speed if orientation else None
        if why:
            unit = next(u for u in stated if u in SLOWEST)
            speed = max(SLOWEST[unit], stated[unit])
            why = f"{why}: written at {language}'s slowest speed, set it before running"
            bound = SLOWEST["rad/s"] if orientation else None
        out.append(dataclasses.replace(motion, speed=speed, speed_unit=unit, speed_why=why,
                                       orientation_speed=bound))
    return tuple(out)


def _converted(motion, index, stated, robot, geometry, orientation):
    """``(speed, unit, why)`` of one motion in the units ``stated`` (``orientation``: and an orientation speed);
    ``why`` says why it could not be."""
    if motion.speed_why:
        return None, None, motion.speed_why
    speed, unit = motion.speed, motion.speed_unit
    known = robot is not None and geometry is not None and geometry.known[index]
    dropped = motion.orientation_speed is not None and not orientation  # a bound the target cannot state
    # a programmed acceleration or share of the arm's: no language states it beside a speed
    dropped |= motion.acceleration is not None or motion.acceleration_share is not None
    if dropped and known:  # it matters only where it binds
        free = cruise_rate(motion.kind, speed, unit, None, geometry, index, robot)
        dropped = cruise_rate(motion.kind, speed, unit, motion.orientation_speed, geometry, index, robot,
                              motion.acceleration, motion.acceleration_share) < free
    default = next(iter(stated))
    if speed is None and not dropped:
        return None, default, ""  # the arm's limits: the language's own default
    if unit in stated and _statable(speed, unit, stated) and not dropped:
        return speed, unit, ""
    if motion.time_why:  # its time under the controller's ramps is not modelled: no other field is known no faster
        return None, None, motion.time_why
    if robot is not None and motion.kind == JOINT and not dropped:
        if "%" in stated and unit == "rad/s":  # every joint at most v: p = v / max v_max
            percent = min(100.0 * speed / np.max(robot.v_max), 100.0)
            if _statable(percent, "%", stated):
                return percent, "%", ""
        if "rad/s" in stated and unit == "%":  # the leading axis at p of the slowest one's limit
            axis = speed / 100.0 * np.min(robot.v_max)
            if _statable(axis, "rad/s", stated):
                return axis, "rad/s", ""
    shown = "the arm's limits" if speed is None else f"{speed:g} {unit}"
    if not known:
        what = "no robot given" if robot is None else "its start is unknown"
        return None, None, f"speed {shown} cannot be converted ({what})"
    if not np.any(geometry.dq[index]):  # the arm does not move: any speed is no faster
        return None, default, ""
    rate = cruise_rate(motion.kind, speed, unit, motion.orientation_speed, geometry, index, robot, motion.acceleration,
                       motion.acceleration_share)
    for target_unit in stated:
        value = field_of_rate(motion.kind, rate, target_unit, geometry, index, robot)
        if value is not None and np.isfinite(value) and _statable(value, target_unit, stated):
            return value, target_unit, ""
    return None, None, f"speed {shown} cannot be stated in {', '.join(stated)}"


def _statable(value, unit, stated):
    """A language writes ``value`` in ``unit`` no faster: a speed at least its smallest (a time is rounded up)."""
    return unit == "s" or value >= stated[unit]
