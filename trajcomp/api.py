"""The Python API for offline programming tools: compensate a pose, a path or a program file.

RoboDK-like: an offline programming (OLP) tool hands over the pose it wants
the real TCP at, with the active tool and reference frame and the joints it
planned, and gets back the pose to send to the controller instead, the
joints of that command and the correction. A `Compensator` holds a loaded
model; the module functions take a model file (loaded once per file
version) and delegate to one::

    import trajcomp

    comp = trajcomp.Compensator("model.yaml")
    command, joints, correction = comp.filter_target(
        [550, 100, 550, 90, 0, 180], joints_hint=[10, -80, 100, -110, -90, 0])
    run = comp.filter_program("weld.src", "weld_compensated.src", report="weld")
    run.passed, run.written

Units at this boundary: mm and degrees. A pose is a homogeneous matrix
(4, 4) in mm or ``x, y, z, a, b, c`` (mm, deg; A, B, C = intrinsic
Z-Y'-X'', R = Rz(A) Ry(B) Rx(C)); a stack of N poses is (N, 4, 4) or
(N, 6). Commands come back in the form and frame the poses were given in.

Posture: ``joints_hint`` chooses the arm posture, the IK branch and joint
turns nearest the hint, and the command's joints are in that posture; a
correction that would leave it is refused (`trajcomp.IKError`). Without a
hint, each pose takes the posture nearest the joints of the pose before it
(the first: nearest the robot's home), as a controller moves on from where
the arm is. Everything else is `trajcomp.compensation.program_rewrite.compensate_program`'s:
this module feeds it a small in-memory program.
"""

import dataclasses
import logging
import os
from pathlib import Path

import numpy as np

from trajcomp.jobs.batch import run_programs
from trajcomp.jobs.options import check_options
from trajcomp.jobs.pipeline import CompensationJob, loaded_model
from trajcomp.compensation.target_correction import program_corrector
from trajcomp.errors import TrajcompError
from trajcomp.model.compensation_model import CompensationModel
from trajcomp.model.model_file import load_model, model_files
from trajcomp.compensation.options import MAX_CORRECTION, MAX_JOINT_CHANGE
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.programs.program import Program
from trajcomp.programs.items import LINEAR, Motion, Target
from trajcomp.arm.transforms import angles_near, matrix_to_pose, pose_to_matrix
from trajcomp.report import Criteria
from trajcomp.timing.path import TOLERANCE

log = logging.getLogger(__name__)

API_FORMAT = "api"  # format name of the in-memory programs: no language, no configuration data
_TOOL, _FRAME = "tool", "frame"  # names of the caller's tool and frame in those programs


@dataclasses.dataclass(frozen=True, eq=False)
class Filtered:
    """Commands for N poses (`Compensator.filter_targets`).

    Attributes
    ----------
    poses : ndarray, shape (N, 4, 4) or (N, 6)
        Pose to send to the nominal controller for each target, in the
        caller's frame and form (matrix in mm, or x, y, z, a, b, c in mm, deg).
    joints : ndarray, shape (N, 6)
        Joints of each command, deg, in the requested posture.
    correction : ndarray, shape (N, 6)
        Command minus target in the robot base frame: dx, dy, dz (mm) and
        rotation vector (deg).
    outside_grid : ndarray of bool, shape (N,)
        Targets outside the calibrated region: the grid, the joint range of a
        joint residual or the arm postures measured (handled by the
        ``outside`` policy); ``report.landing`` tells them apart.
    report : ProgramReport
        Everything compensation knows about each target (planned joints,
        posture source, predicted residual, warnings).
    """

    poses: np.ndarray
    joints: np.ndarray
    correction: np.ndarray
    outside_grid: np.ndarray
    report: object


class Compensator:
    """A compensation model ready to filter poses and programs.

    Parameters
    ----------
    model : str, Path or CompensationModel
        A model file from ``trajcomp calibrate``, or a loaded model.
    mode : str, optional
        Compensation mode (one of the model's modes); default the model's method.
    outside : {"model", "clamp", "error"}
        Targets outside the calibrated grid: model only (flagged, logged),
        nearest grid value, or an error.
    max_joint_change : float
        Largest joint change a correction may cause before the target
        counts as leaving its posture, deg.
    max_correction : float
        Largest plausible position correction, mm.
    workers : int
        Processes that share the targets of a long path or program
        (`trajcomp.support.parallel.map_blocks`; forked, on POSIX); the results do
        not depend on it. Default 1: this process only, safe inside a host
        application's threads.
    source : str or Path, optional
        The file a loaded ``model`` came from: named, with its checksum, in
        the reports of `filter_program` (a model in memory is named as such).

    Raises
    ------
    ModelError
        Unreadable or incompatible model file, or a mode the model lacks.
    """

    def __init__(self, model, *, mode=None, outside="model", max_joint_change=np.degrees(MAX_JOINT_CHANGE),
                 max_correction=MAX_CORRECTION, workers=1, source=None):
        if isinstance(model, CompensationModel):
            self.model, self.model_file = model, None if source is None else str(source)
        else:
            self.model, self.model_file = load_model(model), str(Path(model).resolve())
        self.mode = mode or self.model.method
        self.model.check_mode(self.mode)
        check_options(outside=outside, max_joint_change=max_joint_change, max_correction=max_correction,
                      workers=workers)
        self.outside = outside
        self.max_joint_change = float(max_joint_change)
        self.max_correction = float(max_correction)
        self.workers = workers

    @property
    def robot(self):
        """The nominal robot the model compensates (`trajcomp.arm.robot.Robot`)."""
        return self.model.nominal

    def __repr__(self):
        return f"Compensator(robot={self.robot.name!r}, mode={self.mode!r}, outside={self.outside!r})"

    def filter_target(self, pose, tool=None, frame=None, joints_hint=None):
        """The command for one target pose.

        Parameters
        ----------
        pose : array_like, shape (4, 4) or (6,)
            Where the real TCP must go, in ``frame``: matrix in mm, or
            x, y, z, a, b, c in mm and deg.
        tool : array_like, shape (4, 4) or (6,), optional
            The TCP in the flange frame (T_flange_tool, mm / deg); default
            the TCP the model was calibrated with.
        frame : array_like, shape (4, 4) or (6,), optional
            The reference frame of ``pose`` in the robot base frame
            (T_base_frame, mm / deg); default the robot base.
        joints_hint : array_like, shape (6,), optional
            Joints (deg) choosing the posture: the IK branch and turns
            nearest them. Default: nearest the robot's home.

        Returns
        -------
        command_pose : ndarray, shape (4, 4) or (6,)
            The pose to send, in ``frame`` and in the form of ``pose``.
        joints : ndarray, shape (6,)
            Its joints, deg, in the hinted posture.
        correction : ndarray, shape (6,)
            Command minus target, robot base frame: dx, dy, dz (mm),
            rotation vector (deg).

        Raises
        ------
        IKError
            The pose is unreachable in the posture, or its correction
            leaves the posture.
        CompensationError
            An implausibly large correction (wrong model, tool or units).
        ModelError
            Outside the grid with ``outside="error"``.
        TrajcompError
            A malformed pose, tool, frame or hint.
        """
        single = np.asarray(pose, dtype=float)
        if single.shape not in ((4, 4), (6,)):
            raise TrajcompError(f"pose: expected a 4x4 matrix or x,y,z,a,b,c (mm, deg), got shape {single.shape}")
        hint = None if joints_hint is None else np.asarray(joints_hint, dtype=float)[None]
        result = self.filter_targets(single[None], tool, frame, hint)
        return result.poses[0], result.joints[0], result.correction[0]

    def filter_targets(self, poses, tool=None, frame=None, joints_hint=None, names=None):
        """Commands for a stack of target poses (a path), in one vectorized run.

        Parameters
        ----------
        poses : array_like, shape (N, 4, 4) or (N, 6)
            Targets in ``frame`` (mm; mm and deg), in path order.
        tool, frame : array_like, shape (4, 4) or (6,), optional
            As for `filter_target`, the same for every pose.
        joints_hint : array_like, shape (N, 6) or (6,), optional
            Joints (deg) choosing each pose's posture; default: each pose
            nearest the joints of the one before (the first nearest home).
        names : sequence of str, length N, optional
            How error messages name the poses (e.g. the caller's move
            numbers), each followed by its 1-based place in the stack as
            ``(line k)``; default ``pose k``.

        Returns
        -------
        Filtered

        Raises
        ------
        As `filter_target`; messages name the poses.
        """
        T, form = _pose_stack(poses, "poses")
        n = len(T)
        names = [f"pose {k + 1}" for k in range(n)] if names is None else [str(name) for name in names]
        if len(names) != n:
            raise TrajcompError(f"names: {len(names)} names for {n} poses")
        hint = None if joints_hint is None else self._hint(joints_hint, n)
        tools = {} if tool is None else {_TOOL: _one_pose(tool, "tool")}
        frames = {} if frame is None else {_FRAME: self.robot.T_world_base @ _one_pose(frame, "frame")}
        program = Program(
            format=API_FORMAT,
            name="filter_targets",
            items=tuple(Motion(LINEAR, target=k, tool=_TOOL if tools else None, frame=_FRAME if frames else None,
                               line=k + 1) for k in range(n)),
            targets=tuple(Target(name=names[k], line=k + 1, pose=T[k], joints=None if hint is None else hint[k])
                          for k in range(n)),
            tools=tools,
            frames=frames,
        )
        edited, report = self._compensate(program, label="filter_targets")
        command = np.array([t.pose for t in edited.targets]).reshape(n, 4, 4)
        joints = np.degrees(np.array([t.joints for t in edited.targets]).reshape(n, 6))
        outside = report.outside_grid | report.landing["unmeasured_posture"]
        return Filtered(_in_form(command, form, poses), joints, report.correction, outside, report)

    def filter_program(self, path, out_path=None, *, tools=None, frames=None, joint_targets="keep", in_place=False,
                       retime="auto", path_tolerance=TOLERANCE, criteria=None, report=None, json_only=False):
        """Compensate a robot program file, re-time it, write it and judge it, as ``trajcomp compensate`` does.

        The file is read in its language (`trajcomp.formats`, plugins
        included), every Cartesian target is replaced by its command in the
        posture the program declares, configuration data are rewritten from
        the corrected joints, the program is re-timed under the arm's
        limits (never faster than programmed) and written in the same
        language, and its verdict is computed: the same job
        (`trajcomp.jobs.pipeline.CompensationJob`) as the command
        line's, so the same bytes and verdict for the same options.

        Parameters
        ----------
        path : str or Path
            The program (its extension names the language).
        out_path : str or Path, optional
            Where to write, in the input's language (another language's
            extension is refused); default ``<stem>_compensated<suffix>`` beside it.
        tools : Mapping[str, array_like (4, 4) or (6,)], optional
            Tools (T_flange_tool, mm / deg) the program uses but does not define.
        frames : Mapping[str, array_like (4, 4) or (6,)], optional
            User frames / bases / work objects (T_world_frame, mm / deg) the
            program uses but does not define.
        joint_targets : {"keep", "compensate"}
            Joint-space targets: kept as written, or compensated as the pose they stand for.
        in_place : bool
            Allow ``out_path`` to replace the input program (refused otherwise).
        retime : {"auto", "toppra", "ruckig", "none"}
            Re-time the corrected program under the arm's limits (``trajcomp
            compensate --retime``); "none" keeps the program's speed fields.
        path_tolerance : float
            Largest distance of the timed joint path from a waypoint, mm.
        criteria : Criteria, optional
            The verdict's criteria (`trajcomp.report.Criteria`); default
            ``--tolerance 0.1`` and the command line's margins.
        report : str or Path, optional
            Write the compliance report as ``report.html`` and ``report.json``.
        json_only : bool
            Only ``report.json``.

        Returns
        -------
        ProgramRun
            ``.written`` (the files written, program first), ``.passed``
            (the verdict), ``.compliance`` (the report: ``.doc`` is its
            JSON), ``.report`` (per target; ``.not_compensated`` lists
            motions whose position is computed at run time) and ``.timing``.

        Raises
        ------
        ReadError, WriteError, IKError, CompensationError, RobotError, TimingError, TrajcompError
            As ``trajcomp compensate`` (RobotError: a program in another
            maker's language than the model's arm); nothing is written on error.
        """
        path = Path(path)
        out_path = path.with_name(f"{path.stem}_compensated{path.suffix}") if out_path is None else Path(out_path)
        job = self._job(tools=tools, frames=frames, joint_targets=joint_targets, in_place=in_place, retime=retime,
                        path_tolerance=path_tolerance, criteria=criteria, report=report, json_only=json_only)
        run = job.run(path, out_path)
        _log_warnings(str(path), run.report, self.outside)
        return run

    def filter_programs(self, programs, out_dir, *, tools=None, frames=None, joint_targets="keep", in_place=False,
                        retime="auto", path_tolerance=TOLERANCE, criteria=None, report=None, json_only=False,
                        summary=None, jobs=1):
        """Compensate a batch of program files into a folder, as ``trajcomp compensate`` does with several.

        Every file is compensated as `filter_program` would (the same bytes
        and verdict), written under ``out_dir`` at its path relative to the
        folder or pattern that named it; the files of one task that share
        points run as one program; a file that fails or is refused never
        stops the others; a summary JSON (``trajcomp-batch/1``) lists them
        all (`trajcomp.jobs.batch.run_programs`).

        Parameters
        ----------
        programs : sequence of str or Path
            Program files, folders or glob patterns.
        out_dir : str or Path
            The folder to write into.
        report : str or Path, optional
            The folder of the compliance reports, one per program, mirrored as the outputs are.
        summary : str or Path, optional
            The summary JSON; default ``out_dir / "summary.json"``.
        jobs : int
            Files compensated at once (processes).
        tools, frames, joint_targets, in_place, retime, path_tolerance, criteria, json_only
            As `filter_program`.

        Returns
        -------
        results : list of trajcomp.jobs.batch.FileResult
            Per program, in input order: ``.status`` (``"pass"``, ``"fail"``,
            ``"error"``, ``"crash"``), ``.outputs``, ``.message``, ``.lines``.
        summary : Path
            The summary written.
        """
        job = dataclasses.replace(
            self._job(tools=tools, frames=frames, joint_targets=joint_targets, in_place=in_place, retime=retime,
                      path_tolerance=path_tolerance, criteria=criteria, report=report, json_only=json_only),
            report_folder=True, output_root=str(out_dir), workers=self.workers if jobs == 1 else 1)
        return run_programs(job, programs, out_dir, in_place=in_place,
                            models=model_files(self.model_file) if self.model_file else [], report=report,
                            summary=summary, jobs=jobs, model=self.model_file,
                            mode=self.mode or "model default")

    def _job(self, *, tools, frames, criteria, **options):
        """The `CompensationJob` of this compensator's model and options and a program's ``options``."""
        return CompensationJob(
            self.model, model_file=self.model_file, mode=self.mode, outside=self.outside,
            tools=_named_poses(tools, "tools") or {}, frames=_named_poses(frames, "frames") or {},
            max_joint_change=np.radians(self.max_joint_change), max_correction=self.max_correction,
            criteria=criteria or Criteria(), workers=self.workers, **options,
        )

    def _hint(self, joints_hint, n):
        """Hint joints (n, 6), rad, of a (6,) or (n, 6) array in deg, finite and inside the joint limits."""
        hint = np.broadcast_to(np.radians(_finite(joints_hint, "joints_hint", (6,), (n, 6))), (n, 6))
        outside = np.flatnonzero(~self.robot.within_limits(hint))
        if outside.size:
            k = outside[0]
            joint = int(np.argmax((hint[k] < self.robot.q_min) | (hint[k] > self.robot.q_max)))
            raise TrajcompError(
                f"joints_hint of pose {k + 1}: J{joint + 1} = {np.degrees(hint[k, joint]):.3f} deg is outside the "
                f"limits of robot {self.robot.name} ({np.degrees(self.robot.q_min[joint]):g} to "
                f"{np.degrees(self.robot.q_max[joint]):g} deg); the arm cannot be in that posture"
            )
        return hint

    def _compensate(self, program, label, **options):
        correct = program_corrector(self.model, mode=self.mode, outside=self.outside, label=label,
                                    workers=self.workers)
        edited, report = compensate_program(
            program, correct, self.robot, max_joint_change=np.radians(self.max_joint_change),
            max_correction=self.max_correction, workers=self.workers, **options,
        )
        _log_warnings(label, report, self.outside)
        return edited, report


def _log_warnings(label, report, outside):
    """Log what compensation warns of: targets outside the grid and each warning of the report."""
    if report.outside_grid.any():
        log.warning("%s: %d of %d targets lie outside the compensation grid: %s policy applied",
                    label, int(report.outside_grid.sum()), len(report.outside_grid), outside)
    for warning in report.warnings:
        log.warning("%s: %s", label, warning)


def compensator(model, **options):
    """A `Compensator` for ``model``: a file path (loaded once per file version), a model or a Compensator.

    Parameters
    ----------
    model : str, Path, CompensationModel or Compensator
    **options
        `Compensator` options (``mode``, ``outside``, ...); not with a Compensator.
    """
    if isinstance(model, Compensator):
        if options:
            raise TypeError(f"options {sorted(options)} belong to the Compensator's constructor")
        return model
    if isinstance(model, (str, os.PathLike)):
        return Compensator(loaded_model(model), source=Path(model).resolve(), **options)
    return Compensator(model, **options)


def filter_target(pose, tool=None, frame=None, joints_hint=None, *, model, **options):
    """`Compensator.filter_target` with a model file, model or Compensator (see `compensator`)."""
    return compensator(model, **options).filter_target(pose, tool, frame, joints_hint)


def filter_targets(poses, tool=None, frame=None, joints_hint=None, names=None, *, model, **options):
    """`Compensator.filter_targets` with a model file, model or Compensator (see `compensator`)."""
    return compensator(model, **options).filter_targets(poses, tool, frame, joints_hint, names)


def filter_program(path, out_path=None, *, model, tools=None, frames=None, joint_targets="keep", in_place=False,
                   retime="auto", path_tolerance=TOLERANCE, criteria=None, report=None, json_only=False, **options):
    """`Compensator.filter_program` with a model file, model or Compensator (see `compensator`)."""
    return compensator(model, **options).filter_program(
        path, out_path, tools=tools, frames=frames, joint_targets=joint_targets, in_place=in_place, retime=retime,
        path_tolerance=path_tolerance, criteria=criteria, report=report, json_only=json_only)


def filter_programs(programs, out_dir, *, model, tools=None, frames=None, joint_targets="keep", in_place=False,
                    retime="auto", path_tolerance=TOLERANCE, criteria=None, report=None, json_only=False,
                    summary=None, jobs=1, **options):
    """`Compensator.filter_programs` with a model file, model or Compensator (see `compensator`)."""
    return compensator(model, **options).filter_programs(
        programs, out_dir, tools=tools, frames=frames, joint_targets=joint_targets, in_place=in_place,
        retime=retime, path_tolerance=path_tolerance, criteria=criteria, report=report, json_only=json_only,
        summary=summary, jobs=jobs)


def _finite(values, what, *shapes):
    """``values`` as a float array of one of ``shapes``, all finite; else TrajcompError naming ``what``."""
    arr = np.asarray(values, dtype=float)
    if arr.shape not in shapes:
        expected = " or ".join(str(s) for s in shapes)
        raise TrajcompError(f"{what}: expected shape {expected}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise TrajcompError(f"{what}: not finite: {arr.tolist()}")
    return arr


def _pose_stack(poses, what):
    """Matrices (N, 4, 4) of poses given as (N, 4, 4) or (N, 6) mm / deg, and that form."""
    arr = np.asarray(poses, dtype=float)
    if arr.ndim == 3 and arr.shape[1:] == (4, 4):
        T, form = _finite(arr, what, arr.shape), "matrix"
    elif arr.ndim == 2 and arr.shape[1] == 6:
        xyzabc = _finite(arr, what, arr.shape)
        T, form = pose_to_matrix(np.column_stack([xyzabc[:, :3], np.radians(xyzabc[:, 3:])])), "xyzabc"
    else:
        raise TrajcompError(f"{what}: expected poses of shape (N, 4, 4) or (N, 6) (mm, deg), got {arr.shape}")
    if not len(T):
        raise TrajcompError(f"{what}: no poses")
    rotation = T[:, :3, :3]
    orthonormal = np.abs(rotation @ np.swapaxes(rotation, 1, 2) - np.eye(3)).max(axis=(1, 2)) < 1e-6
    proper = orthonormal & (np.linalg.det(rotation) > 0) & np.all(np.abs(T[:, 3] - [0, 0, 0, 1]) < 1e-12, axis=1)
    if not proper.all():
        bad = np.flatnonzero(~proper)
        raise TrajcompError(f"{what}: not a rigid transform (rotation not orthonormal, or last row not "
                            f"0 0 0 1) at pose {', '.join(str(k + 1) for k in bad[:5])}")
    return T, form


def _one_pose(pose, what):
    """T (4, 4) of one pose given as (4, 4) or (6,) mm / deg."""
    arr = np.asarray(pose, dtype=float)
    if arr.shape not in ((4, 4), (6,)):
        raise TrajcompError(f"{what}: expected a 4x4 matrix or x,y,z,a,b,c (mm, deg), got shape {arr.shape}")
    return _pose_stack(arr[None], what)[0][0]


def _named_poses(values, what):
    """``{name: T (4, 4)}`` of a mapping of poses, or None."""
    return None if values is None else {str(name): _one_pose(pose, f"{what}[{name!r}]") for name, pose in values.items()}


def _in_form(T, form, given):
    """Matrices (N, 4, 4) returned as ``given`` (N, 4, 4) or (N, 6) was: matrices, or x, y, z, a, b, c (mm, deg),
    each angle within 180 deg of the given one (C 180.077 for a given 180, not -179.923)."""
    if form == "matrix":
        return T
    pose = matrix_to_pose(T)
    pose[:, 3:] = angles_near(np.degrees(pose[:, 3:]), np.asarray(given, dtype=float)[:, 3:])
    return pose
