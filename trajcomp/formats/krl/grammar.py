"""The KRL grammar: the statement forms of a .src and a .dat and their fields, declared once.

Both of the reader's strategies run on these declarations, so that a
form changes in one place:

- the line reader (`trajcomp.formats.krl.reader`) matches the patterns
  built here from the declared words (`MOTION`, `DECL`, the settings);
- the at-once strategy (`trajcomp.formats.krl.at_once`) runs the forms
  CAM post-processors write a line each (`WRITTEN_POINT`,
  `WRITTEN_MOTION`, `INLINE_MOTION`: `forms.Form`, declared from the
  same words) over every line of a text together, and matches their
  patterns on the lines the run at once leaves (`forms.written_lines`).

Words are matched in any case, as the controller reads them.
"""

import re

from trajcomp.formats.forms import Blank, Either, Form, Group, LineEnd, Literal, Name, Number, Optional, Repeat, Words
from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.text import ANGLE_LIMIT, INDENT, JOINT_LIMIT, LENGTH_LIMIT
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR

# --- points: their types and members (lower case: the members' keys) ---
POSE = ("x", "y", "z", "a", "b", "c")  # a Cartesian point's position (mm) and orientation (deg), in this order
AXES = ("a1", "a2", "a3", "a4", "a5", "a6")  # a joint point's axes, deg
STATUS = ("s", "t")  # a Cartesian point's status and turn, after its C
STATUS_LARGEST = {"s": 0xFF, "t": 0x3F}  # S: the status byte, T: one sign bit per axis A1-A6
EXTERNAL = ("e1", "e2", "e3", "e4", "e5", "e6")  # the external axes, after the rest
CARTESIAN_TYPES = ("E6POS", "POS", "FRAME")  # the point types of POSE (FRAME: no S, T, E; read alike)
JOINT_TYPES = ("E6AXIS", "AXIS")  # the point types of AXES
POINT_TYPES = CARTESIAN_TYPES + JOINT_TYPES
DATA_TYPES = ("FDAT", "PDAT", "LDAT")  # an inline form's data: tool and base, a PTP's, a LIN's speed and zone
NUMBER_TYPES = ("REAL", "INT")
QUALIFIERS = ("GLOBAL", "CONST")  # DECL GLOBAL CONST E6POS ..: a data list's constant is a point too
SHARED = "GLOBAL"  # the qualifier of a point other programs see (and may assign)
MIN_PLACES = dict.fromkeys(POSE[:3], 3) | dict.fromkeys(POSE[3:], 4) | dict.fromkeys(AXES, 4)
LIMITS = dict.fromkeys(POSE[:3], LENGTH_LIMIT) | dict.fromkeys(POSE[3:], ANGLE_LIMIT) | dict.fromkeys(AXES, JOINT_LIMIT)

# --- motions ---
MOTIONS = {"PTP": JOINT, "LIN": LINEAR, "CIRC": CIRCULAR, "SPTP": JOINT, "SLIN": LINEAR, "SCIRC": CIRCULAR}
RELATIVE = "_REL"  # LIN_REL ..: a motion relative to where the arm is
APPROXIMATIONS = ("C_PTP", "C_DIS", "C_VEL", "C_ORI", "C_SPL")  # the words after a motion's point that blend it
WITH = "WITH"  # a spline motion's own settings follow it
# the motions to one point (a CIRC's go via another), those CAM post-processors write a line each (read at once)
MOTION_KEYWORDS = tuple(keyword for keyword, kind in MOTIONS.items() if kind != CIRCULAR)
MOTION_SPANS = ("motion", "via_name", "target_name", "speed_with", "speed")  # a motion's fields kept, in this order

# --- speed and acceleration settings: the system variables and BAS commands the motions after them run with ---
SPEED_AXES = 6  # $VEL_AXIS[1..6], $ACC_AXIS[1..6]: the arm's axes
EXTERNAL_AXES = 6  # $VEL_EXTAX[1..6], $ACC_EXTAX[1..6]: the external axes (a track's)
BAS_FRAMES = ("TOOL", "BASE")  # BAS(#TOOL, n), BAS(#BASE, n): the tool or base in force
BAS_SPEEDS = {"VEL_PTP": JOINT, "VEL_CP": LINEAR, "PTP_PARAMS": JOINT, "CP_PARAMS": LINEAR}  # -> the motions set
BAS_ACC = "ACC_PTP"  # BAS(#ACC_PTP, %): every axis's $ACC_AXIS
ACC_GROUPS = tuple(f"acc{n}" for n in range(1, SPEED_AXES + 1))  # the flow's acceleration groups of a PTP: axes' %
EXTERNAL_ACC_GROUPS = tuple(f"acc_extax{n}" for n in range(1, EXTERNAL_AXES + 1))  # each external axis's % ($ACC_EXTAX)
# a PTP's acceleration groups: its axes accelerate together, so the slowest share of any binds the motion (a track's
# $ACC_EXTAX too); BAS(#ACC_PTP) sets the arm's (read so: the external axes' it may leave stay the slowest)
PTP_ACC_GROUPS = ACC_GROUPS + EXTERNAL_ACC_GROUPS
ORI_GROUPS = ("acc_ori1", "acc_ori2")  # the orientation accelerations of a LIN or CIRC, deg/s^2
AXIS_GROUPS = tuple(f"ptp{n}" for n in range(1, SPEED_AXES + 1))  # the flow's speed groups of a PTP: each axis's %
EXTERNAL_GROUPS = tuple(f"extax{n}" for n in range(1, EXTERNAL_AXES + 1))  # each external axis's % ($VEL_EXTAX)
# a PTP's speed groups: the controller moves its axes together, so the slowest setting of any binds the motion (a
# track's $VEL_EXTAX too); BAS(#VEL_PTP) sets them all
JOINT_GROUPS = AXIS_GROUPS + EXTERNAL_GROUPS

# --- the order a program runs in (`trajcomp.programs.flow.Step`): keyword -> step kind ---
FLOW_WORDS = {"IF": "if", "ELSE": "else", "ENDIF": "endif", "SWITCH": "if", "CASE": "elif", "DEFAULT": "elif",
              "ENDSWITCH": "endif", "FOR": "loop", "ENDFOR": "endloop", "WHILE": "loop", "ENDWHILE": "endloop",
              "LOOP": "loop", "ENDLOOP": "endloop", "REPEAT": "loop", "UNTIL": "endloop", "EXIT": "exit",
              "RETURN": "return", "END": "end", "ENDFCT": "end", "WAIT": "wait", "HALT": "wait", "GOTO": "jump"}
# the blocks of a .src (a routine, first: what a statement outside them all lacks; a function, the control
# structures, a spline block) and the keywords closing them
CLOSING = {"DEF": "END", "DEFFCT": "ENDFCT", "IF": "ENDIF", "FOR": "ENDFOR", "WHILE": "ENDWHILE", "LOOP": "ENDLOOP",
           "REPEAT": "UNTIL", "SWITCH": "ENDSWITCH", "SPLINE": "ENDSPLINE", "PTP_SPLINE": "ENDSPLINE"}


def _one_of(words):
    """The pattern of any of ``words`` (a group that captures nothing)."""
    return "(?:" + "|".join(words) + ")"


def _assignment(variable, value=r"(.*?)"):
    """A statement ``variable = value`` alone on its line (both patterns; blanks around the ``=``)."""
    return re.compile(r"^\s*" + variable + r"\s*=\s*" + value + r"\s*$", re.I)


def _indexed(variable, largest=SPEED_AXES):
    """The pattern of ``variable[n]`` (a KRL name, ``$`` escaped), n in 1..``largest`` captured."""
    return re.escape(variable) + rf"\s*\[\s*([1-{largest}])\s*\]"


def _bas(commands):
    """A ``BAS(#COMMAND, value)`` call alone on its line: the command of ``commands`` (pattern) and the value."""
    return re.compile(r"^\s*BAS\s*\(\s*#" + commands + r"\s*,\s*(.*?)\s*\)\s*$", re.I)


_QUALIFIED = r"(?:" + _one_of(QUALIFIERS) + r"\s+)*"
_ANY_POINT = _one_of(POINT_TYPES)

# --- declarations (.dat and .src) ---
DECL = re.compile(r"^\s*(?:DECL\s+)?" + _QUALIFIED + "(" + "|".join(POINT_TYPES + DATA_TYPES)
                  + r")\s+(\w+)\s*=\s*\{(.*)\}\s*$", re.I)  # a point or inline form's data with its value
DECL_START = re.compile(r"^\s*(?:DECL\s+)?" + _QUALIFIED + _ANY_POINT + r"\s+\w+\s*=", re.I)
DECL_BARE = re.compile(r"^\s*(?:DECL\s+)?(?:" + SHARED + r"\s+)?" + _ANY_POINT + r"\s+(\w+(?:\s*,\s*\w+)*)\s*$", re.I)
NUMBER_DECL = re.compile(r"^\s*(?:DECL\s+)?(" + _QUALIFIED + ")" + _one_of(NUMBER_TYPES) + r"\s+(\w+)\s*=\s*("
                         + NUMBER + r")\s*$", re.I)
# a point another data list declares, with a value or without (`DeclaredElsewhere`)
GLOBAL_POINT = re.compile(r"^[ \t]*(?:DECL\s+)?" + _QUALIFIED + _ANY_POINT + r"\s+(\w+)\s*(?:=|$)", re.I | re.M)
GLOBAL_WORD = re.compile(r"\b" + SHARED + r"\b", re.I)
MEMBER = re.compile(r"\s*([A-Za-z_]\w*)\s+(" + NUMBER + r"|'B[01]+')\s*$")  # a member of an aggregate's body
DATA = _assignment(r"(TOOL_DATA|BASE_DATA)\s*\[\s*(\d+)\s*\]")  # TOOL_DATA[2] = {..}
DATA_REF = re.compile(r"^(TOOL_DATA|BASE_DATA)\s*\[\s*(\d+)\s*\]$", re.I)
HOME = re.compile(r"^(XHOME\d*|\$AXIS_ACT)$", re.I)  # axis positions stated outside the program: kept

# --- routines, data lists, names ---
DEF = re.compile(r"^\s*(?:" + SHARED + r"\s+)?DEF(?:FCT\s+\w+)?\s+(\w+)\s*\(", re.I | re.M)
DEF_LINE = re.compile(r"^\s*(?:" + SHARED + r"\s+)?DEF(?:FCT\s+\w+)?\s+\w+\s*\((.*?)\)", re.I)
DEFDAT = re.compile(r"^\s*DEFDAT\s+(\w+)", re.I | re.M)
ENDDAT = re.compile(r"^\s*ENDDAT\b", re.I | re.M)
NAME = re.compile(r"^[A-Za-z_$][\w$]*$")
ARRAY_ELEMENT = re.compile(r"[A-Za-z_][\w$]*\s*\[[^\]]*\]")  # a point of an array (``P[1]``, ``P[I]``)
WORD = re.compile(r"[A-Za-z_$][\w$]*")
PROGRAM_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,23}$")  # KRL names: 24 characters at most
ASSIGN = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:\.\w+|\[[^\]]*\])*\s*=(?!=)")

# --- motions ---
MOTION = re.compile(r"^\s*(" + "|".join(MOTIONS) + ")(" + RELATIVE + r")?\b\s*(.*?)\s*$", re.I)
APPROX = re.compile(r"\s*((?:\b" + _one_of(APPROXIMATIONS) + r"\b\s*)+)$", re.I)
WITH_WORD = re.compile(r"\b" + WITH + r"\b", re.I)
WITH_TOOL = re.compile(r"\$TOOL\s*=\s*STOOL2\s*\(\s*(\w+)\s*\)", re.I)
WITH_BASE = re.compile(r"\$BASE\s*=\s*SBASE\s*\(\s*(\w+)\s*\.\s*BASE_NO\s*\)", re.I)
# a speed in a spline motion's WITH clause: $VEL = SVEL_CP(v, ..), $VEL.CP = v, $VEL_AXIS[n] = SVEL_JOINT(%)
WITH_SPEED = re.compile(r"\$VEL(?:\.CP|_AXIS\s*\[\s*\d+\s*\])?\s*=", re.I)
# an external axis's own % of its maximum speed or acceleration in a WITH clause, for that motion alone: group 1 the
# setting (VEL, ACC), group 2 the axis
WITH_EXTAX = re.compile(r"\$(VEL|ACC)_EXTAX\s*\[\s*([1-" + str(EXTERNAL_AXES) + r"])\s*\]\s*=", re.I)
WITH_CALL = re.compile(r"\s*(SVEL_CP|SVEL_JOINT)\s*\(", re.I)
SPLINE = re.compile(r"^\s*(?:PTP_)?SPLINE\b(?:.*?\b" + WITH + r"\b(.*))?$", re.I)  # a spline block: its WITH holds
END_SPLINE = re.compile(r"^\s*ENDSPLINE\b", re.I)

# --- tool, base, speed, acceleration and zone settings ---
SYSVAR = _assignment(r"\$(TOOL|BASE)")  # $TOOL = TOOL_DATA[1], $BASE = {X ..}
BAS = _bas("(" + "|".join(BAS_FRAMES + tuple(BAS_SPEEDS)) + ")")
BAS_ACC_PTP = _bas(BAS_ACC)
ACT = _assignment("(" + "|".join(DATA_TYPES) + ")_ACT", r"(\w+)")  # FDAT_ACT = F1: an inline form's data in force
VEL_CP = _assignment(r"\$VEL\.CP")  # m/s
VEL = _assignment(r"\$VEL", r"\{(.*)\}")  # $VEL={CP 0.2,ORI1 200,ORI2 200}
VEL_AXIS = _assignment(_indexed("$VEL_AXIS"))  # %
VEL_EXTAX = _assignment(_indexed("$VEL_EXTAX", EXTERNAL_AXES))  # % of the external axis's own maximum
ACC_CP = _assignment(r"\$ACC\.CP")  # m/s^2
ACC = _assignment(r"\$ACC", r"\{(.*)\}")  # $ACC={CP 2.3,ORI1 100,ORI2 100}
ACC_ORI = _assignment(r"\$ACC\.(ORI[12])")  # deg/s^2
ACC_AXIS = _assignment(_indexed("$ACC_AXIS"))  # %
ACC_EXTAX = _assignment(_indexed("$ACC_EXTAX", EXTERNAL_AXES))  # % of the external axis's own maximum
APO = _assignment(r"\$APO\.CDIS", "(" + NUMBER + ")")  # mm

# --- the order a program runs in ---
FIRST_WORD = re.compile(r"^\s*([A-Za-z_$][\w$]*)\s*(\(|:\s*$)?")
JUMP_TO = re.compile(r"^\s*GOTO\s+(\w+)", re.I)
BLOCK_OPENS = re.compile(INDENT + r"(?:" + SHARED + r"\s+)?(" + "|".join(CLOSING) + r")\b", re.I | re.M)
BLOCK_CLOSES = re.compile(INDENT + r"(" + "|".join(dict.fromkeys(CLOSING.values())) + r")\b", re.I | re.M)
OUTSIDE_ROUTINES = re.compile(r"[ \t]*&")  # what a .src holds outside its routines: its &ACCESS, &REL ... lines


# --- the forms CAM post-processors write a line each (`forms.Form`), read at once (`trajcomp.formats.krl.at_once`) ---
_ENDS_MEMBER = ",}"  # what ends a member's value in an aggregate (`forms.Number` run at once)


def _members(*separator):
    """A Cartesian point's members as KUKA writes them: X..C, then S and T, then E1..Ek (k = 0..6), each its name,
    one space and its value (S and T digits), ``separator`` (elements) between them; each value a group named as
    its member (`POINT_FIELDS`)."""
    def member(name, value=NUMBER):
        return Literal(name.upper() + " "), Group(Number(value, _ENDS_MEMBER), name=name)

    pose = [e for k, p in enumerate(POSE) for e in (separator if k else ()) + member(p)]
    status = Optional(*(e for s in STATUS for e in separator + member(s, r"\d+")))
    externals = ()
    for e in reversed(EXTERNAL):  # E2 only after E1, ..
        externals = (Optional(*separator, *member(e), *externals),)
    return (*pose, status, *externals)


POINT_FIELDS = ("name",) + POSE + STATUS + EXTERNAL  # the groups of a point read at once, after its line's
# the keyword (PTP, SPTP: also a group "joint") of a motion to one point (a CIRC's go via another)
_MOTION_KEYWORD = Group(Either(Group(Words(*(k for k in MOTION_KEYWORDS if MOTIONS[k] == JOINT)), name="joint"),
                               Words(*(k for k in MOTION_KEYWORDS if MOTIONS[k] != JOINT))), name="keyword")
_APPROXIMATION = Optional(Blank(True), Group(Words(*APPROXIMATIONS), name="approximation"))
MOTION_GROUPS = ("keyword", "joint", "name", "approximation")  # the groups of a motion read at once, after its line's
# DECL E6POS XP1={X 1.0,Y 2.0,Z 3.0,A 0.0,B 90.0,C 0.0,S 2,T 35,E1 0.0,..,E6 0.0} (S, T and E1..E6 optional), as
# KUKA's editors and CAM post-processors declare a Cartesian point
WRITTEN_POINT = Form(
    Words("DECL"), Blank(True), Group(Repeat(Words(*QUALIFIERS), Blank(True)), name="qualifiers"),
    Words(*CARTESIAN_TYPES), Blank(True), Group(Name(), name="name"), Blank(), Literal("="), Blank(), Literal("{"),
    *_members(Literal(",")), Literal("}"), Blank(), LineEnd())
# LIN XP1 C_DIS, PTP P2: a motion to a named point (no WITH, no _REL)
WRITTEN_MOTION = Form(
    _MOTION_KEYWORD, Blank(True), Group(Name(first="A-Za-z_", ascii=True, excluding=APPROXIMATIONS + (WITH,)),
                                        name="name"),
    _APPROXIMATION, Blank(), LineEnd())
# LIN {X 446.0,Y 70.0,Z 635.0,A 0.0,B 90.0,C 0.0} C_DIS as RoboDK's and SprutCAM's KUKA posts write it, or
# LIN {E6POS: X 446.0, Y 70.0, ..} C_DIS as other generators do (the members as `WRITTEN_POINT` has them, a blank
# or none after each comma; no WITH, no _REL); an empty name before the members
INLINE_MOTION = Form(
    _MOTION_KEYWORD, Blank(True), Literal("{"), Optional(Words(*CARTESIAN_TYPES), Literal(":"), Optional(Literal(" "))),
    Group(name="name"), *_members(Literal(","), Optional(Literal(" "))), Literal("}"), _APPROXIMATION, Blank(),
    LineEnd())
