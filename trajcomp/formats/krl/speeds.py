"""Re-timing written into a KRL program: ``$VEL.CP`` and ``BAS(#VEL_PTP, %)`` (`trajcomp.timing.writeback`)."""

import bisect
import math
import re

import numpy as np

from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.number_writing import floor_places, format_number
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.programs.items import JOINT, Span

_INDENT = re.compile(r"[ \t]*")


def write_speeds(program, result, robot, plan):
    """A lowered cruise speed is written ``$VEL.CP`` (m/s), a joint motion's time ``BAS(#VEL_PTP, %)``.

    KRL speeds are modal: the statement that sets a motion's speed
    (``$VEL.CP``, ``BAS``, the ``BAS(#CP_PARAMS, v)`` of an inline form, a
    spline's ``WITH $VEL``) is edited when it serves that motion first, else
    a line is inserted before the motion; a motion after it that keeps its
    speed gets its original value back. An edit inside an inline form's
    fold edits the speed its header shows too; a line inserted for a motion
    inside one goes before the fold.

    The language's `trajcomp.formats.capabilities.SpeedFields` writer: ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint.
    """
    table = program.motion_table()
    joint = table.kind == JOINT  # (M,)
    wanted = {}
    for k in sorted({**plan.times, **plan.cruise}):
        m = int(result.motion[k])
        if k in plan.cruise:
            wanted[m] = (k, format_number(floor_places(plan.cruise[k] / 1000.0, 6), 6))
        elif joint[m]:
            percent = _ptp_percent(result.q[k] - result.q[k - 1], plan.times[k], robot)
            if percent is not None:
                wanted[m] = (k, str(percent))
    folds = [_Folds(source.text) for source in program.sources]
    text = program.sources[0].text
    newline = "\r\n" if "\r\n" in text else "\n"
    edits = [[] for _ in program.sources]
    settings = {}

    def edit(span, value):
        """Write ``value`` over ``span`` (and in its fold's header); the statement as it now reads. A span edited
        for an earlier motion (one statement serving motions the program runs apart: a loop, a spline block
        between) keeps the slowest value."""
        key = (span.source, span.start, span.end)
        if key in edited and not _slower(value, edited[key]):
            value = edited[key]
        edited[key] = value
        text = program.sources[span.source].text
        start, end = text.rfind("\n", 0, span.start) + 1, text.find("\n", span.end)
        end = len(text) if end < 0 else end
        return " ".join((text[start:span.start] + value + text[span.end:end]).split())

    def span_of(offsets, m):
        """The `Span` of motion ``m`` in ``offsets`` (`MotionTable.span_offsets`), or None."""
        source, start, end = (int(column[m]) for column in offsets)
        return None if start < 0 else Span(source, start, end, program.sources[source].text[start:end])

    speed_with, speed, motion_at = (table.span_offsets(role) for role in ("speed_with", "speed", "motion"))
    inserted = {}  # (source, offset, group) -> (the line inserted there, its value)
    restored = _restored(joint, speed_with[1] >= 0, np.isin(np.arange(len(table)), list(wanted)),
                         np.asarray(table.start_why, dtype=object) != "")
    edited = {}  # (source, start, end) of a span edited -> the value written there
    running = {"ptp": None, "cp": None}  # the speed value in force as the program runs down
    governing = {"ptp": None, "cp": None}  # (source, offset) of the statement that set it
    for m in _changing(joint, speed_with[1] >= 0, speed[:2], np.isin(np.arange(len(table)), list(wanted))).tolist():
        group = "ptp" if joint[m] else "cp"
        k, want = wanted.get(m, (None, None))
        if speed_with[1][m] >= 0:  # the motion's own speed, in its WITH clause: the modal one stays
            if want is not None:
                settings[k] = edit(span_of(speed_with, m), want)
            continue
        span = span_of(speed, m)
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
        at = span_of(motion_at, m)
        source_text = program.sources[at.source].text
        line_start = folds[at.source].outside(source_text.rfind("\n", 0, at.start) + 1)
        indent = _INDENT.match(source_text, line_start).group()  # in place: a slice would copy the rest
        key = (at.source, line_start, group)
        if key in inserted and _slower(inserted[key][1], need):  # a spline block's motions: before it, the slowest
            need = inserted[key][1]
        inserted[key] = (f"{indent}{_krl_statement(group, '{}')}{newline}", need)
        running[group] = need
        if want is None:
            continue
        settings[k] = _krl_statement(group, want)
        programmed = span.text if span is not None else _programmed(table.speed[m], group)
        if restored[m] and programmed is not None and not _same(want, programmed):
            after = folds[at.source].after(at.end)  # the state the program has there, on every path from it
            key = (at.source, after, group)
            if key in inserted and _slower(inserted[key][1], programmed):
                programmed = inserted[key][1]
            inserted[key] = (f"{indent}{_krl_statement(group, '{}')}{newline}", programmed)
            running[group] = programmed
    for (source, start, end), value in edited.items():
        span = Span(source, start, end, program.sources[source].text[start:end])
        edits[source].append((start, end, value))
        edits[source].extend(folds[source].header_edits(span, value))
    for (source, offset, _), (line, value) in inserted.items():
        edits[source].append((offset, offset, line.format(value)))
    return edit_sources(program, [sorted(set(e)) for e in edits]), settings


def _changing(joint, own, speed, wanted):
    """The motions (ascending) at which the speed write-back can do anything; the others keep their speed.

    A motion whose speed is set by the same statement as the motion of its
    group before it (``$VEL.CP`` for LIN and CIRC, ``BAS(#VEL_PTP)`` for
    PTP), that wants no new speed, and whose group's motion before it
    wanted none either runs at that statement's value, unchanged: nothing
    is written for it.

    Parameters
    ----------
    joint, own, wanted : ndarray of bool, shape (M,)
        PTP motions; motions with their own speed (WITH); motions given a new speed.
    speed : tuple of ndarray of int, shape (M,)
        Source and start of each motion's speed statement (-1: none).
    """
    changing = own | wanted
    for group in (joint & ~own, ~joint & ~own):
        rows = np.flatnonzero(group)
        key = np.stack([speed[0][rows], speed[1][rows]], axis=1)
        new = np.ones(len(rows), dtype=bool)
        new[1:] = (key[1:] != key[:-1]).any(axis=1) | wanted[rows[:-1]]
        changing[rows[new]] = True
    return np.flatnonzero(changing)


def _restored(joint, own, wanted, elsewhere):
    """The motions (M,) bool after whose line a speed inserted for them is set back to the programmed one.

    A line inserted before a motion sets the modal speed for whatever runs
    next on every path: the motion after it in the file, and, through a
    loop's back jump, a branch's end or a jump, others. Set back right
    after the motion, every path from there runs the programmed speed, as
    the program's own statements give it. Not needed where nothing of its
    group runs after it: the next motion of its group in the file follows
    it alone (no other path reaches it) and gets its own speed, or it is
    the last of its group and no path leads back (no motion of the program
    is reached from elsewhere).

    Parameters
    ----------
    joint, own, wanted, elsewhere : ndarray of bool, shape (M,)
        PTP motions; motions with their own speed (WITH); motions given a
        new speed; motions reached from elsewhere than the one before them
        (`trajcomp.programs.items.Motion.start_why`).
    """
    m = len(joint)
    out = np.zeros(m, dtype=bool)
    flow = bool(elsewhere.any())
    for group in (joint & ~own, ~joint & ~own):
        rows = np.flatnonzero(group & wanted)
        members = np.flatnonzero(group)
        following = np.searchsorted(members, rows, side="right")  # index in members of the next of its group
        has_next = following < len(members)
        nxt = members[np.minimum(following, len(members) - 1)]
        alone = has_next & wanted[nxt] & ~elsewhere[nxt] & (nxt == rows + 1)
        out[rows] = ~alone & (has_next | flow)
    return out


def _programmed(speed, group):
    """The KRL value of a programmed speed ``speed`` (LIN: mm/s, written in m/s; PTP: %), rounded down; None where
    unknown (NaN)."""
    if np.isnan(speed):
        return None
    if group == "cp":
        return format_number(floor_places(speed / 1000.0, 6), 6)
    return format_number(floor_places(speed, 3), 3)


def _slower(a, b):
    """KRL speed value ``a`` is a number below ``b`` (a name is never known slower)."""
    try:
        return float(a) < float(b)
    except ValueError:
        return False


def _same(a, b):
    """Two KRL speed values are the same: equal numbers, or the same text (a name)."""
    try:
        return float(a) == float(b)
    except ValueError:
        return a.strip().upper() == b.strip().upper()


def _krl_statement(group, value):
    return f"$VEL.CP={value}" if group == "cp" else f"BAS(#VEL_PTP,{value})"


_FOLD = re.compile(r"^[ \t]*;[ \t]*(END)?FOLD\b", re.I | re.M)
_SPLINE_BLOCK = re.compile(r"^[ \t]*(?:PTP_)?SPLINE\b.*?^[ \t]*ENDSPLINE\b", re.I | re.M | re.S)
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
        # the spline blocks (SPLINE .. ENDSPLINE): a statement inserted for a motion in one goes before it
        self.splines = [(m.start(), m.end()) for m in _SPLINE_BLOCK.finditer(text)]

    def enclosing(self, offset):
        """``(start, end)`` of the inline form's fold around ``offset``, or None (inline forms do not nest)."""
        at = bisect.bisect_right(self.folds, (offset, math.inf)) - 1
        return self.folds[at] if at >= 0 and offset < self.folds[at][1] else None

    def outside(self, offset):
        """Where a line inserted at line start ``offset`` goes: before the inline form's fold or the spline block
        around it (KRL allows no statement inside a spline block)."""
        fold = self.enclosing(offset)
        offset = offset if fold is None else fold[0]
        block = bisect.bisect_right(self.splines, (offset, math.inf)) - 1
        return self.splines[block][0] if block >= 0 and offset < self.splines[block][1] else offset

    def after(self, offset):
        """Where a line inserted after the statement at ``offset`` goes: the start of the line after it, or after
        the inline form's fold or the spline block around it."""
        fold = self.enclosing(offset)
        offset = offset if fold is None else fold[1]
        block = bisect.bisect_right(self.splines, (offset, math.inf)) - 1
        if block >= 0 and offset < self.splines[block][1]:
            offset = self.splines[block][1]
        end = self.text.find("\n", offset)
        return len(self.text) if end < 0 else end + 1

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
