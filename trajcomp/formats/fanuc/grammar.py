"""The FANUC LS grammar: the statement forms of a .LS program and their fields, declared once.

Both reads of `trajcomp.formats.fanuc.reader` execute this declaration:

- the line-by-line read matches the patterns compiled from each field's
  ``accepted`` spelling (every spelling the controller reads: ``MOTION``,
  ``SPEED_TERM``, ``POSITION_ENTRY`` ..);
- the at-once read executes the ``written`` spelling of the same fields (the
  one CAM post-processors and the teach pendant write): ``WRITTEN_MOTION``
  finds the lines, `Piece` by `Piece` (`MOTION_PIECES`) their fields are
  located column-wise from the characters each piece is made of; a /POS
  entry is located by the delimiters of its declared members
  (`POSITION_LAYOUT`). A line or entry the written spelling does not cover
  is read line by line.

A program (`SECTIONS`)::

    /PROG  NAME
    /ATTR ..
    /MN
       1:  UTOOL_NUM=1 ;                         frame and tool numbers (`FRAME_STATE`, `SET_FRAME`)
       2:J P[1] 100% FINE    ;                   motions: J, L, C (`KIND`) to P[n] or PR[n] (`POSITION`),
       3:L P[2] 50mm/sec CNT10 ACC80   ;         a speed (`SPEED`), FINE or CNTn (`TERMINATION`), options
       4:C P[3]                                  a circle's via point, its end point on the next line
           :  P[4] 50mm/sec FINE    ;
       5:  CALL SUB ;  JMP LBL[1] ;  IF ..       instructions that change the order it runs in (`CALL` ..)
    /POS
    P[1]{ GP1: UF : 0, UT : 1, CONFIG : 'N U T, 0, 0, 0',      entries (`MEMBERS`)
      X = 1.0 mm, Y = 2.0 mm, Z = 3.0 mm, W = 180.0 deg, P = 0.0 deg, R = 0.0 deg };
    /END

Nothing but blank lines may follow /END (`AFTER_END`): the controller's
loader refuses such a file.
"""

import dataclasses
import re

import numpy as np

from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.text import mask
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR

# --- sections ---------------------------------------------------------------------------------------------------------
SECTIONS = ("PROG", "ATTR", "APPL", "MN", "POS", "END")
_SECTION_WORDS = "|".join(SECTIONS)
SECTION_WORD = re.compile(r"/(" + _SECTION_WORDS + r")\b")  # a section header where white space alone precedes it
AFTER_END = re.compile(r"\s*")  # what may follow the /END line: blank lines alone (fullmatch)


@dataclasses.dataclass(frozen=True)
class Piece:
    """A piece of a field's written spelling, as the at-once read executes it.

    Attributes
    ----------
    written : str
        Regular expression of the piece (no groups).
    blanks : str
        What may stand before it: "" (nothing), ``"[ \\t]*"`` or ``"[ \\t]+"``.
    characters : str or None
        The characters it is made of: the at-once read locates its end as
        the first character not among them. None: a literal, ``written``
        as it is spelt (its length is its width).
    """

    written: str
    blanks: str = ""
    characters: str = None

    @property
    def width(self):
        """Characters of a literal piece."""
        return len(self.written.replace("\\", ""))


@dataclasses.dataclass(frozen=True)
class Field:
    """One field of a statement form.

    Attributes
    ----------
    name : str
    accepted : str
        Regular expression of every spelling the controller reads (the
        line-by-line read); its groups are the field's parts.
    written : dict of str: Piece
        The spelling CAM post-processors write, by piece name (the at-once
        read); empty where they write none that is read at once.
    """

    name: str
    accepted: str
    written: dict = dataclasses.field(default_factory=dict)


BLANK, BLANKS = "[ \t]*", "[ \t]+"
DIGITS = "0123456789"
# Speed units: spelling -> (scale to the unit read, unit read); the German export writes "sek" for "sec".
SPEED_UNITS = {"%": (1.0, "%"), "mm/sec": (1.0, "mm/s"), "cm/min": (10.0 / 60.0, "mm/s"),
               "inch/min": (25.4 / 60.0, "mm/s"), "deg/sec": (np.pi / 180.0, "rad/s"),
               "sec": (1.0, "s"), "msec": (1e-3, "s")}
_UNIT_ORDER = ("%", "mm/sec", "cm/min", "inch/min", "deg/sec", "msec", "sec")  # a longer one first
_UNIT = "|".join(u.replace("sec", "se[ck]") for u in _UNIT_ORDER)
_WRITTEN_UNIT = "|".join(_UNIT_ORDER)
MAX_SPEED = "max_speed"  # a motion's speed: the arm's own limits


def speed_unit(spelling):
    """``(scale, unit)`` of a speed unit as spelt (`SPEED_UNITS`): any case, "sek" for "sec"."""
    return SPEED_UNITS[re.sub("sek$", "sec", spelling.lower())]


# an index: P[3], or P[R[3]] / P[R[3:idx]] (one a register holds)
INDEX = r"((?:A?R\[[^\]]*\]|[^\]:\[])+?)"
_COMMENT = r"\s*(?::[^\]]*)?\]"  # an index's comment, P[3:"seam"], and the closing bracket

KINDS = {"J": JOINT, "L": LINEAR, "C": CIRCULAR}
LINE_NUMBER = Field("line number", r"(\d+):", {"number": Piece(r"\d*", BLANK, DIGITS), ":": Piece(":")})
KIND = Field("kind", "([" + "".join(KINDS) + "])", {"kind": Piece("[JL]", BLANK, "JL")})  # C: two lines, not at once
POSITION = Field("position", r"(P|PR)\[\s*" + INDEX + _COMMENT,
                 {"P[": Piece(r"P\[", BLANKS), "position": Piece(r"\d{1,9}", BLANK, DIGITS), "]": Piece(r"\]", BLANK)})
VIA_END = Field("circle's end point", r"P\[\s*" + INDEX + _COMMENT)  # after the via point (PR[n]: REGISTER_POINT)
SPEED = Field(  # a number and its unit, a register holding one (set at run time), or max_speed (the arm's limits)
    "speed", r"(?:(" + NUMBER + r")\s*(" + _UNIT + r")|A?R\[[^\]]*\]\s*(?:" + _UNIT + r")?|\S+)",
    {"speed": Piece(r"\d{1,9}(?:\.\d{0,9})?", BLANKS, DIGITS + "."),
     "unit": Piece("(?:" + _WRITTEN_UNIT + ")", BLANK, "".join(sorted(set(_WRITTEN_UNIT) - {"|"})))})
TERMINATION = Field(  # FINE, CNTn (read as an n mm blend), CRn, CDn
    "termination", r"(FINE|FEIN|CNT\s*(" + NUMBER + r")?\S*|C[RD]\s*(" + NUMBER + r")?\S*)",
    {"termination": Piece(r"FINE(?=[ \t])|CNT(?=\d)", BLANKS, "CEFINT"),
     "zone": Piece(r"\d{0,3}", "", DIGITS)})
TERMINATION_WORDS = "FINE|FEIN|CNT|CR|CD"
END = Field("end", ";", {";": Piece(";", BLANK)})
# options after the termination: the acceleration override ACC n (%), modifiers applied at run time
ACC = re.compile(r"\bACC\s*(" + NUMBER + r"|A?R\[[^\]]*\])", re.I)
RUNTIME = re.compile(r"\b(Offset|Tool_Offset|INC|VOFFSET)\b", re.I)

MOTION_FIELDS = (LINE_NUMBER, KIND, POSITION, SPEED, TERMINATION, END)  # the written form, in order

# /MN instructions: numbered lines, continued by lines without a number up to one ended by its ";"
NUMBERED = re.compile(r"^\s*" + LINE_NUMBER.accepted + "(.*)$")
CONTINUED = re.compile(r"^\s*:(.*)$")
# an instruction ended, or a comment (masked): none continues it
CLOSED = re.compile(r"(?:^|" + END.accepted + r")\s*$")

# the line-by-line read's patterns of a motion instruction (its text after the line number)
MOTION = re.compile(r"^\s*" + KIND.accepted + r"\s+" + POSITION.accepted + r"(.*)$", re.I)
POINT = re.compile(r"^\s*" + VIA_END.accepted + r"(.*)$", re.I)  # a circle's end point P[n]
REGISTER_POINT = re.compile(r"\b(PR)\[\s*" + INDEX + _COMMENT + r"(.*)$", re.I)  # .. or PR[n]
SPEED_TERM = re.compile(r"^\s*" + SPEED.accepted + r"\s+" + TERMINATION.accepted + r"(?:\s|$)", re.I)
SPEED_FIELD = re.compile(  # where re-timing writes a motion's speed
    r"(?:" + NUMBER + r")\s*(?:" + _UNIT + r")(?=\s+(?:" + TERMINATION_WORDS + r"))", re.I)
POINT_REF = re.compile(r"\bP\[\s*(\d+)" + _COMMENT, re.I)  # a position any instruction names
MOTION_REGISTER = re.compile(  # a motion line's register (``J PR[3] ...``, a circle's continuation ``: PR[4] ...``)
    r"^\s*(?:\d+:\s*" + KIND.accepted.strip("()") + r"|:)\s*PR\[\s*(\d+)\s*[:\]]", re.I | re.M)

# The at-once read's pattern: the motion lines written as their written pieces spell them, one a line.
MOTION_PIECES = tuple((name, piece) for field in MOTION_FIELDS for name, piece in field.written.items())
WRITTEN_MOTION = re.compile(
    "^" + "".join(piece.blanks + "(?:" + piece.written + ")" for _, piece in MOTION_PIECES) + r"[ \t]*\r?$", re.M)
WRITTEN_NUMBERS = 10**9  # position numbers of the written motion lines (9 digits) are below

COMMENTED_OUT = "//"  # an instruction the pendant commented out (``  7:  //PR[1]=LPOS ;``): it does not run


def masked(text):
    """`trajcomp.formats.text.mask` of a listing: remarks (``!``), instructions commented out (`COMMENTED_OUT`)
    and the contents of strings blanked, so that no pattern finds what the controller does not run."""
    return mask(mask(text, "!", quote='"'), COMMENTED_OUT, quote='"')


# --- /MN instructions that are not motions ---------------------------------------------------------------------------
FRAME_WORDS = {"UTOOL_NUM": "tool", "WKZ_NUM": "tool", "UFRAME_NUM": "frame", "BENUTZER_NUM": "frame",
               "UTOOL": "tool", "WKZ": "tool", "UFRAME": "frame", "BENUTZER": "frame"}  # English and German exports
FRAME_STATE = re.compile(  # UTOOL_NUM=1 ; UFRAME_NUM=R[1] ;
    r"^\s*(" + "|".join(w for w in FRAME_WORDS if w.endswith("_NUM")) + r")\s*=\s*(.*?)\s*;", re.I)
SET_FRAME = re.compile(  # UTOOL[1]=PR[3] ;
    r"^\s*(" + "|".join(w for w in FRAME_WORDS if not w.endswith("_NUM")) + r")\s*\[\s*(\d+)\s*\]\s*=\s*(.*?)\s*;",
    re.I)
# the instructions that change the order a program runs in (`trajcomp.programs.flow.Step`)
CALL = re.compile(r"\bCALL\s+(\w+)", re.I)
JUMP = re.compile(r"\bJMP\s+LBL\s*\[\s*(\w+)", re.I)
LABEL = re.compile(r"^\s*LBL\s*\[\s*(\w+)", re.I)
CONDITION = re.compile(r"^\s*(IF|SELECT|=|ELSE\s*,)", re.I)  # IF .., JMP / CALL; SELECT .. =n, JMP ..; ELSE, JMP
THEN = re.compile(r"\bTHEN\s*$", re.I)  # IF .. THEN: a block up to ENDIF
BLOCK_WORDS = {"ELSE": "else", "ENDIF": "endif", "ENDFOR": "endloop", "END": "return", "ABORT": "return"}
WAIT = re.compile(r"^\s*(WAIT|PAUSE)\b", re.I)


# --- /POS entries -----------------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Member:
    """A member of a /POS entry's group: its keywords (the written one first) and what it holds.

    ``value``: "frame" (a whole number after ``:``), "config" (a quoted
    string after ``:``) or a unit (a number after ``=``, then the unit).
    """

    keys: tuple
    value: str


XYZWPR = ("x", "y", "z", "w", "p", "r")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
UNITS = dict.fromkeys(XYZWPR[:3], "mm") | dict.fromkeys(XYZWPR[3:], "deg")
GROUP = "GP1"  # the motion group whose members are the target (others: external axes)
# the members of a Cartesian position of group 1, in the order the pendant writes them
MEMBERS = ((Member(("UF",), "frame"), Member(("UT",), "frame"), Member(("CONFIG", "KONFIG"), "config"))
           + tuple(Member((c.upper(),), UNITS[c]) for c in XYZWPR))
_FRAME_KEYS = "|".join(key for m in MEMBERS if m.value == "frame" for key in m.keys)
_CONFIG_KEYS = "|".join(key for m in MEMBERS if m.value == "config" for key in m.keys)
_COORDINATES = "".join(m.keys[0] for m in MEMBERS if m.value in ("mm", "deg"))
_MEMBER_UNITS = "|".join(sorted({m.value for m in MEMBERS if m.value in ("mm", "deg")}, key=["mm", "deg"].index))

POSITION_ENTRY = re.compile(r"P\[\s*(\d+)\s*(?::\s*\"[^\"]*\")?\s*\]\s*\{(.*?)\};", re.S)  # P[n:"comment"]{ .. };
GROUPS = re.compile(r"GP(\d+)\s*:(.*?)(?=GP\d+\s*:|$)", re.S)
COORDINATE = re.compile(  # X = 1.5 mm; J1 = 10 deg (joint representation); E1 = 5 mm (an extended axis)
    r"\b([" + _COORDINATES + r"]|J\d|E\d)\s*=\s*(" + NUMBER + r"|\*+)\s*(" + _MEMBER_UNITS + ")", re.I)
FRAME_NUMBER = re.compile(r"\b(" + _FRAME_KEYS + r")\s*:\s*(\d+)", re.I)
CONFIG = re.compile(r"(?:" + _CONFIG_KEYS + r")\s*:\s*'([^']*)'", re.I)
CONFIG_VALUE = re.compile(  # flip, elbow, front, turns of J1, J4, J6
    r"^\s*([NF])\s*([UD])\s*([TB])\s*,\s*(-?\d{1,3})\s*,\s*(-?\d{1,3})\s*,\s*(-?\d{1,3})\s*$", re.I)
SCARA_CONFIG = re.compile(r"^\s*[LR]\s*,(?:\s*-?\d{1,3}\s*,?)*\s*$", re.I)  # a 4-axis arm's: not supported


def config(text):
    """``(flip, elbow, front, t1, t4, t6)`` of a CONFIG string; None where it is not one (`CONFIG_VALUE`)."""
    value = CONFIG_VALUE.match(text)
    if value is None:
        return None
    return (value.group(1).upper(), value.group(2).upper(), value.group(3).upper(), *map(int, value.groups()[3:]))


OTHER_REPRESENTATION = re.compile(r"\bR[" + _COORDINATES + r"]\s*=", re.I)  # RX, RY ..: not read

# The at-once read's layout of an entry: its delimiters, each with what stands before it: None (not looked at), ""
# (white space or nothing), `NEXT_TO` (nothing), a keyword (upper case, any case in the file) or a field (lower case),
# white space around them (`POSITION_ENTRY` ends an entry at the first "};").
NEXT_TO = "next to"
_QUOTED = (("'", ""), (",", None), (",", None), (",", None), ("'", "config"))  # 'N U T, 0, 0, 0': its four parts


def _member_layout(member, last):
    """The delimiters of one member (`MEMBERS`) as written, ``last``: the group's last (closed by "}")."""
    key, after = member.keys[0], "}" if last else ","
    if member.value == "frame":
        return ((":", key), (",", key.lower()))
    if member.value == "config":
        return ((":", key),) + _QUOTED + ((",", ""),)
    return (("=", key), (after, key.lower()))


POSITION_LAYOUT = ((("[", None), ("]", "number"), ("{", ""), (":", GROUP))
                   + tuple(pair for k, m in enumerate(MEMBERS) for pair in _member_layout(m, k == len(MEMBERS) - 1))
                   + ((";", NEXT_TO),))
COMMENTED_LAYOUT = POSITION_LAYOUT[:1] + ((":", "number"), ('"', ""), ('"', None), ("]", "")) + POSITION_LAYOUT[2:]
LAYOUT_FIELDS = ("number", "uf", "ut") + XYZWPR + ("config",)  # the fields a layout gives, in this order
LAYOUT_DELIMITERS = "".join(dict.fromkeys(c for c, _ in POSITION_LAYOUT + COMMENTED_LAYOUT))  # what it finds
