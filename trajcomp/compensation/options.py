"""The compensation's bounds and re-timing choices: the defaults ``trajcomp compensate`` and the API offer.

Plain constants, no numpy: a command's ``--help`` builds its parser from
them without loading the compensation (`trajcomp.compensation.posture`,
`trajcomp.compensation.program_rewrite` and `trajcomp.jobs.pipeline`
import them from here).
"""

import math

from trajcomp.timing.options import RETIME_METHODS

MAX_JOINT_CHANGE = math.radians(5.0)  # rad: default bound of the joint change a correction may cause
MAX_CORRECTION = 10.0  # mm, default bound of a plausible correction of a calibrated arm
RETIME_CHOICES = RETIME_METHODS + ("none",)  # a re-timing method, or none: the program's speeds kept
OUTSIDE = ("model", "clamp", "error")  # a target outside the grid: the model alone (flagged), the grid clamped, refused
JOINT_TARGETS = ("keep", "compensate")  # a joint target: kept as written, or compensated as the pose it stands for
