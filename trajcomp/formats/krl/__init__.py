"""KUKA KRL: a .src program with its .dat data list.

Read:
- points declared in the .dat or .src: ``DECL E6POS XP1={X ..,Y ..,Z ..,A ..,B
  ..,C ..,S ..,T ..,E1 ..}`` (GLOBAL, CONST or both), POS and FRAME (Cartesian), E6AXIS and AXIS
  (joint targets); A, B, C are intrinsic Z-Y'-X'' angles in degrees; the
  external axes E1..E6 are carried unchanged (`Target.external`);
- PTP / LIN / CIRC (and SPTP / SLIN / SCIRC) to a point name or an inline
  aggregate ``{X ..}`` / ``{A1 ..}``, with C_PTP / C_DIS / C_VEL / C_ORI;
- inline forms (``;FOLD PTP P1 ...;%{PE}`` with ``FDAT_ACT`` / ``PDAT_ACT`` /
  ``LDAT_ACT`` and the FDAT / PDAT / LDAT of the .dat, spline forms ``WITH
  $TOOL=STOOL2(FP1), $BASE=SBASE(FP1.BASE_NO)``): they name the point, so
  changing the point's numbers keeps the fold consistent;
- tool and base: ``$TOOL = TOOL_DATA[n]``, ``$BASE = BASE_DATA[n]``,
  ``BAS(#TOOL, n)``, ``BAS(#BASE, n)``, FDAT TOOL_NO / BASE_NO, inline
  ``$TOOL = {X ..}`` and ``TOOL_DATA[n] = {X ..}`` definitions (tool and
  base 0 are the flange and the world; a number the program selects and
  does not define is the controller's, read from its ``$config.dat``:
  `trajcomp.formats.krl.config_dat`); speeds ``$VEL.CP`` (m/s),
  ``BAS(#VEL_PTP, %)``, ``$VEL_AXIS[n]`` and an external axis's ``$VEL_EXTAX[n]`` (%: a PTP runs at the
  slowest), ``BAS(#VEL_CP, m/s)``, the inline forms'
  ``BAS(#PTP_PARAMS, %)`` and ``BAS(#CP_PARAMS, m/s)`` (after their PDAT /
  LDAT, whose VEL they replace), a spline motion's own ``WITH $VEL =
  SVEL_CP(m/s, ..)``, ``$VEL.CP = m/s`` or ``$VEL_AXIS[n] =
  SVEL_JOINT(%)``, and a spline PTP's (or PTP spline block's) ``WITH
  $VEL_EXTAX[n] = %`` (for it alone: the slowest of it and the speed in
  force): a number, or REAL / INT data declared with one (CONST or not
  GLOBAL) that the .src never assigns; any other value, or no speed set
  before the motion, is set at run time (`Motion.speed_why`); accelerations ``$ACC_AXIS[n]``, ``$ACC_EXTAX[n]``
  (a PTP's share: the slowest, a spline PTP's ``WITH $ACC_EXTAX[n]`` for it
  alone), ``BAS(#ACC_PTP, %)`` and ``$ACC.CP``, read likewise; zone
  ``$APO.CDIS`` or the PDAT / LDAT APO_DIST.
Not compensated, with the reason (`Motion.reason`): relative motions
(PTP_REL ...), expressions (geometric operator ``XP1:{X 10}``, function
calls, array elements), system variables (``$POS_ACT``), routine
parameters, points declared without a value or changed by the program at
run time (``XP1.Z = ...``), motions after a tool or base set at run time,
the home positions ``XHOME``.. of $config.dat and ``$AXIS_ACT`` (axis positions: kept like joint targets), and points another program
assigns (GLOBAL ones). A point another data list beside the program
declares GLOBAL, or $config.dat (beside it or in a backup's R1/System),
is read from that file (a companion `Source`): corrected there, which is
written back beside the output (`trajcomp.formats.file_writing.companion_outputs`)
when it changed. A motion to a point no data list defines (no .dat, a
cut .dat) is a ReadError naming the points; so is a declaration cut off mid-line. Points the program passes to
routines (``MYPROC(XP1)``) are `Statement.refs`.

Write: the edited points' numbers, with S and T from their configuration
(`trajcomp.formats.configuration.written_configuration`: Status bits 3-7 kept). A
program from another language is generated with its tools and bases set
inline (``$TOOL={X ..}``): the controller's TOOL_DATA and BASE_DATA tables
are never written.
KUKA requires the DEF name of the .src and the DEFDAT name of the .dat to be
the file name: a program written under another name gets both renamed (and
its .dat written beside it under the same name); written under its own name
(in any case) the files are written back byte for byte.
"""

from trajcomp.formats import register_format
from trajcomp.formats.capabilities import (ConfigurationData, ExternalAxes, KeptExternalAxes, PointCopies, SpeedFields,
                                           SpeedUnits, Tasks, Vendor)

register_format(
    "krl", [".src"],
    f"{__name__}.reader:read",
    f"{__name__}.writer:write",
    Vendor("KUKA"),
    Tasks(),
    PointCopies(),
    SpeedFields(f"{__name__}.speeds:write_speeds", "$VEL.CP, BAS(#VEL_PTP, %)"),
    SpeedUnits({"joint": {"%": 1e-3}, "linear": {"mm/s": 1e-3}, "circular": {"mm/s": 1e-3}}),
    ConfigurationData(f"{__name__}.configuration"),
    ExternalAxes("krl"),  # track: {fields: {krl: E1}}
    KeptExternalAxes(),  # a POS or FRAME point, or an E6POS without E1, leaves the external axes where they are
)
