"""The virtual robot's error profiles, and the paper's arm: what ``trajcomp simulate`` and ``demo`` offer.

Profiles (``PROFILES``): ``ideal`` (no error at all), ``paper`` (a UR10-class
arm with 1-3 mm uncompensated error, as in the paper), ``harsh`` (twice the
geometric and non-geometric errors, heavier payload, noisier). Plain data,
no numpy: a command's ``--help`` builds its parser from them without loading
the virtual robot (`trajcomp.calibration.virtual_arm`, which draws the errors).
"""

import dataclasses
import math

PAPER_ROBOT = "ur10"  # the arm class of the paper's cubes, whose masses the paper profile carries


@dataclasses.dataclass(frozen=True)
class ErrorProfile:
    """Magnitudes of the virtual robot's errors (standard deviations unless noted).

    Attributes
    ----------
    name : str
    length_sigma : float
        DH a and d errors, mm.
    angle_sigma : float
        DH alpha and theta-offset errors, rad.
    tool_sigma : float
        Error of the declared tool (TCP) position, mm per axis.
    link_mass : tuple of float
        Mass of links 1..6, kg (centre of mass midway along each link).
    payload : float
        Mass at the TCP, kg.
    stiffness : float
        Joint stiffness, N m/rad (all joints).
    gear_amplitude : float
        Amplitude of the once- and twice-per-turn joint errors, rad.
    repeatability_sigma, tracker_sigma : float
        Noise of the reached and of the measured position, mm per axis.
    tracker_angle_sigma : float
        Noise of a measured orientation (6-DoF tracker), rad per axis.
    """

    name: str
    length_sigma: float = 0.0
    angle_sigma: float = 0.0
    tool_sigma: float = 0.0
    link_mass: tuple = (0.0,) * 6
    payload: float = 0.0
    stiffness: float = math.inf
    gear_amplitude: float = 0.0
    repeatability_sigma: float = 0.0
    tracker_sigma: float = 0.0
    tracker_angle_sigma: float = 0.0

    @property
    def noise_sigma(self):
        """Combined per-axis noise of one measurement, mm."""
        return math.hypot(self.repeatability_sigma, self.tracker_sigma)


_UR10_MASSES = (7.1, 12.7, 4.27, 2.0, 2.0, 0.365)  # kg, UR10 data sheet

PROFILES = {
    "ideal": ErrorProfile("ideal"),
    "paper": ErrorProfile(
        "paper",
        length_sigma=0.5,
        angle_sigma=math.radians(0.05),
        tool_sigma=0.2,
        link_mass=_UR10_MASSES,
        payload=2.0,
        stiffness=4.0e5,
        gear_amplitude=math.radians(0.004),
        repeatability_sigma=0.008,
        tracker_sigma=0.005,
        tracker_angle_sigma=math.radians(0.003),
    ),
    "harsh": ErrorProfile(
        "harsh",
        length_sigma=1.0,
        angle_sigma=math.radians(0.1),
        tool_sigma=0.5,
        link_mass=_UR10_MASSES,
        payload=8.0,
        stiffness=2.0e5,
        gear_amplitude=math.radians(0.01),
        repeatability_sigma=0.02,
        tracker_sigma=0.01,
        tracker_angle_sigma=math.radians(0.006),
    ),
}
