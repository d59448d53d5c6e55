"""The program format registry: read and write robot programs by extension or name.

Each language is one folder here (``formats/urscript/``: the simplest to
copy) whose ``__init__`` describes the language and registers it with
`register_format`: a name, extensions, the protocol every language keeps
(its modules are imported on first use only)

- ``reader.py``: ``read(path) -> Program``;
- ``writer.py``: ``write(program, path) -> {path: bytes}`` (the content of
  every file it produces, e.g. a KRL .src and its .dat; `write` puts them on
  disk atomically);

and the capability objects it declares (`trajcomp.formats.capabilities`:
the maker whose controllers run it, speed fields the re-timing writes into
(``speeds.py``), speed units, configuration data (``configuration.py``),
tasks of several files, copies of a point per use, ...). The pipeline asks
for a capability (`capability`), never for a language's name.

Adding a language is one folder with these faces and one line in
`BUILT_IN` (or, outside trajcomp, an entry point), and its contract test
(``tests/formats/<language>/``: the protocol and every capability it
declares, run on its samples). The text toolkit the
built-in languages share is public, a module per job: `trajcomp.formats.text`
(reading and scanning a source), `number_fields` (reading its numbers),
`number_writing`, `pose_encoding`, `text_edits` (the edit engine),
`source_shifts`, `file_writing` and `text_sequence`.

Third-party packages add formats through the entry-point group
``trajcomp.formats``: an entry point names a module (or object) whose import
calls `register_format`::

    [project.entry-points."trajcomp.formats"]
    myformat = "mypackage.trajcomp_format"

Plugins are imported lazily, on the first lookup that needs them.
"""

import contextlib
import dataclasses
import importlib
import os
from pathlib import Path

from trajcomp.errors import ReadError, RobotError, TrajcompError, WriteError
from trajcomp.formats.capabilities import (
    KINDS, ExternalAxes, KeptExternalAxes, PointCopies, RowBlocks, Vendor, resolved,
)
from trajcomp.support.atomic import FileSet, recover
from trajcomp.support.memory import collection_paused

ENTRY_POINT_GROUP = "trajcomp.formats"


@dataclasses.dataclass(frozen=True)
class Format:
    """A registered language: a name, its file extensions, ``read`` and ``write``, and the capability objects it
    declares (`trajcomp.formats.capabilities`).

    ``reader`` and ``writer`` are callables, or ``"module:function"``
    strings resolved on first use (`register_format` describes them).
    """

    name: str
    extensions: tuple
    reader: object
    writer: object
    capabilities: tuple = ()
    source: str = "built-in"

    def capability(self, kind):
        """The language's capability object of type ``kind`` (`trajcomp.formats.capabilities`), or None."""
        return next((c for c in self.capabilities if isinstance(c, kind)), None)

    def read(self, path, workers=1):
        """The program in ``path`` (``workers``: processes sharing its blocks of rows, where it has `RowBlocks`)."""
        blocks = self.capability(RowBlocks)
        return resolved(self.reader)(path) if blocks is None else resolved(blocks.read)(path, workers)

    def write(self, program, path, workers=1):
        """``{path: bytes}`` of every file ``program`` is written as (``workers``: as `read`)."""
        blocks = self.capability(RowBlocks)
        return resolved(self.writer)(program, path) if blocks is None \
            else resolved(blocks.write)(program, path, workers)


_FORMATS = {}
_PLUGINS = {"loaded": False, "failed": {}}


def register_format(name, extensions, reader, writer, *capabilities, source="built-in"):
    """Register (or replace) a language.

    Parameters
    ----------
    name : str
        Registry name, e.g. ``"krl"``.
    extensions : sequence of str
        File extensions with the dot, e.g. ``[".src"]``; matched case-insensitively.
    reader : callable or str
        ``reader(path) -> Program``, or ``"module:function"``.
    writer : callable or str
        ``writer(program, path) -> {Path: bytes}`` (or an iterable of bytes pieces, e.g. a generator, for a long
        file), or ``"module:function"``.
    *capabilities
        What else the language can do, one object of each type of
        `trajcomp.formats.capabilities` it has (`Vendor`, `SpeedFields`,
        `ConfigurationData` ...); the pipeline asks for them by type.
    source : str
        Shown by ``trajcomp formats``.

    Raises
    ------
    TypeError
        An object that is not a capability, or two of one type.
    """
    kinds = [type(c) for c in capabilities]
    if not all(kind in KINDS for kind in kinds) or len(set(kinds)) < len(kinds):
        raise TypeError(f"register_format({name!r}): expected one object each of trajcomp.formats.capabilities' "
                        f"{', '.join(k.__name__ for k in KINDS)}; got {', '.join(k.__name__ for k in kinds)}")
    _FORMATS[name] = Format(name, tuple(e.lower() for e in extensions), reader, writer, tuple(capabilities), source)


def capability(program, kind):
    """The capability of type ``kind`` (`trajcomp.formats.capabilities`) of the language ``program`` was read in
    (or converted into); None where it has none, or for a program built in memory (format ``"api"``)."""
    language = registered(program.format)
    return None if language is None else language.capability(kind)


def entry_points(group):
    """The installed entry points of ``group`` (`importlib.metadata.entry_points`, imported here on first use:
    it costs a command's start-up more than the registry does)."""
    from importlib import metadata

    return metadata.entry_points(group=group)


def _load_plugins():
    """Import every ``trajcomp.formats`` entry point once; remember the ones that fail."""
    if _PLUGINS["loaded"]:
        return
    _PLUGINS["loaded"] = True
    for entry in entry_points(group=ENTRY_POINT_GROUP):
        before = set(_FORMATS)
        try:
            entry.load()
        except Exception as exc:  # a broken plugin must not break the built-in formats
            _PLUGINS["failed"][entry.name] = f"{entry.value}: {type(exc).__name__}: {exc}"
            continue
        for name in set(_FORMATS) - before:
            _FORMATS[name] = dataclasses.replace(_FORMATS[name], source=f"plugin {entry.value}")


def _plugin_failures():
    failed = _PLUGINS["failed"]
    if not failed:
        return ""
    return "; plugins that failed to import: " + "; ".join(f"{n} ({why})" for n, why in failed.items())


def formats(plugins=True):
    """All registered formats (plugins included), sorted by name.

    ``plugins=False``: only those registered so far (the built-in ones, and
    plugins a lookup has already imported), without importing the others:
    for a help text, which must not import a plugin (nor what it imports).
    """
    if plugins:
        _load_plugins()
    return [_FORMATS[name] for name in sorted(_FORMATS)]


def plugin_failures():
    """``{entry point name: reason}`` of plugins whose import failed."""
    _load_plugins()
    return dict(_PLUGINS["failed"])


def registered(name):
    """The `Format` registered as ``name`` (plugins included), or None (a program built in memory, ``"api"``)."""
    if name not in _FORMATS:
        _load_plugins()
    return _FORMATS.get(name)


def find_format(path=None, format=None):
    """The `Format` named ``format``, or else the one owning ``path``'s extension.

    Raises
    ------
    TrajcompError
        Unknown name or extension; the message lists the known ones and any
        plugin that failed to import.
    """
    if format is None and path is None:
        raise TrajcompError("give a path or a format name")
    if format is None:
        suffix = Path(path).suffix.lower()
        found = [f for f in _FORMATS.values() if suffix in f.extensions]
        if not found:
            _load_plugins()
            found = [f for f in _FORMATS.values() if suffix in f.extensions]
        if not found:
            known = ", ".join(sorted(e for f in _FORMATS.values() for e in f.extensions))
            raise TrajcompError(
                f"{path}: unknown program extension {suffix or '(none)'!r}; known: {known}"
                f"{_plugin_failures()}"
            )
        return found[0]
    if registered(format) is None:
        raise TrajcompError(
            f"unknown program format {format!r}; known: {', '.join(sorted(_FORMATS))}{_plugin_failures()}"
        )
    return _FORMATS[format]


def output_format(output, program, to=None):
    """The format a program read in one language is written to ``output`` in: its own, unless ``to`` names another.

    Parameters
    ----------
    output : str or Path
        The file to write.
    program : Program
        The program as read (``program.format``: its language).
    to : str, optional
        Registry name of another language to write (``--to``).

    Returns
    -------
    Format

    Raises
    ------
    TrajcompError
        Without ``to``, an output whose extension belongs to another
        language than the program's (a CSV program to ``out.src``): never
        converted silently.
    """
    if to is not None:
        return find_format(output, to)
    own = find_format(format=program.format)
    written = find_format(output)
    if written.name != own.name:
        raise TrajcompError(
            f"{output}: {Path(output).suffix!r} is the extension of {written.name} programs, but the input is a "
            f"{own.name} program: the output keeps the input's language (name it *{own.extensions[0]}), or give "
            f"--to {written.name} to convert it"
        )
    return own


def read(path, format=None, *, workers=1, copies=True):
    """Read a robot program.

    Parameters
    ----------
    path : str or Path
    format : str, optional
        Registry name; default from the extension.
    workers : int
        Processes sharing the work of a format that reads blocks of rows (CSV).
    copies : bool
        False: the program as its files state it, a point used with several
        tools or frames kept as one: for a program written back with its
        points' numbers as they are (a same-language `convert`), which need
        no copy per use.

    Returns
    -------
    Program
        A point used with several tools or frames is written as a copy per
        use where the language declares points by name (`uses_resolved`);
        otherwise (or without ``copies``) its motions are left as written.

    Raises
    ------
    ReadError
        Missing file, or malformed content (file:line and the text).
    """
    path = Path(path)
    fmt = find_format(path, format)
    if not path.is_file():
        what = "a folder" if path.is_dir() else "not a regular file (a FIFO, socket or device)" if path.exists() \
            else None
        raise ReadError(f"{path}: no such file" if what is None else f"{path}: is {what}; a program is read from a file")
    recover(path.parent)  # a set of files a killed run left half-renamed is completed first
    with collection_paused():  # a program is made of many objects without cycles (`trajcomp.support.memory`)
        program = _with_external_axes(fmt.read(path, workers), fmt)
        return uses_resolved(program, fmt) if copies else program.with_shared_targets_left()


def uses_resolved(program, fmt):
    """``program`` with each point used with several tools or frames copied per use (`trajcomp.formats.uses`,
    languages with `PointCopies`), the motions of any such point left otherwise, each listed with why."""
    copies = fmt.capability(PointCopies) is not None
    if copies or program.with_shared_targets_left() is not program:
        from trajcomp.formats.uses import per_use  # lazily, like the format modules

        program = per_use(program, copies=copies)
    return program.with_shared_targets_left()


def read_task(paths, format=None):
    """Several files of one controller that share points, read as one program (`trajcomp.formats.task.merge`).

    Parameters
    ----------
    paths : sequence of str or Path
        Program files of one language (a RAPID task's modules, KUKA
        programs using one ``$config.dat``); the first that has motions names the program.
    format : str, optional
        Registry name; default from the extensions.

    Raises
    ------
    ReadError
        As `read`, for any of the files.
    """
    from trajcomp.formats.task import merge

    programs = [read(path, format) for path in paths]
    fmt = find_format(paths[0], format)
    return uses_resolved(_with_external_axes(merge(programs), fmt), fmt)


def _with_external_axes(program, fmt):
    """``program`` marked with its language's external axes: the key of the language in a robot's track fields
    (`ExternalAxes`), whether a target that does not state them keeps them (`KeptExternalAxes`)."""
    marks = {"track_key": track_key(fmt)} if track_key(fmt) else {}
    if fmt.capability(KeptExternalAxes):
        marks["kept_axes"] = True
    return dataclasses.replace(program, **marks) if marks else program


def track_key(language):
    """The key naming ``language`` (`Format`) in a robot's track fields (`ExternalAxes`), or None."""
    axes = language.capability(ExternalAxes)
    return None if axes is None else axes.track_key


def input_paths(path, program):
    """The files a program read from ``path`` came from (a KRL .src and its .dat, the other modules of a RAPID
    task, $config.dat it uses points of)."""
    path = Path(path)
    return [path] + [Path(source.path) if source.path else path.parent / source.name for source in program.sources]


def write(path, program, format=None, *, protect=(), workers=1, root=None, into=None):
    """Write a robot program; its output files (a KRL .src and .dat, the other files of its task) land all or none.

    The content is written to temporary files (a writer's generator of
    pieces is consumed while writing), then committed with
    `trajcomp.support.atomic.write_files_atomic`.

    Parameters
    ----------
    path : str or Path
    program : Program
    format : str, optional
        Registry name; default from the extension.
    protect : sequence of Path, optional
        Files that must not be overwritten (the program's inputs, see `input_paths`).
    workers : int
        Processes sharing the work of a format that writes blocks of rows (CSV).
    root : str or Path, optional
        The folder every output must stay in (a batch's output folder);
        default the folder of ``path``. The other files of the program's
        task are written where they lie relative to it (`trajcomp.formats.task`),
        their folders made inside ``root``; one that would land outside is
        refused unless it is written over itself (in place).
    into : trajcomp.support.atomic.FileSet, optional
        Stage the files into this set, committed with its other files (a
        program and its report); default: committed here.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    WriteError
        An output is one of the ``protect`` files, lies outside ``root``,
        or cannot be written, or a number to write is not finite (``nan``,
        ``inf``: never into robot code).
    """
    from trajcomp.formats.file_writing import check_writable  # lazily, like the format modules

    path = Path(path)
    check_writable(program)
    with collection_paused():  # the texts are made of many objects without cycles (`trajcomp.support.memory`)
        files = find_format(path, format).write(program, path, workers)
        _task_folders(files, path, program, Path(root) if root is not None else path.parent)
        with FileSet() if into is None else contextlib.nullcontext(into) as outputs:
            outputs.stage(files, protect=protect, advice="write to another file (-o) or give --in-place to replace it")
    return list(files)


def check_robot_language(path, format, robot, whose):
    """Refuse a program in one maker's language for an arm of another maker.

    A KRL program runs on a KUKA controller, never on a UR arm; a program
    CSV (no maker) or an arm whose description names no maker is not
    checked.

    Parameters
    ----------
    path : str or Path
        The program, for the message.
    format : Format
        Its language (`trajcomp.formats.Format`).
    robot : Robot
        The arm it is to run on.
    whose : str
        Where that arm comes from, for the message: ``"the arm of the model
        m.yaml"``, ``"the arm --robot names"``.

    Raises
    ------
    RobotError
        Naming the program's maker and language and the arm's.
    """
    maker = format.capability(Vendor)
    if maker and robot.vendor and maker.name.casefold() != robot.vendor.casefold():
        raise RobotError(
            f"{path}: {'an' if maker.name[0] in 'AEIO' else 'a'} {maker.name} program ({format.name}) "
            f"cannot run on robot {robot.name} "
            f"({robot.vendor}), {whose}: give the arm (or a model of the arm) that runs it"
        )


def _task_folders(files, path, program, root):
    """Make the folders of the files written beside ``path`` (the other files of its task) inside ``root``.

    Raises
    ------
    WriteError
        A file outside ``root`` that is not a file of the program written
        over itself (in place).
    """
    own = {os.path.abspath(source.path) for source in program.sources if source.path}
    top = os.path.abspath(root)
    for file in files:
        place = os.path.normpath(os.path.abspath(file))
        if Path(file) == path or place in own:
            continue
        if os.path.commonpath([place, top]) != top:
            raise WriteError(
                f"{place}: {Path(file).name}, a file of the program's task whose points are corrected, would be "
                f"written outside the output's folder {root}: compensate the controller's backup folder into an "
                "output folder (its layout is kept), or give --in-place"
            )
        if os.path.isdir(top):  # a missing output folder is refused when the files are committed
            os.makedirs(os.path.dirname(place), exist_ok=True)


# The built-in languages, one folder each under formats/; each registers itself on import, as a plugin does.
BUILT_IN = ("csv", "krl", "rapid", "fanuc", "urscript")
for _language in BUILT_IN:
    importlib.import_module(f"{__name__}.{_language}")
