"""Re-timing written into a RAPID module: ``\\T`` and ``\\V`` after a motion's speed data (`trajcomp.timing.writeback`)."""

from trajcomp.formats.number_writing import ceil_places, floor_places, format_number
from trajcomp.formats.source_shifts import edit_sources


def write_speeds(program, result, robot, plan):
    """A timed motion's speed data get ``\\T:=`` (a time, s) or ``\\V:=`` (a lowered cruise TCP speed, mm/s).

    The language's `trajcomp.formats.capabilities.SpeedFields` writer: ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint.
    """
    edits, settings = [[] for _ in program.sources], {}  # per source: a task's motions may lie in any module
    source, start, end = program.motion_table().span_offsets("speed")  # as columns: no object per motion
    for k in sorted({**plan.times, **plan.cruise}):
        m = result.motion[k]
        text = program.sources[source[m]].text[start[m]:end[m]]
        speed_data = text.split("\\")[0].rstrip()  # v20 of v20\V:=15 or v20\T:=4
        if k in plan.cruise:
            written = f"{speed_data}\\V:={format_number(floor_places(plan.cruise[k], 3), 3)}"
        else:
            written = f"{speed_data}\\T:={format_number(ceil_places(plan.times[k], 3), 3)}"
        edits[source[m]].append((int(start[m]), int(end[m]), written))
        settings[k] = written
    return edit_sources(program, edits), settings
