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
  speed the tool cannot compare with it;
- any other motion (joint motions, motions with a stated time) gets its
  timed duration T (for a linear or circular one at least its TCP length
  over its cruise speed, so that a controller cruising at L/T keeps the
  limits):

  - CSV: a ``t`` column, the time stamp of each row (s, to the ns), added or
    replaced (the rows are the trajectory: every row is timed);
  - ABB RAPID: ``\\T:=T`` after the speed data (replacing a ``\\V`` or ``\\T``);
  - URScript: ``t=T`` on movej / movel;
  - FANUC: the speed becomes time-based: ``Tmsec`` (1 ms resolution), ``T sec``
    beyond 32 s;
  - KUKA KRL, which has no motion time: ``BAS(#VEL_PTP, %)`` before each PTP,
    the percentage with which the leading axis, accelerating at its limit,
    needs T (a trapezoid).

KRL speeds are modal: the statement that sets a motion's speed (``$VEL.CP``,
``BAS``, the ``BAS(#CP_PARAMS, v)`` of an inline form, a spline's ``WITH
$VEL``) is edited when it serves that motion first, else a line is inserted
before the motion; a motion after it that keeps its speed gets its original
value back. An edit inside an inline form's fold edits the speed its header
shows too; a line inserted for a motion inside one goes before the fold.

Times are rounded up and speeds down at the written resolution: never
faster than the timing. Motions that are not timed (their start is unknown)
or have no length keep their fields.
"""

import bisect
import dataclasses
import math
import re

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.formats.text import NUMBER, edit_sources, format_number
from trajcomp.formats.csv.writer import time_texts, with_times
from trajcomp.programs.items import JOINT
from trajcomp.timing.moves import moves_from_program
from trajcomp.timing.path import TOLERANCE
from trajcomp.timing.result import Texts
from trajcomp.timing.retime import retime

MSEC_LIMIT = 32000  # FANUC msec speeds: 1 .. 32000
# a cruise speed is kept this much below its bound: the fitted path's second derivative differs from the exact
# line's (solved every 0.05 mm) by up to ~0.05 % of the acceleration at the slowest point
CRUISE_MARGIN = 0.999
_INDENT = re.compile(r"[ \t]*")


def retime_program(program, robot, joints, *, method="auto", tools=None, frames=None, tolerance=TOLERANCE):
    """Re-time a program whose targets' joints (N, 6) are known (`moves_from_program`, then `retime`).

    Returns
    -------
    TimingResult
    """
    moves = moves_from_program(program, robot, joints, tools=tools, frames=frames)
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
        A program without sources, or a language timing cannot be written in.
    """
    writer = _WRITERS.get(program.format)
    if not writable(program):
        raise TimingError(
            f"{program.name}: timing can be written into CSV, KRL, RAPID, FANUC LS and URScript programs read "
            f"from a file, not into a {program.format} program{'' if program.sources else ' built in memory'}"
        )
    if program.format == "csv":  # its rows are the trajectory: every one gets its time stamp
        timed, settings = _csv(program, result)
        return timed, result.with_settings(settings)
    plan = _plan(program, result, robot)
    timed, settings = writer(program, result, robot, plan)
    return timed, result.with_settings(settings, as_written=plan.as_written, lowered=plan.notes(result, settings))


def writable(program):
    """True if `apply_timing` can write into this program (a supported language, read from a file)."""
    return program.format in _WRITERS and bool(program.sources)


def _timed(result):
    """Waypoints whose motion has a duration to write: (k, duration s)."""
    untimed = set(result.untimed)
    durations = result.durations
    return [(k, durations[k]) for k in range(1, len(result.t)) if k not in untimed and durations[k] > 0]


@dataclasses.dataclass
class _Plan:
    """What to write per timed motion, and what to list.

    Attributes
    ----------
    times : dict of int to float
        Waypoint k -> total time to write, s (joint motions, stated times).
    cruise : dict of int to float
        Waypoint k -> lowered cruise TCP speed to write, mm/s.
    as_written : tuple of (int, str)
        Waypoints whose speed is set at run time, and why.
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
    """The `_Plan` of a timing: run-time speeds kept, stated process speeds kept or lowered, times."""
    timed = _timed(result)
    motions = program.motions
    cruise, binding = cruise_speeds(result, robot, program.motion_table().zone[result.motion])
    plan = _Plan({}, {}, (), {}, {})
    as_written = []
    for k, duration in timed:
        motion = motions[result.motion[k]]
        if motion.speed_why:
            as_written.append((k, motion.speed_why))
            continue
        path = motion.kind != JOINT and result.tcp_length[k] > 0
        if path and motion.speed is not None and motion.speed_unit == "mm/s":  # a stated process speed
            if cruise[k] < motion.speed:
                plan.cruise[k], plan.reasons[k], plan.stated[k] = cruise[k], binding[k], motion.speed
            continue
        plan.times[k] = duration
        if path and result.tcp_length[k] / cruise[k] > duration:
            plan.times[k], plan.reasons[k] = result.tcp_length[k] / cruise[k], binding[k]
            plan.stated[k] = duration
    plan.as_written = tuple(as_written)
    return plan


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
    return speed, binding


def _ceil(value, places):
    return math.ceil(value * 10**places - 1e-9) / 10**places


def _floor(value, places):
    return max(math.floor(value * 10**places + 1e-9), 1) / 10**places


def _csv(program, result):
    """The ``t`` column: each row's time stamp (`trajcomp.formats.csv.writer.with_times`).

    The rows are the trajectory (a CSV program has no speed field of the
    controller's), so every row is timed. The settings are ``t=`` and the
    text written, made on demand from the time stamps as the writer makes
    them (no str per waypoint held).
    """
    times = np.full(len(program.motion_table()), np.nan)
    times[result.motion] = result.t
    timed = with_times(program, times)
    t = result.t

    def make(lo, hi):
        return ["t=" + text for text in time_texts(t[lo:hi])]

    return timed, Texts(make, 0, len(t))


def _rapid(program, result, robot, plan):
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        span = program.motions[result.motion[k]].spans["speed"]
        speed_data = span.text.split("\\")[0].rstrip()  # v20 of v20\V:=15 or v20\T:=4
        if k in plan.cruise:
            written = f"{speed_data}\\V:={format_number(_floor(plan.cruise[k], 3), 3)}"
        else:
            written = f"{speed_data}\\T:={format_number(_ceil(plan.times[k], 3), 3)}"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def _urscript(program, result, robot, plan):
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        motion = program.motions[result.motion[k]]
        function = re.search(r"(\w+)\s*\(", motion.text).group(1)  # also after a sign (``+movel(...)``)
        if k in plan.cruise:
            key, value = "v", format_number(_floor(plan.cruise[k] / 1000.0, 6), 6)
        elif function in ("movej", "movel"):
            key, value = "t", format_number(_ceil(plan.times[k], 4), 4)
        else:  # movep / movec take no time: their TCP speed was stated
            continue
        if key in motion.spans:
            edits.append((motion.spans[key].start, motion.spans[key].end, value))
        else:
            edits.append((motion.spans["end"].start, motion.spans["end"].start, f", {key}={value}"))
        settings[k] = f"{key}={value}"
    return edit_sources(program, [edits]), settings


def _fanuc(program, result, robot, plan):
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        span = program.motions[result.motion[k]].spans.get("speed")
        if span is None:  # max_speed: the arm's own limits, left as it is
            continue
        if k in plan.cruise:
            written = f"{max(math.floor(plan.cruise[k] + 1e-9), 1)}mm/sec"
        else:
            ms = math.ceil(plan.times[k] * 1000.0 - 1e-6)
            written = f"{ms}msec" if ms <= MSEC_LIMIT else f"{format_number(_ceil(plan.times[k], 1), 1)}sec"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def _krl(program, result, robot, plan):
    wanted = {}
    for k in sorted({**plan.times, **plan.cruise}):
        m = int(result.motion[k])
        if k in plan.cruise:
            wanted[m] = (k, format_number(_floor(plan.cruise[k] / 1000.0, 6), 6))
        elif program.motions[m].kind == JOINT:
            percent = _ptp_percent(result.q[k] - result.q[k - 1], plan.times[k], robot)
            if percent is not None:
                wanted[m] = (k, str(percent))
    folds = [_Folds(source.text) for source in program.sources]
    text = program.sources[0].text
    newline = "\r\n" if "\r\n" in text else "\n"
    edits = [[] for _ in program.sources]
    settings = {}

    def edit(span, value):
        """Write ``value`` over ``span`` (and in its fold's header); the statement as it now reads."""
        edits[span.source].append((span.start, span.end, value))
        edits[span.source].extend(folds[span.source].header_edits(span, value))
        text = program.sources[span.source].text
        start, end = text.rfind("\n", 0, span.start) + 1, text.find("\n", span.end)
        end = len(text) if end < 0 else end
        return " ".join((text[start:span.start] + value + text[span.end:end]).split())

    running = {"ptp": None, "cp": None}  # the speed value in force as the program runs down
    governing = {"ptp": None, "cp": None}  # (source, offset) of the statement that set it
    for m, motion in enumerate(program.motions):
        group = "ptp" if motion.kind == JOINT else "cp"
        k, want = wanted.get(m, (None, None))
        if "speed_with" in motion.spans:  # the motion's own speed, in its WITH clause: the modal one stays
            if want is not None:
                settings[k] = edit(motion.spans["speed_with"], want)
            continue
        span = motion.spans.get("speed")
        key = None if span is None else (span.source, span.start)
        if key != governing[group]:  # a new statement sets this motion's speed
            governing[group] = key
            running[group] = None if span is None else span.text
            if span is not None and want is not None:
                settings[k] = edit(span, want)
                running[group] = want
        need = want if want is not None else (None if span is None else span.text)
        if need is None or (running[group] is not None and _same(need, running[group])):
            if want is not None:
                settings.setdefault(k, _krl_statement(group, want))
            continue
        at = motion.spans["motion"]
        source_text = program.sources[at.source].text
        line_start = folds[at.source].outside(source_text.rfind("\n", 0, at.start) + 1)
        indent = _INDENT.match(source_text, line_start).group()  # in place: a slice would copy the rest
        edits[at.source].append((line_start, line_start, f"{indent}{_krl_statement(group, need)}{newline}"))
        running[group] = need
        if want is not None:
            settings[k] = _krl_statement(group, want)
    return edit_sources(program, [sorted(set(e)) for e in edits]), settings


def _same(a, b):
    """Two KRL speed values are the same: equal numbers, or the same text (a name)."""
    try:
        return float(a) == float(b)
    except ValueError:
        return a.strip().upper() == b.strip().upper()


def _krl_statement(group, value):
    return f"$VEL.CP={value}" if group == "cp" else f"BAS(#VEL_PTP,{value})"


_FOLD = re.compile(r"^[ \t]*;[ \t]*(END)?FOLD\b", re.I | re.M)
# the speed an inline form's header (and its parameter fold) shows: Vel=0.2 m/s, %P .. 5:0.2, Kuka.VelocityPath=0.2
_HEADER_SPEED = re.compile(r"(?:\bVel\s*=\s*|\bKuka\.Velocity\w*\s*=\s*|%P\b[^\r\n]*?,\s*5\s*:\s*)(" + NUMBER + ")", re.I)


class _Folds:
    """The inline-form folds of a KRL text (``;FOLD .. ;%{PE}`` .. ``;ENDFOLD``): where they start and end."""

    def __init__(self, text):
        self.text = text
        self.folds, stack = [], []  # (start of the ;FOLD line, end of the ;ENDFOLD line) of inline forms
        for m in _FOLD.finditer(text):
            if m.group(1) is None:
                end = text.find("\n", m.start())
                stack.append((m.start(), "%{PE}" in text[m.start():end if end >= 0 else len(text)].upper()))
            elif stack:
                begin, inline = stack.pop()
                if inline:
                    self.folds.append((begin, m.end()))
        self.folds.sort()

    def enclosing(self, offset):
        """``(start, end)`` of the inline form's fold around ``offset``, or None (inline forms do not nest)."""
        at = bisect.bisect_right(self.folds, (offset, math.inf)) - 1
        return self.folds[at] if at >= 0 and offset < self.folds[at][1] else None

    def outside(self, offset):
        """Where a line inserted at line start ``offset`` goes: before the inline form's fold around it."""
        fold = self.enclosing(offset)
        return offset if fold is None else fold[0]

    def header_edits(self, span, value):
        """Edits (start, end, text) that make the fold around ``span`` show speed ``value`` where it showed the old one."""
        fold = self.enclosing(span.start)
        if fold is None or not re.fullmatch(NUMBER, span.text.strip()):
            return []
        old = float(span.text)
        out = []
        for line in re.finditer(r"^[ \t]*;[^\r\n]*", self.text[fold[0]:span.start], re.M):  # its comment lines
            for m in _HEADER_SPEED.finditer(line.group()):
                if float(m.group(1)) == old:
                    at = fold[0] + line.start() + m.start(1)
                    out.append((at, at + len(m.group(1)), value))
        return out


def _ptp_percent(delta, duration, robot):
    """Integer % of axis speed with which a synchronized PTP takes ``duration``; None if any would.

    The axes move in phase along the joint line, the line parameter l from
    0 to 1 with acceleration a_l = min_j a_j / |delta_j| (the leading axis
    at its limit). A trapezoid of l that takes T cruises at
    v_l = (a_l T - sqrt(a_l^2 T^2 - 4 a_l)) / 2, and the percentage is the
    largest v_l |delta_j| / v_max_j, rounded down (never faster), at least 1.
    None when T is the acceleration-limited time (no cruise, whatever the
    percentage): the program's own value then stands.
    """
    distance = np.abs(delta)
    moving = distance > 0
    if not moving.any():
        return None
    a = np.min(robot.a_max[moving] / distance[moving])
    root = (a * duration) ** 2 - 4.0 * a
    if root <= 1e-6 * (a * duration) ** 2:
        return None
    speed = 0.5 * (a * duration - np.sqrt(root))
    return max(math.floor(100.0 * speed * np.max(distance / robot.v_max) + 1e-9), 1)


_WRITERS = {"csv": _csv, "rapid": _rapid, "urscript": _urscript, "fanuc_ls": _fanuc, "krl": _krl}
