"""The timing written into a program's own speed and time fields, every other byte kept.

Per language, for each timed motion of duration T (TCP path length L):

- CSV: a ``t`` column, the time stamp of each row (s, to the ns), added or replaced;
- ABB RAPID: ``\\T:=T`` after the speed data (replacing a ``\\V`` or ``\\T``);
- URScript: ``t=T`` on movej / movel; movep / movec take no time, so ``v=L/T``;
- FANUC: the speed becomes time-based: ``Tmsec`` (1 ms resolution), ``T sec``
  beyond 32 s;
- KUKA KRL, which has no motion time: ``$VEL.CP = L/T`` before each LIN /
  CIRC and ``BAS(#VEL_PTP, %)`` before each PTP, the percentage with which
  the leading axis, accelerating at its limit, needs T (a trapezoid). The
  statement that sets a motion's speed is edited when it serves that motion
  first, else a line is inserted before the motion; a motion after it that
  is not re-timed gets its original value back.

Times are rounded up and speeds down at the written resolution: never
faster than the timing. Motions that are not timed (their start is unknown)
or have no length keep their fields.
"""

import dataclasses
import math
import re

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.formats._text import Lines, apply_edits, format_number
from trajcomp.formats.csv_program import time_texts, with_times
from trajcomp.memory import collection_paused
from trajcomp.program_items import JOINT, Span
from trajcomp.timing.moves import moves_from_program
from trajcomp.timing.path import TOLERANCE
from trajcomp.timing.result import Texts
from trajcomp.timing.retime import retime

MSEC_LIMIT = 32000  # FANUC msec speeds: 1 .. 32000
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
        Axis limits for the KRL PTP percentage.

    Returns
    -------
    (Program, TimingResult)

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
    timed, settings = writer(program, result, robot)
    return timed, result.with_settings(settings)


def writable(program):
    """True if `apply_timing` can write into this program (a supported language, read from a file)."""
    return program.format in _WRITERS and bool(program.sources)


def _timed(result):
    """Waypoints whose motion has a duration to write: (k, duration s)."""
    untimed = set(result.untimed)
    durations = result.durations
    return [(k, durations[k]) for k in range(1, len(result.t)) if k not in untimed and durations[k] > 0]


def _ceil(value, places):
    return math.ceil(value * 10**places - 1e-9) / 10**places


def _floor(value, places):
    return max(math.floor(value * 10**places + 1e-9), 1) / 10**places


def _csv(program, result, robot):
    """The ``t`` column: each row's time stamp (`trajcomp.formats.csv_program.with_times`).

    The settings are ``t=`` and the text written, made on demand from the
    time stamps as the writer makes them (no str per waypoint held).
    """
    times = np.full(len(program.motion_table()), np.nan)
    times[result.motion] = result.t
    timed = with_times(program, times)
    t = result.t

    def make(lo, hi):
        return ["t=" + text for text in time_texts(t[lo:hi])]

    return timed, Texts(make, 0, len(t))


def _rapid(program, result, robot):
    edits, settings = [], {}
    for k, duration in _timed(result):
        span = program.motions[result.motion[k]].spans["speed"]
        speed_data = span.text.split("\\")[0].rstrip()  # v20 of v20\V:=15 or v20\T:=4
        written = f"{speed_data}\\T:={format_number(_ceil(duration, 3), 3)}"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def _urscript(program, result, robot):
    edits, settings = [], {}
    for k, duration in _timed(result):
        motion = program.motions[result.motion[k]]
        function = re.match(r"\s*(\w+)", motion.text).group(1)
        if function in ("movej", "movel"):
            key, value = "t", format_number(_ceil(duration, 4), 4)
        elif result.tcp_length[k] > 0:
            key, value = "v", format_number(_floor(result.tcp_length[k] / duration / 1000.0, 6), 6)
        else:
            continue
        if key in motion.spans:
            edits.append((motion.spans[key].start, motion.spans[key].end, value))
        else:
            edits.append((motion.spans["end"].start, motion.spans["end"].start, f", {key}={value}"))
        settings[k] = f"{key}={value}"
    return edit_sources(program, [edits]), settings


def _fanuc(program, result, robot):
    edits, settings = [], {}
    for k, duration in _timed(result):
        span = program.motions[result.motion[k]].spans.get("speed")
        if span is None:  # a speed register or max_speed: set at run time, left as it is
            continue
        ms = math.ceil(duration * 1000.0 - 1e-6)
        written = f"{ms}msec" if ms <= MSEC_LIMIT else f"{format_number(_ceil(duration, 1), 1)}sec"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def _krl(program, result, robot):
    wanted = {}
    for k, duration in _timed(result):
        m = int(result.motion[k])
        if program.motions[m].kind == JOINT:
            percent = _ptp_percent(result.q[k] - result.q[k - 1], duration, robot)
            if percent is not None:
                wanted[m] = (k, str(percent))
        elif result.tcp_length[k] > 0:
            wanted[m] = (k, format_number(_floor(result.tcp_length[k] / duration / 1000.0, 6), 6))
    text = program.sources[0].text
    newline = "\r\n" if "\r\n" in text else "\n"
    edits = [[] for _ in program.sources]
    settings = {}
    running = {"ptp": None, "cp": None}  # the speed value in force as the program runs down
    governing = {"ptp": None, "cp": None}  # (source, offset) of the statement that set it
    for m, motion in enumerate(program.motions):
        group = "ptp" if motion.kind == JOINT else "cp"
        span = motion.spans.get("speed")
        key = None if span is None else (span.source, span.start)
        k, want = wanted.get(m, (None, None))
        if key != governing[group]:  # a new statement sets this motion's speed
            governing[group] = key
            running[group] = None if span is None else span.text
            if span is not None and want is not None:
                edits[span.source].append((span.start, span.end, want))
                running[group] = want
        need = want if want is not None else (None if span is None else span.text)
        if need is None or (running[group] is not None and float(need) == float(running[group])):
            if want is not None:
                settings[k] = _krl_statement(group, want)
            continue
        at = motion.spans["motion"]
        line_start = text.rfind("\n", 0, at.start) + 1
        indent = _INDENT.match(text, line_start).group()  # matched in place: a slice would copy the rest of the text
        edits[at.source].append((line_start, line_start, f"{indent}{_krl_statement(group, need)}{newline}"))
        running[group] = need
        if want is not None:
            settings[k] = _krl_statement(group, want)
    return edit_sources(program, edits), settings


def _krl_statement(group, value):
    return f"$VEL.CP={value}" if group == "cp" else f"BAS(#VEL_PTP,{value})"


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


def edit_sources(program, edits):
    """The program with text edits applied to its sources and every span and line number moved along.

    Parameters
    ----------
    program : Program
    edits : sequence of list of (start, end, text)
        Per source; non-overlapping; an insertion (start == end) goes before
        a span starting there and after a span ending there.

    Returns
    -------
    Program
    """
    with collection_paused():  # a span and an item object each (`trajcomp.memory`)
        return _edited(program, [_Shift(source.text, sorted(e)) for source, e in zip(program.sources, edits)])


def _edited(program, shifts):
    """`edit_sources` of the edits ``shifts`` (one `_Shift` per source)."""
    sources = tuple(s.source_like(source) for s, source in zip(shifts, program.sources))
    every_target = list(program.targets)
    targets = [t for t in every_target if t.spans]  # a target without spans keeps its line
    things = targets + list(program.items)  # statements and motions are lines of the first file
    spans = [getattr(thing, "spans", {}) for thing in things]
    moved = iter(_moved_spans(shifts, [span for of in spans for span in of.values()]))
    first_file = [0] * (len(things) - len(targets))
    lines = _moved_lines(shifts, [next(iter(t.spans.values())).source for t in targets] + first_file,
                         [thing.line for thing in things])
    edited = iter([dataclasses.replace(thing, line=line, **({"spans": {role: next(moved) for role in of}} if of else {}))
                   for thing, of, line in zip(things, spans, lines)])
    return program.replace(sources=sources, targets=tuple(next(edited) if t.spans else t for t in every_target),
                           items=tuple(edited))


def _moved_spans(shifts, spans):
    """The spans (list of Span) in the edited texts, each source's positions moved at once."""
    source = np.array([span.source for span in spans], dtype=int)
    start = np.array([span.start for span in spans], dtype=int)
    end = np.array([span.end for span in spans], dtype=int)
    for k, shift in enumerate(shifts):
        rows = np.flatnonzero(source == k)
        start[rows] = shift.starts(start[rows])
        end[rows] = np.maximum(shift.ends(end[rows]), start[rows])
    texts = [shift.new for shift in shifts]
    return [Span(k, a, b, texts[k][a:b]) for k, a, b in zip(source.tolist(), start.tolist(), end.tolist())]


def _moved_lines(shifts, sources, numbers):
    """Line numbers (list of int) in the edited texts of lines ``numbers`` of ``sources``."""
    source, number = np.array(sources, dtype=int), np.array(numbers, dtype=int)
    for k, shift in enumerate(shifts):
        rows = np.flatnonzero(source == k)
        number[rows] = shift.lines(number[rows])
    return number.tolist()


class _Shift:
    """Offsets and line numbers of a text before edits mapped to the edited text, for arrays of them."""

    def __init__(self, text, edits):
        self.old, self.new = text, apply_edits(text, edits)
        self.edit_ends = np.array([e[1] for e in edits], dtype=int)
        self.insertions = np.array([e[0] for e in edits if e[0] == e[1]], dtype=int)  # ascending, as the edits
        self.delta = np.cumsum([0] + [len(e[2]) - (e[1] - e[0]) for e in edits])
        self.old_starts = np.array(Lines(self.old).starts)
        self.new_starts = np.array(Lines(self.new).starts)

    def starts(self, positions):
        """New offsets of span starts (n,): after every edit ending at or before them."""
        return positions + self.delta[np.searchsorted(self.edit_ends, positions, side="right")]

    def ends(self, positions):
        """New offsets of span ends (n,): after every edit ending at or before them, except insertions at them."""
        at = np.searchsorted(self.insertions, positions, side="right") - np.searchsorted(self.insertions, positions)
        return positions + self.delta[np.searchsorted(self.edit_ends, positions, side="right") - at]

    def lines(self, numbers):
        """New numbers of lines (n,) (by their starts); numbers outside the text as they are."""
        inside = (numbers >= 1) & (numbers <= len(self.old_starts))
        moved = self.starts(self.old_starts[np.clip(numbers, 1, len(self.old_starts)) - 1])
        return np.where(inside, np.searchsorted(self.new_starts, moved, side="right"), numbers)

    def source_like(self, source):
        return source.__class__(source.name, self.new, source.encoding)
