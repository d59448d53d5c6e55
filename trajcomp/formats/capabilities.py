"""What a language can do beyond reading and writing: capability objects it declares or not.

A language (`trajcomp.formats.Format`) is a small protocol, ``read(path)
-> Program`` and ``write(program, path) -> {path: bytes}``; everything else
it may do is an object of one of the types below, given to
`trajcomp.formats.register_format` (compas_fab's backend features: a type
a backend has or has not). The pipeline asks for a capability
(`trajcomp.formats.capability`), never for a language's name: a new
language that declares `SpeedFields` is re-timed, one that declares
`ConfigurationData` has its postures kept, with no word of the pipeline
changed. Each language's contract test (``tests/formats/<language>/``,
`tests/formats/contract.py`) runs every capability it declares.

Callables are given as themselves or as ``"module:function"`` strings,
imported on first use (`resolved`): registering a language imports none of
its modules.
"""

import dataclasses
import importlib
from collections.abc import Mapping


def resolved(ref):
    """The callable ``ref`` names: itself, or the function of a ``"module:function"`` string, imported now."""
    if callable(ref):
        return ref
    module, _, function = ref.partition(":")
    return getattr(importlib.import_module(module), function)


@dataclasses.dataclass(frozen=True)
class Vendor:
    """The maker whose controllers run the language (``"KUKA"``), compared with `trajcomp.arm.robot.Robot.vendor`:
    a program of one maker's language is refused for another maker's arm. A language without it (CSV) is any arm's.
    """

    name: str


@dataclasses.dataclass(frozen=True)
class RowBlocks:
    """Reading and writing share blocks of rows among processes (`trajcomp.support.parallel.map_blocks`).

    ``read(path, workers)`` and ``write(program, path, workers)``: the
    language's own reader and writer given a number of processes (CSV's
    millions of rows). The language's plain ``read`` and ``write`` stay the
    one-process protocol.
    """

    read: object
    write: object


@dataclasses.dataclass(frozen=True)
class SpeedFields:
    """The re-timing can be written into the program's own speed and time fields (`trajcomp.timing.writeback`).

    Attributes
    ----------
    write : callable or str
        ``write(program, result, robot, plan) -> (Program, settings)``:
        ``plan`` (`trajcomp.timing.writeback.SpeedPlan`) says what to write
        per waypoint, ``settings`` is what was written per waypoint.
    names : str
        The fields written, as the language names them, for help texts and
        ``trajcomp formats`` (``"$VEL.CP, BAS(#VEL_PTP, %)"``).
    timed_rows : bool
        The program's rows are the trajectory (CSV): every one gets its
        time stamp, and ``write`` is given no plan (None).
    """

    write: object
    names: str = ""
    timed_rows: bool = False


@dataclasses.dataclass(frozen=True)
class SpeedUnits:
    """The speed units a generated program states, per motion kind: a program converted into the language gets
    its speeds in them, never faster (`trajcomp.formats.speeds.convert_speeds`). A language without it gets the
    speeds as they are, the writer's choice.

    Attributes
    ----------
    units : Mapping[str, Mapping[str, float]]
        Per motion kind (``"joint"``, ``"linear"``, ``"circular"``), the
        units (`Motion.speed_unit`: ``"%"``, ``"rad/s"``, ``"mm/s"``,
        ``"s"``), the one a converted speed takes first, each with the
        smallest value the writer states in it (a smaller speed would be
        written faster).
    """

    units: Mapping


@dataclasses.dataclass(frozen=True)
class OrientationSpeed:
    """The language's speed data bound the tool's reorientation beside its TCP speed (RAPID speeddata's v_ori:
    `trajcomp.programs.items.Motion.orientation_speed`). A motion converted into the language keeps that bound;
    a time the re-timing writes in place of such speed data takes at least the time the bound allows."""


@dataclasses.dataclass(frozen=True)
class ConfigurationData:
    """The arm configuration data the language's targets declare (KUKA Status and Turn, ABB confdata, FANUC CONFIG).

    ``module`` names the module with ``encode``, ``windows``, ``merge``,
    ``describe`` and optionally ``BINDING_KINDS``
    (`trajcomp.formats.configuration` describes them and uses them). A
    language without it declares none: its joints are written as joints,
    or the controller chooses.
    """

    module: str

    def codec(self):
        """The module of the data (`trajcomp.formats.configuration`)."""
        return importlib.import_module(self.module)


@dataclasses.dataclass(frozen=True)
class Tasks:
    """A program may use points other files of its controller declare: its reader puts them in companion sources
    (`trajcomp.programs.items.Source`), and a batch reads such files as one program (`trajcomp.formats.task`)."""


@dataclasses.dataclass(frozen=True)
class PointCopies:
    """Points are declared by name and motions name them (spans ``target_name``, ``via_name``): a point used with
    several tools or frames is written as a copy per use (`trajcomp.formats.uses`); in a language without it, the
    motions of such a point are left as written and listed."""


@dataclasses.dataclass(frozen=True)
class BaseFrameOnly:
    """The language's poses are always in the robot's base frame (no work object, base or user frame): a program
    converted into it has its poses moved there."""


@dataclasses.dataclass(frozen=True)
class ExternalAxes:
    """The language's targets state external axes (`trajcomp.programs.items.Target.external`: KUKA E1..E6, ABB
    eax_a..eax_f, FANUC E1..), a track's position among them (`trajcomp.arm.track.Track`).

    ``track_key`` is the key naming the language in a robot YAML's
    ``track.fields`` (``krl: E1``), whose value is the field that holds the
    track position. A program read in (or converted into) the language
    carries it (`trajcomp.programs.program.Program.track_key`); a language
    without it runs at track position 0.
    """

    track_key: str


@dataclasses.dataclass(frozen=True)
class KeptExternalAxes:
    """A Cartesian target that does not state an external axis keeps it where the motion before left it (KRL: a
    POS or FRAME point, or an E6POS without E1); in a language without it the axis is unknown there
    (`trajcomp.programs.frames.FrameTable.track_positions`)."""


KINDS = (Vendor, RowBlocks, SpeedFields, SpeedUnits, OrientationSpeed, ConfigurationData, Tasks, PointCopies,
         BaseFrameOnly, ExternalAxes, KeptExternalAxes)
