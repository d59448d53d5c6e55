"""A trajcomp format plugin: ISO G-code for robots (CAM output), ``.nc``, ``.ngc``, ``.gcode``.

Robot CNC controllers and CAM posts for robots write 6-DoF paths as ISO
G-code: one block per line, ``G0`` (rapid) and ``G1`` (linear feed) with
``X Y Z`` and an orientation, modal (a word left out keeps its last value).
Installing this package (``pip install plugins/trajcomp-gcode``) registers
the format through the ``trajcomp.formats`` entry point.

Read
    ``X Y Z``: TCP position, mm (``G21``, default) or inch (``G20``).
    ``A B C``: orientation, deg, in trajcomp's convention (KUKA.CNC's):
    R = Rz(A) Ry(B) Rx(C). Or ``I J K``: the tool axis (5-axis output), a
    unit vector from the tool tip towards the spindle, as CNC posts write
    it; the TCP z axis points the other way (out of the tool) and the TCP x
    axis is the base x axis projected normal to it (the base y axis when the
    tool axis lies along x): the rotation about the tool axis is the
    controller's choice, and compensation assumes this one.
    ``F``: feed, units/min (``G94``). ``G54``-``G59`` select a work offset:
    a user frame of that name (``--frame G54=x,y,z,a,b,c``); none: the robot
    base. ``T<n> M6`` selects tool ``n`` (``--tool n=...``); none: the
    robot's tool. Comments ``( ... )`` and ``; ...``, ``N`` numbers, ``%``
    and ``O`` lines, ``M``, ``S``, ``E`` words and ``G4`` dwells are kept.
    Blocks before the position and orientation are fully known (e.g. a
    first ``G0 Z100``) depend on where the arm is: reported as not
    compensated. Refused with file and line: arcs (``G2``/``G3``: post
    linear moves), incremental ``G91``, other G codes (offsets, cycles,
    cutter compensation), expressions and variables, unknown words.

Write
    Only the numbers of edited targets change; a word a block left out is
    inserted where the corrected value differs from the modal one, so
    every block still means what its target says. An unchanged program
    writes back byte for byte. Programs from other languages are written
    fresh (``G21 G90 G94``, one block per motion, other statements as
    comments).

Re-timing (`write_speeds`)
    A feed the arm cannot keep along its whole line within its joint limits
    is lowered in the block's ``F`` (rounded down); ``F`` is modal, so the
    next block that moved at the former feed gets it back. Rapids (``G0``)
    run at the controller's own limits and G-code states no motion time
    (``G93`` inverse time is not written): those blocks keep their words.
"""

import dataclasses
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError, WriteError
from trajcomp.formats import register_format
from trajcomp.formats.capabilities import SpeedFields
from trajcomp.formats.text import Lines, read_source
from trajcomp.formats.file_writing import numbered
from trajcomp.formats.number_fields import NUMBER, decimals
from trajcomp.formats.number_writing import floor_places, format_number
from trajcomp.formats.pose_encoding import encode_xyzabc
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.formats.text_edits import apply_edits, encode_text
from trajcomp.programs.program import JOINT, LINEAR, Motion, Program, Span, Statement, Target
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc

POSITION, ANGLES, AXIS = ("x", "y", "z"), ("a", "b", "c"), ("i", "j", "k")
ROLES = POSITION + ANGLES + AXIS
MIN_PLACES = dict.fromkeys(POSITION, 3) | dict.fromkeys(ANGLES, 4) | dict.fromkeys(AXIS, 6)
INCH = 25.4  # mm
KEPT_G = {4, 17, 18, 19, 40, 49, 61, 64, 80, 90, 94}  # read and kept as written, no effect on poses
WORK_OFFSETS = {54, 55, 56, 57, 58, 59}
PASSED_LETTERS = set("NOMFSETP")  # sequence and program numbers, M codes, feed, spindle, extruder, tool, dwell
REFUSED_G = {2: "arcs (G2/G3) are not supported: post the path as linear moves (G1)",
             3: "arcs (G2/G3) are not supported: post the path as linear moves (G1)",
             91: "incremental coordinates (G91) are not supported: post with G90"}

_COMMENT = re.compile(r"\([^)\r\n]*\)?|;[^\r\n]*")
_WORD = re.compile(r"([A-Za-z])\s*(" + NUMBER + r")")


@dataclasses.dataclass
class Modal:
    """The controller state after a block: axis values (file units / deg; NaN unknown) and modes."""

    values: dict = dataclasses.field(default_factory=lambda: dict.fromkeys(ROLES, np.nan))
    style: str = None  # "abc" or "ijk": which orientation words the last oriented block used
    motion: int = None  # 0 or 1
    scale: float = 1.0  # mm per file unit
    feed: float = None  # file units / min
    frame: str = None
    tool: str = None
    pending_tool: str = None


@dataclasses.dataclass
class Block:
    """One line: its words ``{letter or role: (value, Span)}`` and whether it moves the arm."""

    line: int
    words: dict
    moves: bool
    insert_at: int  # where inserted axis words go: after the block's last axis word


def tool_axis_matrix(ijk):
    """Rotations (N, 3, 3) of tool axes (N, 3): TCP z = -axis, TCP x = base x (or y) projected normal to it."""
    z = -np.asarray(ijk, dtype=float) / np.linalg.norm(ijk, axis=1, keepdims=True)
    reference = np.where(np.linalg.norm(np.cross(z, [1.0, 0.0, 0.0]), axis=1, keepdims=True) > 1e-6,
                         [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x = reference - np.einsum("ni,ni->n", reference, z)[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=2)


def _blocks(source, path):
    """Parse every line: `Block` and the `Modal` state after it. Raises ReadError with file:line."""
    state = Modal()
    masked = _COMMENT.sub(lambda m: " " * len(m.group()), source.text)
    for number, start, end in Lines(source.text):
        text = masked[start:end]
        line = source.text[start:end]
        if text.strip() in ("", "%"):
            yield Block(number, {}, False, end), state
            continue
        words, rest = {}, list(text)
        for m in _WORD.finditer(text):
            letter = m.group(1).upper()
            rest[m.start():m.end()] = " " * (m.end() - m.start())
            if letter in "GM":  # several G and M codes may share a block
                words.setdefault(letter, []).append(float(m.group(2)))
                continue
            role = letter.lower()
            if letter in words or role in words:
                raise ReadError(f"{path}:{number}: word {letter} twice in one block: {line.strip()!r}")
            span = Span(0, start + m.start(2), start + m.end(2), m.group(2))
            words[role if role in ROLES else letter] = (float(m.group(2)), span)
        leftover = "".join(rest).strip()
        if leftover and leftover != "%":
            raise ReadError(f"{path}:{number}: not plain ISO G-code (expressions, variables and "
                            f"parameters are not supported): {line.strip()!r}")
        state = dataclasses.replace(state, values=dict(state.values))
        dwell = _apply_g_codes(words.pop("G", []), state, path, number, line)
        for letter in words:
            if letter not in ROLES and letter not in PASSED_LETTERS:
                raise ReadError(f"{path}:{number}: unknown word {letter}: {line.strip()!r}")
        if "T" in words:
            state.pending_tool = format_number(words["T"][0], 0)
        if 6 in words.get("M", ()) and state.pending_tool is not None:
            state.tool = state.pending_tool
        if "F" in words:
            state.feed = words["F"][0]
        axes = [role for role in ROLES if role in words]
        if dwell or not axes:
            yield Block(number, words, False, end), state
            continue
        if state.motion is None:
            raise ReadError(f"{path}:{number}: axis words before any G0 or G1: the motion is unknown: {line.strip()!r}")
        styles = {"abc" for r in axes if r in ANGLES} | {"ijk" for r in axes if r in AXIS}
        if len(styles) > 1:
            raise ReadError(f"{path}:{number}: both A B C and I J K in one block: {line.strip()!r}")
        state.style = styles.pop() if styles else state.style
        for role in axes:
            state.values[role] = words[role][0]
        yield Block(number, words, True, max(words[r][1].end for r in axes)), state


def _apply_g_codes(codes, state, path, number, line):
    """Apply a block's G codes to ``state``; True for a dwell (G4) block."""
    dwell = False
    for code in codes:
        if code in (0, 1):
            state.motion = int(code)
        elif code in (20, 21):
            state.scale = INCH if code == 20 else 1.0
        elif code in WORK_OFFSETS:
            state.frame = f"G{int(code)}"
        elif code in KEPT_G:
            dwell = dwell or code == 4
        else:
            why = REFUSED_G.get(code, f"G{code:g} is not supported (read: G0 G1 G4 G17-G21 G40 G49 G54-G59 "
                                      "G61 G64 G80 G90 G94)")
            raise ReadError(f"{path}:{number}: {why}: {line.strip()!r}")
    return dwell


def _pose(state):
    """T (4, 4), mm, of a modal state, or None while a position or orientation value is unknown."""
    position = np.array([state.values[r] for r in POSITION]) * state.scale
    roles = ANGLES if state.style == "abc" else AXIS
    orientation = np.array([state.values[r] for r in roles]) if state.style else np.full(3, np.nan)
    if not np.all(np.isfinite(position)) or not np.all(np.isfinite(orientation)):
        return None
    T = np.eye(4)
    T[:3, 3] = position
    T[:3, :3] = abc_to_matrix(np.radians(orientation)) if state.style == "abc" else tool_axis_matrix(orientation[None])[0]
    return T


def read(path):
    """Read a G-code program into a Program; malformed or unsupported blocks raise ReadError (file:line)."""
    path = Path(path)
    source = read_source(path)
    lines = Lines(source.text)
    items, targets = [], []
    for block, state in _blocks(source, path):
        line = lines.line(block.line)
        if not block.moves:
            items.append(Statement(block.line, line))
            continue
        if state.style == "ijk":
            norm = np.linalg.norm([state.values[r] for r in AXIS])
            if np.isfinite(norm) and not 0.99 < norm < 1.01:
                raise ReadError(f"{path}:{block.line}: tool axis I J K has length {norm:.4f}, not a unit "
                                f"direction: {line.strip()!r}")
        pose = _pose(state)
        target = None
        if pose is not None:
            spans = {role: block.words[role][1] for role in ROLES if role in block.words}
            targets.append(Target(name="", line=block.line, pose=pose, spans=spans))
            target = len(targets) - 1
        speed = None if state.motion == 0 or state.feed is None else state.feed * state.scale / 60.0
        items.append(Motion(JOINT if state.motion == 0 else LINEAR, target=target, speed=speed,
                            tool=state.tool, frame=state.frame, line=block.line, text=line.strip()))
    return Program("gcode", path.stem, tuple(items), tuple(targets), sources=(source,))


def _values(pose, state, read_values):
    """Axis values ``{role: float}`` (file units, deg) of a target pose in the block's orientation style."""
    old = {role: read_values[role] * state.scale if role in POSITION else read_values[role] for role in ROLES}
    if state.style == "abc":
        out = encode_xyzabc(pose[None], [old], POSITION + ANGLES)[0]
        out.update({role: old[role] for role in ANGLES if role not in out})
    else:
        out = dict(zip(POSITION, pose[:3, 3]))
        ijk = -pose[:3, 2]
        same = np.allclose(tool_axis_matrix([[old[r] for r in AXIS]])[0][:, 2], pose[:3, 2], rtol=0.0, atol=1e-12)
        out.update({role: old[role] if same else v for role, v in zip(AXIS, ijk)})
    return {role: v / state.scale if role in POSITION else v for role, v in out.items()}


def _patch(program):
    """The source text with edited targets rewritten and modal words inserted where needed."""
    source = program.sources[0]
    lines = Lines(source.text)
    edited = {t.line: t for t in program.targets if t.edited}
    written = dict.fromkeys(ROLES, np.nan)  # modal values as the output states them
    places = dict(MIN_PLACES)
    edits = []
    for block, state in _blocks(source, source.name):
        for role in ROLES:
            if role in block.words:
                places[role] = max(places[role], decimals(block.words[role][1].text))
        if not block.moves:
            continue
        target = edited.get(block.line)
        wanted = state.values if target is None else _values(target.pose, state, state.values)
        roles = POSITION + (ANGLES if state.style == "abc" else AXIS if state.style == "ijk" else ())
        inserted = []
        for role in roles:
            if not np.isfinite(wanted[role]):
                continue
            if role in block.words:
                span = block.words[role][1]
                text = span.text if target is None else format_number(wanted[role], places[role])
                if float(text) == float(span.text):
                    text = span.text
                else:
                    edits.append((span.start, span.end, text))
            else:
                text = format_number(wanted[role], places[role])
                if not (np.isfinite(written[role]) and float(text) == written[role]):
                    inserted.append(f"{role.upper()}{text}")
            written[role] = float(text)
        if inserted:
            words = _WORD.findall(lines.line(block.line))
            separator = "" if len(words) > 1 and " " not in lines.line(block.line).strip() else " "
            edits.append((block.insert_at, block.insert_at, "".join(separator + word for word in inserted)))
    return apply_edits(source.text, edits)


def write(program, path):
    """``{path: bytes}``: the source patched when the program was read from G-code, else generated."""
    path = Path(path)
    if program.format == "gcode" and program.sources:
        return {path: encode_text(program.sources[0], _patch(program))}
    return {path: _generate(program).encode("utf-8")}


def _generate(program):
    """G-code text of a program from another language: one block per motion, statements as comments."""
    tools = numbered([m.tool for m in program.motions])
    lines = ["%", f"({_comment(program.name)})", "G21 G90 G94"]
    frame, tool, feed = None, None, None
    for item in program.items:
        if isinstance(item, Statement):
            if item.text.strip():
                lines.append(f"({_comment(item.text)})")
            continue
        if item.target is None:
            lines.append(f"(not converted, computed at run time: {_comment(item.text)})")
            continue
        target = program.targets[item.target]
        if target.is_joint:
            raise WriteError(f"{program.location(item)}: a joint target ({target.label}) cannot be "
                             "written in G-code; compensate or convert it to a pose first")
        if item.frame != frame:
            if item.frame is None or not re.fullmatch(r"G5[4-9]", str(item.frame)):
                raise WriteError(f"{program.location(item)}: frame {item.frame!r} after {frame!r}: G-code "
                                 "states frames as work offsets G54 to G59 and cannot return to the base")
            lines.append(str(item.frame))
            frame = item.frame
        if item.tool != tool:
            if item.tool is None:
                raise WriteError(f"{program.location(item)}: G-code cannot return to the robot's own "
                                 f"tool after tool {tool!r}")
            name = "" if str(item.tool).isdigit() else f" ({_comment(str(item.tool))})"
            lines.append(f"T{tools[item.tool]} M6{name}")
            tool = item.tool
        abc = np.degrees(matrix_to_abc(target.pose[:3, :3]))
        words = [f"G{0 if item.kind == JOINT else 1}"]
        words += [f"{r.upper()}{format_number(v, MIN_PLACES[r])}" for r, v in zip(POSITION + ANGLES, [*target.pose[:3, 3], *abc])]
        if item.kind != JOINT and item.speed is not None and item.speed_unit == "mm/s" and item.speed * 60.0 != feed:
            feed = item.speed * 60.0
            words.append(f"F{format_number(feed, 1)}")
        lines.append(" ".join(words))
    lines.append("%")
    return "\n".join(lines) + "\n"


def write_speeds(program, result, robot, plan):
    """Lowered cruise speeds written in the feed words of a G-code program read from a file.

    Parameters
    ----------
    program : Program
        Read from a file.
    result : TimingResult
        Its timing (waypoint k ends motion ``result.motion[k]``).
    robot : Robot
        Unused: the plan holds the speeds.
    plan : SpeedPlan
        ``cruise[k]``: the TCP speed, mm/s, motion k's line is kept at
        (`trajcomp.timing.writeback.SpeedPlan`); its ``times`` have no
        G-code field.

    Returns
    -------
    (Program, dict of int to str)
        The program with ``F`` edited or inserted (file units/min, one
        decimal, rounded down), and ``F..`` per lowered waypoint.
    """
    source = program.sources[0]
    lowered = {program.motions[result.motion[k]].line: (k, v) for k, v in plan.cruise.items()}
    edits, settings = [], {}
    feed_text, written = None, None  # the input's modal feed word, and the feed the output states
    for block, state in _blocks(source, source.name):
        if "F" in block.words:
            feed_text = block.words["F"][1].text
            written = state.feed
        if not block.moves or state.motion != 1 or state.feed is None:
            continue
        k, speed = lowered.get(block.line, (None, None))
        if k is not None:
            text = format_number(floor_places(speed * 60.0 / state.scale, 1), 1)
            settings[k] = f"F{text}"
        elif written != state.feed:  # the block ran at the input's modal feed, which the output changed
            text = feed_text
        else:
            continue
        if "F" in block.words:
            span = block.words["F"][1]
            edits.append((span.start, span.end, text))
        else:
            edits.append((block.insert_at, block.insert_at, f" F{text}"))
        written = float(text)
    return edit_sources(program, [edits]), settings


def _comment(text):
    """Text made safe inside a G-code comment (no parentheses)."""
    return text.replace("(", "[").replace(")", "]").strip()


register_format("gcode", (".nc", ".ngc", ".gcode"), read, write, SpeedFields(write_speeds, "F (G94 feed)"))
