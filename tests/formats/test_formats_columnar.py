"""The robot languages' declarations read at once (KRL, RAPID, FANUC LS, URScript) against the line-by-line read, and
the numbers of edited targets formatted together against `format_number`."""

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, TrajcompError, WriteError
from trajcomp.formats.fanuc import columns as fanuc_columns
from trajcomp.formats.fanuc import grammar as fanuc_grammar
from trajcomp.formats.krl import at_once as krl_at_once
from trajcomp.formats.krl import grammar as krl_grammar
from trajcomp.formats.krl import writer as krl_writer
from trajcomp.formats.forms import Number
from trajcomp.formats.rapid import grammar as rapid_grammar
from trajcomp.formats.rapid import reader as rapid_reader
from trajcomp.formats.urscript import reader as urscript_reader
from trajcomp.formats import text_edits
from trajcomp.formats.number_writing import format_number, written_numbers
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.formats.text_edits import Edits, apply_edits, patched, target_edits
from trajcomp.programs.items import SpanColumns
from trajcomp.programs.tables import TargetRows, TextSlices
from trajcomp.arm.transforms import abc_to_matrix

DATA = Path(__file__).parents[1] / "data"
EXAMPLES = Path(__file__).parents[2] / "examples" / "programs"
AT_ONCE = {  # language -> (module, the function reading declarations at once)
    ".src": (krl_at_once, "written_points"),
    ".mod": (rapid_reader, rapid_grammar.WRITTEN_FORMS),  # the forms of the lines read at once
    ".ls": (fanuc_columns, "written_positions"),
    ".script": (urscript_reader, "_literal_poses"),
}
CORPUS = sorted(p for root in (DATA / "programs", EXAMPLES) for p in root.rglob("*")
                if p.suffix.lower() in AT_ONCE)


def _seen(program):
    """Everything a read gives, comparable: targets' numbers bit for bit, spans, items."""
    def bits(array):
        return None if array is None else np.asarray(array).tobytes()

    targets = [(t.name, t.line, bits(t.pose), bits(t.joints), t.config, t.tool, t.frame, bits(t.external),
                dict(t.spans), t.edited) for t in program.targets]
    return targets, [repr(item) for item in program.items], sorted(program.tools), sorted(program.frames)


_FANUC_WRITTEN = fanuc_columns.written_positions
NONE_AT_ONCE = {  # what a language's reader at once gives when it reads nothing
    krl_at_once: lambda *args: (np.zeros(0, dtype=int), None, np.zeros(0, dtype=bool)),
    fanuc_columns: lambda masked, start, end: _FANUC_WRITTEN(masked, 0, 0),
}


def never_written(patch, *written_forms):
    """Patch ``written_forms`` (`trajcomp.formats.forms.Form`) so that no line is found written in them: neither
    at once (a `Number` not run at once) nor by their patterns."""
    for form in written_forms:
        patch.setattr(form, "regex", re.compile(r"(?!)"))
        patch.setattr(form, "elements", form.elements[:1] + (Number(),))


def _line_by_line(path, monkeypatch):
    """The program read with no declaration (FANUC, KRL: nor motion line) read at once."""
    module, function = AT_ONCE[path.suffix.lower()]
    with monkeypatch.context() as patch:
        if isinstance(function, tuple):  # forms: no line written so
            never_written(patch, *function)
        else:
            patch.setattr(module, function, NONE_AT_ONCE.get(module, lambda *args: {}))
        if module is fanuc_columns:  # nor any motion line
            patch.setattr(fanuc_grammar, "WRITTEN_MOTION", re.compile(r"(?!)"))
        if module is krl_at_once:  # nor any motion line, to a name or to an inline point
            never_written(patch, krl_grammar.WRITTEN_MOTION, krl_grammar.INLINE_MOTION)
        return formats.read(path)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_a_corpus_program_reads_the_same_at_once_and_line_by_line(path, monkeypatch):
    try:
        at_once = formats.read(path)
    except ReadError as error:
        with pytest.raises(ReadError) as refused:
            _line_by_line(path, monkeypatch)
        assert str(refused.value) == str(error)
        return
    assert _seen(at_once) == _seen(_line_by_line(path, monkeypatch))


def _krl(tmp_path, lines):
    (tmp_path / "p.src").write_text("DEF p( )\n  PTP XP1\n  LIN XP2 C_DIS\n  LIN XP3\nEND\n")
    (tmp_path / "p.dat").write_text("DEFDAT p\n" + "".join(f"{line}\n" for line in lines) + "ENDDAT\n")
    return tmp_path / "p.src"


@pytest.mark.parametrize("third", [
    "DECL E6POS XP3={X 1.5,Y -2,Z .25,A 0,B 90,C 0,S 2,T 35,E1 10,E2 0}",  # as KUKA writes it, external axes
    "DECL E6POS XP3={X 1.5, Y -2,Z .25,A 0,B 90,C 0}",  # a blank after a comma: read line by line
    "DECL POS XP3={X 1.5,Y -2,Z .25,A 0,B 90,C 0,S 'B010',T 'B100011'}",  # bit strings: line by line
])
def test_krl_points_written_otherwise_read_the_same(tmp_path, monkeypatch, third):
    path = _krl(tmp_path, ["DECL E6POS XP1={X 500,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}",
                           "DECL E6POS XP2={X 510.25,Y 1e1,Z 600,A -180,B 89.5,C 0.001,S 6,T 27}", third])
    program = formats.read(path)
    assert program.targets[2].name == "XP3" and np.allclose(program.targets[2].pose[:3, 3], [1.5, -2, 0.25])
    assert _seen(program) == _seen(_line_by_line(path, monkeypatch))


@pytest.mark.parametrize("bad, message", [
    ("DECL E6POS XP2={X 1e9,Y 0,Z 0,A 0,B 0,C 0,S 2,T 35}", "X: '1e9' is out of range"),
    ("DECL E6POS XP2={X 1,Y 0,Z 0,A 0,B 0,C 0,S 2,T 99}", "T 99: outside 0..63"),
])
def test_krl_point_the_line_read_refuses_is_refused_naming_its_line(tmp_path, bad, message):
    path = _krl(tmp_path, ["DECL E6POS XP1={X 500,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}", bad,
                           "DECL E6POS XP3={X 1,Y 0,Z 0,A 0,B 0,C 0}"])
    with pytest.raises(ReadError, match=f"p.dat:3: .*{message}"):
        formats.read(path)


def test_numbers_formatted_together_are_what_format_number_writes():
    rng = np.random.default_rng(7)
    values = np.concatenate([rng.normal(0, 300, 500), rng.normal(0, 1e-3, 200),
                             [0.0, -0.0, 0.0005, -0.0005, -0.0004, 0.00049999, 2.5, -2.5, 1e-9, -1e-9, 123456.7895]])
    places = rng.integers(0, 10, len(values))
    old_texts = np.where(rng.random(len(values)) < 0.2, ".5", "1.0").tolist()
    old_values = np.array([float(t) for t in old_texts])
    old_values[::7] = values[::7]  # some numbers stay the same
    changed, texts = written_numbers(values, np.char.startswith(old_texts, "."), old_values, places)
    for value, old_text, old_value, p, change, text in zip(values.tolist(), old_texts, old_values.tolist(),
                                                           places.tolist(), changed.tolist(), texts):
        expected = format_number(value, p)
        assert change == (float(expected) != old_value or math.isnan(old_value))
        if change and old_text.startswith("."):
            expected = expected.replace("0.", ".", 1) if expected.startswith(("0.", "-0.")) else expected
        assert text == expected


@pytest.mark.parametrize("characters, replacement", [("abc,.0123456789\n", "x"), ("abc,.0123456789\n", "é"),
                                                     ("abç,.01234€\r\n", "x")])
def test_edits_as_columns_apply_as_the_tuples_do(monkeypatch, characters, replacement):
    """ASCII text and replacements are gathered from their codes, others joined piece by piece: both as
    `apply_edits` applies the tuples."""
    rng = np.random.default_rng(3)
    text = "".join(rng.choice(list(characters), 5000).tolist())
    cuts = np.sort(rng.choice(len(text), 800, replace=False)).reshape(-1, 2).tolist()
    edits = [(start, end, replacement * int(rng.integers(0, 4))) for start, end in cuts] + [(0, 0, "inserted")]
    edits += [(end, end, "+") for _, end in cuts[::5]]  # insertions right after an edit
    monkeypatch.setattr(Edits, "EDITS_AT_ONCE", 16)  # pieces joined in many batches
    parts = [Edits.of(edits[k::3]) for k in range(3)]  # batches of targets whose edits interleave
    assert Edits.joined(parts).applied(text) == apply_edits(text, edits)
    assert Edits.joined([Edits.of(edits[:150]), Edits.of(edits[150:])]).applied(text) == apply_edits(text, edits)
    assert Edits.joined([]).applied(text) == text


def test_edited_sources_move_spans_held_as_columns_as_they_move_span_objects(tmp_path, monkeypatch):
    path = _krl(tmp_path, ["DECL E6POS XP1={X 500,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}",
                           "DECL E6POS XP2={X 510.25,Y 1e1,Z 600,A -180,B 89.5,C 0.001,S 6,T 27}",
                           "DECL E6POS XP3={X 1.5,Y -2,Z .25,A 0,B 90,C 0}"])
    at_once, line_by_line = formats.read(path), _line_by_line(path, monkeypatch)
    assert isinstance(at_once.targets, TargetRows) and not isinstance(line_by_line.targets, TargetRows)
    src, dat = (source.text for source in at_once.sources)
    edits = [[(src.index("  LIN XP2"), src.index("  LIN XP2"), "  $VEL.CP=0.2\n")],  # a line before a motion
             [(dat.index("DECL E6POS XP2"), dat.index("DECL E6POS XP2"), ";moved\n"),  # before a point
              (dat.index("1e1"), dat.index("1e1") + 3, "10.5")]]  # and a number of it rewritten
    moved, expected = edit_sources(at_once, edits), edit_sources(line_by_line, edits)
    assert _seen(moved) == _seen(expected)
    assert [t.line for t in moved.targets] == [2, 4, 5] and moved.targets[1].spans["y"].text == "10.5"
    assert moved.motions[1].line == 4 and moved.motions[1].spans["motion"].text == "LIN"



COLUMN_ENCODERS = {".src": (krl_writer._encode, krl_writer._encode_columns, krl_writer.MIN_PLACES)}


def _moved(program, rng):
    """The program with every used Cartesian target moved (mm) and turned (about 0.01 deg), its S and T changed for
    some: every number of a point rewritten somewhere."""
    stack = program.cartesian_targets()
    T = stack.T.copy()
    T[:, :3, 3] += rng.normal(0.0, 0.5, (len(T), 3))
    T[:, :3, :3] = T[:, :3, :3] @ abc_to_matrix(rng.normal(0.0, 2e-4, (len(T), 3)))
    configs = [config if not config or k % 3 else (config[0] ^ 2, config[1] ^ 1)
               for k, config in enumerate(program.target_table().config[i] for i in stack.index.tolist())]
    return program.with_targets(stack.index, poses=T, configs=configs)


@pytest.mark.parametrize("path", [p for p in CORPUS if p.suffix.lower() in COLUMN_ENCODERS], ids=lambda p: p.name)
def test_targets_of_a_table_write_as_columns_what_they_write_as_objects(path):
    try:
        program = formats.read(path)
        moved = _moved(program, np.random.default_rng(7))
    except TrajcompError:
        pytest.skip("refused or not compensable as a whole: the object path has nothing else to compare")
    if not isinstance(moved.targets, TargetRows) or not len(program.cartesian_targets()):
        pytest.skip("targets read one by one (not a table), or no motion to a Cartesian one")
    encode, columns, places = COLUMN_ENCODERS[path.suffix.lower()]
    as_columns, as_objects = target_edits(moved, encode, places, columns), target_edits(moved, encode, places)
    texts = [source.text for source in moved.sources]
    assert [e.applied(t) for e, t in zip(as_columns, texts)] == [e.applied(t) for e, t in zip(as_objects, texts)]
    assert sum(map(len, as_columns)) > 0


def test_a_table_target_not_finite_is_refused_by_name(tmp_path):
    path = _krl(tmp_path, ["DECL E6POS XP1={X 500,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}",
                           "DECL E6POS XP2={X 510,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}",
                           "DECL E6POS XP3={X 520,Y 0,Z 600,A 0,B 90,C 0,S 2,T 35}"])
    program = formats.read(path)
    T = program.target_table().pose[[1]].copy()
    T[0, 0, 3] = np.inf
    with pytest.raises(WriteError, match=r"XP2 \(line 3\): x is not a finite number"):
        target_edits(program.with_targets([1], poses=T), krl_writer._encode, krl_writer.MIN_PLACES,
                     krl_writer._encode_columns)


def _helix_krl(tmp_path, n, encoding="utf-8"):
    """A KRL program of n motions to points declared one a line, as a CAM post-processor writes it."""
    angle = np.linspace(0.0, 2.0 * np.pi, n)
    points = "".join(f"DECL E6POS XP{k + 1}={{X {500 + 80 * np.cos(a):.3f},Y {80 * np.sin(a):.3f},Z {600 + k:.3f},"
                     f"A 0.0,B 90.0,C 0.0,S 2,T 35}}\n" for k, a in enumerate(angle))
    (tmp_path / "p.src").write_bytes(("DEF p( )\n" + "".join(f"  LIN XP{k + 1} C_DIS\n" for k in range(n))
                                      + "END\n").encode(encoding))
    mark = "\ufeff" if encoding == "utf-8" else ""  # a BOM: written once, first
    (tmp_path / "p.dat").write_bytes(f"{mark}DEFDAT p ; hélix\n{points}ENDDAT\n".encode(encoding))
    return tmp_path / "p.src"


def _permuted(table, order):
    """A `TargetTable` with its rows in another order (spans and all)."""
    def rows(value):
        if isinstance(value, np.ndarray):
            return value[order]
        if isinstance(value, tuple):
            return tuple(value[k] for k in order.tolist())
        if isinstance(value, SpanColumns):
            return SpanColumns(value.source, value.text, value.roles, value.start[order], value.end[order])
        return TextSlices(value.text, value.start[order], value.end[order])

    return dataclasses.replace(table, **{f.name: rows(getattr(table, f.name)) for f in dataclasses.fields(table)})


@pytest.mark.parametrize("encoding", ["utf-8", "latin-1"])
def test_a_table_written_as_its_edits_are_made_is_the_text_with_every_edit_applied(tmp_path, monkeypatch, encoding):
    moved = _moved(formats.read(_helix_krl(tmp_path, 60, encoding)), np.random.default_rng(5))
    mark = "\ufeff" if encoding == "utf-8" else ""
    src, dat = (source.text for source in moved.sources)
    renames = [[(src.index("p( )"), src.index("p( )") + 1, "q")],  # before every edit of the .src
               [(dat.index("DEFDAT p") + 7, dat.index("DEFDAT p") + 8, "q"),  # before every point, among them
                (dat.index("XP31="), dat.index("XP31=") + 4, "YP31"), (dat.index("ENDDAT"), dat.index("ENDDAT"), ";")]]
    expected = [apply_edits(text, [(int(a), int(b), e.texts[c:d]) for a, b, c, d in
                                   zip(e.start, e.end, e.cut[:-1], e.cut[1:])] + extra).encode(source.encoding)
                for text, e, extra, source in zip((src, dat), target_edits(moved, *COLUMN_ENCODERS[".src"][::2],
                                                                           krl_writer._encode_columns),
                                                  renames, moved.sources)]
    monkeypatch.setattr(text_edits, "TARGETS_AT_ONCE", 7)  # edits made in many batches,
    monkeypatch.setattr(Edits, "EDITS_AT_ONCE", 5)  # joined a few at a time,
    monkeypatch.setattr(text_edits, "TEXT_PIECE", 100)  # the text after the last one encoded in pieces
    monkeypatch.setattr(text_edits, "target_edits", None)  # never made all at once
    written = patched(moved, krl_writer._encode, krl_writer.MIN_PLACES, krl_writer._encode_columns, renames)
    assert [b"".join(w) for w in written] == expected == [b"".join(w) for w in written]  # made again when iterated
    assert expected[1].startswith(f"{mark}DEFDAT q ; hélix".encode(encoding)) and b"YP31=" in expected[1]


def test_a_table_whose_points_are_not_in_text_order_is_edited_at_once_before_it_is_written(tmp_path, monkeypatch):
    moved = _moved(formats.read(_helix_krl(tmp_path, 40)), np.random.default_rng(6))
    table = moved.targets.table
    monkeypatch.setattr(text_edits, "TARGETS_AT_ONCE", 8)
    assert text_edits._batches_in_order(table)
    shuffled = _permuted(table, np.random.default_rng(1).permutation(len(table)))
    assert not text_edits._batches_in_order(shuffled)
    encoders = krl_writer._encode, krl_writer.MIN_PLACES, krl_writer._encode_columns
    expected = [e.applied(s.text).encode(s.encoding) for e, s in zip(target_edits(moved, *encoders), moved.sources)]
    written = patched(moved.replace(targets=TargetRows(shuffled)), *encoders)
    assert [b"".join(w) for w in written] == expected
    assert expected[1] != moved.sources[1].text.encode(moved.sources[1].encoding)
