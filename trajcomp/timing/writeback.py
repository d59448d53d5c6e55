"""The timing written into a program's own speed and time fields, every other byte kept.

Each field is written as its controller reads it: a cruise speed (KRL
``$VEL.CP``, UR ``v=``, RAPID ``\\V``, FANUC ``mm/sec``) is the speed the
TCP keeps between the controller's own ramps; a time (RAPID ``\\T``, UR
``t=``, FANUC ``msec`` / ``sec``) is the motion's total time. Per motion:

- a linear or circular motion with a stated TCP speed (a process speed: a
  weld at 20 mm/s) keeps its field exactly as written when the arm can
  cruise at that speed along the whole motion within its joint velocity and
  acceleration limits (`cruise_speeds`); else the cruise speed is lowered to
  the largest one it can keep at its slowest point, and the timing lists it
  (`TimingResult.lowered`);
- a motion whose speed the program sets at run time (a variable, register,
  PERS speeddata: `trajcomp.programs.items.Motion.speed_why`) keeps its field
  as written and is listed (`TimingResult.as_written`): never replaced by a
  speed the tool cannot compare with it; so does a motion whose start is
  not unique (after a call, a loop's back jump, a branch:
  `trajcomp.programs.items.Motion.start_why`), which is not timed;
- any other motion (joint motions, motions with a stated time) gets its
  timed duration T (for a linear or circular one at least its programmed
  TCP length L over its cruise speed, so that a controller cruising at L/T
  keeps the limits: L corner to corner, `TimingResult.programmed_length`,
  as a controller paces a time given to a blended motion, not the
  shorter timed path between blend middles; for a RAPID motion at least the time its speed data's v_ori
  allows the reorientation, `trajcomp.formats.speeds.orientation_time`:
  ``\\T`` replaces the speed data); but a motion whose controller would
  not run a time as timed (`trajcomp.programs.items.Motion.time_why`: a
  RAPID AccSet ramp below 100 %) keeps its field as written and is listed
  (`TimingResult.not_modelled`), whatever its kind: a joint motion, a
  linear one that only turns the tool.

The timing decides what to write (`SpeedPlan`); each language writes it in
its own fields, the writer of its `trajcomp.formats.capabilities.SpeedFields`:
CSV a ``t`` column of time stamps (every row: the rows are the trajectory,
``timed_rows``); RAPID ``\\T:=T`` or ``\\V:=v`` after the speed data; URScript
``t=T`` or ``v=v``; FANUC ``Tmsec`` / ``T sec`` or ``v mm/sec``; KRL, which
has no motion time, ``BAS(#VEL_PTP, %)`` before a PTP (the percentage with
which the leading axis, accelerating at its limit, needs T) and
``$VEL.CP``, modal statements edited or inserted
(`trajcomp.formats.krl.speeds`). Times are rounded up and speeds down at the
written resolution: never faster than the timing. Motions that are not
timed (their start is unknown) or have no length keep their fields.
"""

import dataclasses

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.formats import capability, formats
from trajcomp.formats.capabilities import OrientationSpeed, SpeedFields, resolved
from trajcomp.formats.speeds import orientation_time
from trajcomp.programs.items import JOINT
from trajcomp.timing.moves import moves_from_program
from trajcomp.timing.path import TOLERANCE
from trajcomp.timing.retiming import retime
from trajcomp.timing.track import programmed_limits, retime_on_track, track_values

# a cruise speed is kept this much below its bound: the fitted path's second derivative differs from the exact
# line's (solved every 0.05 mm) by up to ~0.05 % of the acceleration at the slowest point
CRUISE_MARGIN = 0.999
# mm: a linear or circular motion whose TCP travels less only turns the tool (no TCP speed to cruise at): its time
# is written, as a joint motion's (the written positions' resolution)
MIN_TRAVEL = 1e-6


def retime_program(program, robot, joints, *, method="auto", tools=None, frames=None, tolerance=TOLERANCE):
    """Re-time a program whose targets' joints (N, 6) are known (`moves_from_program`, then `retime`).

    Returns
    -------
    TimingResult
    """
    moves = moves_from_program(program, robot, joints, tools=tools, frames=frames)
    values = track_values(program, robot, moves, tools, frames)
    if values is not None:  # the track moves: a joint of the timed path
        velocity, acceleration = programmed_limits(program.motion_table(), moves.motion, robot.track)
        return retime_on_track(moves, robot, values, robot.track.written[program.track_key], programmed=velocity,
                               programmed_acceleration=acceleration, method=method, tolerance=tolerance)
    return retime(moves, robot, method=method, tolerance=tolerance)


def apply_timing(program, result, robot):
    """The program with its speed / time fields set from a timing, and the timing with its settings.

    Parameters
    ----------
    program : Program
        Read from a file (its sources are patched).
    result : TimingResult
        Of this program (`retime_program`).
    robot : Robot
        Joint limits: the cruise speeds and the KRL PTP percentage.

    Returns
    -------
    (Program, TimingResult)
        The timing carries the settings written, the motions left as
        written because their speed is set at run time (``as_written``) and
        those a joint limit made slower than programmed (``lowered``).

    Raises
    ------
    TimingError
        A program without sources, or a language timing cannot be written in
        (it has no `SpeedFields`).
    """
    if not writable(program):
        languages = ", ".join(f.name for f in formats() if f.capability(SpeedFields))
        raise TimingError(
            f"{program.name}: timing can be written into programs of {languages} read from a file, not into a "
            f"{program.format} program{'' if program.sources else ' built in memory'}"
        )
    fields = capability(program, SpeedFields)
    write_speeds = resolved(fields.write)
    if fields.timed_rows:  # its rows are the trajectory: every one gets its time stamp
        timed, settings = write_speeds(program, result, robot, None)
        return timed, result.with_settings(settings)
    plan = _plan(program, result, robot)
    timed, settings = write_speeds(program, result, robot, plan)
    return timed, result.with_settings(settings, as_written=plan.as_written, lowered=plan.notes(result, settings),
                                       not_modelled=plan.not_modelled)


def run_time_speeds(program, result):
    """``((k, why), ...)``: the waypoints of a timing whose motion's speed the program does not state.

    Every one, timed or not: a program converted from another language
    whose speeds could not be carried over (written at the language's
    slowest, `trajcomp.formats.speeds.convert_speeds`), whose timing is not
    written into it, lists them all (`TimingResult.as_written`).
    """
    why = program.motion_table().speed_why[result.motion]
    return tuple((k, why[k]) for k in np.flatnonzero(why != "").tolist())


def writable(program):
    """True if `apply_timing` can write into this program (read from a file in a language with `SpeedFields`)."""
    return bool(program.sources) and capability(program, SpeedFields) is not None


def _timed(result):
    """Waypoints whose motion has a duration to write: their indices (T,) and durations (T,), s."""
    durations = result.durations
    timed = durations > 0
    timed[:1] = False
    timed[list(result.untimed)] = False
    return np.flatnonzero(timed), durations[timed]


@dataclasses.dataclass
class SpeedPlan:
    """What to write per timed motion, and what to list.

    Attributes
    ----------
    times : dict of int to float
        Waypoint k -> total time to write, s (joint motions, stated times).
    cruise : dict of int to float
        Waypoint k -> lowered cruise TCP speed to write, mm/s.
    as_written : tuple of (int, str)
        Waypoints whose speed is set at run time, and why.
    not_modelled : tuple of (int, str)
        Waypoints that would get a time their controller would not run as
        timed (`trajcomp.programs.items.Motion.time_why`), and why: left as written.
    reasons : dict of int to str
        Why a cruise speed was lowered or a time raised (the binding joint limit).
    stated : dict of int to float
        The programmed TCP speed (mm/s) or time (s) of each lowered or raised motion.
    """

    times: dict
    cruise: dict
    as_written: tuple
    reasons: dict
    stated: dict
    not_modelled: tuple = ()

    def notes(self, result, settings):
        """``((k, text), ...)``: each lowered speed and raised time, with the limit that forced it."""
        out = []
        for k in sorted(self.reasons):
            if k not in settings:
                continue
            if k in self.cruise:
                change = f"{self.stated[k]:g} mm/s lowered to {self.cruise[k]:.3f} mm/s"
            else:
                change = f"{result.durations[k]:.3f} s raised to {self.times[k]:.3f} s"
            out.append((k, f"{result.labels[k]}: {change} ({settings[k]}): {self.reasons[k]}"))
        return tuple(out)


def _plan(program, result, robot):
    """The `SpeedPlan` of a timing: run-time speeds kept, stated process speeds kept or lowered, times.

    Decided for every timed waypoint at once from the program's motion columns; the plan's
    entries are in waypoint order.
    """
    k, duration = _timed(result)
    table = program.motion_table()
    cruise, binding = cruise_speeds(result, robot, table.zone[result.motion])
    why = table.speed_why[result.motion[k]]
    written = why != ""
    untimed = np.array(result.untimed, dtype=int)
    start_why = table.start_why[result.motion[untimed]]
    as_written = tuple(sorted([*zip(k[written].tolist(), why[written].tolist()),
                               *((w, s) for w, s in zip(untimed.tolist(), start_why.tolist()) if s)]))
    k, duration = k[~written], duration[~written]
    rows = result.motion[k]
    length, speed, limit = result.tcp_length[k], table.speed[rows], cruise[k]
    path = (table.kind[rows] != JOINT) & (length > MIN_TRAVEL)
    process = path & ~np.isnan(speed) & (table.speed_unit[rows] == "mm/s")  # a stated process speed
    lowered = process & (limit < speed)
    times = np.where(process, np.nan, duration)
    programmed = result.programmed_length[k]  # a controller paces a time over it, corner to corner
    with np.errstate(divide="ignore"):
        slower = ~process & path & (programmed / limit > duration)
    times[slower] = programmed[slower] / limit[slower]
    reasons = {w: binding[w] for w in k[lowered | slower].tolist()}
    stated = dict(zip(k[lowered | slower].tolist(), np.where(lowered, speed, duration)[lowered | slower].tolist()))
    bounds = capability(program, OrientationSpeed) is not None  # RAPID's v_ori: a time written replaces the speed
    bounded = np.flatnonzero(bounds & ~process & ~np.isnan(table.orientation_speed[rows]))  # data, bound and all
    for j in bounded.tolist():
        w, motion = int(k[j]), int(rows[j])
        ori = float(table.orientation_speed[motion])
        turning = orientation_time(table.kind[motion], result.q[w - 1], result.q[w], ori, robot)
        if turning > times[j]:
            times[j], stated[w] = turning, float(duration[j])
            reasons[w] = f"its orientation speed {np.degrees(ori):g} deg/s (v_ori) bounds the reorientation"
    time_why = table.time_why[rows]
    kept = ~process & (time_why != "")  # a time its controller would not run as timed: the field as written
    written_time, left = ~process & ~kept, set(k[kept].tolist())
    return SpeedPlan(
        times=dict(zip(k[written_time].tolist(), times[written_time].tolist())),
        cruise=dict(zip(k[lowered].tolist(), limit[lowered].tolist())),
        as_written=as_written,
        reasons={w: why for w, why in sorted(reasons.items()) if w not in left},
        stated={w: value for w, value in sorted(stated.items()) if w not in left},
        not_modelled=tuple(zip(k[kept].tolist(), (f"{why}: left as written" for why in time_why[kept]))),
    )


def cruise_speeds(result, robot, zone):
    """The largest constant TCP speed each timed motion can keep along its whole path within the joint limits.

    A controller given a cruise speed v keeps the TCP at v between its own
    ramps. Along a path q(s) whose TCP moves r(s) = |dp/ds| mm per unit of
    s, that needs s' = v / r, joint velocities q_s v / r and accelerations
    v^2 (q_ss / r^2 - q_s r_s / r^3). So at each grid point of the timed
    path the cruise speed is bounded by v_max_j r / |q_s,j| and
    sqrt(a_max_j / |q_ss,j / r^2 - q_s,j r_s / r^3|); the motion's is the
    smallest over its points (its slowest point). Within a blended corner's
    zone (TCP distance from the waypoint) only the velocity bound counts:
    the controller plans the blend's accelerations itself. The bound is
    taken `CRUISE_MARGIN` lower (the fit's derivatives are not exact).

    Parameters
    ----------
    result : TimingResult
    robot : Robot
        Joint velocity (rad/s) and acceleration (rad/s^2) limits.
    zone : ndarray, shape (M,)
        Blend radius at each waypoint, mm (NaN or 0: an exact stop).

    Returns
    -------
    speed : ndarray, shape (M,)
        mm/s; ``inf`` for motions without a timed path.
    binding : list of str, length M
        The limit that binds at the slowest point (``"J5 velocity limit at
        its slowest point"``), ``""`` where none does.
    """
    m = len(result.t)
    speed, which = np.full(m, np.inf), np.full(m, -1)
    zone = np.nan_to_num(np.asarray(zone, dtype=float), nan=0.0)
    for _, run, _ in result.pieces:
        s, r = run.grid, run.grid_rate
        if len(s) < 2:
            continue
        dq, ddq = run.path(s, 1), run.path(s, 2)
        dr = np.gradient(r, s)
        with np.errstate(divide="ignore", invalid="ignore"):
            by_velocity = robot.v_max * r[:, None] / np.abs(dq)
            demand = np.abs(ddq / (r**2)[:, None] - dq * (dr / r**3)[:, None])
            by_acceleration = np.sqrt(robot.a_max / demand)
        travel = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * np.diff(s))])  # TCP mm along the run
        corner = np.interp(run.s_waypoints, s, travel)
        radius = zone[run.first : run.last + 1].copy()
        radius[[0, -1]] = 0.0  # the run starts and ends at rest
        blended = radius > 0
        count = np.zeros(len(s) + 1, dtype=int)  # +1 from where a corner's zone begins, -1 where it ends
        np.add.at(count, np.searchsorted(travel, corner[blended] - radius[blended], side="right"), 1)
        np.add.at(count, np.searchsorted(travel, corner[blended] + radius[blended], side="left"), -1)
        by_acceleration[np.cumsum(count)[:-1] > 0] = np.inf
        bounds = np.nan_to_num(np.concatenate([by_velocity, by_acceleration], axis=1), nan=np.inf)
        bound, limit = CRUISE_MARGIN * bounds.min(axis=1), bounds.argmin(axis=1)
        for k in (run.motion_at(s), run.motion_at(s, "right")):  # a point on a waypoint bounds both motions
            order = np.lexsort((bound, k))
            first = order[np.r_[True, k[order][1:] != k[order][:-1]]]  # the slowest point of each motion
            lower = bound[first] < speed[k[first]]
            speed[k[first][lower]], which[k[first][lower]] = bound[first][lower], limit[first][lower]
    binding = [f"J{w % 6 + 1} {'velocity' if w < 6 else 'acceleration'} limit at its slowest point" if w >= 0 else ""
               for w in which.tolist()]
    if result.track is not None:  # world TCP speeds, and the track's velocity limit along each line
        speed = speed * result.track.world_ratio
        by_track = result.track.speed_bound < speed
        speed[by_track] = CRUISE_MARGIN * result.track.speed_bound[by_track]
        for k in np.flatnonzero(by_track).tolist():
            binding[k] = f"the track's ({result.track.field}) velocity limit"
    return speed, binding
