"""The FANUC LS reader: /MN motion lines and /POS positions into a `Program` (see `trajcomp.formats.fanuc`)."""

import dataclasses
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.fanuc import columns, grammar
from trajcomp.formats.fanuc.grammar import JOINTS, KINDS, XYZWPR
from trajcomp.formats.number_fields import NUMBER, offset_type
from trajcomp.formats.text import (
    ANGLE_LIMIT,
    JOINT_LIMIT,
    LENGTH_LIMIT,
    Lines,
    fail,
    finite,
    last_line,
    read_source,
    whole_circle,
)
from trajcomp.programs import flow
from trajcomp.programs.flow import Step
from trajcomp.programs.program import Program
from trajcomp.programs.items import CIRCULAR, Motion, Span, SpanColumns, Target, replaced
from trajcomp.programs.tables import ItemRows, MotionTable, StatementTable, TargetRows, TargetTable, TextSlices
from trajcomp.arm.transforms import pose_to_matrix

ABC_ORDER = ("x", "y", "z", "r", "p", "w")  # A = R, B = P, C = W
MIN_PLACES = dict.fromkeys(XYZWPR[:3], 3) | dict.fromkeys(XYZWPR[3:], 4) | dict.fromkeys(JOINTS, 4)
_LONE_CR = re.compile(r"\r(?!\n)")  # a line ending of its own (`Lines`), which `^` and `$` do not see


@dataclasses.dataclass
class _State:
    """Active tool and user frame numbers while reading /MN, and which are set at run time."""

    tool: str = None
    frame: str = None
    why: dict = dataclasses.field(default_factory=lambda: {"tool": "", "frame": ""})  # active one set at run time
    set_at_run_time: dict = dataclasses.field(default_factory=lambda: {"tool": {}, "frame": {}})  # number -> why

    def update(self, content, line):
        """Follow ``UTOOL_NUM=n``, ``UTOOL_NUM=R[1]`` and ``UTOOL[n]=PR[m]`` (and the user frame ones)."""
        if m := grammar.FRAME_STATE.match(content):
            what, value = grammar.FRAME_WORDS[m.group(1).upper()], m.group(2)
            if value.isdigit():
                setattr(self, what, value)
                self.why[what] = ""
            else:
                setattr(self, what, None)
                self.why[what] = f"{m.group(1).upper()}={value} chosen at run time (line {line})"
        elif m := grammar.SET_FRAME.match(content):
            what = grammar.FRAME_WORDS[m.group(1).upper()]
            self.set_at_run_time[what][m.group(2)] = (
                f"{what} {m.group(2)} set at run time by {m.group(1).upper()}[{m.group(2)}]={m.group(3)} (line {line})")

    def key(self):
        """What the state holds, hashable: motions read with equal keys run with the same tool and frame."""
        return (self.tool, self.frame, self.why["tool"], self.why["frame"],
                *(tuple(sorted(self.set_at_run_time[what].items())) for what in ("tool", "frame")))

    def copy(self):
        """A copy that later updates leave as it is."""
        return _State(self.tool, self.frame, dict(self.why), {what: dict(numbers) for what, numbers in
                                                              self.set_at_run_time.items()})

    def runtime(self):
        """Whether a tool or user frame is set at run time (some motion's may then be unknown)."""
        return any(self.why.values()) or any(self.set_at_run_time.values())

    def reason(self, what, number):
        """Why the tool or frame a motion uses is only known at run time ("" if it is not)."""
        if number is None:
            return self.why[what]
        return self.set_at_run_time[what].get(number, "")


def read(path):
    """Read a FANUC .LS program.

    The /MN motion lines and /POS positions a CAM post-processor writes
    (`grammar.WRITTEN_MOTION`, `grammar.POSITION_LAYOUT`) are read together as columns
    (`Program.from_tables`: no object per motion or position); every other
    /MN line is read one by one, in order, and the tool and user frame it
    sets hold for the motions after it.

    Raises
    ------
    ReadError
        Malformed text, numbers out of range, motions to positions
        without a /POS entry or not taught, no /END line (the file is
        cut off) or text after it (`grammar.AFTER_END`): the controller's
        loader refuses both too.
    """
    source = read_source(path)
    masked = grammar.masked(source.text)
    lines = Lines(source.text)
    head = next((source.text[s:e] for _, s, e in lines if source.text[s:e].strip()), "")
    if not head.lstrip().upper().startswith("/PROG"):
        raise ReadError(f"{path}: not a FANUC .LS program: it does not start with /PROG")
    name = head.split()[1] if len(head.split()) > 1 else Path(path).stem
    starts, ends = _line_offsets(lines)
    count = len(starts)
    by_line = _LONE_CR.sub("\n", masked) if "\r" in masked else masked  # `^` and `$` at every line's ends
    headers = _sections(source, by_line, lines, ends)
    pos_start, pos_end = None, len(source.text)
    in_mn = np.zeros(count + 1, dtype=bool)  # by line number (1-based): a line of the /MN section
    for (number, what), (following, _) in zip(headers, headers[1:] + [(count + 1, None)]):
        if what == "POS":
            pos_start = int(ends[number - 1])
        elif what == "END" and pos_start is not None:
            pos_end = int(starts[number - 1])
        in_mn[number + 1:following] = what == "MN"
    table, points, unread = _positions(source, masked, lines, starts, pos_start, pos_end)
    targets = TargetRows(table)
    from trajcomp.formats.fanuc import posreg  # it reads positions as this module does

    sources, registers, register_why, notes = (source,), {}, {}, ()
    if posreg.used_registers(masked):
        targets = list(targets)  # the registers' targets join the positions (objects)
        registers_source, registers, register_why, notes = posreg.resolve(path, masked, lines, targets, 1)
        sources += (registers_source,) if registers_source is not None else ()
    written = columns.written_motions(by_line, starts, ends, in_mn, points, unread)
    covered = np.zeros(count + 1, dtype=bool)  # lines of a motion or an instruction: the others are statements
    covered[written["line"]] = True
    state, one_by_one, speed_at, kept, blocks, steps = _State(), [], [], [], {}, []
    done = 0  # the written motions before the instruction
    for number, last, start, end, content in _instructions(masked, starts, ends, np.flatnonzero(in_mn & ~covered)):
        covered[number:last + 1] = True
        upto = int(np.searchsorted(written["line"], number))
        blocks.setdefault(state.key(), (state.copy(), []))[1].append(np.arange(done, upto))
        done = upto
        state.update(content, number)
        m = grammar.MOTION.match(content)
        if not m:
            steps += _flow_steps(content, number)
            kept.append((number, start, end, tuple(points[int(n)] for n in grammar.POINT_REF.findall(content)
                                                   if int(n) in points)))
            continue
        motion = _motion(m, points, unread, source.name, number, source.text[start:end], registers, register_why)
        speed = grammar.SPEED_FIELD.search(masked, start, end)  # where re-timing writes the motion's speed
        speed_at.append((-1, -1) if speed is None else speed.span())
        one_by_one.append(_with_frames(motion, targets, state))
    blocks.setdefault(state.key(), (state.copy(), []))[1].append(np.arange(done, len(written["line"])))
    parts = [(np.concatenate(rows), at) for at, rows in blocks.values()]
    motions = MotionTable.merged([MotionTable.of(one_by_one)]
                                 + [_motion_block(written, rows, at, table, source.text) for rows, at in parts])
    speed_at = np.concatenate([np.array(speed_at, dtype=np.int64).reshape(-1, 2)]
                              + [written["speed"][rows] for rows, _ in parts])
    order = np.argsort(np.concatenate([[m.line for m in one_by_one]] + [written["line"][rows] for rows, _ in parts]),
                       kind="stable")
    speed_at = speed_at[order].astype(offset_type(source.text))
    motions = dataclasses.replace(motions, spans=SpanColumns(0, source.text, ("speed",), speed_at[:, :1],
                                                             speed_at[:, 1:]))
    statements = _statements(source.text, starts, ends, np.flatnonzero(~covered[1:]) + 1, kept)
    tools, frames = {"0": np.eye(4)}, {"0": np.eye(4)}
    if isinstance(targets, TargetRows):
        program = Program.from_tables("fanuc_ls", name, statements, motions, table, sources, tools=tools,
                                      frames=frames, notes=notes)
    else:
        program = Program("fanuc_ls", name, ItemRows(statements, motions), tuple(targets), tools, frames, sources,
                          notes=notes)
    # CALL, JMP LBL, IF, SELECT, FOR, WAIT: starts and stops
    return flow.program_followed(_with_controller_frames(program, path), steps, {})


def _sections(source, by_line, lines, ends):
    """``[(line, word)]`` of the section headers (`grammar.SECTION_WORD` at a line's start) up to the first /END;
    ReadError where there is none (the program is cut off) or where more than `grammar.AFTER_END` follows it."""
    headers = []
    for m in grammar.SECTION_WORD.finditer(by_line):
        number = lines.number(m.start())
        if by_line[lines.starts[number - 1]:m.start()].strip():
            continue
        headers.append((number, m.group(1)))
        if m.group(1) == "END":
            break
    else:
        last = last_line(lines)
        fail(source.name, last, lines.line(last), "no /END after it: the program is cut off")
    after = int(ends[headers[-1][0] - 1])
    if not grammar.AFTER_END.fullmatch(source.text, after):
        extra = lines.number(after + len(source.text[after:]) - len(source.text[after:].lstrip()))
        fail(source.name, extra, lines.line(extra), "text after /END: nothing but blank lines may follow it "
                                                   "(the controller refuses to load the program)")
    return headers


def _flow_steps(content, line):
    """The `trajcomp.programs.flow.Step` s of one /MN instruction that is not a motion (none for most)."""
    text = content.strip().rstrip(";").strip()
    word = text.split("(")[0].split()[0].upper() if text else ""
    if grammar.WAIT.match(text):
        return [Step("wait", line=line)]
    if m := grammar.LABEL.match(text):
        return [Step("label", m.group(1), line=line)]
    if word == "FOR":
        return [Step("loop", line=line)]
    if word == "IF" and grammar.THEN.search(text):
        return [Step("if", line=line)]
    if word in grammar.BLOCK_WORDS and text.upper() == word:
        return [Step(grammar.BLOCK_WORDS[word], line=line)]
    conditional = bool(grammar.CONDITION.match(text))
    if m := grammar.JUMP.search(text):
        return [Step("jump", m.group(1), conditional, line)]
    if (conditional or word == "CALL") and (m := grammar.CALL.search(text)):
        call = Step("call", m.group(1), f"program {m.group(1).upper()}, which may move the arm", line)
        return [Step("if", line=line), call, Step("endif", line=line)] if conditional else [call]
    return []


def _with_controller_frames(program, path):
    """The program with the user frames and tools its motions use and it does not define read from its
    controller's SYSFRAME.VA (`trajcomp.formats.fanuc.sysframe`), and the report's notes on them."""
    from trajcomp.formats.fanuc import sysframe

    if sysframe.find(path) is None:  # no backup beside the program: nothing to look at
        return program
    uses = program.target_uses()
    wanted = {what: {n for n in set(uses[what].tolist()) if n is not None and n.isdigit() and n not in defined}
              for what, defined in (("tool", program.tools), ("frame", program.frames))}
    found, notes = sysframe.tables(path, wanted)
    if not notes:
        return program
    return program.replace(tools={**program.tools, **found["tool"]}, frames={**program.frames, **found["frame"]},
                           notes=program.notes + notes)


def _line_offsets(lines):
    """Starts and ends (ndarray of int, shape (L,)) of the lines `Lines` gives; an end excludes the line ending."""
    text = lines.text
    starts = np.array(lines.starts, dtype=np.int64)
    ending = np.ones(len(starts), dtype=np.int64)
    if "\r\n" in text:
        ending[:-1] += np.array([text[k - 2:k] == "\r\n" for k in lines.starts[1:]], dtype=bool)
    ends = np.append(starts[1:], len(text)) - ending
    ends[-1] = len(text)
    if len(starts) > 1 and starts[-1] == len(text):  # nothing after the last line ending
        starts, ends = starts[:-1], ends[:-1]
    return starts, ends


def _instructions(masked, starts, ends, numbers):
    """``(first line, last line, start, end, content)`` of the /MN instructions on lines ``numbers`` (ascending).

    A line ``  12:L P[3] ...`` is an instruction, ``content`` the text after
    its number. An instruction not ended by its ``;`` (``   3:C P[3]``)
    goes on over the lines after it that have no number, ``  :  P[4] ..``
    or ``       P[4] ..`` (RoboDK's posts write it so), up to one that ends
    it; after an instruction ended, a line ``:L P[3] .. ;`` is an
    instruction of its own, unnumbered (MakeTP numbers it; the Grasshopper
    plug-in Robots writes every instruction so). Other lines are none
    (statements).
    """
    out = []
    for number in numbers.tolist():
        start, end = int(starts[number - 1]), int(ends[number - 1])
        text = masked[start:end]
        head = grammar.NUMBERED.match(text)
        if not head and out and out[-1][1] == number - 1 and not grammar.CLOSED.search(out[-1][4]):
            first, _, begin, _, content = out[-1]
            c = grammar.CONTINUED.match(text)
            out[-1] = (first, number, begin, end, content + " " + (c.group(1) if c else text))
        elif head := head or grammar.CONTINUED.match(text):
            out.append((number, number, start, end, head.group(head.lastindex)))
    return out


def _statements(text, starts, ends, plain, kept):
    """The statements: lines ``plain`` (their numbers, ascending) and the instructions ``kept``
    (``(line, start, end, refs)``), as a `StatementTable` in line order."""
    offset = offset_type(text)
    kept_line, kept_start, kept_end = (np.array([k[j] for k in kept], dtype=np.int64) for j in range(3))
    at = np.searchsorted(plain, kept_line)  # both ascending, no line in both: merged in line order
    line = np.insert(plain, at, kept_line)
    start, end = (np.insert(offsets[plain - 1].astype(offset), at, more) for offsets, more in
                  ((starts, kept_start), (ends, kept_end)))
    refs = {int(at[k]) + k: named[3] for k, named in enumerate(kept) if named[3]}
    return StatementTable(line, TextSlices(text, start, end), 0, refs)


def _motion_block(written, rows, state, table, text):
    """The `MotionTable` of the written motions ``rows`` (K,), read with the tool and frame ``state`` in force.

    A motion whose position's tool or user frame is set at run time is not
    compensated, as `_with_frames` decides for the motions read one by one.
    """
    target = written["target"][rows]
    block = MotionTable.block(written["kind"][rows], target, written["line"][rows],
                              _Squeezed(text, written["start"][rows], written["end"][rows]),
                              speed=written["value"][rows], speed_unit=written["unit"][rows],
                              zone=written["zone"][rows], tool=state.tool, frame=state.frame)
    if not state.runtime():
        return block
    why = []
    for tool, frame, joint in zip(table.tool[target].tolist(), table.frame[target].tolist(),
                                  table.is_joint[target].tolist()):
        tool, frame = (state.tool if tool is None else tool), (state.frame if frame is None else frame)
        why.append(("" if joint else state.reason("tool", tool)) or state.reason("frame", frame))
    index = [k for k, reason in enumerate(why) if reason]
    return block.with_rows(index, target=-1, reason=[why[k] for k in index],
                           refs=[(int(target[k]),) for k in index]) if index else block


class _Squeezed(TextSlices):
    """Lines of a text given by offsets (N,), each built on access with its white space runs made one space."""

    def __getitem__(self, k):
        pieces = super().__getitem__(k)
        return [" ".join(p.split()) for p in pieces] if isinstance(k, slice) else " ".join(pieces.split())


class _Named(TextSlices):
    """Names ``P[n]`` of positions from where their numbers ``n`` are written (N,), each built on access."""

    def __getitem__(self, k):
        numbers = super().__getitem__(k)
        return [f"P[{n}]" for n in numbers] if isinstance(k, slice) else f"P[{numbers}]"


def _with_frames(motion, targets, state):
    """The motion with the tool and frame it runs with; not compensated if one is set at run time."""
    motion = replaced(motion, tool=state.tool, frame=state.frame)
    for index in (motion.via, motion.target):
        if index is None:
            continue
        target = targets[index]
        tool = target.tool if target.tool is not None else state.tool
        frame = target.frame if target.frame is not None else state.frame
        why = ("" if target.is_joint else state.reason("tool", tool)) or state.reason("frame", frame)
        if not why and not target.is_joint and target.name.startswith("PR[") and None in (tool, frame):
            unset = " and ".join(word for word, number in (("UTOOL_NUM", tool), ("UFRAME_NUM", frame))
                                 if number is None)
            why = (f"{target.name} is a position in the tool and user frame active when the line runs: the program "
                   f"sets no {unset} before it")
        if why:
            points = tuple(i for i in (motion.via, motion.target) if i is not None)
            return dataclasses.replace(motion, target=None, via=None, reason=why, refs=motion.refs + points)
    return motion


def _motion(m, points, unread, name, number, original, registers, register_why):
    kind = KINDS[m.group(1).upper()]
    rest = m.group(4)
    refs = [(m.group(2).upper(), m.group(3))]
    if kind == CIRCULAR:
        second = grammar.POINT.search(rest) or grammar.REGISTER_POINT.search(rest)
        if not second:
            fail(name, number, original, "C needs a via point and an end point")
        if second.re is grammar.POINT:
            refs.append(("P", second.group(1)))
            rest = second.group(2)
        else:
            refs.append(("PR", second.group(2)))
            rest = second.group(3)
    spec = grammar.SPEED_TERM.match(rest)
    if not spec:
        fail(name, number, original, "motion needs a speed and FINE, CNT or CR")
    speed, unit, speed_why = None, "%", ""
    if spec.group(1) is not None:
        scale, unit = grammar.speed_unit(spec.group(2))
        speed = finite(spec.group(1), name, number, original, "speed") * scale
    elif (term := " ".join(rest[: spec.start(3)].split())).lower() != grammar.MAX_SPEED:
        speed_why = f"speed {term}: a register, set at run time"
    blend = spec.group(4) or spec.group(5)
    zone = finite(blend, name, number, original, "CNT") if blend is not None else None
    share, speed_why = _acceleration_share(rest[spec.end(3):], speed_why, name, number, original)
    runtime = grammar.RUNTIME.search(rest)
    found, reason = [], ""
    for kind_ref, ref in refs:
        if kind_ref == "P" and ref.isdigit() and int(ref) in unread:
            found.append(None)
            reason = reason or f"P[{ref}] {unread[int(ref)]}"
        elif kind_ref == "PR" and not runtime and ref in registers:  # read from POSREG.VA (`posreg`)
            found.append(registers[ref])
        elif runtime or kind_ref == "PR" or not ref.isdigit():
            found.append(None)
            reason = reason or (f"{runtime.group(1)} applied at run time" if runtime
                                else f"position register PR[{ref}]"
                                     + register_why.get(ref, "" if ref.isdigit() else ": its number is set at run time")
                                if kind_ref == "PR"
                                else f"P[{ref}]: position index computed at run time")
        elif int(ref) not in points:
            fail(name, number, original, f"P[{ref}] has no entry in /POS")
        else:
            found.append(points[int(ref)])
    named = tuple(points[int(r)] if k == "P" else registers[r] for k, r in refs
                  if (k == "P" and r.isdigit() and int(r) in points) or (k == "PR" and r in registers))
    motion = Motion(
        kind=kind,
        target=found[-1],
        via=found[0] if kind == CIRCULAR else None,
        speed=speed,
        speed_unit=unit,
        zone=zone or None,
        line=number,
        text=" ".join(original.split()),
        reason=reason,
        refs=named if reason else (),
        speed_why=speed_why,
        acceleration_share=share,
    )
    if reason:
        return dataclasses.replace(motion, target=None, via=None)
    return whole_circle(motion)


def _acceleration_share(options, speed_why, name, number, original):
    """``(share, speed_why)`` of a motion's options (after its FINE / CNT): ``ACC n`` runs its accelerations at n %
    of the arm's (`trajcomp.programs.items.Motion.acceleration_share`; above 100 read as 100: the timing keeps the
    arm's limits, and a time written at them is no shorter than the controller's steeper ramps take); ``ACC R[n]``
    is set at run time."""
    m = grammar.ACC.search(options)
    if m is None:
        return None, speed_why
    if not re.fullmatch(NUMBER, m.group(1)):
        return None, speed_why or f"ACC {m.group(1)}: a register, set at run time"
    percent = finite(m.group(1), name, number, original, "ACC")
    if percent <= 0:
        fail(name, number, original, f"ACC {m.group(1)}: an acceleration override is positive")
    return (percent / 100.0 if percent < 100.0 else None), speed_why


def _positions(source, masked, lines, starts, start, end):
    """Targets of the /POS section as a `TargetTable`, ``{P number: target index}`` and ``{P number: why}`` of
    positions not read.

    The positions written as the pendant writes them are read at once
    (`columns.written_positions`), the others one by one (`_position`), in the
    order of the section's entries (``P[n]{ .. };``).
    """
    points, unread, order, slow = {}, {}, [], []  # order: row of the written ones, or -1 - k of slow[k]
    if start is not None:
        written = columns.written_positions(masked, start, end)
        heads = columns.entry_heads(masked, start, end)
        if np.array_equal(heads, written["at"][:, 0]):  # every entry is written as the pendant writes it
            _once(source, written["p"].tolist(), heads.tolist(), starts)
            points = dict(zip(written["p"].tolist(), range(len(heads))))
            return _target_table(source.text, written, np.arange(len(heads)), [], starts), points, unread
        at = dict(zip(written["at"][:, 0].tolist(), range(len(written["at"]))))
        written_end, written_p = written["at"][:, 1].tolist(), written["p"].tolist()
        reached = start  # the entries are those `_POS.finditer` gives: where one ends the next is looked for
        given = []  # (P number, offset) of each entry, in order
        for head in heads.tolist():
            if head < reached:
                continue
            if (k := at.get(head)) is not None:
                given.append((written_p[k], head))
                points[written_p[k]] = len(order)
                order.append(k)
                reached = written_end[k]
            elif m := grammar.POSITION_ENTRY.match(masked, head, end):
                reached = m.end()
                given.append((int(m.group(1)), head))
                target = _position(source, masked, lines, m, unread)
                if target is not None:
                    points[int(m.group(1))] = len(order)
                    order.append(-1 - len(slow))
                    slow.append((target, m.span(1)))
        _once(source, [number for number, _ in given], [offset for _, offset in given], starts)
    else:
        written = columns.written_positions(masked, 0, 0)
    return _target_table(source.text, written, np.array(order, dtype=np.int64), slow, starts), points, unread


def _once(source, numbers, offsets, starts):
    """Refuse a /POS section that gives a position number twice (``numbers``: list of int, of its entries, at
    ``offsets`` of ``source``'s text; ``starts``: its lines' start offsets), as the controller refuses to load it."""
    if len(set(numbers)) == len(numbers):
        return
    first = {}
    for number, offset in zip(numbers, offsets):
        line = int(np.searchsorted(starts, offset, side="right"))
        if number in first:
            fail(source.name, line, source.text[offset:offset + 40].splitlines()[0],
                 f"P[{number}] is given again in /POS (first at line {first[number]}): a program has one of each")
        first[number] = line


def _target_table(text, written, order, slow, starts):
    """The `TargetTable` of positions in ``order`` (N,): row k of ``written`` where >= 0, else ``slow[-1 - k]``
    (``(Target, offsets of its P number)``)."""
    n, rows = len(order), order[order >= 0]
    fast = order >= 0
    one_by_one = TargetTable.of([t for t, _ in slow])
    roles = XYZWPR + ("config",) + (JOINTS if any(t.is_joint for t, _ in slow) else ())
    offset = offset_type(text)
    span_at = np.full((n, 2, len(roles)), -1, dtype=offset)
    span_at[fast, :, :7] = written["spans"][rows]
    column = {role: j for j, role in enumerate(roles)}
    for k, (target, _) in zip(np.flatnonzero(~fast).tolist(), slow):
        for role, span in target.spans.items():
            span_at[k, :, column[role]] = span.start, span.end
    number_at = np.empty((n, 2), dtype=offset)
    number_at[fast] = written["number"][rows]
    number_at[~fast] = np.array([at for _, at in slow], dtype=np.int64).reshape(-1, 2)

    def merged(fast_values, slow_values, dtype):
        if not len(slow):
            return np.asarray(fast_values, dtype=dtype)
        out = np.empty((n,) + np.shape(slow_values)[1:], dtype=dtype)
        out[fast], out[~fast] = fast_values, slow_values
        return out

    vector = written["xyzwpr"][rows]
    vector = np.concatenate([vector[:, :3], np.radians(vector[:, 5:2:-1])], axis=1)  # A, B, C = R, P, W
    config = merged(written["config"][rows], columns.objects(one_by_one.config), object)
    return TargetTable(
        pose=merged(pose_to_matrix(vector.reshape(-1, 6)), one_by_one.pose, float),
        is_joint=merged(np.zeros(len(rows), dtype=bool), one_by_one.is_joint, bool),
        joints=merged(np.full((len(rows), 6), np.nan), one_by_one.joints, float) if len(slow)
        else np.broadcast_to(np.nan, (n, 6)),  # every row Cartesian: one NaN row shared
        line=merged(np.searchsorted(starts, written["at"][rows, 0], side="right"), one_by_one.line, np.int64),
        config=tuple(config.tolist()),
        tool=merged(written["ut"][rows], one_by_one.tool, object),
        frame=merged(written["uf"][rows], one_by_one.frame, object),
        external=tuple(merged(columns.objects([None] * len(rows)), columns.objects(one_by_one.external),
                              object).tolist()),
        edited=np.zeros(n, dtype=bool), name=_Named(text, number_at[:, 0], number_at[:, 1]),
        spans=SpanColumns(0, text, roles, span_at[:, 0], span_at[:, 1]))


def _position(source, masked, lines, m, unread):
    """The target of a /POS entry (`_POS` match ``m``) read one by one, or None (its why put in ``unread``)."""
    body_start = m.start(2)
    body = masked[body_start:m.end(2)]
    groups = {int(g.group(1)): (body_start + g.start(2), g.group(2)) for g in grammar.GROUPS.finditer(body)}
    if 1 not in groups:
        return None
    gp_start, gp = groups[1]
    line = lines.number(m.start())
    original = source.text[m.start():m.end()]
    label = f"P[{m.group(1)}]"
    if "*" in "".join(f.group(2) for f in grammar.COORDINATE.finditer(gp)):
        unread[int(m.group(1))] = (f"is not taught (its position is ********, line {line}): the controller faults "
                                   "only if this line runs")
        return None
    fields, units = {}, {}
    for f in grammar.COORDINATE.finditer(gp):
        fields[f.group(1).lower()] = Span(0, gp_start + f.start(2), gp_start + f.end(2), f.group(2))
        units[f.group(1).lower()] = f.group(3).lower()
    if "x" not in fields and "j1" not in fields and grammar.OTHER_REPRESENTATION.search(gp):
        unread[int(m.group(1))] = (f"is stated as RX, RY, RZ, RW, RP, RR (line {line}), a representation "
                                   "trajcomp does not read: left as written")
        return None

    def value(role):
        limit = (LENGTH_LIMIT if role in "xyz" or units[role] == "mm"  # a track's E1 in mm
                 else ANGLE_LIMIT if role in "wpr" else JOINT_LIMIT)
        return finite(fields[role].text, source.name, line, original, f"{label} {role.upper()}", limit)

    frames = {f.group(1).upper(): f.group(2) for f in grammar.FRAME_NUMBER.finditer(gp)}
    external = [value(e) for e in sorted(f for f in fields if f.startswith("e"))]
    for k in sorted(g for g in groups if g > 1):
        external += [finite(f.group(2), source.name, line, original, f"{label} GP{k} {f.group(1)}", LENGTH_LIMIT)
                     for f in grammar.COORDINATE.finditer(groups[k][1]) if "*" not in f.group(2)]
    where = {"name": label, "line": line, "tool": frames.get("UT"), "frame": frames.get("UF"),
             "external": np.array(external) if external else None}
    if "j1" in fields:
        missing = [j for j in JOINTS if j not in fields]
        if missing:
            fail(source.name, line, original, f"{label} lacks {', '.join(j.upper() for j in missing)}")
        joints = np.radians([value(j) for j in JOINTS])
        return Target(**where, joints=joints, spans={j: fields[j] for j in JOINTS})
    missing = [c for c in XYZWPR if c not in fields]
    if missing:
        fail(source.name, line, original, f"{label} lacks {', '.join(c.upper() for c in missing)}")
    x, y, z, w, p, r = (value(c) for c in XYZWPR)
    spans = {c: fields[c] for c in XYZWPR}
    config = ()
    c = grammar.CONFIG.search(gp)
    if c:
        v = grammar.CONFIG_VALUE.match(c.group(1))
        if not v and grammar.SCARA_CONFIG.match(c.group(1)):
            fail(source.name, line, original, f"{label}: CONFIG '{c.group(1)}' is a 4-axis arm's (SCARA, "
                                              "arm left or right): 4-axis arms are not supported")
        if not v:
            fail(source.name, line, original, f"{label}: malformed CONFIG")
        config = grammar.config(c.group(1))
        spans["config"] = Span(0, gp_start + c.start(1), gp_start + c.end(1), c.group(1))
    pose = pose_to_matrix([x, y, z, *np.radians([r, p, w])])
    return Target(**where, pose=pose, config=config, spans=spans)
