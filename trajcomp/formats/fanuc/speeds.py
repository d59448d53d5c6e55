"""Re-timing written into a FANUC LS program: a motion's speed field (`trajcomp.timing.writeback`)."""

import math

from trajcomp.formats.text import ceil_places, edit_sources, format_number

MSEC_LIMIT = 32000  # FANUC msec speeds: 1 .. 32000


def write_speeds(program, result, robot, plan):
    """A timed motion's speed becomes ``Tmsec`` (``T sec`` beyond 32 s); a lowered cruise speed ``v mm/sec``.

    Parameters
    ----------
    program : Program
        Read from a file (its sources are edited).
    result : TimingResult
        Its timing (`trajcomp.timing.writeback.retime_program`).
    robot : Robot
        Joint limits.
    plan : SpeedPlan
        What to write per waypoint k (`trajcomp.timing.writeback.SpeedPlan`):
        ``times[k]`` s or ``cruise[k]`` mm/s; waypoint k is the end of motion
        ``result.motion[k]``.

    Returns
    -------
    (Program, dict of int to str)
        The program with the fields written, and the setting written per waypoint.
    """
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        span = program.motions[result.motion[k]].spans.get("speed")
        if span is None:  # max_speed: the arm's own limits, left as it is
            continue
        if k in plan.cruise:
            written = f"{max(math.floor(plan.cruise[k] + 1e-9), 1)}mm/sec"
        else:
            ms = math.ceil(plan.times[k] * 1000.0 - 1e-6)
            written = f"{ms}msec" if ms <= MSEC_LIMIT else f"{format_number(ceil_places(plan.times[k], 1), 1)}sec"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings
