"""FANUC teach pendant programs in ASCII form (.LS).

Read:
- the sections /PROG, /ATTR, /MN, /POS, /END, in English or German
  exports (``CONFIG`` / ``KONFIG``, ``UTOOL_NUM`` / ``WKZ_NUM``,
  ``UFRAME_NUM`` / ``BENUTZER_NUM``, ``sec`` / ``sek``);
- /MN motion lines ``J|L|C P[n] speed FINE|CNTn|CRn`` (a C line continues
  with ``: P[m] speed ...``; FINE, CNTn, CRn or CDn), speeds in ``%``, ``mm/sec``, ``cm/min``,
  ``deg/sec``, ``sec``, ``msec`` (``max_speed``: the arm's limits; a speed
  register ``R[n:comment]mm/sec`` or ``AR[n]``: set at run time,
  `Motion.speed_why`); ``UFRAME_NUM=n`` / ``UTOOL_NUM=n``. CNTn is read as an n mm blend
  (FANUC's CNT is a rounding percentage);
- /POS entries ``P[n:"comment"]{ GP1: UF : u, UT : t, CONFIG : 'N U T, 0,
  0, 0', X = .. mm, Y, Z, W = .. deg, P, R (, E1 ..) }`` or with J1..J6
  (joint representation). W, P, R: R = Rz(R) Ry(P) Rx(W), the matrix of
  A, B, C = R, P, W. UF 0 and UT 0 are the world frame and the faceplate.
  E1.. of group 1, then the axes of groups 2.. (servo gun, positioner) are
  the target's external axes, carried unchanged. A UF or UT number the
  program uses is the controller's user frame or tool, read from the
  backup's SYSFRAME.VA beside it or in the folder above
  (`trajcomp.formats.fanuc.sysframe`).
Position registers: a motion to ``PR[n]`` goes to the value the backup's
POSREG.VA lists (beside the program or in the folder above it,
`trajcomp.formats.fanuc.posreg`), in the active UTOOL_NUM and UFRAME_NUM;
the register is corrected there and written into a POSREG.VA beside the
output with the program.
Not compensated, with the reason (`Motion.reason`): position registers
without a value in POSREG.VA (none beside the program, uninitialized,
``********``) or set at run time by the program or another TP listing
beside it (``PR[n]=LPOS``, ``PR[n,i]=``, ``PR[R[k]]=``), a Cartesian
register before any UTOOL_NUM / UFRAME_NUM, indirect positions
(``P[R[n]]``, ``P[AR[n]]``, ``PR[R[n]]``), run-time modifiers (Offset, Tool_Offset, INC, VOFFSET),
and motions with a tool or user frame set at run time (``UTOOL[1]=PR[1]``,
``UTOOL_NUM=R[1]``) from that line on, and motions to an untaught
position (``X = ********``: the controller loads the program and faults
only if that line runs). A motion to a position without a /POS entry is a
ReadError; a 4-axis arm's CONFIG (``'L, 0, 0, 0'``) too: 4-axis arms are
not supported. Positions named by other
instructions (``PR[1]=P[3]``) are `Statement.refs`.

Write: the edited positions' numbers and CONFIG; lines are never added or
removed, so LINE_COUNT stays right. Generated programs count their lines.
"""

from trajcomp.formats import register_format
from trajcomp.formats.capabilities import ConfigurationData, ExternalAxes, SpeedFields, SpeedUnits, Tasks, Vendor

register_format(
    "fanuc_ls", [".ls"],
    f"{__name__}.reader:read",
    f"{__name__}.writer:write",
    Vendor("FANUC"),
    SpeedFields(f"{__name__}.speeds:write_speeds", "msec, sec, mm/sec"),
    # whole %, mm/sec and deg/sec (1 deg/s in rad/s); msec
    SpeedUnits({"joint": {"%": 1.0, "s": 1e-3}, "linear": {"mm/s": 1.0, "s": 1e-3, "rad/s": 0.017453292519943295},
                "circular": {"mm/s": 1.0, "s": 1e-3}}),
    ConfigurationData(f"{__name__}.configuration"),
    Tasks(),
    ExternalAxes("fanuc_ls"),  # track: {fields: {fanuc_ls: E1}} (or GP2:J1)
)
