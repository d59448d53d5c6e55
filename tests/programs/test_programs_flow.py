"""`trajcomp.programs.flow` on hand-made steps: the motions that can run before each, the settings reaching it,
checked against the paths written out by hand."""

import numpy as np

from trajcomp.programs.flow import START, Step, Unknown, follow, needed, start_reasons
from trajcomp.programs.tables import MotionTable


def table(lines):
    """Motions on ``lines`` (one each)."""
    n = len(lines)
    return MotionTable.block("linear", np.arange(n), np.array(lines), [""] * n, speed=np.full(n, 100.0),
                             speed_unit="mm/s", zone=np.full(n, 5.0))


def before(reached, motions):
    """The motions (or why) that can run before each motion, as sets."""
    out = [set()] * len(motions.line)
    for r, first in enumerate(reached.first.tolist()):
        rows = reached.rows(r)
        out = out[:first] + [set(reached.before[r])] + [{m - 1} for m in range(first + 1, rows.stop)] + out[rows.stop:]
    return out


def test_branches_loops_jumps_exits_and_calls():
    steps = [Step("routine", "main", line=1), Step("set", "v", 1.0, line=2),
             Step("if", line=4), Step("set", "v", 2.0, line=5), Step("elif", line=7), Step("else", line=9),
             Step("endif", line=11),  # motion 0 on 3, 1 on 6, 2 on 8, 3 on 10
             Step("loop", line=13), Step("if", line=15), Step("exit", line=15), Step("endif", line=15),
             Step("endloop", line=17),  # motion 4 on 12, 5 on 14, 6 on 16
             Step("label", "again", line=18), Step("wait", line=20), Step("jump", "again", True, line=22),  # 7, 8
             Step("call", "sub", line=23), Step("call", "elsewhere", "another file's", line=25),  # 9 on 24, 10 on 26
             Step("end", line=27), Step("routine", "sub", line=28), Step("set", "v", 0.5, line=29),
             Step("end", line=31)]  # 11 on 30
    motions = table([3, 6, 8, 10, 12, 14, 16, 19, 21, 24, 26, 30])
    assert needed(steps) and not needed([Step("routine", "main"), Step("call", "BAS"), Step("end")])
    reached = follow(steps, motions, {"v": 0.0})
    got = before(reached, motions)
    assert got[0] == {START} and got[1] == {0} and got[2] == {0} and got[3] == {0}  # each branch from before the IF
    assert got[4] == {1, 2, 3}  # after the branches' ends
    assert got[5] == {4, 6} and got[6] == {5}  # the loop's top: from before it and from its end
    assert got[7] == {4, 5, 6, 8}  # the label: after the loop (none, exit, end) and the jump back
    assert got[11] == {8} and got[9] == {11}  # into sub from its call, back after it
    assert any("elsewhere" in b for b in got[10] if isinstance(b, str))  # after another file's routine: unknown
    assert reached.waits[7] and not reached.waits[8]  # the wait after motion 7 (in front of the jump)
    settings = [reached.settings[r]["v"] for r in range(len(reached.first))]
    values = {int(m): settings[np.searchsorted(reached.first, m, side="right") - 1] for m in range(12)}
    assert values[1] == {2.0} and values[2] == {1.0} and values[4] == {1.0, 2.0}
    assert values[11] == values[9] == {0.5}  # set in sub, in force after the call
    assert isinstance(next(iter(values[10])), Unknown)
    reasons = start_reasons(reached, motions)
    assert reasons[0] == "" and reasons[1] == "" and "line 3" in reasons[2]  # 2 starts at motion 0, not at 1
    assert "line 6, line 8, line 10" in reasons[4]


def test_a_call_of_a_routine_not_read_makes_the_start_and_settings_unknown():
    steps = [Step("routine", "main", line=1), Step("set", "v", 1.0, line=2),
             Step("call", "other", "a routine of other.src", line=4), Step("end", line=6)]
    motions = table([3, 5])
    reached = follow(steps, motions, {"v": 0.0})
    (unknown,) = reached.settings[1]["v"]
    assert isinstance(unknown, Unknown) and "other.src" in unknown.why
    assert "after a call to other (line 4)" in start_reasons(reached, motions)[1]
