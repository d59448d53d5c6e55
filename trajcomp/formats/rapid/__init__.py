"""ABB RAPID modules (.mod, .prg, .modx).

Read:
- declarations ``[LOCAL|TASK] CONST|PERS|VAR robtarget p10 :=
  [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]];`` (mm,
  quaternion scalar first; the external axes carried unchanged, 9E9 =
  unused), ``jointtarget`` (deg), ``tooldata`` (its tframe: the tool) and
  ``wobjdata`` (uframe * oframe: the work object), possibly spread over
  several lines; ``tool.tframe := [..]`` / ``wobj.uframe := [..]`` with a
  literal pose (as RoboDK writes them) give the tool or work object a new
  value from that line on;
- MoveJ / MoveL / MoveC / MoveAbsJ (and their DO / AO / GO / Sync variants,
  TriggL/J/C, ArcL/C, CladL/C) to a declared name or an inline literal, with
  speeddata ``vN`` / ``vmax`` / ``\\V:=`` / ``\\T:=``, zonedata ``fine`` /
  ``zN`` / ``\\Z:=``, the tool and ``\\WObj:=``, also after a comma
  (``tool0,\\WObj:=wobj1``). A named speeddata or num is read where its
  value is known as the controller runs it: a CONST with a literal or
  another such CONST; a VAR or PERS speeddata or num at its declared value
  where no statement of the task may change it (VelSet, AccSet, TPWrite ...
  read their arguments: `grammar.STRAIGHT`), or at the literal a
  straight-line assignment before the motion gave it; one another module of the task
  declares (not LOCAL) likewise. A PERS without TASK or LOCAL is one datum
  of every task of the controller declaring it, and its value in a module
  is the one saved last: read only where every task is read (a backup's
  ``RAPID/TASKn``) and none may change it (`task_data.TaskData.
  other_tasks_change`); outside a backup the other tasks are not known, so
  it is set at run time. Routine parameters and the others are set at run
  time (`Motion.speed_why`).
  The language's statement forms and their fields: `grammar`.
  Identifiers are case-insensitive; tool0 (the flange) and wobj0 (the
  world frame) need no declaration.
Not compensated, with the reason (`Motion.reason`): expressions (Offs,
RelTool, CRobT, array elements), routine parameters, points declared without
a value or assigned in the code, tools and work objects changed at run time
or not supported (stationary tool, robot-held work object), and motion
instructions trajcomp does not read (SearchL, MoveExtJ, EGMMoveL ...), points,
tools and work objects another module of the task assigns. A point
another module of the task declares (not LOCAL; a module of the same
folder, or of a backup's TASKn/PROGMOD and SYSMOD) is read from that module
(a companion `Source`): corrected there, which is written back beside the
output (`trajcomp.formats.file_writing.companion_outputs`) when it changed. A
motion to a point no module declares is a ReadError naming the points; so are
blocks (MODULE, PROC, FUNC, TRAP, IF ... THEN, FOR, WHILE, TEST) not closed in order,
numbers out of range and quaternions that are not rotations. Points passed
to routines (``MyProc p10;``) are `Statement.refs`.

Write: the edited targets' numbers, with confdata from their configuration.
"""

from trajcomp.formats import register_format
from trajcomp.formats.capabilities import (ConfigurationData, ExternalAxes, OrientationSpeed, PointCopies, SpeedFields,
                                           SpeedUnits, Tasks, Vendor)

register_format(
    "rapid", [".mod", ".prg", ".modx", ".sys"],
    f"{__name__}.reader:read",
    f"{__name__}.writer:write",
    Vendor("ABB"),
    Tasks(),
    PointCopies(),
    SpeedFields(f"{__name__}.speeds:write_speeds", "\\T, \\V of the speeddata"),
    SpeedUnits({"joint": {"s": 1e-3, "mm/s": 1e-3}, "linear": {"mm/s": 1e-3, "s": 1e-3},
                "circular": {"mm/s": 1e-3, "s": 1e-3}}),
    OrientationSpeed(),  # the speeddata's v_ori
    ConfigurationData(f"{__name__}.configuration"),
    ExternalAxes("rapid"),  # track: {fields: {rapid: eax_a}}
)
