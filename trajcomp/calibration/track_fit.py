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
track's straightness and the noise (`TrackFit.residual_rms`). The fit
names the track positions it measured: a target beyond them is a
forecast outside the measured travel (`trajcomp.arm.track.Track.beyond_measured`).

A measurement file states the track position of each row in its
``track`` column (`with_identified_track`): the rows at track position 0
calibrate the arm, every row identifies the track.
"""

import dataclasses

import numpy as np

from trajcomp.errors import CalibrationError

MIN_POSITIONS = 3  # distinct carriage positions: a line through two leaves nothing to check it with


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

    def summary(self):
        """The fit as plain data for the model's report (mm, deg)."""
        return {"direction": self.track.actual_direction.tolist(), "scale": self.track.actual_scale,
                "direction_change_deg": self.direction_change_deg, "scale_change": self.scale_change,
                "offset_mm": self.offset.tolist(), "residual_rms_mm": self.residual_rms,
                "positions_mm": self.positions.tolist()}


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
    identified = track.replace(actual_direction=direction, actual_scale=scale, measured_positions=distinct)
    return TrackFit(identified, offset, distinct,
                    float(np.sqrt(np.mean(np.sum(left ** 2, axis=1)))), float(turn), scale / track.scale - 1.0)


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
