"""What re-timing produced: time stamps, segments with their speed settings, and the dense check."""

import dataclasses
from collections.abc import Mapping

import numpy as np

from trajcomp.formats.text_sequence import Texts
from trajcomp.timing.check import LIMIT_TOLERANCE, RATE, evaluate, sample_times

@dataclasses.dataclass(frozen=True)
class Segment:
    """A stretch of waypoints timed together, at rest at both ends.

    Attributes
    ----------
    kind : {"toppra", "ruckig"}
        How it was timed.
    first, last : int
        Waypoint indices; the segment's motions are first + 1 .. last.
    duration : float
        s.
    settings : tuple of str or Texts
        The speed setting written for each of its motions, as the program
        text (``"v20\\T:=4.213"``, ``"t=4.2130"``, ``"4213msec"``,
        ``"$VEL.CP=0.018991"``, ``"t=4.213000"``); empty until the timing is
        written into a program (`trajcomp.timing.apply_timing`), ``""`` for
        a motion left as written. A CSV program's are `Texts` (made on
        demand, compared equal to the tuple of the same texts).
    jerk_limited : bool
        The joint jerk is bounded by the robot's jerk limits (a ruckig
        segment of an arm with a jerk limit on every joint); False: not
        bounded (a TOPP-RA law steps its path acceleration at every grid
        point; ruckig without a jerk limit steps its acceleration).
    """

    kind: str
    first: int
    last: int
    duration: float
    settings: tuple = ()
    jerk_limited: bool = False

    @property
    def written(self):
        """The number of motions a setting was written for."""
        return len(self.settings) if isinstance(self.settings, Texts) else sum(1 for s in self.settings if s)

    @property
    def speed(self):
        """The speed or time settings written, as one line (``"-"`` when none were)."""
        if isinstance(self.settings, Texts):  # none empty: no text made but the first and the last
            first = last = self.settings[0] if len(self.settings) else None
            if len(self.settings) > 1:
                last = self.settings[-1]
            count = len(self.settings)
        else:
            written = [s for s in self.settings if s]
            first, last, count = (written[0], written[-1], len(written)) if written else (None, None, 0)
        if not count:
            return "-"
        return first if count == 1 else f"{first} .. {last} ({count} motions)"


@dataclasses.dataclass(frozen=True, eq=False)
class TimingResult:
    """A re-timed motion sequence of M waypoints.

    Attributes
    ----------
    t : ndarray, shape (M,)
        Time stamp of each waypoint, s (0 at the first).
    cycle_time : float
        s, the time from the first to the last waypoint (untimed motions count 0).
    segments : tuple of Segment
    peak_velocity, peak_acceleration : ndarray, shape (6,)
        Largest sampled |joint velocity| (rad/s) and |acceleration| (rad/s^2).
    peak_jerk : ndarray, shape (6,)
        Largest sampled |joint jerk| (finite differences of the 1 kHz
        acceleration) in the jerk-limited segments, rad/s^3; NaN when no
        segment is jerk-limited (see `Segment.jerk_limited`: the jerk of
        the other segments is neither bounded nor measured).
    limit_velocity, limit_acceleration, limit_jerk : ndarray, shape (6,)
        The robot's limits, same units (jerk ``inf`` where unknown).
    within_limits : bool
        No 1 kHz sample exceeds its motion's velocity or acceleration limit
        (or programmed TCP speed), nor a jerk-limited segment the jerk
        limit, by more than 1 %.
    peak_speed_ratio : float
        Largest sampled TCP speed |J(q) q'| over the programmed TCP speed
        (linear and circular motions; 0 when none has one).
    q : ndarray, shape (M, 6)
        Joints of each waypoint, rad.
    tcp_length : ndarray, shape (M,)
        TCP path length of the motion into each waypoint, mm (0 for untimed).
    programmed_length : ndarray, shape (M,)
        TCP length of the motion into each waypoint as programmed, corner
        to corner (`trajcomp.timing.moves.corner_lengths`), where a
        blended corner at either end makes the timed path shorter; else
        ``tcp_length``. A controller paces a time given to a blended
        motion over this length (`trajcomp.timing.writeback`).
    labels : tuple of str, length M
        Waypoint names with file and line.
    motion : ndarray of int, shape (M,)
        Index into `Program.motions` of the motion into each waypoint.
    untimed : tuple of int
        Waypoints whose motion was not timed: it starts from a position the
        program does not state (the first motion, one after a position
        computed at run time). They belong to no segment.
    deviation : float
        Largest deviation of the timed joint path from a waypoint or path
        sample outside blended corners, mm (linearized).
    warnings : tuple of str
        What the timing assumed that differs from the program's declaration
        (a joint turn a linear motion cannot honour).
    as_written : tuple of (int, str)
        Waypoints whose motion's speed the program sets at run time (a
        variable, a register), timed at the arm's limits, or whose start is
        not unique (not timed), and why: their fields are left as written
        (set by `trajcomp.timing.apply_timing`).
    lowered : tuple of (int, str)
        Waypoints whose stated speed a joint limit forced lower (or whose
        time it forced longer), with what was written and why.
    not_modelled : tuple of (int, str)
        Timed waypoints that would get a time their controller would not run
        as timed (a RAPID AccSet ramp below 100 %), and why: their fields
        left as written (set by `trajcomp.timing.apply_timing`).
    track : TrackTiming or None
        On a track that moves: its positions, peaks and limits, the world
        TCP's share of each motion (`trajcomp.timing.track`); None otherwise.
    """

    t: np.ndarray
    cycle_time: float
    segments: tuple
    peak_velocity: np.ndarray
    peak_acceleration: np.ndarray
    peak_jerk: np.ndarray
    limit_velocity: np.ndarray
    limit_acceleration: np.ndarray
    limit_jerk: np.ndarray
    within_limits: bool
    peak_speed_ratio: float
    q: np.ndarray
    tcp_length: np.ndarray
    programmed_length: np.ndarray
    labels: tuple
    motion: np.ndarray
    untimed: tuple
    deviation: float
    warnings: tuple = ()
    pieces: tuple = dataclasses.field(default=(), repr=False)
    as_written: tuple = ()
    lowered: tuple = ()
    track: object = None
    not_modelled: tuple = ()

    @property
    def notices(self):
        """What the user must know of this timing (tuple of str): the motions left untimed, then `warnings`."""
        on_track = {k for k, _ in self.track.left} if self.track is not None else set()  # said with the track
        untimed = [k for k in self.untimed if k not in on_track]
        if not untimed:
            return tuple(self.warnings)
        names = ", ".join(self.labels[k] for k in untimed[:5])
        more = f" and {len(untimed) - 5} more" if len(untimed) > 5 else ""
        return (f"not timed (the arm's position before the motion is unknown): motions to {names}{more}",
                *self.warnings)

    @property
    def jerk_measured(self):
        """Mask (6,) of the joints whose `peak_jerk` was measured: in jerk-limited segments (not NaN)."""
        return ~np.isnan(self.peak_jerk)

    @property
    def durations(self):
        """Duration of the motion into each waypoint (M,), s (0 for the first and untimed ones)."""
        return np.diff(self.t, prepend=self.t[:1])

    def sample(self, rate=RATE):
        """The timed trajectory sampled every 1/rate s within each segment.

        Returns
        -------
        t : ndarray, shape (N,)
            s, non-decreasing (segment ends appear twice: end of one, start of the next).
        q, qd, qdd : ndarray, shape (N, 6)
            rad, rad/s, rad/s^2.
        """
        parts = []
        for start, run, law in self.pieces:
            local = sample_times(law.duration, rate)
            q, qd, qdd, _, _ = evaluate(run, law, local)
            parts.append((start + local, q, qd, qdd))
        if not parts:
            return np.zeros(0), np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 6))
        return tuple(np.concatenate(column) for column in zip(*parts))

    def at(self, t):
        """Joints, velocities and accelerations (each (N, 6)) at times t (N,), s.

        Between segments (zero-length or untimed motions) the arm rests at
        the last waypoint reached.
        """
        t = np.asarray(t, dtype=float)
        q = np.tile(self.q[0], (len(t), 1))
        qd, qdd = np.zeros((len(t), 6)), np.zeros((len(t), 6))
        for start, run, law in self.pieces:
            after = t >= start
            q[after] = run.path(np.array([run.length]))[0]
            qd[after] = qdd[after] = 0.0
            inside = after & (t <= start + law.duration)
            if inside.any():
                q[inside], qd[inside], qdd[inside], _, _ = evaluate(run, law, t[inside] - start)
        return q, qd, qdd

    @property
    def jerk_limited_segments(self):
        """The number of segments whose joint jerk is bounded (`Segment.jerk_limited`)."""
        return sum(1 for s in self.segments if s.jerk_limited)

    def jerk_statement(self):
        """What the timing says of the jerk: in how many segments it is bounded, in how many not."""
        limited, total = self.jerk_limited_segments, len(self.segments)
        if limited == total:
            return f"jerk: within the robot's jerk limits in all {total} segments" if total else "jerk: no segment"
        unbounded = (f"not bounded in {total - limited} of {total} segments (TOPP-RA steps the path "
                     "acceleration at its grid points; without a jerk limit ruckig steps the acceleration)")
        return f"jerk: {unbounded}" if not limited else f"jerk: within the limits in {limited} segments, {unbounded}"

    @property
    def unknown_starts(self):
        """``((k, why), ...)`` of `as_written`: the motions not timed because their start is not unique."""
        untimed = set(self.untimed)
        return tuple((k, why) for k, why in self.as_written if k in untimed)

    @property
    def run_time_speeds(self):
        """``((k, why), ...)`` of `as_written`: the timed motions whose speed the program sets at run time."""
        untimed = set(self.untimed)
        return tuple((k, why) for k, why in self.as_written if k not in untimed)

    def with_settings(self, settings, as_written=(), lowered=(), not_modelled=()):
        """A copy whose segments carry the written settings.

        Parameters
        ----------
        settings : Mapping[int, str] or Sequence[str] or Texts
            ``{waypoint index: text}`` for the waypoints that got one, or a
            text for every waypoint (M,) (a long CSV program: its segments
            share the texts instead of a dict of them); `Texts` of every
            waypoint are sliced, their texts still made on demand.
        as_written, lowered, not_modelled : tuple of (int, str)
            The motions left as written and those lowered (the attributes).
        """
        if isinstance(settings, Mapping):
            def texts(s):
                return tuple(settings.get(k, "") for k in range(s.first + 1, s.last + 1))
        elif isinstance(settings, Texts):
            def texts(s):
                return settings[s.first + 1 : s.last + 1]
        else:
            def texts(s):
                return tuple(settings[s.first + 1 : s.last + 1])
        return dataclasses.replace(self, segments=tuple(dataclasses.replace(s, settings=texts(s))
                                                        for s in self.segments),
                                   as_written=tuple(as_written), lowered=tuple(lowered),
                                   not_modelled=tuple(not_modelled))

    def lines_of_text(self, before=None):
        """Summary lines: per joint peaks against limits, cycle time (and before, s)."""
        out = [f"{'joint':<6}{'|v| deg/s':>11}{'limit':>8}{'|a| deg/s^2':>13}{'limit':>8}"
               f"{'|j| deg/s^3':>13}{'limit':>9}"]
        deg = np.degrees
        for j in range(6):
            jerk = f"{deg(self.peak_jerk[j]):.0f}" if self.jerk_measured[j] else "-"
            jerk_limit = "-" if np.isinf(self.limit_jerk[j]) else f"{deg(self.limit_jerk[j]):.0f}"
            out.append(
                f"J{j + 1:<5}{deg(self.peak_velocity[j]):>11.1f}{deg(self.limit_velocity[j]):>8.0f}"
                f"{deg(self.peak_acceleration[j]):>13.1f}{deg(self.limit_acceleration[j]):>8.0f}"
                f"{jerk:>13}{jerk_limit:>9}"
            )
        if self.track is not None:
            out += self.track.lines(self.labels)
        verdict = "within" if self.within_limits else f"ABOVE (by more than {100 * LIMIT_TOLERANCE:.0f} %)"
        out.append(f"dense check at {RATE:.0f} Hz: {verdict} the limits; peak TCP speed "
                   f"{100 * self.peak_speed_ratio:.1f} % of the programmed speed")
        out.append(self.jerk_statement())
        cycle = f"cycle time {self.cycle_time:.3f} s"
        if before is not None:
            change = 100.0 * (self.cycle_time - before) / before if before > 0 else 0.0
            cycle = f"cycle time before compensation {before:.3f} s, after {self.cycle_time:.3f} s ({change:+.2f} %)"
        if self.lowered:  # the cycle is the timing's; these motions run longer than it
            cycle += f" as timed; {len(self.lowered)} motion(s) written slower than timed (a limit binds, below)"
        out.append(cycle)
        for listed, what in ((self.run_time_speeds, "not re-timed, speed set at run time (left as written)"),
                             (self.not_modelled, "no time written, the controller would not run it as timed (left "
                                                 "as written, no faster than programmed)"),
                             (self.unknown_starts, "not timed, start not unique (left as written, no faster than "
                                                   "programmed; its timing and limits not checked)")):
            if listed:
                names = ", ".join(self.labels[k] for k, _ in listed[:5])
                more = f" and {len(listed) - 5} more" if len(listed) > 5 else ""
                out.append(f"{what}: {len(listed)} motion(s): {names}{more}; first: {listed[0][1]}")
        out += [f"slower than timed, a limit binds: {text}" for _, text in self.lowered[:5]]
        if len(self.lowered) > 5:
            out.append(f"slower than timed, a limit binds: {len(self.lowered) - 5} more motion(s) (see the report)")
        out += [f"warning: {w}" for w in self.notices]
        return out
