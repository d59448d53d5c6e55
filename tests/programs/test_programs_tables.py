"""The column form of a program (`trajcomp.programs.tables`): a table holds every field of its motions and
statements, in program order, and a table-backed program reads as the same program held as objects."""

import numpy as np

from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR, Motion, Span, SpanColumns, Statement, Target
from trajcomp.programs.program import Program
from trajcomp.programs.tables import MotionTable, StatementTable, TargetTable

TEXT = "DEF p()\nLIN P1\nPTP P2 C_PTP\nLIN P3\nCIRC P1, P2\nEND\n"


def _motions():
    """Four motions of `TEXT` as objects, every field set somewhere."""
    return (
        Motion(LINEAR, target=0, speed=100.0, zone=1.0, line=2, text="LIN P1",
               spans={"speed": Span(0, 11, 14, "0.1")}),
        Motion(JOINT, target=1, speed=50.0, speed_unit="%", line=3, text="PTP P2 C_PTP", speed_why="set at run time"),
        Motion(LINEAR, line=4, text="LIN P3", reason="P3 is changed at run time", refs=(2,)),
        Motion(CIRCULAR, target=1, via=0, line=5, text="CIRC P1, P2", orientation_speed=0.5, axis_position=False),
    )


def test_a_table_of_motions_gives_them_back_field_for_field():
    motions = _motions()
    table = MotionTable.of(motions)
    assert [table.motion(k) for k in range(len(table))] == list(motions)
    assert table.refs == {2: (2,)}


def test_merged_tables_are_in_program_order_with_every_field():
    motions = _motions()
    read_at_once = MotionTable.block(LINEAR, [0, 2], [2, 4], ["LIN P1", "LIN P3"], speed=[100.0, np.nan],
                                     speed_unit="mm/s", zone=[1.0, np.nan], tool="1", frame="2")
    one_by_one = MotionTable.of([motions[3], motions[1]])  # any order: merged sorts by line
    merged = MotionTable.merged([read_at_once, one_by_one])
    assert merged.line.tolist() == [2, 3, 4, 5]
    assert merged.motion(1) == motions[1] and merged.motion(3) == motions[3]
    assert merged.motion(0) == Motion(LINEAR, target=0, speed=100.0, zone=1.0, tool="1", frame="2", line=2,
                                      text="LIN P1")
    changed = merged.with_rows([2], target=[-1], reason=["P3 is changed at run time"], refs=[(2,)])
    assert changed.motion(2).reason == "P3 is changed at run time" and changed.motion(2).target is None
    assert changed.motion(2).refs == (2,) and merged.motion(2).refs == ()  # the original is unchanged
    assert changed.refs == {2: (2,)}


def test_spans_of_columns_are_kept_through_a_merge():
    columns = SpanColumns(0, TEXT, ("motion",), np.array([[8], [28]]), np.array([[11], [31]]))
    block = MotionTable.block(LINEAR, [0, 2], [2, 4], ["LIN P1", "LIN P3"], speed=[np.nan] * 2, speed_unit="mm/s",
                              zone=[np.nan] * 2, spans=columns)
    merged = MotionTable.merged([block, MotionTable.of([_motions()[1]])])
    assert dict(merged.motion(0).spans) == {"motion": Span(0, 8, 11, "LIN")}
    assert dict(merged.motion(2).spans) == {"motion": Span(0, 28, 31, "LIN")}
    assert merged.motion(1).spans == {}


def test_a_table_backed_program_reads_as_the_program_of_objects():
    motions = _motions()
    statements = (Statement(1, "DEF p()"), Statement(6, "END", refs=(2,)))
    targets = tuple(Target(name, line=0, pose=np.eye(4)) for name in ("P1", "P2", "P3"))
    objects = Program("krl", "p", (statements[0], *motions, statements[1]), targets)
    table = Program.from_tables("krl", "p", StatementTable.of(statements), MotionTable.of(motions),
                                TargetTable.of(targets))
    assert list(table.items) == list(objects.items)
    assert list(table.motions) == list(objects.motions)
    assert table.referenced_targets() == objects.referenced_targets() == ((2, 4, "LIN P3"), (2, 6, "END"))
    assert table.not_compensated() == objects.not_compensated()


def test_a_program_with_other_target_numbers_keeps_the_uses_it_built_and_builds_the_same_ones():
    targets = tuple(Target(name, line=0, pose=np.eye(4)) for name in ("P1", "P2", "P3"))
    for program in (Program("krl", "p", _motions(), targets),
                    Program.from_tables("krl", "p", (), MotionTable.of(_motions()), TargetTable.of(targets))):
        uses, usage = program.target_uses(), program.usage_table()
        moved = program.with_targets([0, 1], poses=np.stack([np.eye(4)] * 2) + 1.0)
        assert moved.target_uses() is uses and moved.usage_table() is usage  # kept, not built again
        fresh = moved.replace()  # the same program without what this one kept: built from its own items
        assert fresh.target_uses() is not uses
        for name, built in fresh.target_uses().items():
            np.testing.assert_array_equal(built, uses[name])
        assert fresh.usage_table().index.tolist() == usage.index.tolist() == [0, 1]
        assert np.array_equal(moved.target_table().pose[0], np.eye(4) + 1.0)


def test_statement_tables_merge_in_the_parts_order():
    first = StatementTable([1, 3], ["A", "B"], refs={1: (0,)})
    merged = StatementTable.merged([first, [Statement(7, "C", source=1)]])
    assert list(merged) == [Statement(1, "A"), Statement(3, "B", refs=(0,)), Statement(7, "C", source=1)]
    assert merged.naming() == (Statement(3, "B", refs=(0,)),)


def test_span_offsets_of_a_merged_table_are_each_motions_span_of_the_role():
    columns = SpanColumns(0, TEXT, ("motion", "speed"), np.array([[8, -1], [28, 14]]), np.array([[11, -1], [31, 16]]))
    block = MotionTable.block(LINEAR, [0, 2], [2, 4], ["LIN P1", "LIN P3"], speed=[np.nan] * 2, speed_unit="mm/s",
                              zone=[np.nan] * 2, spans=columns)
    merged = MotionTable.merged([block, MotionTable.of(_motions()[:2])])  # lines 2, 2, 3, 4
    source, start, end = merged.span_offsets("speed")
    assert start.tolist() == [-1, 11, -1, 14] and end.tolist() == [-1, 14, -1, 16]
    assert source.tolist() == [-1, 0, -1, 0]
    assert merged.span_offsets("motion")[1].tolist() == [8, -1, -1, 28]
    assert MotionTable.of(_motions()).span_offsets("motion")[1].tolist() == [-1] * 4

