"""The virtual robot: a nominal arm plus a seeded, documented error profile.

It stands in for the real arm in every demo and test. Its controller knows
only the nominal model: a joint command is taken as it is, a Cartesian command
goes through nominal inverse kinematics. The arm then ends where its *true*
kinematics put it:

- DH parameter errors (a, d in mm; alpha, theta offset in rad) and a small
  error of the declared tool position. The flange is machined to the last
  axis: the a, d and alpha errors drawn for link 6 are errors of the
  measured tool's mounting (its TCP lands exactly where that link's errors
  would put it), while joint 6 keeps its zero error. A tool other than the
  measured one, taken as exact, is exact on the real flange;
- gravity compliance: each joint deflects by the gravity torque of the links
  and payload beyond it divided by its stiffness;
- gear eccentricity: once- and twice-per-turn joint angle errors;
- repeatability noise on the reached position and laser-tracker noise on the
  measurement (isotropic Gaussian, per axis; orientation noise for 6-DoF).

The error magnitudes are an `ErrorProfile`, named ones in ``PROFILES``
(`trajcomp.calibration.profiles`).
"""

import dataclasses

import numpy as np

from trajcomp.arm.kinematics import dh_link_transforms, fk, link_frames
from trajcomp.arm.transforms import rotvec_to_matrix
from trajcomp.calibration.profiles import PROFILES, ErrorProfile

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2, in the base frame


@dataclasses.dataclass(frozen=True, eq=False)
class VirtualRobot:
    """A nominal robot with a seeded set of true errors.

    Build one with `VirtualRobot.create`; `true_robot` holds the perturbed
    kinematics, the other fields the non-geometric errors.
    """

    nominal: object
    true_robot: object
    profile: ErrorProfile
    gear_phase: np.ndarray  # (6, 2) rad, phases of the once/twice-per-turn terms
    seed: int

    @classmethod
    def create(cls, nominal, profile="paper", seed=0):
        """Draw the true errors of a virtual copy of ``nominal``.

        Parameters
        ----------
        nominal : Robot
        profile : str or ErrorProfile
            A name from `PROFILES` or a custom profile.
        seed : int
            Seeds the drawn errors (noise uses its own generator per call).
        """
        if isinstance(profile, str):
            profile = PROFILES[profile]
        rng = np.random.default_rng(seed)
        std = nominal.as_standard()
        tool = std.T_flange_tool.copy()
        tool[:3, 3] += rng.normal(0.0, profile.tool_sigma, 3)
        a = std.a + rng.normal(0.0, profile.length_sigma, 6)
        d = std.d + rng.normal(0.0, profile.length_sigma, 6)
        alpha = std.alpha + rng.normal(0.0, profile.angle_sigma, 6)
        theta_offset = std.theta_offset + rng.normal(0.0, profile.angle_sigma, 6)
        # Link 6's a, d, alpha errors go to the mounting of the measured tool: same TCP, exact flange.
        drawn, exact = (dh_link_transforms(link[0], link[1], link[2], np.zeros((1, 1)))[0, 0]
                        for link in ((a[5], alpha[5], d[5]), (std.a[5], std.alpha[5], std.d[5])))
        flange = std.T_link6_flange
        tool = np.linalg.inv(flange) @ np.linalg.inv(exact) @ drawn @ flange @ tool
        true_robot = std.replace(
            a=np.append(a[:5], std.a[5]),
            d=np.append(d[:5], std.d[5]),
            alpha=np.append(alpha[:5], std.alpha[5]),
            theta_offset=theta_offset,
            T_flange_tool=tool,
        )
        return cls(nominal, true_robot, profile, rng.uniform(0, 2 * np.pi, (6, 2)), seed)

    def reached_joints(self, q_cmd):
        """Joint angles (N, 6) rad the arm really takes for commands q_cmd (N, 6)."""
        q_cmd = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        gear = self.profile.gear_amplitude * (
            np.sin(q_cmd + self.gear_phase[:, 0]) + np.sin(2 * q_cmd + self.gear_phase[:, 1])
        )
        q = q_cmd + gear
        return q + self._gravity_deflection(q)

    def _gravity_deflection(self, q):
        """Joint deflection (N, 6) rad under gravity, from torques of the links beyond each joint."""
        if not np.isfinite(self.profile.stiffness):
            return np.zeros_like(q)
        frames = link_frames(self.true_robot, q)
        origins = frames[:, :, :3, 3] / 1000.0  # m
        centres = 0.5 * (origins[:, :-1] + origins[:, 1:])  # (N, 6, 3) link k+1 centre
        masses = np.asarray(self.profile.link_mass, dtype=float)
        tcp = fk(self.true_robot, q)[:, :3, 3] / 1000.0
        axes = frames[:, :6, :3, 2]
        torque = np.zeros(q.shape)
        for joint in range(6):
            lever = centres[:, joint:] - origins[:, joint, None]
            force = masses[joint:, None] * GRAVITY
            moment = np.cross(lever, force).sum(axis=1)
            moment += np.cross(tcp - origins[:, joint], self.profile.payload * GRAVITY)
            torque[:, joint] = np.einsum("ij,ij->i", moment, axes[:, joint])
        # The joint map turns DH-angle deflections into controller joint angles.
        return (torque / self.profile.stiffness) @ np.linalg.inv(self.true_robot.joint_map).T

    def reached_poses(self, q_cmd, rng=None):
        """True TCP poses (N, 4, 4) for joint commands, with repeatability noise.

        Parameters
        ----------
        q_cmd : array_like, shape (N, 6)
            Commanded joint angles, rad.
        rng : numpy.random.Generator, optional
            Noise source; ``None`` gives noise-free poses.
        """
        poses = fk(self.true_robot, self.reached_joints(q_cmd))
        if rng is not None:
            poses[:, :3, 3] += rng.normal(0.0, self.profile.repeatability_sigma, (len(poses), 3))
        return poses

    def measure(self, q_cmd, rng):
        """Tracker measurements of the TCP position (N, 3) mm, base frame, noisy."""
        positions = self.reached_poses(q_cmd, rng)[:, :3, 3]
        return positions + rng.normal(0.0, self.profile.tracker_sigma, positions.shape)

    def measure_poses(self, q_cmd, rng):
        """6-DoF tracker measurements of the TCP frame (N, 4, 4), base frame, noisy in position and orientation."""
        poses = self.reached_poses(q_cmd, rng)
        poses[:, :3, 3] += rng.normal(0.0, self.profile.tracker_sigma, (len(poses), 3))
        turn = rotvec_to_matrix(rng.normal(0.0, self.profile.tracker_angle_sigma, (len(poses), 3)))
        poses[:, :3, :3] = turn @ poses[:, :3, :3]
        return poses
