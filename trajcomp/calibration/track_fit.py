"""A linear track's direction and scale, identified from measurements at several carriage positions.

The arm is calibrated in its base frame (a grid at one carriage
position: `trajcomp.calibration.calibrate`). Measured again in the world
at several track positions ``e``, the arm's TCP lands where the
calibrated arm model places it, moved by the carriage:

    measured = T_world_base(0) @ predicted + scale * e * direction + offset

``offset`` takes up what is common to every position (the arm model's
registration at the carriage's zero). A least-squares line through the
residuals ``measured - T_world_base(0) @ predicted`` against ``e`` gives
``scale * direction`` (its slope) and ``offset``; what is left is the
track's straightness and the noise (`TrackFit.residual_rms`). With
`STRAIGHTNESS_POSITIONS` positions or more, each measured by at least two
rows, the mean left at each position is the track's straightness there
(`trajcomp.arm.track.Track.straightness`, a table of world mm the carriage
is placed with, linear between the positions), kept when it stands out of
the noise: its RMS above `SIGNIFICANCE` times that of its own standard
errors. The fit names the track positions it measured: a target beyond
them is a forecast outside the measured travel
(`trajcomp.arm.track.Track.beyond_measured`).

A measurement file states the track position of each row in its
``track`` column (`with_identified_track`): the rows at track position 0
calibrate the arm, every row identifies the track.
"""

import dataclasses

import numpy as np

from trajcomp.errors import CalibrationError

MIN_POSITIONS = 3  # distinct carriage positions: a line through two leaves nothing to check it with
STRAIGHTNESS_POSITIONS = 5  # distinct positions (two rows each at least) before the straightness is a table
SIGNIFICANCE = 3.0  # the table's RMS over its standard errors' RMS above which the track is not straight


@dataclasses.dataclass(frozen=True, eq=False)
class TrackFit:
    """The identified track and what the fit found.

    Attributes
    ----------
    track : Track
        The nominal track (the controller's) with the identified ``actual_direction`` and ``actual_scale``.
    offset : ndarray, shape (3,)
        World translation common to every position, mm.
    positions : ndarray, shape (P,)
        The distinct track positions measured, mm, ascending.
    residual_rms : float
        RMS of the measured positions about the fitted line, mm (straightness and noise).
    straightness_rms : float or None
        RMS of the straightness table (``track.straightness``), mm, whether kept or not; None when the
        positions are too few to tell.
    noise_rms : float or None
        RMS of the table's standard errors, mm (the measurement noise averaged at each position).
    direction_change_deg : float
        Angle between the nominal and the identified direction, deg.
    scale_change : float
        Identified scale over the nominal one, minus 1.
    """

    track: object
    offset: np.ndarray
    positions: np.ndarray
    residual_rms: float
    direction_change_deg: float
    scale_change: float
    straightness_rms: float = None
    noise_rms: float = None

    def summary(self):
        """The fit as plain data for the model's report (mm, deg)."""
        return {"direction": self.track.actual_direction.tolist(), "scale": self.track.actual_scale,
                "direction_change_deg": self.direction_change_deg, "scale_change": self.scale_change,
                "offset_mm": self.offset.tolist(), "residual_rms_mm": self.residual_rms,
                "positions_mm": self.positions.tolist(), "straightness_rms_mm": self.straightness_rms,
                "straightness_noise_rms_mm": self.noise_rms,
                "straightness_mm": None if self.track.straightness is None else self.track.straightness.tolist()}


def identify_track(track, T_world_base, positions, predicted, measured):
    """Identify a track's direction and scale from TCP measurements at several carriage positions.

    Parameters
    ----------
    track : Track
        The nominal track (its limits and fields are kept).
    T_world_base : ndarray, shape (4, 4)
        The arm base in the world at track position 0 (the robot's ``T_world_base``).
    positions : ndarray, shape (N,)
        Track position of each measurement, mm.
    predicted : ndarray, shape (N, 3)
        Where the calibrated arm model places the TCP of each measurement's commanded joints, in its base, mm.
    measured : ndarray, shape (N, 3)
        The measured TCP positions in the world, mm.

    Returns
    -------
    TrackFit

    Raises
    ------
    CalibrationError
        Fewer than `MIN_POSITIONS` distinct track positions, or shapes that do not agree.
    """
    positions = np.asarray(positions, dtype=float).reshape(-1)
    predicted, measured = np.asarray(predicted, dtype=float), np.asarray(measured, dtype=float)
    if predicted.shape != (len(positions), 3) or measured.shape != (len(positions), 3):
        raise CalibrationError(f"track: {len(positions)} positions need predicted and measured (N, 3) positions, "
                               f"got {predicted.shape} and {measured.shape}")
    distinct = np.unique(positions)
    if len(distinct) < MIN_POSITIONS:
        raise CalibrationError(f"track: measurements at {len(distinct)} carriage position(s) "
                               f"({', '.join(f'{v:g}' for v in distinct)} mm); at least {MIN_POSITIONS} distinct ones, "
                               "spread over the travel, identify its direction and scale")
    residual = measured - (predicted @ T_world_base[:3, :3].T + T_world_base[:3, 3])
    design = np.c_[positions, np.ones(len(positions))]
    (slope, offset), *_ = np.linalg.lstsq(design, residual, rcond=None)
    scale = float(np.linalg.norm(slope))
    direction = slope / scale
    left = residual - design @ np.array([slope, offset])
    turn = np.degrees(np.arccos(np.clip(direction @ track.direction, -1.0, 1.0)))
    table, table_rms, noise_rms = _straightness(positions, distinct, left)
    scatter = _scatter(np.searchsorted(distinct, positions), left)
    if table is not None:  # the carriage's displacement beyond the line through track position 0, where the arm's
        table = table + offset  # calibration placed it (there the rows' mean residual is about 0)
    identified = track.replace(actual_direction=direction, actual_scale=scale, measured_positions=distinct,
                               straightness=table, scatter=scatter)
    return TrackFit(identified, offset, distinct, float(np.sqrt(np.mean(np.sum(left ** 2, axis=1)))), float(turn),
                    scale / track.scale - 1.0, table_rms, noise_rms)


def _straightness(positions, distinct, left):
    """The straightness table (P, 3) or None, its RMS and its standard errors' RMS (mm; None: too few positions).

    ``left`` (N, 3): each row's residual about the fitted line at its position ``positions`` (N,).
    """
    which = np.searchsorted(distinct, positions)
    counts = np.bincount(which, minlength=len(distinct))
    if len(distinct) < STRAIGHTNESS_POSITIONS or counts.min() < 2:
        return None, None, None
    mean = _position_means(which, left)
    spread = left - mean[which]
    variance = np.sum(spread**2) / max(len(positions) - len(distinct), 1) / 3.0  # per axis, about each position's mean
    table_rms = float(np.sqrt(np.mean(np.sum(mean**2, axis=1))))
    noise_rms = float(np.sqrt(3.0 * variance * np.mean(1.0 / counts)))
    return (mean if table_rms > SIGNIFICANCE * noise_rms else None), table_rms, noise_rms


def arm_rows(meas, robot):
    """The rows of a measurement file that calibrate the arm: all, or those at track position 0 on a track.

    Raises
    ------
    CalibrationError
        A ``track`` column for a robot that describes no track, or no row at track position 0.
    """
    if meas.track is None:
        return np.ones(len(meas), dtype=bool)
    if robot.track is None:
        raise CalibrationError(f"{meas.path}: a track column, but robot {robot.name} describes no track (track: in its "
                               "YAML, docs/tracks.md)")
    rows = meas.track == 0
    if not rows.any():
        raise CalibrationError(f"{meas.path}: no row at track position 0: the arm is calibrated in its base frame at "
                               "track position 0 (measure its grid there), the other positions identify the track")
    return rows


def with_identified_track(model, meas):
    """The model with its robot's track identified from every row of ``meas`` (`identify_track`), and the fit.

    The measured positions are taken to the arm's base frame at track
    position 0 with the model's registration (a tracker frame), then to
    the world; the model predicts each row's commanded joints (its own
    method's arm and residual).
    """
    from trajcomp.arm.kinematics import fk
    from trajcomp.calibration.calibrate import to_base

    robot = model.nominal
    joints = meas.joints
    if joints is None:
        raise CalibrationError(f"{meas.path}: the track fit needs each row's commanded joints j1..j6")
    position = fk(robot, joints)[:, :3, 3] if meas.position is None else meas.position
    predicted, _ = model.predict(model.method, joints, position)
    base = to_base(model.T_tracker_base, meas.measured)
    measured = base @ robot.T_world_base[:3, :3].T + robot.T_world_base[:3, 3]
    fit = identify_track(robot.track, robot.T_world_base, meas.track, predicted, measured)
    report = {**model.report, "track": fit.summary()}
    return dataclasses.replace(model, nominal=robot.replace(track=fit.track), report=report), fit


def _position_means(which, left):
    """The mean (P, 3) of the rows ``left`` (N, 3) at each measured position (``which`` (N,): its index)."""
    counts = np.bincount(which)
    return np.stack([np.bincount(which, weights=column, minlength=len(counts)) for column in left.T],
                    axis=1) / counts[:, None]


def _scatter(which, left):
    """Per axis standard deviation (mm) of a position's mean offset from the fitted line: the larger of the means'
    own scatter (P - 2 degrees of freedom: the line took two) and the rows' noise averaged over a position's rows."""
    means, counts = _position_means(which, left), np.bincount(which)
    between = np.sum(means**2) / (3.0 * max(len(counts) - 2, 1))
    spread = left - means[which]
    within = np.sum(spread**2) / (3.0 * max(len(which) - len(counts), 1)) * np.mean(1.0 / counts)
    return float(np.sqrt(max(between, within)))
