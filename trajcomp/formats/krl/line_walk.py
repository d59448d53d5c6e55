"""The KRL reader's line walk: the motions read at once (`trajcomp.formats.krl.at_once`) joined with the lines
read one by one (`trajcomp.formats.krl.reader`), in the order the .src states them."""

import array

import numpy as np

from trajcomp.formats.krl.grammar import AXES, MOTION_SPANS
from trajcomp.formats.number_fields import offset_type
from trajcomp.programs.items import JOINT, LINEAR, SpanColumns
from trajcomp.programs.tables import MotionTable, TargetRows, TextSlices, joined_targets


def other_lines(lines, taken):
    """``(number, start, end)`` of the lines of ``lines`` (`Lines`) not in ``taken`` (ascending line numbers), as
    `Lines` iterates them."""
    starts, text = lines.starts, lines.text
    other = np.ones(len(starts) + 1, dtype=bool)
    other[0] = False
    other[taken] = False
    out = []
    for number in np.flatnonzero(other).tolist():
        start = starts[number - 1]
        stop = starts[number] if number < len(starts) else len(text)
        line = text[start:stop].rstrip("\r\n")
        if number == len(starts) and not line:
            break
        out.append((number, start, start + len(line)))
    return out


class Walk:
    """The motions read at once (`written_motions`) given the reader's state in force at their lines.

    The .src's other lines are read one by one in order; before each,
    `motions_before` takes the motions read at once above it: with the
    tool, base, speeds and zone then in force (a snapshot shared by the
    rows between two other lines), or, where that state is known only at
    run time (a tool or base set at run time, routine parameters), in a
    spline block whose WITH bounds its external axes, or where the point
    is not one the program has declared so far, through the
    one-by-one read (`trajcomp.formats.krl.reader._Reader.statement`), which says why.
    """

    def __init__(self, reader, index, masked, written, first_inline):
        self.reader, self.index, self.masked, self.written = reader, index, masked, written
        self.first_inline = first_inline  # the target index (`targets`) of row 0 of the inline points
        self.next = 0  # the first motion read at once not yet taken
        # the rows kept as columns, the index of each one's point when read, its state (in `states`)
        self.rows, self.point, self.snapshot = array.array("q"), array.array("q"), array.array("q")
        self.states = []

    def motions_before(self, line_no):
        """Take the motions read at once above line ``line_no``."""
        reader, written = self.reader, self.written
        stop = int(np.searchsorted(written["line"], line_no))
        if stop == self.next:
            return
        rows = range(self.next, stop)
        self.next = stop
        one_by_one = bool(reader.tool_why or reader.base_why or reader.params or reader.block_caps)
        text = reader.sources[self.index].text
        inline = written["inline"][rows.start:rows.stop]
        named = np.flatnonzero(inline < 0)
        state = len(self.states)
        self.states.append((reader.tool, reader.base, reader.speed_ptp, reader.speed_cp, reader.zone,
                            reader.speed_spans[JOINT], reader.speed_spans[LINEAR], reader.speed_why[JOINT],
                            reader.speed_why[LINEAR]))
        point = np.full(len(rows), -1, dtype=np.int64)
        if not one_by_one:
            point[named] = [reader.points.get(text[a:b].upper(), -1) for a, b in
                            zip(written["name_start"][rows.start + named].tolist(),
                                written["name_end"][rows.start + named].tolist())]
            points = self.first_inline + inline[inline >= 0]  # the inline points: targets in program order
            point[inline >= 0] = len(reader.targets) + np.arange(len(points))
            reader.targets.extend(points.tolist())
        known = point >= 0
        self.rows.frombytes(np.arange(rows.start, rows.stop, dtype=np.int64)[known].tobytes())
        self.point.frombytes(point[known].tobytes())
        self.snapshot.frombytes(np.full(np.count_nonzero(known), state, dtype=np.int64).tobytes())
        for row in (rows.start + np.flatnonzero(~known)).tolist():  # the motion lines read one by one say why
            reader.statement(self.index, self.masked, int(written["line"][row]), int(written["start"][row]),
                             int(written["start"][row]) + len(text[written["start"][row]:written["end"][row]]
                                                              .rstrip("\r\n")))

    def table(self, resolved):
        """The `MotionTable` of the rows kept as columns, their targets ``resolved`` (`_resolved_rows`)."""
        written, text = self.written, self.reader.sources[self.index].text
        rows, state = np.frombuffer(self.rows, dtype=np.int64), np.frombuffer(self.snapshot, dtype=np.int64)
        tool, base, speed_ptp, speed_cp, zone, span_ptp, span_cp, why_ptp, why_cp = (
            np.array(column + (None,), dtype=object)[:-1] for column in zip(*self.states))  # (S,) each

        def number(values):
            return np.array([np.nan if v is None else v for v in values], dtype=float)

        def offsets(spans):
            return np.array([(-1, -1) if s is None else (s.start, s.end) for s in spans], dtype=np.int64).reshape(-1, 2)

        joint, approximated = written["joint"][rows], written["approximated"][rows]
        span = np.where(joint[:, None], offsets(span_ptp)[state], offsets(span_cp)[state])
        none = np.full(len(rows), -1)
        start = np.stack([written["keyword_start"][rows], none, written["name_start"][rows], none, span[:, 0]], 1)
        end = np.stack([written["keyword_end"][rows], none, written["name_end"][rows], none, span[:, 1]], 1)
        target, reason, refs, home = resolved
        offset = offset_type(text)  # the spans and the line as int32 where they fit: 48 bytes a motion less
        table = MotionTable(
            kind=np.array([LINEAR, JOINT], dtype=object)[joint.astype(int)], target=target, via=np.full(len(rows), -1),
            speed=np.where(joint, number(speed_ptp)[state], number(speed_cp)[state]),
            speed_unit=np.array(["mm/s", "%"], dtype=object)[joint.astype(int)],
            zone=np.where(approximated, number(zone)[state], np.nan), tool=tool[state], frame=base[state],
            line=written["line"][rows], axis_position=np.zeros(len(rows), dtype=bool),
            text=_Stripped(text, written["start"][rows].astype(offset), written["end"][rows].astype(offset)),
            speed_why=np.where(joint, why_ptp[state], why_cp[state]),
            spans=SpanColumns(self.index, text, MOTION_SPANS, start.astype(offset), end.astype(offset)))
        if len(reason):
            table = table.with_rows(list(reason), target=-1, reason=list(reason.values()), refs=list(refs),
                                    axis_position=home)
        return table


class _Stripped(TextSlices):
    """Lines of a text given by their offsets (N,), each stripped on access (a motion's text as the one-by-one
    read keeps it: `Motion.text`)."""

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [line.strip() for line in super().__getitem__(k)]
        return super().__getitem__(k).strip()


def targets(targets, table, inline):
    """The program's targets: ``targets`` in order, each a row of the .dat's ``table`` (int below its length),
    of the .src's ``inline`` points (int from it) or a `Target`; as `TargetRows` of one table when only one
    holds rows and the objects lie in its file (`joined_targets`: a program written as a CAM post-processor
    writes it, no object each), else a tuple of `Target`."""
    tables = [t for t in (table, inline) if t is not None]
    if len(tables) == 1 and (joined := joined_targets(targets, tables[0], AXES)) is not None:
        return TargetRows(joined)  # the rows of each table are taken once each, in order
    first_inline = 0 if table is None else len(table)
    return tuple(t if not isinstance(t, int) else table.target(t) if t < first_inline else
                 inline.target(t - first_inline) for t in targets)
