"""Writing a program's files: what robot code may receive (`check_writable`, `active_axes`), a one-file language's
output and the companion files written beside it, controller numbers of tools and frames, generated speeds."""

import os
from pathlib import Path

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats.text_edits import patched
from trajcomp.programs.items import CIRCULAR


def written_speed(motion, language):
    """``(speed, unit)`` a generated program of ``language`` (a registered name) writes for ``motion``.

    Raises
    ------
    WriteError
        A speed in a unit the language does not state (its
        `trajcomp.formats.capabilities.SpeedUnits`): the program must be converted into it first
        (`trajcomp.compensation.program_rewrite.convert_program`), never written faster.
    """
    from trajcomp.formats import find_format
    from trajcomp.formats.capabilities import SpeedUnits

    units = find_format(format=language).capability(SpeedUnits).units[motion.kind]
    if motion.speed is not None and motion.speed_unit not in units:
        raise WriteError(f"line {motion.line}: a {motion.kind} motion's speed in {motion.speed_unit} cannot be written "
                         f"in {language} (convert the program into it first: its speeds are converted no faster)")
    return motion.speed, motion.speed_unit


def check_writable(program):
    """WriteError naming the first target, tool, frame or motion that cannot become robot code.

    Robot code must never receive ``nan`` or ``inf``, nor a circle without
    its via point; every writer is fed through this check
    (`trajcomp.formats.write`).
    """
    motions, targets = program.motion_table(), program.target_table()
    used = np.zeros(len(targets), dtype=bool)
    used[motions.target[motions.target >= 0]] = used[motions.via[motions.via >= 0]] = True
    used = np.flatnonzero(used)  # the targets used, ascending (as np.unique, without its sort or hash of every index)
    pose, joints = targets.pose, targets.joints  # judged whole, then the used picked: no copy of the arrays
    bad_pose = (np.isinf(pose).any(axis=(1, 2)) | (~targets.is_joint & np.isnan(pose).any(axis=(1, 2))))[used]
    stated = ~np.isnan(joints).all(axis=1)  # NaN: no joints
    bad_joints = (stated & ~np.isfinite(joints).all(axis=1))[used]
    for what, bad in (("pose", bad_pose), ("joints", bad_joints)):
        if bad.any():
            raise WriteError(f"target {program.where(used[np.argmax(bad)])}: {what} not finite, nothing written")
    for i in used.tolist():
        external = targets.external[i]
        if external is not None and np.isinf(external).any():  # NaN: an unused axis
            raise WriteError(f"target {program.where(i)}: external axes not finite, nothing written")
    for kind, table in (("tool", program.tools), ("frame", program.frames)):
        for name, T in table.items():
            if not np.isfinite(T).all():
                raise WriteError(f"{kind} {name}: value not finite, nothing written")
    circle_without_via = (motions.kind == CIRCULAR) & (motions.target >= 0) & (motions.via < 0)
    bad_speed = ~np.isnan(motions.speed) & ~np.isfinite(motions.speed)
    bad_zone = ~np.isnan(motions.zone) & ~np.isfinite(motions.zone)
    for bad, problem in ((circle_without_via, "a circle needs its via point"), (bad_speed, "speed not finite"),
                         (bad_zone, "zone not finite")):
        if bad.any():
            m = program.motions[int(np.argmax(bad))]
            raise WriteError(f"motion at line {m.line} ({m.text[:60]}): {problem}, nothing written")


def active_axes(program, capacity, language):
    """External axes a generated program writes: those a used target gives a value other than 0.

    A program without external axes may still state them as 0 (KUKA E1..E6):
    those are left out of languages that do not need them.

    Parameters
    ----------
    capacity : int
        How many external axes a point of the language holds.
    language : str
        For the message.

    Returns
    -------
    list of int
        Axis indices (0 = E1), ascending.

    Raises
    ------
    WriteError
        An axis with a value beyond what the language holds: dropping it
        would move the program elsewhere.
    """
    used = sorted({i for m in program.motions for i in (m.target, m.via) if i is not None})
    first = {}  # axis -> the index of the first target giving it a value
    for i in used:
        external = program.targets[i].external
        if external is not None:
            for k, v in enumerate(external):
                if not np.isnan(v) and v != 0.0:
                    first.setdefault(k, i)
    beyond = sorted(k for k in first if k >= capacity)
    if beyond:
        raise WriteError(f"{language} points hold {capacity} external axes; target {program.where(first[beyond[0]])} gives "
                         f"E{beyond[0] + 1} a value: it cannot be written without changing what the program does")
    active = set(first)
    return sorted(active)


def write_single_file(program, path, format_name, encode, min_places, emit, columns=None):
    """``{path: bytes or Patched}`` of a one-file language.

    The program's source patched in place (see `patched`, ``encode`` and
    ``columns`` as `target_edits` takes them) when it was read from
    ``format_name``; otherwise ``emit(program, path.stem)`` generated as
    UTF-8 text.
    """
    path = Path(path)
    if program.format == format_name and program.sources:
        written = patched(program, encode, min_places, columns)
        return {path: written[0]} | companion_outputs(program, written, path)
    return {path: emit(program, path.stem).encode("utf-8")}


def companion_outputs(program, written, path, own=1):
    """``{file: Patched}`` of a program's sources beyond the ``own`` first ones (those written as ``path``).

    Each lies where it lay relative to the program's first file (another
    module of its task beside it, ``../System/$config.dat`` of a KUKA
    backup); a companion (`Source`) is written only when its points changed.
    `trajcomp.formats.write` refuses a file that would land outside the
    output's folder.

    Parameters
    ----------
    program : Program
    written : sequence of Patched
        Every source as written (`patched`).
    path : Path
        Where the program's first file is written.
    own : int
        How many first sources the language's writer places itself.
    """
    home = Path(program.sources[0].path).parent
    return {Path(path).parent / os.path.relpath(source.path, home): patch
            for source, patch in zip(program.sources[own:], written[own:])
            if not (source.companion and not patch.changed)}


def numbered(names):
    """Map tool or frame names to controller numbers: numeric names keep theirs, others get free ones."""
    taken = {int(n) for n in names if n is not None and str(n).isdigit()}
    out, free = {None: 0}, 1
    for name in names:
        if name in out:
            continue
        if str(name).isdigit():
            out[name] = int(name)
            continue
        while free in taken:
            free += 1
        out[name] = free
        taken.add(free)
    return out
