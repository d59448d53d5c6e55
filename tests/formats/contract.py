"""The contract of a language: its protocol (read, write) and every capability it declares, run on it.

As meshio's ``write_read``, one check serves every language: a language's
test (``tests/formats/<language>/test_<language>_contract.py``) gives its
samples to `check_language`, which reads and writes them and then runs the
check of each capability object the language declares
(`trajcomp.formats.capabilities`). A capability type without a check here
fails the contract: a new capability comes with its check.
"""

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.arm import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.compensation.program_rewrite import convert_program
from trajcomp.errors import RobotError
from trajcomp.formats import capabilities as caps
from trajcomp.formats.configuration import BOUNDARY_TOLERANCE
from trajcomp.jobs.retime import RetimeJob
from trajcomp.programs.frames import FrameTable
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR, Motion, Target
from trajcomp.programs.program import Program

SHIFT = 0.5  # mm along x: every Cartesian target moved by it is written and read back moved
WRITTEN = 1e-3  # mm: the coarsest position resolution a writer keeps (three places)
TOOL = np.eye(4)
TOOL[2, 3] = 120.0
TOOLS = {"1": TOOL}  # a language that numbers its tools leaves tool 1's value to the controller


@dataclasses.dataclass(frozen=True)
class Samples:
    """What a language's contract runs on.

    Attributes
    ----------
    program : Path
        A program of the language (read, written back, moved).
    robot : str
        A built-in arm its controllers drive: generated programs are solved on it.
    files : Mapping[str, str], optional
        Small programs written for a capability's check, by name
        (``"shared_point"``: a point used with two tools; ``"kept_axes"``: a
        target stating the track at 500 mm and one after it that does not): ``{name:
        {file name: text}}``, the program first.
    task : (Path, str), optional
        A folder of the controller's files and the program in it (relative)
        whose points another file declares.
    """

    program: Path
    robot: str
    files: dict = dataclasses.field(default_factory=dict)
    task: tuple = None


def check_language(name, samples, tmp_path):
    """Run the protocol of language ``name`` and the check of every capability it declares on ``samples``."""
    language = formats.find_format(format=name)
    robot = load_robot(samples.robot)
    tmp_path.mkdir(parents=True, exist_ok=True)
    write_read(language, samples.program, tmp_path / "protocol")
    generated_write_read(language, robot, tmp_path / "generated")
    for capability in language.capabilities:
        check = CHECKS.get(type(capability))
        assert check is not None, f"{type(capability).__name__}: a capability without a contract check"
        folder = tmp_path / type(capability).__name__
        folder.mkdir()
        check(language, capability, samples, robot, folder)


def _positions(program):
    """(index (N,), x y z (N, 3)) of the program's Cartesian targets, mm in their frames."""
    stack = program.cartesian_targets()
    return stack.index, stack.T[:, :3, 3]


def _moved(program):
    """The program with every Cartesian target moved `SHIFT` mm along x."""
    stack = program.cartesian_targets()
    poses = stack.T.copy()
    poses[:, 0, 3] += SHIFT
    return program.with_targets(stack.index, poses=poses)


def write_read(language, sample, folder):
    """Read ``sample``, write it back unchanged (byte for byte), then moved, and read the moved program back."""
    folder.mkdir()
    program = formats.read(sample)
    assert program.format == language.name and program.motions
    same = folder / sample.name
    formats.write(same, program)
    assert same.read_bytes() == sample.read_bytes()
    out = folder / f"moved{sample.suffix}"
    formats.write(out, _moved(program))
    again = formats.read(out)
    assert [m.kind for m in again.motions] == [m.kind for m in program.motions]
    (index, before), (index_again, after) = _positions(program), _positions(again)
    np.testing.assert_array_equal(index_again, index)
    np.testing.assert_allclose(after, before + [SHIFT, 0.0, 0.0], atol=WRITTEN)


def joints(robot):
    """Three joint vectors (3, 6) of ``robot`` well inside its limits and away from the wrist singularity, rad."""
    share = np.array([[0.50, 0.55, 0.35, 0.45, 0.30, 0.50],  # one branch on every built-in arm
                      [0.53, 0.57, 0.33, 0.47, 0.32, 0.52],
                      [0.56, 0.55, 0.31, 0.50, 0.34, 0.55]])
    q = robot.q_min + share * (robot.q_max - robot.q_min)
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.3, 0.6, q[:, 4])
    return q


def generated(robot, *, frame=None, orientation_speed=None):
    """A program built in memory (format ``"api"``): two joint motions then a linear one, speeds stated, each
    target's joints known (`joints`), with tool `TOOL`, in ``frame`` (T_world_frame (4, 4)) when given, else in
    the base frame."""
    q = joints(robot)
    T_frame_base = np.eye(4) if frame is None else np.linalg.inv(frame) @ robot.T_world_base
    poses = T_frame_base @ fk(robot, q) @ TOOL
    targets = tuple(Target(name=f"P{k + 1}", line=k + 1, pose=poses[k], joints=q[k]) for k in range(3))
    name = None if frame is None else "1"
    items = (Motion(JOINT, target=0, tool="1", frame=name, speed=30.0, speed_unit="%", line=1),
             Motion(JOINT, target=1, tool="1", frame=name, speed=40.0, speed_unit="%", line=2),
             Motion(LINEAR, target=2, tool="1", frame=name, speed=2000.0, line=3, orientation_speed=orientation_speed))
    return Program(format="api", name="generated", items=items, targets=targets, tools={"1": TOOL},
                   frames={} if frame is None else {name: frame})


def _converted_write_read(language, program, robot, folder, stem="generated"):
    """``(converted, read back)``: ``program`` converted into ``language``, written and read again."""
    folder.mkdir(exist_ok=True)
    converted = convert_program(program, language.name, robot=robot)
    out = folder / f"{stem}{language.extensions[0]}"
    formats.write(out, converted)
    return converted, formats.read(out)


def generated_write_read(language, robot, folder):
    """A program of another language converted into this one is written and read back at its poses."""
    program = generated(robot)
    _, again = _converted_write_read(language, program, robot, folder)
    assert [m.kind for m in again.motions] == [m.kind for m in program.motions]
    _tcp_in_base(again, robot)


def _tcp_in_base(program, robot):
    """The TCP positions of ``program``'s targets, read back, are those of `generated`'s joints, mm in the base."""
    read = FrameTable(program, robot, TOOLS).targets_in_base(program.cartesian_targets().index)[2]
    expected = fk(robot, joints(robot)) @ TOOL
    np.testing.assert_allclose(read[:, :3, 3], expected[:, :3, 3], atol=WRITTEN)


def check_vendor(language, vendor, samples, robot, folder):
    """A program of the language is accepted for its maker's arm and refused for another maker's."""
    assert robot.vendor == vendor.name
    formats.check_robot_language(samples.program, language, robot, "the sample's arm")
    other = next(load_robot(n) for n in builtin_robot_names() if load_robot(n).vendor != vendor.name)
    with pytest.raises(RobotError, match=vendor.name):
        formats.check_robot_language(samples.program, language, other, "another maker's arm")


def check_row_blocks(language, blocks, samples, robot, folder):
    """Processes sharing the rows read and write what one process does."""
    one, two = (language.read(samples.program, workers) for workers in (1, 2))
    np.testing.assert_array_equal(two.target_table().pose, one.target_table().pose)
    moved = _moved(one)
    written = [language.write(moved, folder / f"w{workers}{samples.program.suffix}", workers) for workers in (1, 2)]
    texts = [b"".join(piece if isinstance(piece, bytes) else bytes(piece) for piece in _pieces(files))
             for files in written]
    assert texts[0] == texts[1]


def _pieces(files):
    """The bytes of a writer's files (bytes, or an iterable of bytes pieces), in order."""
    for content in files.values():
        if isinstance(content, (bytes, bytearray)):
            yield bytes(content)
        else:
            yield from content


def check_speed_fields(language, fields, samples, robot, folder):
    """A generated program of the language is re-timed (its linear motion asks 2 m/s, more than an arm keeps along
    it): the timing is written into its fields, and the fields read back run no faster than it, nor much slower
    (rounded at the written resolution)."""
    _, program = _converted_write_read(language, generated(robot), robot, folder)
    source = folder / f"generated{language.extensions[0]}"
    out = folder / f"timed{language.extensions[0]}"
    job = RetimeJob(robot, tools=TOOLS)
    run = job.run(source, out)
    assert run.timing.within_limits and sum(s.written for s in run.timing.segments) > 0
    assert len(formats.read(out).motions) == len(program.motions)
    again = job.run(out, folder / f"again{language.extensions[0]}").timing  # the fields as the controller reads them
    assert run.timing.cycle_time - 1e-9 <= again.cycle_time <= 1.05 * run.timing.cycle_time  # never faster; rounded
    if fields.timed_rows:  # every row stamped, in time order
        times = [float(row.split(",")[-1]) for row in out.read_text().splitlines()[1:]]
        assert np.all(np.diff(times) > 0)


def check_speed_units(language, units, samples, robot, folder):
    """Speeds converted into the language are in its units and read back no faster than converted."""
    converted, again = _converted_write_read(language, generated(robot), robot, folder)
    for motion, read in zip(converted.motions, again.motions):
        assert motion.speed is None or motion.speed_unit in units.units[motion.kind], motion
        assert read.speed_unit == motion.speed_unit or motion.speed is None
        if motion.speed is not None and motion.speed_unit == "s":
            assert read.speed >= motion.speed - 1e-9
        elif motion.speed is not None:
            assert read.speed <= motion.speed + 1e-9 and read.speed > 0.9 * motion.speed


def check_orientation_speed(language, orientation, samples, robot, folder):
    """A program's orientation speeds are carried into the language and read back no faster."""
    bound = np.radians(40.0)
    converted, again = _converted_write_read(language, generated(robot, orientation_speed=bound), robot, folder)
    linear = [k for k, m in enumerate(converted.motions) if m.kind in (LINEAR, CIRCULAR)]
    assert [converted.motions[k].orientation_speed for k in linear] == [bound] * len(linear)
    for k in linear:
        assert 0.9 * bound < again.motions[k].orientation_speed <= bound + 1e-12


def check_configuration_data(language, data, samples, robot, folder):
    """The language's configuration data name the arm's branch and joint windows, and are written and read back."""
    q = joints(robot)
    codec = data.codec()
    configs = codec.encode(robot, q)
    branch, lower, upper = codec.windows(configs)
    np.testing.assert_array_equal(branch, ik.branch_index(robot, q))
    assert np.all((q >= lower - BOUNDARY_TOLERANCE) & (q <= upper + BOUNDARY_TOLERANCE))
    assert all(isinstance(codec.describe(c), str) and codec.describe(c) for c in configs)
    converted, again = _converted_write_read(language, generated(robot), robot, folder)
    assert [t.config for t in again.targets] == [t.config for t in converted.targets] == list(configs)


def check_tasks(language, tasks, samples, robot, folder):
    """A program using points another file of its controller declares: they are corrected in that file."""
    source, relative = samples.task
    shutil.copytree(source, folder / "task")
    path = folder / "task" / relative
    program = formats.read(path)
    others = {k for k, s in enumerate(program.sources) if Path(s.name).stem.lower() != path.stem.lower()}
    index, before = _positions(program)
    elsewhere = [i for i in index.tolist() if {span.source for span in program.targets[i].spans.values()} & others]
    assert elsewhere, "the task sample's program uses no point of another file"
    files = {k: Path(formats.input_paths(path, program)[k + 1 if k else 0]) for k in others}
    old = {k: f.read_bytes() for k, f in files.items()}
    formats.write(path, _moved(program))
    changed = [k for k, f in files.items() if f.read_bytes() != old[k]]
    assert changed
    index_again, after = _positions(formats.read(path))
    np.testing.assert_array_equal(index_again, index)
    np.testing.assert_allclose(after, before + [SHIFT, 0.0, 0.0], atol=WRITTEN)


def _write_files(files, folder):
    """Write ``{file name: text}`` into ``folder``; the first file's path."""
    folder.mkdir(exist_ok=True)
    for file, text in files.items():
        (folder / file).write_text(text)
    return folder / next(iter(files))


def check_point_copies(language, copies, samples, robot, folder):
    """A point used with two tools is written as a copy per use, each use then compensated."""
    path = _write_files(samples.files["shared_point"], folder)
    shared = formats.read(path, copies=False)
    assert len({m.target for m in shared.motions if m.target is not None}) < len(shared.motions)
    program = formats.read(path)
    assert len({m.target for m in program.motions}) == len(program.motions) and not program.not_compensated()
    out = folder / "out" / path.name
    out.parent.mkdir()
    formats.write(out, program)
    again = formats.read(out, copies=False)  # the copy is declared in the written files
    assert len({again.targets[m.target].name for m in again.motions}) == len(again.motions)


def check_base_frame_only(language, base, samples, robot, folder):
    """A program with a user frame converted into the language has its poses in the robot's base frame."""
    frame = np.eye(4)
    frame[:3, 3] = [50.0, -20.0, 10.0]
    program = generated(robot, frame=robot.T_world_base @ frame)
    converted, again = _converted_write_read(language, program, robot, folder)
    assert all(m.frame is None for m in converted.motions) and not again.frames
    _tcp_in_base(again, robot)


def check_external_axes(language, axes, samples, robot, folder):
    """A program converted into the language, its targets stating a track position, is written and read back with
    it: on a robot whose track names a field for the language's key (and only for it), the targets are placed there."""
    from tests.compensation.test_compensate_track import on_track

    program = generated(robot)
    program = dataclasses.replace(program, targets=tuple(dataclasses.replace(t, external=np.array([750.0]))
                                                         for t in program.targets))
    converted, again = _converted_write_read(language, program, robot, folder)
    assert converted.track_key == again.track_key == axes.track_key
    used = again.usage_table().index
    track = ("\ntrack:\n  direction: [1.0, 0.0, 0.0]\n  limits: {position_min: -100, position_max: 5800, velocity: 2000, "
             "acceleration: 2500}\n  fields: {%s: E1, another_language: E2}\n")
    np.testing.assert_array_equal(FrameTable(again, on_track(samples.robot, track % axes.track_key))
                                  .track_positions(used), np.full(len(used), 750.0))
    np.testing.assert_array_equal(FrameTable(again, on_track(samples.robot, track % "another_key"))
                                  .track_positions(used), np.zeros(len(used)))  # no field for it: position 0


def check_kept_external_axes(language, kept, samples, robot, folder):
    """A target that states no external axis is where the motion before left it."""
    from tests.compensation.test_compensate_track import on_track

    path = _write_files(samples.files["kept_axes"], folder)
    program = formats.read(path)
    used = program.usage_table().index
    unstated = [i for i in used.tolist() if program.targets[i].external is None
                or np.isnan(program.targets[i].external[0])]
    assert program.kept_axes and unstated, "the sample's targets all state the track"
    positions = FrameTable(program, on_track(samples.robot)).track_positions(used)
    np.testing.assert_array_equal(positions, np.full(len(used), 500.0))  # the first target's E1, kept


CHECKS = {caps.Vendor: check_vendor, caps.RowBlocks: check_row_blocks, caps.SpeedFields: check_speed_fields,
          caps.SpeedUnits: check_speed_units, caps.OrientationSpeed: check_orientation_speed,
          caps.ConfigurationData: check_configuration_data, caps.Tasks: check_tasks,
          caps.PointCopies: check_point_copies, caps.BaseFrameOnly: check_base_frame_only,
          caps.ExternalAxes: check_external_axes, caps.KeptExternalAxes: check_kept_external_axes}
