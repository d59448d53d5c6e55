"""Re-timing written into a URScript program: ``t=`` and ``v=`` of its moves (`trajcomp.timing.writeback`)."""

import re

from trajcomp.formats.text import ceil_places, edit_sources, floor_places, format_number


def write_speeds(program, result, robot, plan):
    """A timed movej / movel gets ``t=`` (s); a lowered cruise speed is written ``v=`` (m/s).

    The ``speeds`` hook of the format (`trajcomp.formats.register_format`): ``plan.times[k]`` (s) and
    ``plan.cruise[k]`` (mm/s) are written for waypoint k, the end of motion ``result.motion[k]``; returns the
    program with its fields written and the setting written per waypoint.
    """
    edits, settings = [], {}
    for k in sorted({**plan.times, **plan.cruise}):
        motion = program.motions[result.motion[k]]
        function = re.search(r"(\w+)\s*\(", motion.text).group(1)  # also after a sign (``+movel(...)``)
        if k in plan.cruise:
            key, value = "v", format_number(floor_places(plan.cruise[k] / 1000.0, 6), 6)
        elif function in ("movej", "movel"):
            key, value = "t", format_number(ceil_places(plan.times[k], 4), 4)
        else:  # movep / movec take no time: their TCP speed was stated
            continue
        if key in motion.spans:
            edits.append((motion.spans[key].start, motion.spans[key].end, value))
        else:
            edits.append((motion.spans["end"].start, motion.spans["end"].start, f", {key}={value}"))
        settings[k] = f"{key}={value}"
    return edit_sources(program, [edits]), settings
