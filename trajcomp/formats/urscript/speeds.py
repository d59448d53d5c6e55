"""Re-timing written into a URScript program: ``t=`` and ``v=`` of its moves (`trajcomp.timing.writeback`)."""

import re

from trajcomp.formats.number_writing import ceil_places, floor_places, format_number
from trajcomp.formats.source_shifts import edit_sources

_FUNCTION = re.compile(r"(\w+)\s*\(")  # the function a motion calls (also after a sign: ``+movel(...)``)


def write_speeds(program, result, robot, plan):
    """A timed movej / movel gets ``t=`` (s); a lowered cruise speed is written ``v=`` (m/s).

    The language's `trajcomp.formats.capabilities.SpeedFields` writer: ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint. The motions' fields are read as columns
    (`trajcomp.programs.tables.MotionTable.span_offsets`): no motion object per waypoint.
    """
    motions = program.motion_table()
    fields = {key: motions.span_offsets(key)[1:] for key in ("t", "v", "end")}  # (start, end) (M,) each
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        row = int(result.motion[k])
        if k in plan.cruise:
            key, value = "v", format_number(floor_places(plan.cruise[k] / 1000.0, 6), 6)
        elif _FUNCTION.search(motions.text[row]).group(1) in ("movej", "movel"):
            key, value = "t", format_number(ceil_places(plan.times[k], 4), 4)
        else:  # movep / movec take no time: their TCP speed was stated
            continue
        start, end = (int(column[row]) for column in fields[key])
        if start >= 0:
            edits.append((start, end, value))
        else:
            at = int(fields["end"][0][row])
            edits.append((at, at, f", {key}={value}"))
        settings[k] = f"{key}={value}"
    return edit_sources(program, [edits]), settings
