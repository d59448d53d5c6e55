"""The RAPID language as trajcomp reads it, declared once: its statement forms and their fields.

Both reads of a module are driven from here (`trajcomp.formats.rapid.reader`):
- the statement-by-statement read matches the patterns these
  declarations compile to (declarations of each data type with its
  record's fields, motion instructions and their arguments, VelSet and
  AccSet, blocks, routines, modules);
- the read at once runs the one-line forms CAM tools write (`WRITTEN_FORMS`:
  a robtarget declaration, a MoveL / MoveJ to a name or to an inline
  robtarget) over every line of a module together (`forms.Form.find`);
  the lines it leaves are matched by the same forms' patterns
  (`forms.Form.regex`), the others statement by statement.
Identifiers and keywords are case-blind (every pattern is ``re.I``).
"""

import dataclasses
import functools
import re

from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.text import INDENT
from trajcomp.formats.forms import (
    Blank, Form, Group, LineEnd, Literal, Name, Number, Optional, Repeat, Value, Words,
)
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR

# ---- data: records and their fields (RAPID reference, Data types), in the order a value writes them


@dataclasses.dataclass(frozen=True)
class Record:
    """A RAPID record type: its fields in order, each ``num``, ``bool``, ``string`` or a `Record`."""

    name: str
    fields: tuple  # (field name, type) pairs

    @property
    def layout(self):
        """Its value's delimiters (``[[,,],[,,,]]`` for a pose): a field between ``[`` or ``,`` and ``,`` or ``]``."""
        return "[" + ",".join(t.layout if isinstance(t, Record) else "" for _, t in self.fields) + "]"

    def pattern(self, read=None, maybe=False):
        """The regular expression of a value (blanks anywhere between its parts), a group per field that is
        not a record: a number, ``TRUE``/``FALSE``, a string (blanked: `trajcomp.formats.text.mask`).

        ``read``: only the first ``read`` fields, then a ``,`` (the others are not read); with ``maybe``, the
        next field is read where it is a number, and the rest to the value's ``]`` is not."""
        fields = self.fields if read is None else self.fields[:read]
        inner = r"\s*,\s*".join(_field_pattern(t) for _, t in fields)
        if read is None:
            return r"\[\s*" + inner + r"\s*\]"
        return r"\[\s*" + inner + (r"\s*,\s*(" + NUMBER + r")?[^\]]*\]" if maybe else r"\s*,")


def _field_pattern(typ):
    return typ.pattern() if isinstance(typ, Record) else {"num": f"({NUMBER})", "bool": "(TRUE|FALSE)",
                                                          "string": r'"(\s*)"'}[typ]


def _numbers(name, *fields):
    return Record(name, tuple((f, "num") for f in fields))


POS = _numbers("pos", "x", "y", "z")  # mm
ORIENT = _numbers("orient", "q1", "q2", "q3", "q4")  # quaternion, scalar first
CONFDATA = _numbers("confdata", "cf1", "cf4", "cf6", "cfx")
EXTJOINT = _numbers("extjoint", "eax_a", "eax_b", "eax_c", "eax_d", "eax_e", "eax_f")  # 9E9: not used
ROBJOINT = _numbers("robjoint", "rax_1", "rax_2", "rax_3", "rax_4", "rax_5", "rax_6")  # deg
POSE = Record("pose", (("trans", POS), ("rot", ORIENT)))
LOADDATA = Record("loaddata", (("mass", "num"), ("cog", POS), ("aom", ORIENT), ("ix", "num"), ("iy", "num"),
                               ("iz", "num")))
ROBTARGET = Record("robtarget", (("trans", POS), ("rot", ORIENT), ("robconf", CONFDATA), ("extax", EXTJOINT)))
JOINTTARGET = Record("jointtarget", (("robax", ROBJOINT), ("extax", EXTJOINT)))
TOOLDATA = Record("tooldata", (("robhold", "bool"), ("tframe", POSE), ("tload", LOADDATA)))
WOBJDATA = Record("wobjdata", (("robhold", "bool"), ("ufprog", "bool"), ("ufmec", "string"), ("uframe", POSE),
                               ("oframe", POSE)))
SPEEDDATA = _numbers("speeddata", "v_tcp", "v_ori", "v_leax", "v_reax")  # mm/s, deg/s, mm/s, deg/s
ZONEDATA = Record("zonedata", (("finep", "bool"), *((f, "num") for f in (
    "pzone_tcp", "pzone_ori", "pzone_eax", "zone_ori", "zone_leax", "zone_reax"))))

POINT_TYPES = ("robtarget", "jointtarget")  # the points a motion goes to
FRAME_TYPES = ("tooldata", "wobjdata")  # the tool and the work object a motion is in
SPEED_TYPES = ("speeddata", "num")  # what a motion's speed data and its \V, \T, VelSet, AccSet name

# the patterns of the values read, a group per field (`Record.pattern`); tooldata: robhold and tframe only,
# speeddata: v_tcp, v_ori, and v_leax where it is a number
ROBTARGET_VALUE = re.compile(r"^\s*" + ROBTARGET.pattern() + r"\s*$")
JOINTTARGET_VALUE = re.compile(r"^\s*" + JOINTTARGET.pattern() + r"\s*$")
TOOLDATA_VALUE = re.compile(r"^\s*" + TOOLDATA.pattern(read=2), re.I)
WOBJDATA_VALUE = re.compile(r"^\s*" + WOBJDATA.pattern() + r"\s*$", re.I)
POSE_VALUE = re.compile(r"^\s*" + POSE.pattern() + r"\s*$")
SPEEDDATA_VALUE = re.compile(r"^\s*" + SPEEDDATA.pattern(read=2, maybe=True) + r"\s*$")
PREDEFINED_SPEED = re.compile(r"^v(\d+(?:\.\d*)?)$", re.I)  # v5 .. v7000: v_tcp in mm/s
PREDEFINED_ZONE = re.compile(r"^(fine|z(\d+(?:\.\d*)?))$", re.I)  # fine, z0 .. z200: mm

# ---- declarations: [LOCAL | TASK] CONST | PERS | VAR type name [:= value];

PREFIXES = ("LOCAL", "TASK")  # LOCAL: seen in its module only; TASK (a PERS): in its task only
STORAGES = ("CONST", "PERS", "VAR")  # a CONST has a value; a PERS keeps the last one the program gave it


def _either(words, capture=False):
    return ("(" if capture else "(?:") + "|".join(words) + ")"


_PREFIX = r"(?:" + _either(PREFIXES) + r"\s+)*"
_HEAD = r"^\s*" + _PREFIX  # a declaration's start, to its storage

DECLARATION = re.compile(  # groups: type, name, value
    _HEAD + _either(STORAGES) + r"\s+" + _either(POINT_TYPES + FRAME_TYPES, True) + r"\s+(\w+)\s*:=(.*);\s*$",
    re.I | re.S)
DECLARATION_WITHOUT_VALUE = re.compile(  # group: the names
    _HEAD + _either(STORAGES[1:]) + r"\s+" + _either(POINT_TYPES + FRAME_TYPES) + r"\s+(\w+(?:\s*,\s*\w+)*)\s*;",
    re.I)
STARTS_DECLARATION = re.compile(_HEAD + _either(STORAGES) + r"\b", re.I)
STORAGE = re.compile(r"^\s*(" + _PREFIX + ")" + _either(STORAGES, True) + r"\b", re.I)  # groups: prefixes, storage
SPEED_DECLARATION = re.compile(  # groups: storage, type, name, value
    r"[ \t]*" + _PREFIX + _either(STORAGES, True) + r"\s+" + _either(SPEED_TYPES, True)
    + r"\s+(\w+)\s*(?::=\s*([^;]*?))?\s*;", re.I | re.M)


def declared_in_task(types):
    """The declarations of ``types`` another module of the task sees (not LOCAL), per line: group 1 the name."""
    return re.compile(r"^[ \t]*(?:TASK\s+)?" + _either(STORAGES) + r"\s+" + _either(types) + r"\s+(\w+)",
                      re.I | re.M)


TASK_POINT, TASK_FRAME, TASK_SPEED = (declared_in_task(types) for types in (POINT_TYPES, FRAME_TYPES, SPEED_TYPES))
ASSIGNED = re.compile(r"^\s*([A-Za-z]\w*)(?:\.\w+)*\s*:=")  # a statement giving a datum (or a field of it) a value
ASSIGNMENT = re.compile(r"^\s*([A-Za-z]\w*)((?:\.\w+)*)\s*:=(.*);\s*$", re.S)  # groups: name, fields, value

# ---- modules, routines and blocks

MODULE = re.compile(r"^\s*MODULE\s+(\w+)", re.I | re.M)
OUTSIDE_MODULES = re.compile(r"[ \t]*(?:%%%|VERSION\s*:|LANGUAGE\s*:)", re.I)  # a file's header
ROUTINES = ("PROC", "FUNC", "TRAP")  # FUNC has its return type before its name
_ROUTINE_HEAD = r"^\s*(?:LOCAL\s+)?(?:PROC|FUNC\s+\w+|TRAP)\s+"
ROUTINE = re.compile(_ROUTINE_HEAD + r"\w+\s*\((.*)\)", re.I | re.S)  # group: the parameters
STARTS_ROUTINE = re.compile(_ROUTINE_HEAD + r"\w+\s*\(", re.I)
ROUTINE_NAME = re.compile(_ROUTINE_HEAD + r"(\w+)", re.I)
ROUTINE_NAME_LINE = re.compile(_ROUTINE_HEAD.replace("^\\s*", "^[ \\t]*") + r"(\w+)", re.I | re.M)  # per line
# every block and the word that closes it: a controller refuses a module whose blocks are not closed in order
BLOCKS = {"MODULE": "ENDMODULE", "PROC": "ENDPROC", "FUNC": "ENDFUNC", "TRAP": "ENDTRAP",
          "IF": "ENDIF", "FOR": "ENDFOR", "WHILE": "ENDWHILE", "TEST": "ENDTEST"}
ROUTINE_OPENS = re.compile(INDENT + r"(?:LOCAL\s+)?(MODULE|PROC|FUNC|TRAP)\b", re.I | re.M)
ROUTINE_CLOSES = re.compile(INDENT + r"(ENDMODULE|ENDPROC|ENDFUNC|ENDTRAP)\b", re.I | re.M)
# ... opened at a line's start: a module or routine, LOCAL or not, or a flow block; an IF only with a THEN before
# its ';' (``IF cond instruction;`` is one statement)
BLOCK_OPENS = re.compile(INDENT + r"(?:LOCAL\s+)?(MODULE|PROC|FUNC|TRAP|IF(?=[^;]*?\bTHEN\b)|FOR|WHILE|TEST)\b",
                         re.I | re.M)
BLOCK_CLOSES = re.compile(INDENT + r"(" + "|".join(BLOCKS.values()) + r")\b", re.I | re.M)
# the statements that change the order a module runs in (`trajcomp.programs.flow.Step`): first word -> step kind
FLOW_STEPS = {"if": "if", "elseif": "elif", "else": "else", "endif": "endif", "test": "if", "case": "elif",
              "default": "elif", "endtest": "endif", "for": "loop", "endfor": "endloop", "while": "loop",
              "endwhile": "endloop", "goto": "jump", "return": "return", "exit": "return", "stop": "wait",
              "endproc": "end", "endfunc": "end", "endtrap": "end"}
WAITS = re.compile(r"^\s*(Wait\w*|Stop|StopMove|Break)\b", re.I)  # the arm stops there: WaitTime, WaitDI, ...
LABEL = re.compile(r"^\s*([A-Za-z]\w*)\s*:\s*$")

# ---- instructions: their arguments in order, \Option:=value after any of them


@dataclasses.dataclass(frozen=True)
class Instruction:
    """An instruction's name, its positional arguments and its optional ones (``\\Name:=value``)."""

    name: str
    arguments: tuple
    options: tuple = ()

    @functools.cached_property
    def pattern(self):
        """Its statement's regular expression: a group per argument, then per option (None where not written)."""
        last = r"([^,;\\]+)" if self.options else r"([^,;]+)"
        arguments = r",\s*".join([r"([^,;]+)"] * (len(self.arguments) - 1) + [last])
        options = "".join(rf"(?:\\{o}\s*:=\s*([^,;\\]+))?" for o in self.options)
        return re.compile(rf"^\s*{self.name}\s+" + arguments + options + r"\s*;", re.I)


VELSET = Instruction("VelSet", ("Override", "Max"))  # %, mm/s
ACCSET = Instruction("AccSet", ("Acc", "Ramp"), ("FinePointRamp",))  # %, %, %


@dataclasses.dataclass(frozen=True)
class MotionInstruction:
    """A motion instruction read: its points (a circle's CirPoint then ToPoint), Speed, Zone, Tool.

    ``tool_last``: data between the zone and the tool (TriggL's triggers,
    ArcL's seam and weld data), the tool the last positional argument;
    else the tool follows the zone. ``joints``: its point a jointtarget.
    """

    name: str
    kind: str
    tool_last: bool = False
    joints: bool = False

    @property
    def points(self):
        return 2 if self.kind == CIRCULAR else 1


_KINDS = {"J": JOINT, "L": LINEAR, "C": CIRCULAR}
MOTIONS = {m.name.upper(): m for m in (
    *(MotionInstruction(f"Move{k}{suffix}", kind) for k, kind in _KINDS.items()
      for suffix in ("", "DO", "AO", "GO", "Sync")),
    MotionInstruction("MoveAbsJ", JOINT, joints=True),
    *(MotionInstruction(f"{family}{k}", kind, tool_last=True) for family in ("Trigg", "Arc", "Clad")
      for k, kind in _KINDS.items()))}
# the optional arguments of a motion read (the others are kept as written)
MOTION_OPTIONS = {"v": "num: the TCP speed in place of the speeddata's v_tcp (mm/s)",
                  "t": "num: the motion's time, its speeds not used (s)",
                  "z": "num: the zone's size in place of the zonedata's (mm)",
                  "wobj": "wobjdata: the work object (default wobj0)"}
# every motion instruction's family: one not in `MOTIONS` (SearchL, MoveExtJ, SpotL, EGMMoveL, EGMRunPose ...) is
# listed, not read
STARTS_MOTION = re.compile(r"^\s*(?:Move|Trigg|Search|Arc|Clad|Spot|Paint|Disp|Contact|EGMMove|EGMRun)\w*\b", re.I)
INSTRUCTION = re.compile(r"^\s*([A-Za-z]\w*)\b(.*);\s*$", re.S)  # groups: its name, its arguments
OPTION = re.compile(r"\\(\w+)(?:\s*:=\s*([^\\]+))?")  # groups: an optional argument's name, its value

# instructions that read their arguments and change none: a VAR speeddata or num assigned before them is still in
# force after them, and one named in them keeps its value
STRAIGHT = {"confj", "confl", "tpwrite", "tperase", "waittime", "setdo", "setao", "setgo", "set", "reset", "pulsedo",
            "singarea", "pathresol", "accset", "velset"}
# words that start a statement but call no routine
NOT_CALLS = {"module", "endmodule", "local", "task", "error", "backward", "undo", "record", "endrecord", "alias"}
# instructions that neither move the arm nor change its speed: a call of any other name not declared in the module
# may (a routine of another module of the task)
BUILT_IN = STRAIGHT | {"accset", "velset", "tpreadfk", "tpreadnum", "tpshow", "errwrite", "incr", "decr", "add",
                       "clear", "setdo", "setao", "setgo", "open", "close", "write", "writestr", "rewind",
                       "iwatch", "isleep", "idelete", "isignaldi", "isignaldo", "itimer", "connect", "triggio",
                       "triggequip", "triggint", "gripload", "load", "unload", "erasemodule", "raise",
                       "retry", "trynext", "skipwarn", "waittime", "waitdi", "waitdo", "waituntil", "waitai",
                       "waitao", "waitgi", "waitgo", "waitrob", "waitsynctask", "stopmove", "startmove",
                       "storepath", "restopath", "clearpath", "confj", "confl", "singarea", "pathresol"}

# ---- the one-line forms read at once (`forms.Form`): what RobotStudio and CAM post-processors write

# CONST robtarget p1:=[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[ea,..,ef]]; (no blanks in the value: its numbers are
# read from its characters): groups LOCAL / TASK, storage, name, value, the end of its ';'
WRITTEN_POINT = Form(Group(Repeat(Words(*PREFIXES), Blank(True))), Group(Words(*STORAGES)), Blank(True),
                     Words("robtarget"), Blank(True), Group(Name()), Blank(), Literal(":="), Blank(),
                     Group(Value(ROBTARGET.layout)), Blank(), Literal(";"), Group(), Blank(), LineEnd())
AT_ONCE_MOTIONS = ("MoveL", "MoveJ")  # one point, then speed, zone, tool
# ..., v50\V:=45, z1, tool0\WObj:=wobj1; (or tool0,\WObj:=wobj1): groups the speed data, the end of its ';'
_MOTION_REST = (
    Blank(), Literal(","), Blank(),
    Group(Name(), Optional(Blank(), Literal("\\"), Words("V", "T"), Blank(), Literal(":="), Blank(), Number())),
    Blank(), Literal(","), Blank(), Name(), Blank(), Literal(","), Blank(), Name(), Blank(),
    Optional(Optional(Literal(","), Blank()), Literal("\\"), Blank(), Words("WObj"), Blank(), Literal(":="), Blank(),
             Name(), Blank()),
    Literal(";"), Group(), Blank(), LineEnd())
# MoveL p1, v50, z1, tool0; groups: instruction, point, speed data, the end of its ';'
WRITTEN_MOTION = Form(Group(Words(*AT_ONCE_MOTIONS)), Blank(True), Group(Name(first="A-Za-z")), *_MOTION_REST)
# MoveL [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[ea,..,ef]],v50,z1,tool0\WObj:=wobj0; as RoboDK's ABB posts write it
WRITTEN_INLINE = Form(Group(Words(*AT_ONCE_MOTIONS)), Blank(True), Group(Value(ROBTARGET.layout)), *_MOTION_REST)
WRITTEN_FORMS = (WRITTEN_POINT, WRITTEN_MOTION, WRITTEN_INLINE)
