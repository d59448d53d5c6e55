"""Refuse implausible input before it becomes a model or a program.

A model drives a physical arm, so data that cannot be what it claims is an
error, with the reason, not a fit: measurements in metres, joints in
radians read as degrees, data of another robot, a duplicated or constant
column, or an identification whose deltas no real arm has. The bounds are
generous: a bought arm misses by 1-3 mm, its DH parameters are off by
tenths of a millimetre and hundredths of a degree. The same checks guard
``validate`` and ``predict`` against data of another arm than the model's.
"""

import numpy as np

from trajcomp.errors import CalibrationError
from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import ANGLE_BOUND, LENGTH_BOUND, TOOL_NAMES, is_angle

NOMINAL_ERROR_BOUND = 50.0  # mm, median |measured - nominal| (an unknown TCP of some cm included)
RESIDUAL_BOUND = 2.0  # mm, median residual after identification
TOOL_BOUND = 60.0  # mm, how far the identified TCP may move from the nominal one
SCALE_BOUND = 3.0  # ratio of measured to commanded spread beyond which units differ
_GROUPS = {"measured": ("mx", "my", "mz"), "position": ("x", "y", "z")}  # joints may repeat: UR j6 = j1 tool down


def check_columns(meas):
    """Refuse a constant measured column, two identical position columns, or measured equal to commanded.

    Raises
    ------
    CalibrationError
        Naming the file and the columns.
    """
    for group, names in _GROUPS.items():
        values = getattr(meas, group)
        if values is None or len(values) < 3:
            continue
        if group == "measured":
            constant = [k for k in range(3) if np.ptp(values[:, k]) == 0.0]
            if constant:
                raise CalibrationError(
                    f"{meas.path}: measured column {names[constant[0]]} is constant ({values[0, constant[0]]:g} in "
                    "every row): a tracker does not measure that; check the column mapping"
                )
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if np.ptp(values[:, i]) > 0 and np.array_equal(values[:, i], values[:, j]):
                    raise CalibrationError(
                        f"{meas.path}: columns {names[i]} and {names[j]} hold the same values in every row: "
                        "a column is duplicated; check the column mapping"
                    )
    if meas.measured is not None and meas.position is not None and np.array_equal(meas.measured, meas.position):
        raise CalibrationError(
            f"{meas.path}: the measured columns mx, my, mz equal the commanded x, y, z in every row: "
            "they are not measurements; check the column mapping"
        )


def check_units(meas, commanded, measured, nominal_error, *, registered=False):
    """Refuse measurements whose scale or error shows wrong units or another robot.

    Parameters
    ----------
    meas : Measurements
    commanded : ndarray, shape (N, 3)
        Commanded TCP positions, mm (base frame).
    measured : ndarray, shape (N, 3)
        Measured positions, mm, in their own frame.
    nominal_error : ndarray, shape (N,)
        ``|measured - commanded|`` after registration, mm.
    registered : bool
        The measured frame was placed by a registration made beforehand (a
        model's, applied to tracker-frame data): the tracker may have moved.

    Raises
    ------
    CalibrationError
        With the reason and a hint.
    """
    spread_commanded = float(np.sqrt(np.sum(np.var(commanded, axis=0))))
    spread_measured = float(np.sqrt(np.sum(np.var(measured, axis=0))))
    ratio = spread_measured / max(spread_commanded, 1e-9)
    scaled = spread_commanded > 1.0 and not 1 / SCALE_BOUND < ratio < SCALE_BOUND
    median = float(np.median(nominal_error))
    if meas.joints is not None and np.max(np.abs(meas.joints)) < np.radians(2 * np.pi + 0.01) and (
        scaled or median > NOMINAL_ERROR_BOUND
    ):
        raise CalibrationError(
            f"{meas.path}: every joint value lies within +-{np.degrees(np.max(np.abs(meas.joints))):.2f} deg and the "
            f"measurements do not fit them (median |measured - nominal| {median:.1f} mm): joints in radians read as "
            "degrees? (a layout file with units: joints: rad)"
        )
    if scaled:
        hint = "measured in metres? (units: measured: m)" if 0.0005 < ratio < 0.002 else "measured in another unit?"
        raise CalibrationError(
            f"{meas.path}: the measured positions spread {spread_measured:.4g} where the commanded ones spread "
            f"{spread_commanded:.4g} mm (ratio {ratio:.3g}): {hint}"
        )
    if median > NOMINAL_ERROR_BOUND:
        raise CalibrationError(
            f"{meas.path}: median |measured - nominal| is {median:.1f} mm, beyond the {NOMINAL_ERROR_BOUND:g} mm "
            "of any plausible arm error: data of another robot or another TCP, or a wrong column mapping?"
            + (" Or a tracker moved since its registration (--register rows measured in the new placement)?"
               if registered else "")
        )


def check_applied(meas, robot, position, nominal_error, *, registered=False):
    """Refuse rows a model of ``robot`` is applied to (validate, predict) with calibrate's checks.

    `check_columns`; commanded joints that put the arm's TCP elsewhere than
    the commanded positions the file also gives (another robot's joints);
    with measured columns, `check_units` against the commanded positions.

    Parameters
    ----------
    meas : Measurements
    robot : Robot
        The model's nominal arm with its TCP.
    position : ndarray, shape (N, 3)
        Commanded TCP positions, mm, base frame (`trajcomp.calibration.calibrate.commanded`).
    nominal_error : ndarray, shape (N,), or None
        ``|measured - commanded|`` in the base frame, mm; None without
        measured columns.
    registered : bool
        As `check_units`.

    Raises
    ------
    CalibrationError
        With the reason and a hint.
    """
    check_columns(meas)
    if meas.joints is not None and meas.position is not None and len(meas):
        median = float(np.median(np.linalg.norm(fk(robot, meas.joints)[:, :3, 3] - meas.position, axis=1)))
        if median > NOMINAL_ERROR_BOUND:
            raise CalibrationError(
                f"{meas.path}: the commanded joints j1..j6 put robot {robot.name}'s TCP a median {median:.1f} mm from "
                f"the commanded x, y, z, beyond the {NOMINAL_ERROR_BOUND:g} mm of any plausible arm error: data of "
                "another robot or another TCP?"
            )
    if nominal_error is not None and len(meas):
        check_units(meas, position, meas.measured, nominal_error, registered=registered)


def check_identification(path, fit, start_tool):
    """Refuse an identification whose deltas or residuals no real arm has.

    Parameters
    ----------
    path : str
        The measurement file, for messages.
    fit : KinematicFit
    start_tool : ndarray, shape (4, 4)
        The nominal TCP in the flange frame.

    Raises
    ------
    CalibrationError
        Naming the parameter or the residual and the bound.
    """
    for name, delta in zip(fit.names, fit.delta):
        if name.startswith(("base_", "target_", "tool_", "gear", "grav")):
            continue
        bound = ANGLE_BOUND if is_angle(name) else LENGTH_BOUND
        if abs(delta) > bound:
            shown = f"{np.degrees(delta):.3f} deg" if is_angle(name) else f"{delta:.3f} mm"
            limit = f"{np.degrees(bound):g} deg" if is_angle(name) else f"{bound:g} mm"
            raise CalibrationError(
                f"{path}: identified {name} moves by {shown}, beyond the {limit} any arm of this type is off: "
                "data of another robot, or commanded and measured columns that do not belong together"
            )
    moved = float(np.linalg.norm(fit.robot.T_flange_tool[:3, 3] - start_tool[:3, 3]))
    if any(n in TOOL_NAMES for n in fit.names) and moved > TOOL_BOUND:
        raise CalibrationError(
            f"{path}: the identified TCP lies {moved:.1f} mm from the nominal one, beyond {TOOL_BOUND:g} mm: "
            "give the measured TCP with --tool"
        )
    median = float(np.median(np.linalg.norm(fit.residuals, axis=1)))
    if median > RESIDUAL_BOUND:
        raise CalibrationError(
            f"{path}: after identification the median residual is still {median:.2f} mm (bound {RESIDUAL_BOUND:g} mm): "
            "the data do not fit this robot's kinematics (another robot, or rows that do not belong together)"
        )
