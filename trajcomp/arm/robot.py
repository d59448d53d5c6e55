"""Robot descriptions: DH table, joint map, limits and fixed frames, loaded from YAML.

A robot YAML file (see ``trajcomp/arm/robots/*.yaml``) holds, in user units
(mm, deg):

``name``, ``source``
    Short name and the data sheet the numbers come from.
``vendor`` (optional)
    The maker, e.g. ``KUKA``: a program in a maker's language
    (its `trajcomp.formats.capabilities.Vendor`) runs only on that maker's arms.
``dh``
    ``convention`` (``standard`` = Craig's distal, or ``modified`` =
    proximal) and six-element lists ``a``, ``alpha``, ``d``,
    ``theta_offset``.
``joints`` (optional)
    ``direction``: +1/-1 per joint; ``j3_coupling``: factor of joint 2
    added to the DH angle of joint 3 (FANUC-style J2/J3 interaction).
    The DH angle is ``theta = M q + theta_offset`` with M built from these.
``limits``
    ``position_min``, ``position_max`` (deg), ``velocity`` (deg/s),
    ``acceleration`` (deg/s^2), optional ``jerk`` (deg/s^3).
``home`` (optional)
    A typical working configuration (deg): the seed for inverse kinematics
    when none is given, and the default planning orientation.
``base``, ``flange``, ``tool``, ``world`` (optional pose ``[x, y, z, a, b, c]``)
    DH frame 0 in the base frame, the manufacturer's flange frame in DH
    frame 6, the TCP in the flange frame and the base in the world frame
    (on a track: at track position 0).
``track`` (optional)
    A linear track carrying the arm (`trajcomp.arm.track`): its direction
    in the world, limits and the program field of each language that
    holds its position.
"""

import dataclasses
import math
from importlib import resources
from pathlib import Path

import numpy as np
import yaml

from trajcomp.support import yaml_text
from trajcomp.errors import RobotError
from trajcomp.arm.track import Track, track_from_doc
from trajcomp.arm.transforms import pose_to_matrix

_ROBOT_PACKAGE = "trajcomp.arm.robots"
MAGNITUDE_BOUND = 1e5  # mm, deg, deg/s, deg/s^2: beyond it a robot file's number is damage (dh.a 1e308), not an arm
JERK_BOUND = 1e9  # deg/s^3
COUPLING_BOUND = 10.0  # |j3_coupling|: FANUC's is 1 (1e5 made every joint-3 angle a thousand turns: IK ran for minutes)


@dataclasses.dataclass(frozen=True, eq=False)
class Robot:
    """An immutable 6-axis arm description. Lengths in mm, angles in rad.

    Attributes
    ----------
    name : str
    convention : {"standard", "modified"}
    a, alpha, d, theta_offset : ndarray, shape (6,)
        DH parameters (mm, rad, mm, rad).
    beta : ndarray, shape (6,)
        Hayati twist about the link's y axis (rad), appended to standard DH
        links as ``... Rx(alpha) Ry(beta)``. Zero in every data-sheet robot;
        identification uses it where consecutive axes are nominally parallel
        and the DH offset d is ill-conditioned.
    joint_map : ndarray, shape (6, 6)
        ``theta = joint_map @ q + theta_offset``.
    q_min, q_max : ndarray, shape (6,)
        Joint position limits, rad.
    v_max, a_max : ndarray, shape (6,)
        Joint velocity (rad/s) and acceleration (rad/s^2) limits.
    j_max : ndarray, shape (6,)
        Joint jerk limits, rad/s^3; ``inf`` where the data sheet gives none.
    home : ndarray, shape (6,)
        Typical working configuration, rad.
    T_base_link0, T_link6_flange, T_flange_tool, T_world_base : ndarray, shape (4, 4)
        ``T_world_base``: on a track, at track position 0.
    source : str
        The data sheet or file the description comes from.
    vendor : str
        The maker (``KUKA``, ``ABB``, ``FANUC``, ``Universal Robots``), or
        ``""`` when the description does not say.
    track : Track or None
        The linear track carrying the arm (`trajcomp.arm.track.Track`); None: a fixed base.
    """

    name: str
    convention: str
    a: np.ndarray
    alpha: np.ndarray
    d: np.ndarray
    theta_offset: np.ndarray
    joint_map: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    j_max: np.ndarray
    home: np.ndarray
    T_base_link0: np.ndarray
    T_link6_flange: np.ndarray
    T_flange_tool: np.ndarray
    T_world_base: np.ndarray
    source: str = ""
    beta: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(6))
    vendor: str = ""
    track: Track = None

    def dh_angles(self, q):
        """DH joint angles theta (N, 6), rad, of joint angles q (N, 6), rad."""
        return np.asarray(q, dtype=float) @ self.joint_map.T + self.theta_offset

    def joint_angles(self, theta):
        """Joint angles q (N, 6), rad, of DH angles theta (N, 6): inverse of `dh_angles`."""
        return (np.asarray(theta, dtype=float) - self.theta_offset) @ np.linalg.inv(self.joint_map).T

    def within_limits(self, q, tol=1e-9):
        """Boolean mask (N,) of configurations q (N, 6) inside the position limits."""
        q = np.atleast_2d(q)
        return np.all((q >= self.q_min - tol) & (q <= self.q_max + tol), axis=-1)

    def replace(self, **changes):
        """A copy with some attributes changed (e.g. identified parameters)."""
        return dataclasses.replace(self, **changes)

    def as_standard(self):
        """An equivalent robot in the standard (distal) DH convention.

        A modified table ``Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``
        regroups into a fixed base transform ``Rx(alpha_0) Tx(a_0)`` followed
        by standard links with (a, alpha) shifted one joint down and a last
        link with a = alpha = 0. Forward kinematics are identical.
        """
        if self.convention == "standard":
            return self
        if np.any(self.beta):
            raise RobotError(f"robot {self.name}: Hayati beta is defined for standard DH tables only")
        base = np.eye(4)
        base[:3, :3] = _rot_x(self.alpha[0])
        base[0, 3] = self.a[0]
        return self.replace(
            convention="standard",
            a=np.append(self.a[1:], 0.0),
            alpha=np.append(self.alpha[1:], 0.0),
            T_base_link0=self.T_base_link0 @ base,
        )


def _rot_x(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def builtin_robot_names():
    """Sorted names of the robots shipped with trajcomp."""
    files = resources.files(_ROBOT_PACKAGE).iterdir()
    return sorted(f.name[: -len(".yaml")] for f in files if f.name.endswith(".yaml"))


def load_robot(name_or_path):
    """Load a built-in robot by name, or a robot YAML file by path.

    Parameters
    ----------
    name_or_path : str or Path
        A built-in name (``trajcomp robots`` lists them) or a ``.yaml`` path.

    Raises
    ------
    RobotError
        Unknown name, unreadable file, or a field that is missing, of the
        wrong shape, not finite, or inconsistent; the message names the file
        and the field.
    """
    text_name = str(name_or_path)
    if text_name in builtin_robot_names():
        source = resources.files(_ROBOT_PACKAGE).joinpath(f"{text_name}.yaml")
        label = f"built-in robot {text_name}"
        text = source.read_text(encoding="utf-8")
    else:
        path = Path(text_name)
        try:
            found = path.is_file()
        except OSError:  # a name longer than the system allows (is_file() answers False to most errors)
            found = False
        if not found:
            raise RobotError(
                f"unknown robot {yaml_text.shown(text_name)}: not a built-in name "
                f"({', '.join(builtin_robot_names())}) and no such file"
            )
        label = str(path)
        try:
            text = yaml_text.read(path)
        except (OSError, UnicodeError) as exc:
            raise RobotError(f"{label}: cannot read: {exc}") from exc
        except yaml.YAMLError as exc:
            raise RobotError(f"{label}: not a robot file: {exc}") from exc
    return robot_from_yaml(text, label)


def robot_from_yaml(text, label="<robot>"):
    """Parse robot YAML text; ``label`` names the source in error messages."""
    try:
        doc = yaml_text.load(text)
    except yaml.YAMLError as exc:
        raise RobotError(f"{label}: not valid YAML: {exc}") from exc
    if not isinstance(doc, dict):
        raise RobotError(f"{label}: expected a mapping of robot fields at the top level")
    fields = _Fields(doc, label)
    dh = fields.mapping("dh")
    convention = fields.choice("dh.convention", dh.get("convention"), ("standard", "modified"))
    deg = math.pi / 180.0
    limits = fields.mapping("limits")
    joints = doc.get("joints") or {}
    direction = fields.vector("joints.direction", joints.get("direction", [1] * 6))
    if not np.all(np.isin(direction, (-1.0, 1.0))):
        raise RobotError(f"{label}: field joints.direction: each entry must be 1 or -1, got {direction.tolist()}")
    joint_map = np.diag(direction)
    joint_map[2, 1] = fields.number("joints.j3_coupling", joints.get("j3_coupling", 0.0), limit=COUPLING_BOUND)
    q_min = fields.vector("limits.position_min", limits.get("position_min")) * deg
    q_max = fields.vector("limits.position_max", limits.get("position_max")) * deg
    bad = np.flatnonzero(q_min >= q_max)
    if bad.size:
        i = bad[0]
        raise RobotError(
            f"{label}: field limits: joint {i + 1} position_min {q_min[i] / deg:g} deg "
            f"is not below position_max {q_max[i] / deg:g} deg"
        )
    jerk = limits.get("jerk")
    track, origin = track_from_doc(doc, label)
    T_world_base = fields.frame("world")
    if origin is not None:
        if doc.get("world") is not None and np.any(T_world_base[:3, 3]) and not np.allclose(T_world_base[:3, 3], origin):
            raise RobotError(f"{label}: field track.origin: {origin.tolist()} mm differs from the position of world "
                             f"{T_world_base[:3, 3].tolist()} mm: give the base's place at track position 0 once")
        T_world_base[:3, 3] = origin
    return Robot(
        name=fields.text("name"),
        convention=convention,
        a=fields.vector("dh.a", dh.get("a")),
        alpha=fields.vector("dh.alpha", dh.get("alpha")) * deg,
        d=fields.vector("dh.d", dh.get("d")),
        theta_offset=fields.vector("dh.theta_offset", dh.get("theta_offset", [0] * 6)) * deg,
        joint_map=joint_map,
        q_min=q_min,
        q_max=q_max,
        v_max=fields.vector("limits.velocity", limits.get("velocity"), positive=True) * deg,
        a_max=fields.vector("limits.acceleration", limits.get("acceleration"), positive=True) * deg,
        j_max=(
            np.full(6, np.inf)
            if jerk is None
            else fields.vector("limits.jerk", jerk, positive=True, limit=JERK_BOUND) * deg
        ),
        home=fields.vector("home", doc.get("home", [0] * 6)) * deg,
        T_base_link0=fields.frame("base"),
        T_link6_flange=fields.frame("flange"),
        T_flange_tool=fields.frame("tool"),
        T_world_base=T_world_base,
        source=str(doc.get("source", "")),
        vendor=str(doc.get("vendor") or ""),
        track=track,
    )


class _Fields:
    """Typed access to the fields of one robot document, with located errors."""

    def __init__(self, doc, label):
        self.doc = doc
        self.label = label

    def fail(self, field, message):
        raise RobotError(f"{self.label}: field {field}: {message}")

    def text(self, field):
        value = self.doc.get(field)
        if not isinstance(value, str) or not value.strip():
            self.fail(field, f"expected a non-empty text, got {yaml_text.shown(value)}")
        return value

    def mapping(self, field):
        value = self.doc.get(field)
        if not isinstance(value, dict):
            self.fail(field, f"expected a mapping, got {yaml_text.shown(value)}")
        return value

    def choice(self, field, value, allowed):
        if not isinstance(value, str) or value not in allowed:
            self.fail(field, f"expected one of {', '.join(allowed)}, got {yaml_text.shown(value)}")
        return value

    def number(self, field, value, limit=MAGNITUDE_BOUND):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(field, f"expected a finite number, got {yaml_text.shown(value)}")
        if abs(value) > limit:
            self.fail(field, f"{value:g} is beyond the {limit:g} of any arm")
        return float(value)

    def vector(self, field, value, size=6, positive=False, limit=MAGNITUDE_BOUND):
        if not isinstance(value, (list, tuple)) or len(value) != size:
            self.fail(field, f"expected a list of {size} numbers, got {yaml_text.shown(value)}")
        numbers = np.array([self.number(f"{field}[{i}]", v, limit) for i, v in enumerate(value)])
        if positive and np.any(numbers <= 0):
            self.fail(field, f"expected positive numbers, got {numbers.tolist()}")
        return numbers

    def frame(self, field):
        value = self.doc.get(field)
        if value is None:
            return np.eye(4)
        pose = self.vector(field, value)
        pose[3:] = np.radians(pose[3:])
        return pose_to_matrix(pose)
