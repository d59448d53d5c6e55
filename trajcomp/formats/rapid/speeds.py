"""Re-timing written into a RAPID module: ``\\T`` and ``\\V`` after a motion's speed data (`trajcomp.timing.writeback`)."""

from trajcomp.formats.text import ceil_places, edit_sources, floor_places, format_number


def write_speeds(program, result, robot, plan):
    """A timed motion's speed data get ``\\T:=`` (a time, s) or ``\\V:=`` (a lowered cruise TCP speed, mm/s).

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
        span = program.motions[result.motion[k]].spans["speed"]
        speed_data = span.text.split("\\")[0].rstrip()  # v20 of v20\V:=15 or v20\T:=4
        if k in plan.cruise:
            written = f"{speed_data}\\V:={format_number(floor_places(plan.cruise[k], 3), 3)}"
        else:
            written = f"{speed_data}\\T:={format_number(ceil_places(plan.times[k], 3), 3)}"
        edits.append((span.start, span.end, written))
        settings[k] = written
    return edit_sources(program, [edits]), settings
