"""Re-timing written into a FANUC LS program: a motion's speed field (`trajcomp.timing.writeback`)."""

import math

from trajcomp.formats.text import ceil_places, edit_sources, format_number

MSEC_LIMIT = 32000  # FANUC msec speeds: 1 .. 32000


def write_speeds(program, result, robot, plan):
    """A timed motion's speed becomes ``Tmsec`` (``T sec`` beyond 32 s); a lowered cruise speed ``v mm/sec``.

    The ``speeds`` hook of the format (`trajcomp.formats.register_format`): ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint.
    """
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        span = program.motions[result.motion[k]].spans.get("speed")
        if span is None:  # max_speed: the arm's own limits, left as it is
            continue
        if k in plan.cruise:
            written = f"{max(math.floor(plan.cruise[k] + 1e-9), 1)}mm/sec"
        else:
            written = time_field(plan.times[k])
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings


def time_field(seconds):
    """A motion time as FANUC writes it, rounded up: ``Tmsec`` up to 32 s, else ``T sec`` (0.1 s)."""
    ms = math.ceil(seconds * 1000.0 - 1e-6)
    return f"{ms}msec" if ms <= MSEC_LIMIT else f"{format_number(ceil_places(seconds, 1), 1)}sec"
