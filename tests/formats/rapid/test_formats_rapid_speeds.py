"""RAPID speed data as the controller reads them: v_ori bounds reorientation; a VAR speeddata assigned by literals.

References: ABB's predefined speed data (v5 .. v7000, vmax: v_ori 500 deg/s,
the second field of ``[v_tcp, v_ori, v_leax, v_reax]``), the time a
reorientation needs at v_ori (angle / v_ori, the ramps on top), and a module
written by RoboDK's own ABB IRC5 post (tests/data/robodk_posts, unmodified),
whose ``VAR speeddata rdkSpeed`` its ``setSpeed`` reassigns between moves.
"""

import importlib.util
import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import matrix_to_quat
from trajcomp.cli import main
from trajcomp.compensation.program_rewrite import convert_program
from trajcomp.formats.rapid.configuration import encode as abb_confdata

POSTS = Path(__file__).parents[2] / "data" / "robodk_posts"
ROBOT = load_robot("abb_irb4600")
Q = np.radians([[0.0, 0.0, 0.0, 0.0, 30.0, 0.0], [5.0, 5.0, 5.0, 0.0, 30.0, 0.0], [5.0, 5.0, 5.0, 0.0, 30.0, 90.0],
                [10.0, 5.0, 0.0, 0.0, 30.0, 90.0]])


def robtarget(q):
    T = fk(ROBOT, q)
    conf = ",".join(map(str, abb_confdata(ROBOT, q[None])[0]))
    return (f"[[{','.join(f'{v:.6f}' for v in T[:3, 3])}],[{','.join(f'{v:.9f}' for v in matrix_to_quat(T[:3, :3]))}],"
            f"[{conf}],[9E9,9E9,9E9,9E9,9E9,9E9]]")


def module(body, decls=""):
    """A module moving through `Q`: ``body`` the PROC's statements, formatted with the robtargets p1..p3 and the
    joint target j0."""
    points = "\n".join(f"  CONST robtarget p{k} := {robtarget(Q[k])};" for k in range(1, 4))
    j0 = ",".join(f"{v:.6f}" for v in np.degrees(Q[0]))
    return (f"MODULE speeds\n  CONST jointtarget j0 := [[{j0}],[9E9,9E9,9E9,9E9,9E9,9E9]];\n{points}\n{decls}\n"
            f"  PROC main()\n{body}\n  ENDPROC\nENDMODULE\n")


def read(tmp_path, text, name="speeds.mod"):
    (tmp_path / name).write_text(text)
    return formats.read(tmp_path / name)


def test_v_ori_is_read_from_the_speed_data(tmp_path):
    program = read(tmp_path, module("    MoveAbsJ j0, v100, fine, tool0;\n"
                                    "    MoveL p1, [300,20,5000,1000], fine, tool0;\n"
                                    "    MoveL p2, vmax\\V:=50, fine, tool0;\n    MoveL p3, v200\\T:=3, fine, tool0;"))
    read_back = [(m.speed, m.speed_unit, m.orientation_speed and round(np.degrees(m.orientation_speed), 9))
                 for m in program.motions]
    # v100 and vmax: the predefined v_ori 500 deg/s (\V replaces v_tcp only); \T: the speed data are not used
    assert read_back == [(100.0, "mm/s", 500.0), (300.0, "mm/s", 20.0), (50.0, "mm/s", 500.0), (3.0, "s", None)]


def test_a_written_time_keeps_the_reorientation_within_v_ori(tmp_path):
    """j0 -> jTurn turns J6 by 90 deg, the TCP in place, and the line to pBack turns it back: at v_ori 20 deg/s
    each takes at least 90 / 20 = 4.5 s, far longer than the joint limits need (0.25 s at 360 deg/s); the \\T
    written, which replaces the speed data, keeps it and the run says why."""
    turned = ",".join(f"{v:.6f}" for v in np.degrees(Q[0]) + [0.0, 0.0, 0.0, 0.0, 0.0, 90.0])
    text = module("    MoveAbsJ j0, v1000, fine, tool0;\n    MoveAbsJ jTurn, [100,20,5000,1000], fine, tool0;\n"
                  "    MoveL pBack, [100,20,5000,1000], fine, tool0;",
                  f"  CONST jointtarget jTurn := [[{turned}],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
                  f"  CONST robtarget pBack := {robtarget(Q[0])};")
    (tmp_path / "speeds.mod").write_text(text)
    out = tmp_path / "out" / "speeds.mod"
    out.parent.mkdir()
    assert main(["retime", str(tmp_path / "speeds.mod"), "-o", str(out), "--robot", "abb_irb4600"]) == 0
    for motion in ("MoveAbsJ jTurn", "MoveL pBack"):  # the line back turns the tool only: its time is written
        written = re.search(motion + r", \[100,20,5000,1000\]\\T:=([\d.]+)", out.read_text())
        assert written is not None and 90.0 / 20.0 <= float(written.group(1)) <= 1.1 * 90.0 / 20.0


def test_a_converted_reorientation_keeps_v_ori(tmp_path):
    """``MoveL p, [100,20,..]`` turning the tool 90 deg over 1 mm takes at least 90 / 20 s at its v_ori (longer
    than J6 needs); converted into languages without an orientation speed, its TCP speed is lowered so that the
    1 mm takes as long."""
    q_turn = Q[1] + np.radians([0.0, 0.0, 0.0, 0.0, 0.0, 90.0])
    T_a, T_b = fk(ROBOT, Q[1]), fk(ROBOT, q_turn)
    travel = np.linalg.norm(T_b[:3, 3] - T_a[:3, 3])
    assert travel < 1e-6  # J6 turns the flange in place: add 1 mm along the tool axis
    shifted = T_b.copy()
    shifted[:3, 3] += T_b[:3, 2]
    quat = ",".join(f"{v:.9f}" for v in matrix_to_quat(shifted[:3, :3]))
    conf = ",".join(map(str, abb_confdata(ROBOT, q_turn[None])[0]))
    target = f"[[{','.join(f'{v:.6f}' for v in shifted[:3, 3])}],[{quat}],[{conf}],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    text = module(f"    MoveAbsJ j0, v100, fine, tool0;\n    MoveL p1, v100, fine, tool0;\n"
                  f"    MoveL {target}, [100,20,5000,1000], fine, tool0;")
    program = read(tmp_path, text)
    for language, extension in (("krl", ".src"), ("fanuc_ls", ".ls"), ("urscript", ".script"), ("csv", ".csv")):
        formats.write(tmp_path / f"out{extension}", convert_program(program, language, robot=ROBOT))
        line = formats.read(tmp_path / f"out{extension}").motions[-1]
        if language == "fanuc_ls":  # 0.22 mm/s is below FANUC's whole mm/sec: a time, its trapezoid's
            assert line.speed_unit == "s" and 90.0 / 20.0 <= line.speed <= 1.1 * 90.0 / 20.0
            continue
        assert line.speed_unit == "mm/s" and 1.0 / line.speed >= 90.0 / 20.0, language  # 1 mm in >= 4.5 s
        assert line.speed >= 0.99 * 20.0 / 90.0  # the v_ori bound, rounded down


def test_a_var_speeddata_assigned_by_literals_is_known_where_the_code_runs_straight(tmp_path):
    body = """    rdkSpeed := [100,500,5000,1000];
    ConfL \\Off;
    MoveAbsJ j0, rdkSpeed, fine, tool0;
    MoveL p1, vFixed, fine, tool0;
    IF TRUE THEN
      rdkSpeed := [900,500,5000,1000];
    ENDIF
    MoveL p2, rdkSpeed, fine, tool0;
    rdkSpeed := [50,20,5000,1000];
    MoveL p3, rdkSpeed, fine, tool0;
    Helper;
    MoveL p1, rdkSpeed, fine, tool0;
    rdkSpeed := vFixed;
    MoveL p2, rdkSpeed, fine, tool0;
    rdkSpeed.v_tcp := 30;
    MoveL p3, rdkSpeed, fine, tool0;"""
    decls = "  VAR speeddata rdkSpeed := [500,500,5000,1000];\n  VAR speeddata vFixed := [40,500,5000,1000];\n"
    motions = read(tmp_path, module(body, decls)).motions
    speeds = [(m.speed, m.orientation_speed and round(np.degrees(m.orientation_speed), 9)) for m in motions]
    # vFixed: a VAR no statement changes, its declared value
    assert speeds[:2] == [(100.0, 500.0), (40.0, 500.0)]
    assert speeds[3] == (50.0, 20.0) and speeds[5] == (40.0, 500.0)
    # after a branch and a routine call: the value the module's code left, set at run time; a member changed
    for k, why in ((2, "module changes (line 10)"), (4, "module changes (line 10)"),
                   (6, "changed at run time (line 24)")):
        assert speeds[k] == (None, None) and why in motions[k].speed_why


def test_a_var_speeddata_another_module_assigns_is_set_at_run_time(tmp_path):
    decls = "  VAR speeddata vShared := [40,500,5000,1000];\n"
    read(tmp_path, module("    MoveAbsJ j0, vShared, fine, tool0;", decls))
    (tmp_path / "Other.mod").write_text("MODULE Other\n  PROC faster()\n    vShared := [2000,500,5000,1000];\n"
                                        "  ENDPROC\nENDMODULE\n")
    [motion] = formats.read(tmp_path / "speeds.mod").motions
    assert motion.speed is None and "Other.mod:3" in motion.speed_why


def test_the_speeds_of_a_module_robodk_writes_are_read(tmp_path):
    pytest.importorskip("robodk")
    from robodk.robomath import Mat

    spec = importlib.util.spec_from_file_location("ABB_RAPID_IRC5", POSTS / "ABB_RAPID_IRC5.py")
    post_module = importlib.util.module_from_spec(spec)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the post's own 'from robodk import *' and string escapes
        spec.loader.exec_module(post_module)
    post = post_module.RobotPost("ABB_RAPID_IRC5", "ABB IRB 4600", 6)
    post.ProgStart("weld")
    post.setFrame(Mat(np.eye(4).tolist()), 1, "Frame 1")
    post.setTool(Mat(np.eye(4).tolist()), 1, "Tool 1")
    poses = fk(ROBOT, Q)
    post.MoveJ(Mat(poses[0].tolist()), list(np.degrees(Q[0])), [0, 0, 0])
    post.setSpeed(100)
    post.MoveL(Mat(poses[1].tolist()), list(np.degrees(Q[1])), [0, 0, 0])
    post.MoveL(Mat(poses[2].tolist()), list(np.degrees(Q[2])), [0, 0, 0])
    post.setSpeed(250)
    post.MoveL(Mat(poses[3].tolist()), list(np.degrees(Q[3])), [0, 0, 0])
    post.ProgFinish("weld")
    post.ProgSave(str(tmp_path), "weld", False, False)
    text = (tmp_path / "weld.mod").read_text()
    assert "VAR speeddata rdkSpeed := [250,500,5000,1000];" in text and "rdkSpeed := [100.00,500,5000,1000];" in text
    motions = formats.read(tmp_path / "weld.mod").motions
    # the MoveAbsJ runs before the routine assigns rdkSpeed: at the value a previous run left, set at run time
    assert motions[0].speed is None and "rdkSpeed: VAR speeddata the module changes" in motions[0].speed_why
    assert [(m.speed, m.speed_why) for m in motions[1:]] == [(100.0, ""), (100.0, ""), (250.0, "")]


def _task(folder, decls, body, tasks=None, **others):
    """A task of a backup under ``folder`` (``RAPID/TASK1/PROGMOD``): speeds.mod (`module` of ``body``, ``decls``)
    and other modules ``{name: text}``; ``tasks``: the backup's other tasks, ``{task: {name: text}}``. Its
    motions."""
    for task, modules in {"TASK1": others, **(tasks or {})}.items():
        (folder / "RAPID" / task / "PROGMOD").mkdir(parents=True, exist_ok=True)
        for name, text in modules.items():
            (folder / "RAPID" / task / "PROGMOD" / f"{name}.mod").write_text(f"MODULE {name}\n{text}\nENDMODULE\n")
    return read(folder / "RAPID" / "TASK1" / "PROGMOD", module(body, decls)).motions


MOVES = "    MoveJ p1, vWeld, fine, tool0;\n    MoveL p2, vWeld, fine, tool0;"


def test_a_pers_speeddata_nothing_changes_is_its_declared_value(tmp_path):
    """The controller runs a PERS at the value it was declared with until the program gives it another
    (issue 35): read so, where no statement of the controller's tasks (each read, in a backup) may change it;
    else set at run time."""
    decls = "  PERS speeddata vWeld := [20,30,5000,1000];"
    assert {(m.speed, round(np.degrees(m.orientation_speed), 9), m.speed_why)
            for m in _task(tmp_path, decls, MOVES)} == {(20.0, 30.0, "")}
    # a straight-line assignment before a motion: that value there, the declared one unknown before it
    first, second = _task(tmp_path, decls, MOVES.replace("    MoveL", "    vWeld := v50;\n    MoveL"))
    assert first.speed is None and "PERS speeddata the module changes (line 9)" in first.speed_why
    assert (second.speed, second.speed_why) == (50.0, "")
    # another module of the task assigns it, or takes it as a routine's argument (INOUT: it may change it)
    for statement in ("vWeld.v_tcp := 2000;", "SetSpeed vWeld;"):
        motions = _task(tmp_path, decls, MOVES, Other=f"  PROC faster()\n    {statement}\n  ENDPROC")
        assert {(m.speed, m.speed_why) for m in motions} == {
            (None, "vWeld: PERS speeddata, set at run time (Other.mod:3)")}
    # a call of a routine no module of the task declares (a module the folder lacks) may change it
    motions = _task(tmp_path / "lacking", decls, "    SetFromHost;\n" + MOVES)
    assert {m.speed for m in motions} == {None} and motions[0].speed_why == (
        "vWeld: PERS speeddata, set at run time: SetFromHost (speeds.mod:8) calls a routine no module of the task "
        "declares, which may change it")
    assert _task(tmp_path / "declared", decls, "    SetFromHost;\n" + MOVES,
                 Host="  PROC SetFromHost()\n    TPWrite \"ready\";\n  ENDPROC")[0].speed == 20.0
    # another module declares the same PERS: it starts at the value of the module loaded first
    motions = _task(tmp_path / "twice", decls, MOVES, Other="  PERS speeddata vWeld := [2000,500,5000,1000];")
    assert {m.speed for m in motions} == {None} and "also declared in Other.mod:2" in motions[0].speed_why


def test_a_pers_speeddata_another_task_may_change_is_set_at_run_time(tmp_path):
    """Every task of the controller declaring a PERS (not TASK, not LOCAL) shares that one datum, and a module
    holds the value saved last (issue 35): it is its declared value only where every task is read (a backup's
    RAPID/TASKn) and none may give it another; a module outside a backup: the other tasks are unknown."""
    decls = "  PERS speeddata vWeld := [20,30,5000,1000];"
    shared = "  PERS speeddata vWeld := [20,30,5000,1000];"
    changes = {"TASK2": {"Other": shared + "\n  PROC main()\n    vWeld.v := 5;\n  ENDPROC"}}
    motions = _task(tmp_path / "changed", decls, MOVES, tasks=changes)
    assert {(m.speed, m.speed_why) for m in motions} == {
        (None, "vWeld: PERS speeddata, set at run time: task TASK2 may change it (Other.mod:4)")}
    # another task declaring it with the same value and not changing it: the value holds
    assert {m.speed for m in _task(tmp_path / "same", decls, MOVES, tasks={"TASK2": {"Other": shared}})} == {20.0}
    # ... declaring another value: that of the task loaded first; calling a routine its task lacks
    assert _task(tmp_path / "other", decls, MOVES, tasks={"TASK2": {"Other": shared.replace("20,", "2000,")}}
                 )[0].speed_why == ("vWeld: PERS speeddata, set at run time: task TASK2 declares it "
                                    "[2000,30,5000,1000] (Other.mod:2): its value is that of the task loaded first")
    lacking = {"TASK2": {"Other": "  PROC main()\n    FromHost;\n  ENDPROC"}}
    assert _task(tmp_path / "lacking", decls, MOVES, tasks=lacking)[0].speed_why == (
        "vWeld: PERS speeddata, set at run time: task TASK2 calls FromHost (Other.mod:3), a routine no module of "
        "its task declares, which may change it")
    # a TASK PERS is its task's own: what another task does with its name is not its concern
    own = _task(tmp_path / "own", decls.replace("PERS", "TASK PERS"), MOVES, tasks=changes)
    assert {m.speed for m in own} == {20.0}
    # outside a backup (a folder of modules): the controller's other tasks are not known
    loose = tmp_path / "loose"
    loose.mkdir()
    motions = read(loose, module(MOVES, decls)).motions
    assert {(m.speed, m.speed_why) for m in motions} == {
        (None, "vWeld: PERS speeddata, set at run time: the controller's other tasks share it and are not read (the "
               "module is not in a backup's RAPID/TASKn folders)")}
    assert {m.speed for m in read(loose, module(MOVES, decls.replace("PERS", "TASK PERS"))).motions} == {20.0}


def test_speeddata_another_module_of_the_task_declares_is_read_where_its_value_is_known(tmp_path):
    """A speeddata (or num) declared in another module of the task, not LOCAL nor a routine's own: a CONST, or a
    VAR or PERS no statement of the task may change, is its stated value; the others are set at run time."""
    data = ("  CONST speeddata vWeld := [20,30,5000,1000];\n  PERS speeddata vPers := v40;\n"
            "  VAR speeddata vVar := [60,500,5000,1000];\n  LOCAL CONST speeddata vLocal := v10;\n"
            "  CONST num nRate := 15;\n  PERS num nPers := 15;\n  CONST speeddata vNamed := vWeld;\n"
            "  PROC own()\n    CONST speeddata vRoutine := v10;\n  ENDPROC")
    body = "\n".join(f"    MoveL p1, {speed}, fine, tool0;" for speed in (
        "vWeld", "vPers", "vVar", "vLocal", "v100\\V:=nRate", "v100\\V:=nPers", "vNamed", "vRoutine"))
    motions = _task(tmp_path, "", body, BData=data)
    assert [m.speed for m in motions] == [20.0, 40.0, 60.0, None, 15.0, 15.0, None, None]
    assert round(np.degrees(motions[0].orientation_speed), 9) == 30.0
    whys = [m.speed_why for m in motions]
    assert (whys[3], whys[7]) == ("vLocal: speeddata not declared in this module, set at run time",
                                  "vRoutine: speeddata not declared in this module, set at run time")
    assert whys[6] == "vNamed: CONST speeddata vWeld of BData.mod:8, known at run time"
    # this module, or a third, changes the VAR and the PERS: set at run time
    motions = _task(tmp_path, "", body.replace("    MoveL p1, vWeld", "    vVar := v100;\n    MoveL p1, vWeld"),
                    BData=data, Tune="  PROC tune()\n    vPers.v_tcp := 900;\n    Incr nPers;\n  ENDPROC")
    assert [m.speed for m in motions][:3] == [20.0, None, None] and motions[5].speed is None
    assert motions[1].speed_why == "vPers: PERS speeddata of BData.mod:3, set at run time (Tune.mod:3)"
    assert motions[5].speed_why == "nPers: PERS num of BData.mod:7, set at run time (Tune.mod:4)"
    assert motions[2].speed_why == "vVar: VAR speeddata of BData.mod:4, set at run time (changed at line 8)"


def test_a_num_in_a_speed_is_read_where_its_value_is_known_as_a_speeddata_is(tmp_path):
    """A VAR or PERS num named in a speed (``\\V:=``, ``\\T:=``, VelSet) is its declared value where no statement
    of the controller's tasks may change it (VelSet, AccSet, TPWrite read their arguments), the literal a
    straight-line assignment gave it, else set at run time (``Incr``, ``TPReadNum`` and a routine may change it)."""
    decls = "  VAR num nSpeed := 50;\n  PERS num nOverride := 40;"
    body = ("    VelSet nOverride, 1000;\n    MoveL p1, v100\\V:=nSpeed, fine, tool0;\n"
            "    TPWrite \"speed\" \\Num:=nSpeed;\n    MoveL p2, v100\\V:=nSpeed, fine, tool0;")
    assert [m.speed for m in _task(tmp_path / "read", decls, body)] == [20.0, 20.0]  # 40 % of 50 mm/s
    assigned = _task(tmp_path / "assigned", decls,
                     body + "\n    nSpeed := 80;\n    MoveL p3, v100\\V:=nSpeed, fine, tool0;")
    assert [m.speed for m in assigned] == [None, None, 32.0]  # before it: the value a previous run left
    motions = _task(tmp_path / "changed", decls, body.replace("TPWrite \"speed\" \\Num:=", "Incr "))
    assert [m.speed for m in motions] == [None, None]
    assert motions[0].speed_why == ("nSpeed: VAR num the module changes (line 11) and does not assign a literal in "
                                    "the code running straight to this motion: set at run time")
    # outside a backup the PERS override is another task's too: set at run time, so is every motion it reaches
    loose = tmp_path / "loose"
    loose.mkdir()
    assert {m.speed_why for m in read(loose, module(body, decls)).motions} == {
        "VelSet: nOverride: PERS num, set at run time: the controller's other tasks share it and are not read (the "
        "module is not in a backup's RAPID/TASKn folders)"}


def test_a_pers_speeddata_of_the_task_is_never_run_faster_than_its_value(tmp_path):
    """Re-timed through the command: the weld at a PERS of another module of a backup's task declared at 20 mm/s,
    which no task changes, is timed at it (its time at least its length over 20 mm/s) and kept as written, never
    sped up."""
    task = tmp_path / "RAPID" / "TASK1" / "PROGMOD"
    task.mkdir(parents=True)
    (task / "BData.mod").write_text("MODULE BData\n  PERS speeddata vWeld := [20,500,5000,1000];\nENDMODULE\n")
    (task / "speeds.mod").write_text(module("    MoveJ p2, v1000, fine, tool0;\n    MoveL p3, vWeld, fine, tool0;"))
    out = tmp_path / "out"
    out.mkdir()
    assert main(["retime", str(task / "speeds.mod"), "-o", str(out / "speeds.mod"), "--robot", "abb_irb4600",
                 "--report", str(out / "speeds.html")]) == 0
    assert "    MoveL p3, vWeld, fine, tool0;" in (out / "speeds.mod").read_text()
    timing = json.loads((out / "speeds.json").read_text())["timing"]
    length = np.linalg.norm(fk(ROBOT, Q[3])[:3, 3] - fk(ROBOT, Q[2])[:3, 3])  # mm
    assert timing["t_s"][-1] - timing["t_s"][-2] >= length / 20.0 and timing["not_retimed"]["count"] == 0


def test_a_pers_another_task_slows_is_never_retimed_from_its_declared_value(tmp_path, abb_model):
    """Issue 35's never-faster gap: a backup's TASK1 welds P2 -> P3 at PERS vWeld, declared [200,..]; TASK2,
    declaring the same PERS, sets ``vWeld.v := 5``, so the controller welds at 5 mm/s. The weld is read as set at
    run time, and retime and compensate leave its field as written and list it, never timed from 200 mm/s."""
    weld = (Path(__file__).parents[3] / "examples" / "programs" / "abb" / "Weld.mod").read_text()
    weld = (weld.replace("1415.000000", "1315.000000").replace("1335.000000", "1235.000000")  # in the model's cube
            .replace("MODULE Weld", "MODULE Weld\n  PERS speeddata vWeld := [200,500,5000,1000];")
            .replace("MoveL P3, v20", "MoveL P3, vWeld"))
    other = ("MODULE Other\n  PERS speeddata vWeld := [200,500,5000,1000];\n  PROC main()\n    vWeld.v := 5;\n"
             "  ENDPROC\nENDMODULE\n")
    rapid = tmp_path / "backup" / "RAPID"
    for task, name, text in (("TASK1", "Weld", weld), ("TASK2", "Other", other)):
        (rapid / task / "PROGMOD").mkdir(parents=True)
        (rapid / task / "PROGMOD" / f"{name}.mod").write_text(text)
    path = rapid / "TASK1" / "PROGMOD" / "Weld.mod"
    why = "vWeld: PERS speeddata, set at run time: task TASK2 may change it (Other.mod:4)"
    assert [(m.speed, m.speed_why) for m in formats.read(path).motions][2] == (None, why)
    for command, option in (("retime", ["--robot", "abb_irb4600"]), ("compensate", ["--model", str(abb_model)])):
        out = tmp_path / command / "Weld.mod"
        out.parent.mkdir()
        assert main([command, str(path), "-o", str(out), *option, "--report", str(out.with_suffix(".html"))]) == 1
        written = out.read_text()
        assert "    MoveL P3, vWeld, z5, tool0;" in written and "vWeld\\" not in written  # no \T, no \V
        timing = json.loads(out.with_suffix(".json").read_text())["timing"]
        assert [(m["waypoint"], m["why"]) for m in timing["not_retimed"]["motions"]] == [("P3 (Weld.mod:5)", why)]
