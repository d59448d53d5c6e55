"""Re-timing written into a URScript program: ``t=`` and ``v=`` of its moves (`trajcomp.timing.writeback`)."""

import re

from trajcomp.formats.text import ceil_places, edit_sources, floor_places, format_number


def write_speeds(program, result, robot, plan):
    """A timed movej / movel gets ``t=`` (s); a lowered cruise speed is written ``v=`` (m/s).

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
