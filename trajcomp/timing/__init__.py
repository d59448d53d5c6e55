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
- `trajcomp.timing.retime`: segments and the `TimingResult`;
- `trajcomp.timing.writeback`: the timing as each language's speed fields.
"""

from trajcomp.timing.moves import Moves, moves_from_program
from trajcomp.timing.result import Segment, TimingResult
from trajcomp.timing.retime import METHODS, plan_segments, retime

__all__ = ["METHODS", "Moves", "Segment", "TimingResult", "moves_from_program", "plan_segments", "retime"]
