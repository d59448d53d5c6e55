"""URScript's CAM-shaped motion lines read in blocks (`trajcomp.formats.urscript.lines`) against the line-by-line
read, and a table's targets and re-timing fields written as columns against the objects' write."""

import types
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, TrajcompError
from trajcomp.formats.text import Lines, mask
from trajcomp.formats.text_edits import target_edits
from trajcomp.formats.urscript import lines as cam
from trajcomp.formats.urscript import reader, speeds, writer
from trajcomp.programs.tables import ItemRows
from trajcomp.arm.transforms import rotvec_to_matrix

DATA = Path(__file__).parents[2] / "data"
EXAMPLES = Path(__file__).parents[3] / "examples" / "programs"
CORPUS = sorted(p for root in (DATA / "programs", EXAMPLES) for p in root.rglob("*.script"))


def _p(k):
    return f"p[{0.4 + 0.001 * k:.6f}, {-0.1 + 0.0005 * k:.6f}, 0.3, {0.01 * (k % 5):.2f}, 3.1, 0.02]"


def _q(k):
    return f"[{0.1 * (k % 7):.1f}, -1.5, 1.6, -1.6, -1.57, 0.1]"


CAM = "def cam():\n" + "".join(f"  movel({_p(k)}, v=0.050000, r=0.001000)\n" for k in range(8)) + "end\ncam()\n"
ROBODK = "\n".join(  # RoboDK's post-processor: variables, a frame, positional options, the TCP changed
    ["def Prog1():", "  global speed_ms    = 0.250", "  global speed_rads  = 0.750", "  global accel_mss   = 1.200",
     "  global accel_radss = 1.200", "  global blend_radius_m = 0.001", "  global ref_frame = p[0,0,0,0,0,0]",
     "  ref_frame = p[0.05, 0.02, 0.1, 0, 0, 0]", "  set_tcp(p[0.002, 0, 0.402, 0, 0.785398, 0])"]
    + [f"  movej({_q(k)},accel_radss,speed_rads,t=0,r=0.001)" for k in range(3)]
    + [f"  movel(pose_trans(ref_frame,{_p(k)}),accel_mss,speed_ms,t=0,r=0.001)" for k in range(4)]
    + ["  ref_frame = p[0.0, 0.1, 0.1, 0.0, 0.0, 0.1]"]
    + [f"  movel(pose_trans(ref_frame,{_p(k)}),accel_mss,speed_ms,t=0,r=blend_radius_m)" for k in range(3)]
    + ["  set_tcp(p[0.0, 0.0, 0.2, 0.0, 0.0, 0.0])"]
    + [f"  movel(pose_trans(ref_frame,{_p(k)}),accel_mss,speed_ms,0,0.001)" for k in range(2)]
    + ["end", "", "Prog1()", ""])
OPTIONS = "def opts():\n" + "".join(f"  {line}\n" for line in [
    f"movel({_p(1)}, 1.2, 0.25, 0, 0.001)", f"movel({_p(2)}, 1.2, 0.25, 1.5, 0.001)",
    f"movep({_p(3)}, 1.2, 0.25, 0.002, 7)", f"movel({_p(4)}, v=0.1, v=0.2)", f"movel({_p(5)}, 1.2, v=0.1, 0.3)",
    f"movel({_p(6)}, a=1e999, v=0.1)", f"movel({_p(7)}, t=2, v=0.3)", f"movel({_p(8)})", f"movej({_p(9)})",
    f"movej({_q(1)})", f"movej({_q(2)}, a=1.4, v=1.05, t=0, r=0)", f"movel({_q(3)}, v=0.1)", f"movep({_q(4)}, v=0.1)",
    f"movel({_p(10)}, r=-0.001)", f"movel({_p(11)}, r=0)", f"movel({_p(12)}, v = 0.1 , r = 0.002 )",
    f"movel( {_p(13)} ,v=.1,r=1e-3)", f"movel({_p(15)}, t=-0.0)", "movel(p[ .5, -.1, +.3, 0, 3.14, 0 ], v=5E-2)",
    f"movel  ({_p(17)}, v=0.1)  # a comment \"quoted\"", f"movel({_p(18)}, v=0.1)\f", f"movel({_p(19)}, v=0.1, q=3)",
    f"movel({_p(20)}, v=0.1, r=0.001, t=1, a=2, a=3)", f"\tmovel({_p(21)},v=0.05,r=0.001)\t"]) + "end\n"
VARIANTS = "\r\n".join(  # what a line's layout must get right: numbers beside names, exponents, blanks, widths
    ["def variants():", "  # réglage: outil n°2 — épaisseur", "  p2e5 = p[0.1, 0.2, 0.3, 0, 3.1, 0]", "",
     "  movel(p[1E-1, 2.5e-1, +.3, -0., 3.14, 6e-0], v=1e-1, r=2E-3)  # ü",
     "  movel(p[0.1, 0.2, 0.3, 0, 3.1, 0], v=1-2)", "  movel(p[0.1, 0.2, 0.3, 0, 3.1, 0], v=e5)",
     "  movel(p[123456789012345678e-18, 0.2, 0.3, 0, 3.1, 0], v=0.1)", f"  movel({_p(3)}, v=spd2, r=0.1e1)",
     "  spd2 = 0.2", f"  movej({_q(2)}, 1.4, 1.05, 0, 0)", "  movel(p[0.1,0.2,0.3,0,3.1,0],v=.1)",
     "  movel(p[0.10000000000000000001, 0.2, 0.3, 0, 3.1, 0], v=0.1)", "  movel(p[0.1, 0.2, 0.3, 0, 3.1, 0], v2, 0.3)",
     " " * 80 + f"movel({_p(4)}, v=0.1)",
     f"  movel({_p(5)}, v=0.1) # é", f"  movel({_p(6)}, v=0.1)", f"  movel({_p(6)}, v=0.1)", "end", ""])
FRAMES = "\n".join(  # frames and speeds known at run time, a point also used as a frame, a TCP set at run time
    ["def appr():", "  pick_p = p[0.5, 0.1, 0.3, 0, 3.14, 0]", "  global v = p[0.5, 0.2, 0.3, 0, 3.14, 0]",
     "  jv = [0.1,0.2,0.3,0.4,0.5,0.6]", "  spd = 0.2", "  spd2 = 0.1", "  spd2 = 0.3", "  rr = 0.004",
     "  q = get_actual_tcp_pose()", "  tt = 1.5"]
    + [f"  movel(pose_trans(pick_p, {_p(k)}), v=spd, r=rr)" for k in range(3)]
    + ["  movel(pick_p, v=0.1)", "  movel(pose_add(pick_p, p[0,0,0.01,0,0,0]), v=0.1)"]
    + [f"  movel(pose_trans(v, {_p(k)}), v=spd2)" for k in range(2)] + ["  movel(v, v=0.1)"]
    + [f"  movel(pose_trans(Plane_1, {_p(k)}), v=later, t=tt)" for k in range(2)]
    + [f"  movel(pose_trans(jv, {_p(k)}), v=unknown, r=spd)" for k in range(2)]
    + [f"  movel(pose_trans(q, {_p(k)}), v=spd)" for k in range(2)] + [f"  movel(pose_trans(pick_p, {_q(1)}), v=spd)"]
    + [f"  movel({_p(k)}, v=jv, t=q, r=pick_p)" for k in range(2)] + [f"  movel({_p(k)}, v=True, t=tt)" for k in range(2)]
    + ["  set_tcp(get_tcp_offset())"] + [f"  movel({_p(k)}, v=0.1, r=0.001)" for k in range(2)]
    + ["  set_tcp(p[0,0,0.1,0,0,0])", f"  movel({_p(1)}, v=0.1)", "  later = 0.3", "  def sub(speed):"]
    + [f"    movel({_p(k)}, v=speed, r=later)" for k in range(2)] + ["  end", "end", ""])
PRINT = "\n".join(  # statements between the motions (RoboDK's 3D-printing post): which are read at once
    ["def print3d():", "  global speed_ms = 0.050", "  DO_SPRAY = 5", "  pick = p[0.5, 0.1, 0.3, 0, 3.14, 0]",
     "  # Main program: réglage n°2 — épaisseur", "", f"  movel({_p(0)},accel_mss,speed_ms,0,0)"]
    + [line for k in range(1, 4) for line in ("  set_standard_digital_out(5, 0.083)", "\t",
                                                f"  movel({_p(k)},accel_mss,speed_ms,0,blend_radius_m)")]
    + ["  sleep(1e-3)  # ü", "  set_standard_digital_out(DO_SPRAY, True)", f"  movel({_p(4)}, v=speed_ms)",
       "  textmsg(pick)", "  popup(\"(a)[b]=c:\", \"Message\", False)", "  Sleep (0.5)", "  sync()",
       f"  movel({_p(5)}, v=speed_ms)", "  set_analog_out(0, floor(2.5))", "  f(a == b)", "  g(x) :",
       "  h(1, [2])", "  spd = get_speed()", "  halt()", f"  movel({_p(6)}, v=spd)", "  set_tcp(get_tcp_offset())",
       "  sync()", f"  movel({_p(7)}, v=0.1)", "  MOVEL(p[0.1, 0.2, 0.3, 0, 3.1, 0])", "  if True:", "    sync()",
       "  end", "end", "", "print3d()", ""])
SHAPES = {
    "cam.script": CAM, "print.script": PRINT, "print_crlf.script": PRINT.replace("\n", "\r\n"),
    "refused_print.script": PRINT.replace("  sync()\n  movel(", "  sync()\n  movel(p[0.1, 0, 0, 0, 0, 1e999], v=0.1)\n  movel("), "crlf.script": CAM.replace("\n", "\r\n"), "cr.script": CAM.replace("\n", "\r"),
    "no_end_of_line.script": CAM.rstrip("\n"), "robodk.script": ROBODK, "options.script": OPTIONS,
    "frames.script": FRAMES, "variants.script": VARIANTS,
    "refused_pose.script": CAM.replace("end\n", "  movel(p[1e9, 0, 0, 0, 0, 0], v=0.1)\nend\n"),
    "refused_speed.script": CAM.replace("end\n", "  movel(p[0.1, 0, 0, 0, 0, 0], v=1e999, r=1e999)\nend\n"),
    "refused_time.script": CAM.replace("end\n", "  movej([0.1, 0, 0, 0, 0, 0], t=1e400)\nend\n"),
    "refused_joint.script": CAM.replace("end\n", "  movej([100, 0, 0, 0, 0, 0], t=1)\nend\n"),
    "unassigned.script": CAM.replace("end\n", "  movel(nowhere, v=0.1)\n  movel(p[0.1, 0, 0, 0, 0, 0], v=1e999)\nend\n"),
}


def _seen(program):
    """Everything a read gives, comparable: targets' numbers bit for bit, spans, items."""
    def bits(array):
        return None if array is None else np.asarray(array).tobytes()

    targets = [(t.name, t.line, bits(t.pose), bits(t.joints), t.config, t.tool, t.frame, t.external, dict(t.spans))
               for t in program.targets]
    return (targets, [repr(item) for item in program.items], sorted(program.tools),
            [(name, bits(T)) for name, T in program.frames.items()], program.notes)


def _line_by_line(path, monkeypatch):
    """The program read with no line read in a block."""
    with monkeypatch.context() as patch:
        patch.setattr(reader, "cam_lines", lambda masked, starts: cam.cam_lines("", np.zeros(1, dtype=int)))
        return formats.read(path)


def _written(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(SHAPES[name].encode("utf-8"))
    return path


@pytest.mark.parametrize("path", [*SHAPES, *CORPUS], ids=str)
def test_a_script_reads_the_same_in_blocks_and_line_by_line(path, tmp_path, monkeypatch):
    path = _written(tmp_path, path) if path in SHAPES else path
    try:
        in_blocks = formats.read(path)
    except ReadError as error:
        with pytest.raises(ReadError) as refused:
            _line_by_line(path, monkeypatch)
        assert str(refused.value) == str(error)
        return
    assert _seen(in_blocks) == _seen(_line_by_line(path, monkeypatch))


# options.script: its a=1e999 (no bound) is read one by one; cr.script as cam.script (its masked copy has line feeds)
@pytest.mark.parametrize("name, blocks", [("cam.script", 8), ("crlf.script", 8), ("cr.script", 8),
                                          ("robodk.script", 9), ("options.script", 18), ("frames.script", 11),
                                          ("variants.script", 12)])
def test_the_lines_a_cam_post_processor_writes_are_read_in_blocks(name, blocks, tmp_path, monkeypatch):
    read_in_blocks = []
    program = reader._program
    monkeypatch.setattr(reader, "_program", lambda state, path: read_in_blocks.append(
        sum(len(block["rows"]) for block in state.blocks)) or program(state, path))
    assert isinstance(formats.read(_written(tmp_path, name)).items, ItemRows)
    assert read_in_blocks == [blocks]


@pytest.mark.parametrize("name", ["print.script", "print_crlf.script"])
def test_plain_statements_between_the_motions_are_read_at_once(name, tmp_path, monkeypatch):
    """Blank and comment lines and calls of other functions with plain arguments that name no variable of the
    script; not a call naming one (it may name a target), nor one with a call, a list, an ``=`` or a ``:``, nor
    a motion function's."""
    at_once = []
    program = reader._program
    monkeypatch.setattr(reader, "_program", lambda state, path: at_once.append(state.plain) or program(state, path))
    read = formats.read(_written(tmp_path, name))
    lines = PRINT.split("\n")
    plain = {k for k, line in enumerate(lines[:-1], start=1) if line.strip() in (
        "", "print3d()", "set_standard_digital_out(5, 0.083)", "sleep(1e-3)  # ü", "popup(\"(a)[b]=c:\", \"Message\", False)",
        "Sleep (0.5)", "sync()", "halt()", "# Main program: réglage n°2 — épaisseur")}
    assert at_once[0].line.tolist() == sorted(plain)
    texts = {s.line: s.text for s in read.items if not hasattr(s, "kind")}
    assert [texts[k] for k in sorted(plain)] == [lines[k - 1] for k in sorted(plain)]  # as written, no line ending
    assert [s.refs for s in read.items if getattr(s, "text", "") == "  textmsg(pick)"] != [()]  # it names a target


def test_cam_lines_are_columns_of_their_numbers_and_offsets():
    text = ("def a():\n  movel(p[0.5, -.1, 3e-1, 0, 3.14, 0], a=1.2, v=0.25, r=0)  # x\n"
            "  movej([1, 2, 3, 4, 5, 6], 1.4, speed)\n  x = 1\n"
            "  movel(pose_trans(base, p[1, 2, 3, 4, 5, 6]))\n  movel(p[1, 2, 3, 4, 5, 6], v=1, v=2)\nend\n")
    found, plain = cam.cam_lines(mask(text, "#"), np.array(Lines(text).starts))
    assert found.line.tolist() == [2, 3, 5]  # line 6 names v twice: read line by line
    assert [cam.FUNCTIONS[f] for f in found.function] == ["movel", "movej", "movel"]
    assert found.is_joint.tolist() == [False, True, False]
    assert np.array_equal(found.values, [[0.5, -0.1, 0.3, 0, 3.14, 0], [1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 6]])
    assert [text[a:b] for a, b in zip(found.number_start[0], found.number_end[0])] == ["0.5", "-.1", "3e-1", "0",
                                                                                      "3.14", "0"]
    assert found.frame.tolist() == [None, None, "base"]
    v, t, r, _ = found.option.T  # and a
    assert np.array_equal(v, [0.25, np.nan, np.nan], equal_nan=True) and np.isnan(t).all()
    assert np.array_equal(r, [0.0, np.nan, np.nan], equal_nan=True)
    assert found.option_name[:, 0].tolist() == [None, "speed", None]  # movej's second positional option is v
    assert text[found.option_start[1, 0]:found.option_end[1, 0]] == "speed"
    assert [text[e - 1] for e in found.end.tolist()] == ["0", "d", ")"]  # where ", t=..." is inserted
    assert found.texts(text)[0] == "movel(p[0.5, -.1, 3e-1, 0, 3.14, 0], a=1.2, v=0.25, r=0)  # x"


def _moved(program, rng):
    """The program with every used target moved: Cartesian ones by about 0.5 mm and 0.01 deg, joint ones by about
    0.001 rad."""
    table = program.target_table()
    used = program.usage_table().index
    cartesian, joint = used[~table.is_joint[used]], used[table.is_joint[used]]
    T = table.pose[cartesian].copy()
    T[:, :3, 3] += rng.normal(0.0, 0.5, (len(T), 3))
    T[:, :3, :3] = T[:, :3, :3] @ rotvec_to_matrix(rng.normal(0.0, 2e-4, (len(T), 3)))
    joints = np.where(np.isnan(table.joints[cartesian]), 0.0, table.joints[cartesian]) + 1e-3
    moved = program.with_targets(cartesian, poses=T, joints=joints) if len(cartesian) else program
    return moved.with_targets(joint, joints=table.joints[joint] - 1e-3) if len(joint) else moved


@pytest.mark.parametrize("path", [*SHAPES, *CORPUS], ids=str)
def test_targets_of_a_table_write_as_columns_what_they_write_as_objects(path, tmp_path):
    path = _written(tmp_path, path) if path in SHAPES else path
    try:
        moved = _moved(formats.read(path), np.random.default_rng(7))
    except TrajcompError:
        pytest.skip("refused: nothing to write")
    as_columns = target_edits(moved, writer._encode, writer.MIN_PLACES, writer._encode_columns)
    as_objects = target_edits(moved, writer._encode, writer.MIN_PLACES)
    text = moved.sources[0].text
    assert as_columns[0].applied(text) == as_objects[0].applied(text)
    assert len(as_columns[0]) > 0


@pytest.mark.parametrize("name", ["cam.script", "robodk.script", "options.script", "frames.script"])
def test_re_timing_fields_are_written_in_blocks_as_line_by_line(name, tmp_path, monkeypatch):
    path = _written(tmp_path, name)
    in_blocks, line_by_line = formats.read(path), _line_by_line(path, monkeypatch)
    m = len(in_blocks.motions)
    plan = types.SimpleNamespace(times={k: 0.5 + k / 7 for k in range(m) if k % 3},  # a speed or a time for each
                                 cruise={k: 12.3456789 for k in range(m) if not k % 3})
    result = types.SimpleNamespace(motion=np.arange(m))
    written, expected = (speeds.write_speeds(p, result, None, plan) for p in (in_blocks, line_by_line))
    assert written[1] == expected[1] and len(written[1]) > m // 2
    assert _seen(written[0]) == _seen(expected[0])
    assert written[0].sources[0].text == expected[0].sources[0].text != in_blocks.sources[0].text
