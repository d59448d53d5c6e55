"""The calibration's methods, residual interpolations, robust losses and weights: what ``trajcomp calibrate`` offers.

Plain constants, no numpy: a command's ``--help`` builds its parser from
them without loading the identification (`trajcomp.calibration.calibrate`
and `trajcomp.calibration.identify` import them from here).
"""

from trajcomp.model.options import FIELD_KINDS, JOINT_KIND

CALIBRATION_METHODS = ("linear", "dh", "grid", "composite")  # the default mode of the model a calibration yields
INTERPOLATIONS = ("auto", JOINT_KIND, *FIELD_KINDS)  # the composite residual; auto: joint at several orientations
LOSSES = ("linear", "soft_l1", "huber", "cauchy")  # robust losses of the fit (scipy.optimize.least_squares)
ORIENTATION_WEIGHT = 100.0  # mm/rad: 1 mrad of orientation error weighs as 0.1 mm of position error
