"""Re-timing written into a program CSV: its ``t`` column (`trajcomp.timing.writeback`)."""

import numpy as np

from trajcomp.formats.csv.writer import time_texts, with_times
from trajcomp.formats.text_sequence import Texts


def write_speeds(program, result, robot, plan):
    """The ``t`` column: each row's time stamp (`trajcomp.formats.csv.writer.with_times`); ``plan`` is None.

    The rows are the trajectory (a CSV program has no speed field of the
    controller's), so every row is timed. The settings are ``t=`` and the
    text written, made on demand from the time stamps as the writer makes
    them (no str per waypoint held).
    """
    times = np.full(len(program.motion_table()), np.nan)
    times[result.motion] = result.t
    timed = with_times(program, times)
    t = result.t

    def make(lo, hi):
        return ["t=" + text for text in time_texts(t[lo:hi])]

    return timed, Texts(make, 0, len(t))
