"""A linear track carrying the arm: where its carriage puts the arm's base, and which program field drives it.

A robot on a track (KUKA KL linear units, FANUC rails, ABB IRBT tracks)
moves its whole base along a straight axis. The robot YAML describes it
under ``track`` (user units: mm, mm/s, mm/s^2)::

    track:
      direction: [1, 0, 0]       # the axis in the world frame (normalised)
      origin: [0, 0, 0]          # the base's origin in the world at track position 0 (default: world's)
      limits:
        position_min: -100       # mm
        position_max: 5800
        velocity: 2000           # mm/s
        acceleration: 2500       # mm/s^2
      fields:                    # the program field that holds the track position, per language
        krl: E1
        fanuc_ls: E1             # or GP2:J1, a rail as motion group 2 (group 1 then states no E1..)
        rapid: eax_a
      scale: 1.0                 # optional: world mm per mm of track position (a calibration identifies it)

At track position ``e`` the arm's base, the carriage frame, is
``T_world_base(e) = Trans(scale * e * direction) @ T_world_base(0)``: a pure
translation of the base placed by ``world`` (and ``origin``). That is the
track as the controller knows it; a calibration may identify the real one
(`trajcomp.calibration.track_fit`: ``actual_direction``, ``actual_scale``):
targets are then placed on the real carriage, and each command is
written so that the controller, with its own track, sends the arm to
it (`trajcomp.programs.frames.FrameTable.written_commands`). A target
stated in the world (KUKA E6POS with E1, FANUC /POS with E1, ABB robtarget
with eax_a) is reached by the arm from its base at the target's own track
position: the arm part is solved and compensated in that carriage frame,
and the track position is written back as it stands.
"""

import dataclasses
import re

import numpy as np

from trajcomp.errors import RobotError

# KUKA / FANUC E1..E6, ABB eax_a..eax_f, a FANUC rail as motion group 2: GP2:J1 (its axes follow group 1's E1..)
_FIELD = re.compile(r"^(?:E([1-6])|eax_([a-f])|GP2\s*:\s*J([1-6]))$", re.I)
MAGNITUDE_BOUND = 1e5  # mm, mm/s, mm/s^2: a track longer than 100 m, or faster than 100 m/s, is damage


@dataclasses.dataclass(frozen=True, eq=False)
class Track:
    """A linear track under the arm (lengths mm, speeds mm/s).

    Attributes
    ----------
    direction : ndarray, shape (3,)
        Unit axis in the world frame.
    position_min, position_max : float
        Travel, mm of track position.
    velocity, acceleration : float
        Limits, mm/s and mm/s^2 of track position.
    fields : dict of str to int
        ``{key: index}``: the external axis (`Target.external`) of a
        language's target that holds the track position (E1 -> 0, eax_b -> 1),
        the language named by its key (``krl``: its
        `trajcomp.formats.capabilities.ExternalAxes`, `Program.track_key`).
    written : dict of str to str
        ``{key: field}`` as the YAML names them (for messages).
    scale : float
        World mm moved per mm of track position, as the controller has it (1 nominally).
    actual_direction : ndarray, shape (3,), or None
        The real axis a calibration identified (None: ``direction``).
    actual_scale : float or None
        The real world mm per mm of track position a calibration identified (None: ``scale``).
    measured_positions : ndarray, shape (P,), or None
        The track positions that calibration measured, mm, ascending.
    straightness : ndarray, shape (P, 3), or None
        The real carriage's displacement beyond ``actual_scale * e *
        actual_direction`` at each measured position, world mm
        (`trajcomp.calibration.track_fit`; about 0 at track position 0, where the
        arm was calibrated): linear between them, held at the ends beyond
        them. None: straight within what the calibration could tell.
    scatter : float or None
        Per axis RMS of the measured positions' mean offsets from the fitted
        line, mm (straightness and noise): the scale of `placement_sigma`.
    """

    direction: np.ndarray
    position_min: float
    position_max: float
    velocity: float
    acceleration: float
    fields: dict
    written: dict
    scale: float = 1.0
    actual_direction: np.ndarray = None
    actual_scale: float = None
    measured_positions: np.ndarray = None
    straightness: np.ndarray = None
    scatter: float = None

    def index(self, key):
        """The external axis index that holds the track position in the targets of the language named ``key``
        (`Program.track_key`), or None (None: a language whose targets state none)."""
        return self.fields.get(key)

    @property
    def identified(self):
        """Whether a calibration identified the real track (it may differ from the controller's)."""
        return self.actual_direction is not None

    def shift(self, values, actual=True):
        """World translations (N, 3), mm, of the base at track positions ``values`` (N,) from its place at 0:
        on the real track (``actual``, as identified; the controller's when none is), else the controller's."""
        direction, scale = self.direction, self.scale
        values = np.asarray(values, dtype=float)
        if actual and self.identified:
            direction, scale = self.actual_direction, self.actual_scale
        out = scale * values[:, None] * direction
        if actual and self.straightness is not None:
            out += np.stack([np.interp(values, self.measured_positions, column) for column in self.straightness.T],
                            axis=1)
        return out

    def placements(self, T_world_base, values, actual=True):
        """``T_world_base(e)`` (N, 4, 4) at track positions ``values`` (N,), mm: the carriage frames (`shift`)."""
        out = np.broadcast_to(T_world_base, (len(values), 4, 4)).copy()
        out[:, :3, 3] += self.shift(values, actual)
        return out

    def beyond_measured(self, values):
        """Boolean mask (N,) of track positions ``values`` (N,) outside the travel a calibration measured (none
        without one)."""
        values = np.asarray(values, dtype=float)
        if self.measured_positions is None:
            return np.zeros(len(values), dtype=bool)
        return (values < self.measured_positions[0]) | (values > self.measured_positions[-1])

    def placement_sigma(self, values):
        """Standard deviation (N,) per axis, mm, of where the identified track places the carriage at track
        positions ``values`` (N,) within the travel its calibration measured (zeros without one).

        ``scatter`` times the square root of the fitted line's variance
        factor, 1 / P + (e - mean)^2 / sum (e_i - mean)^2 over the P measured
        positions, plus the square of the gap to the nearest one, 2 d / h for
        a distance d and a mean spacing h (1 midway: the straightness between
        two positions is not measured). Beyond the measured travel the place
        is not estimated (`beyond_measured`).
        """
        values = np.asarray(values, dtype=float)
        if self.measured_positions is None or self.scatter is None:
            return np.zeros(len(values))
        measured = self.measured_positions
        centre = measured.mean()
        line = 1.0 / len(measured) + (values - centre) ** 2 / np.sum((measured - centre) ** 2)
        gap = 2.0 * np.min(np.abs(values[:, None] - measured), axis=1) / (np.ptp(measured) / (len(measured) - 1))
        return self.scatter * np.sqrt(line + np.minimum(gap, 1.0) ** 2)

    def replace(self, **changes):
        """A copy with some attributes changed (an identified direction or scale)."""
        return dataclasses.replace(self, **changes)


MIN_TRAVEL = 500.0  # mm: an axis that moves less (a servo gun's stroke) is no track that places targets out of reach


def carried_by_a_track(positions, values, reach):
    """Whether targets out of an arm's reach move with an external axis as they would on a track under it.

    A track moves the base one world millimetre per millimetre of its
    position along one straight axis: the targets' positions, fitted
    against the axis values, then have a slope of length 1 (within 10 %),
    the axis travels at least `MIN_TRAVEL`, and taking the fitted travel
    off brings the targets out of reach within it. A servo gun, a
    positioner or an arm taught elsewhere does not do that.

    Parameters
    ----------
    positions : ndarray, shape (N, 3)
        The targets' TCP positions from the arm's shoulder (its reach's centre), mm.
    values : ndarray, shape (N,)
        The external axis' value at each target.
    reach : float
        The arm's reach from its shoulder, mm.
    """
    values = np.asarray(values, dtype=float)
    if len(values) < 2 or np.ptp(values) < MIN_TRAVEL:
        return False
    (slope, _), *_ = np.linalg.lstsq(np.c_[values, np.ones(len(values))], positions, rcond=None)
    if not 0.9 < np.linalg.norm(slope) < 1.1:
        return False
    far = np.linalg.norm(positions, axis=1) > reach
    carried = np.linalg.norm(positions - values[:, None] * slope, axis=1) <= reach
    return bool(far.any() and carried[far].all())


def track_from_doc(doc, label):
    """The `Track` of a robot document's ``track`` mapping, or None without one.

    Returns
    -------
    track : Track or None
    origin : ndarray, shape (3,), or None
        The base's origin in the world at track position 0 when given.

    Raises
    ------
    RobotError
        A field missing, of the wrong shape, not finite or inconsistent (file and field named).
    """
    value = doc.get("track")
    if value is None:
        return None, None
    if not isinstance(value, dict):
        raise RobotError(f"{label}: field track: expected a mapping (direction, limits, fields), got {value!r}")

    def vector(field, size=3):
        got = value.get(field)
        if not isinstance(got, (list, tuple)) or len(got) != size or not all(_number(v) for v in got):
            raise RobotError(f"{label}: field track.{field}: expected {size} finite numbers, got {got!r}")
        out = np.array(got, dtype=float)
        if np.abs(out).max() > MAGNITUDE_BOUND:
            raise RobotError(f"{label}: field track.{field}: beyond the {MAGNITUDE_BOUND:g} mm of any track")
        return out

    direction = vector("direction")
    if np.linalg.norm(direction) < 1e-9:
        raise RobotError(f"{label}: field track.direction: the zero vector gives no axis")
    limits = value.get("limits")
    if not isinstance(limits, dict):
        raise RobotError(f"{label}: field track.limits: expected a mapping of position_min, position_max, velocity, "
                         f"acceleration (mm, mm/s, mm/s^2), got {limits!r}")
    numbers = {}
    for field in ("position_min", "position_max", "velocity", "acceleration"):
        got = limits.get(field)
        if not _number(got) or abs(got) > MAGNITUDE_BOUND:
            raise RobotError(f"{label}: field track.limits.{field}: expected a finite number (mm, mm/s, mm/s^2), "
                             f"got {got!r}")
        numbers[field] = float(got)
    if numbers["position_min"] >= numbers["position_max"]:
        raise RobotError(f"{label}: field track.limits: position_min {numbers['position_min']:g} mm is not below "
                         f"position_max {numbers['position_max']:g} mm")
    for field in ("velocity", "acceleration"):
        if numbers[field] <= 0:
            raise RobotError(f"{label}: field track.limits.{field}: expected a positive number, got {numbers[field]:g}")
    fields = value.get("fields")
    if not isinstance(fields, dict) or not fields:
        raise RobotError(f"{label}: field track.fields: expected the program field of each language that holds the "
                         f"track position (krl: E1, fanuc_ls: E1, rapid: eax_a), got {fields!r}")
    index = {}
    for language, field in fields.items():
        m = _FIELD.match(str(field))
        if m is None:
            raise RobotError(f"{label}: field track.fields.{language}: expected E1..E6, eax_a..eax_f or GP2:J1..J6, "
                             f"got {field!r}")
        index[str(language)] = (int(m.group(1)) - 1 if m.group(1) else int(m.group(3)) - 1 if m.group(3)
                                else ord(m.group(2).lower()) - ord("a"))
    scale = value.get("scale", 1.0)
    if not _number(scale) or not 0.5 < scale < 2.0:
        raise RobotError(f"{label}: field track.scale: expected a number near 1 (world mm per mm of track), "
                         f"got {scale!r}")
    origin = vector("origin") if "origin" in value else None
    track = Track(direction / np.linalg.norm(direction), numbers["position_min"], numbers["position_max"],
                  numbers["velocity"], numbers["acceleration"], index, {str(k): str(v) for k, v in fields.items()},
                  float(scale))
    return track, origin


def _number(value):
    return not isinstance(value, bool) and isinstance(value, (int, float)) and np.isfinite(value)
