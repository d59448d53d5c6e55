"""Re-timing: the corrected program's motions timed under the arm's joint limits and the programmed speeds.

Compensation moves every waypoint, so the joint path changes; this stage
computes when the arm can pass each waypoint without exceeding the joint
velocity, acceleration (and, for point-to-point motions, jerk) limits and
without running faster than the program asked, and writes that timing back
into the program's speed fields.

- `trajcomp.timing.moves`: the motion sequence (`Moves`, from a program or joints);
- `trajcomp.timing.samples`: the controller's interpolation of a run, solved in joints;
- `trajcomp.timing.path`: the joint path of a run, fitted within tolerance;
- `trajcomp.timing.toppra_run`: TOPP-RA along a run (`trajcomp.timing.reachability`, constant acceleration);
- `trajcomp.timing.ruckig_move`: jerk-limited rest-to-rest motion with ruckig;
- `trajcomp.timing.check`: the dense 1 kHz check;
- `trajcomp.timing.retiming`: segments and the `TimingResult`;
- `trajcomp.timing.track`: a moving track as a joint of the timed path;
- `trajcomp.timing.writeback`: the timing as each language's speed fields;
- `trajcomp.timing.options`: the methods and the path tolerance, without numpy (for the command line).

The names below are imported from their module on first use, so that a
command's ``--help`` can read `trajcomp.timing.options` without loading the
timing (numpy, scipy, ruckig).
"""

from trajcomp.support.lazy import lazy_names

_MODULES = {
    "RETIME_METHODS": "options",
    "Moves": "moves",
    "Segment": "result",
    "TimingResult": "result",
    "moves_from_program": "moves",
    "plan_segments": "retiming",
    "retime": "retiming",
}
__all__ = sorted(_MODULES)

__getattr__ = lazy_names(__name__, _MODULES)

