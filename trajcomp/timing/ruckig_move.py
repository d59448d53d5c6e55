"""Jerk-limited rest-to-rest motion with ruckig, along a segment's path.

ruckig (Berscheid & Kroeger 2021) computes the time-optimal jerk-limited
trajectory from one state to another. It is given one degree of freedom,
the path position s, from rest at 0 to rest at the segment's length, and
never intermediate waypoints (the free build would send those to a network
service; a controller program must not depend on one).

For a joint motion the path is the straight line in joint space, so the
bounds below are exact: every joint moves in phase and the leading joint
reaches its velocity, acceleration and jerk limit (a synchronized PTP).
For a curved run (``--retime ruckig``) they are the worst case over the
path: the curvature terms may take half of each joint's acceleration
(q'' sd^2) and then half of its jerk (q''' sd^3 + 3 q'' sd sdd), the path
acceleration and jerk get the rest, so the result is slower than
TOPP-RA's.
"""

import dataclasses

import numpy as np
import ruckig

from trajcomp.errors import TimingError


@dataclasses.dataclass(frozen=True, eq=False)
class RuckigLaw:
    """A time law s(t) from ruckig: rest at s = 0 to rest at s = length.

    Attributes
    ----------
    trajectory : ruckig.Trajectory
        One degree of freedom.
    length : float
        Path length, rad.
    """

    trajectory: object
    length: float

    @property
    def duration(self):
        return float(self.trajectory.duration)

    def __call__(self, t):
        """s, sd, sdd (each (N,)) at times t (N,)."""
        state = np.array([self.trajectory.at_time(float(time)) for time in t]).reshape(len(t), 3)
        return state[:, 0], state[:, 1], state[:, 2]

    def time_at(self, s):
        """Times (N,) at which the law first reaches path positions s (N,)."""
        out = []
        for position in np.minimum(s, self.length):
            found = self.trajectory.get_first_time_at_position(0, float(position))
            out.append(self.duration if found is None else found)
        return np.array(out)


def ruckig_law(run, moves, robot, velocity_scale=1.0, acceleration_scale=1.0, speed_scale=1.0):
    """The rest-to-rest jerk-limited law along a run's path.

    Parameters
    ----------
    run : RunPath
        With a path (non-zero length).
    moves : Moves
        Limits of each motion (joint velocity, acceleration, TCP speed, time).
    robot : Robot
        Jerk limits (``inf``: acceleration-limited) and the TCP Jacobian.
    velocity_scale, acceleration_scale, speed_scale : float or ndarray (6,)
        Factors on the limits (lowered where the dense check finds an overshoot).

    Returns
    -------
    RuckigLaw

    Raises
    ------
    TimingError
        ruckig rejects the input (a limit that cannot be met), naming the
        motion and its line.
    """
    dq, ddq = np.abs(run.path(run.grid, 1)), np.abs(run.path(run.grid, 2))
    dddq = np.abs(run.path.spline(run.grid, 3))
    x_max, _ = run.speed_bound(moves, velocity_scale, speed_scale, times=False)
    motions = slice(run.first + 1, run.last + 1)
    acceleration = np.min(moves.acceleration[motions], axis=0) * acceleration_scale
    jerk = robot.j_max
    with np.errstate(divide="ignore", invalid="ignore"):
        # the path's curvature may take half of each joint's acceleration, then half of its jerk
        speed = np.sqrt(min(np.min(x_max), np.nanmin(0.5 * acceleration / ddq)))
        path_acceleration = np.min((acceleration - ddq * speed**2) / dq)
        curved = dddq * speed**3 + 3.0 * ddq * speed * path_acceleration  # jerk of the curvature terms
        shrink = min(1.0, float(np.nanmin(0.5 * jerk / curved)) ** (1.0 / 3.0))
        speed, path_acceleration = speed * shrink, path_acceleration * shrink**2
        path_jerk = np.min((jerk - curved * shrink**3) / dq)
    otg = ruckig.Ruckig(1)
    query = ruckig.InputParameter(1)
    query.current_position, query.target_position = [0.0], [run.length]
    query.max_velocity, query.max_acceleration = [float(speed)], [float(path_acceleration)]
    query.max_jerk = [float(path_jerk)]
    query.minimum_duration = float(np.sum(moves.min_duration[motions])) or None
    trajectory = ruckig.Trajectory(1)
    label = f"{moves.kind[run.last]} motion to {moves.labels[run.last]}"
    if not (speed > 0 and path_acceleration > 0):
        raise TimingError(f"{label}: no positive speed obeys the joint limits along it")
    try:
        result = otg.calculate(query, trajectory)
    except ruckig.RuckigError as exc:
        raise TimingError(f"{label}: ruckig cannot time it: {str(exc).strip().splitlines()[0]}") from None
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise TimingError(f"{label}: ruckig cannot time it ({result})")
    return RuckigLaw(trajectory, run.length)
