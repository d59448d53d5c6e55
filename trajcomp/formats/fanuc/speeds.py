"""Re-timing written into a FANUC LS program: a motion's speed field (`trajcomp.timing.writeback`)."""

import math

import numpy as np

from trajcomp.formats.number_writing import ceil_places, format_number
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.programs.items import SpanColumns

MSEC_LIMIT = 32000  # FANUC msec speeds: 1 .. 32000


def write_speeds(program, result, robot, plan):
    """A timed motion's speed becomes ``Tmsec`` (``T sec`` beyond 32 s); a lowered cruise speed ``v mm/sec``.

    The language's `trajcomp.formats.capabilities.SpeedFields` writer: ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint.
    """
    waypoints = sorted({**plan.times, **plan.cruise})
    start, end = _speed_fields(program, result.motion[np.array(waypoints, dtype=int)])
    edits, settings = [], {}
    for k, a, b in zip(waypoints, start.tolist(), end.tolist()):
        if a < 0:  # max_speed: the arm's own limits, left as it is
            continue
        if k in plan.cruise:
            written = f"{max(math.floor(plan.cruise[k] + 1e-9), 1)}mm/sec"
        else:
            written = time_field(plan.times[k])
        edits.append((a, b, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def _speed_fields(program, rows):
    """Offsets (K,) of the speed fields of motions ``rows`` (K,) in the program's file; -1 where a motion has
    none (read as columns where the reader keeps them so: no object per motion)."""
    spans = program.motion_table().spans
    if isinstance(spans, SpanColumns) and "speed" in spans.column:
        column = spans.column["speed"]
        return spans.start[rows, column], spans.end[rows, column]
    fields = [program.motions[m].spans.get("speed") for m in rows.tolist()]
    return (np.array([-1 if f is None else f.start for f in fields], dtype=int),
            np.array([-1 if f is None else f.end for f in fields], dtype=int))


def time_field(seconds):
    """A motion time as FANUC writes it, rounded up: ``Tmsec`` up to 32 s, else ``T sec`` (0.1 s)."""
    ms = math.ceil(seconds * 1000.0 - 1e-6)
    return f"{ms}msec" if ms <= MSEC_LIMIT else f"{format_number(ceil_places(seconds, 1), 1)}sec"
