"""The URScript grammar: the statement forms of a script and their fields, declared once.

Both reads of `trajcomp.formats.urscript.reader` execute this declaration:

- the line-by-line read matches the patterns compiled from the forms as a
  script may spell them (``CALL``, ``POSE_VALUE``, ``ASSIGN``, the block
  words ..) and reads a motion's arguments by its function's `Signature`;
- the at-once read (`trajcomp.formats.urscript.lines`) executes the spelling
  CAM post-processors write: ``CAM_LINE``, compiled from the same
  signatures, options and position literals, a group a piece, whose group
  numbers (`CAM_GROUP`) tell that read where each field of a line is.

A script::

    def prog():                                   blocks up to their ``end`` (`BLOCK_WORDS`)
      global speed_ms = 0.25                      assignments (`ASSIGN`): numbers, poses, joint lists
      ref_frame = p[0.5, 0, 0.2, 0, 0, 0]         a pose literal (`POSE`: metres, rotation vector)
      set_tcp(p[0, 0, 0.1, 0, 0, 0])
      movej([0, -1.57, 1.57, 0, 0, 0], a=1.4, v=1.05)            motions (`MOTIONS`): their position,
      movel(pose_trans(ref_frame, p[...]), 1.2, speed_ms, 0, 0.001)   then options named or by position
      if digital_in[0]: .. elif .. else .. end ; while .. ; for ..   the order it runs in (`FLOW_LINE`)
      sleep(0.5)
    end
"""

import dataclasses
import re

from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.text import INDENT
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR

NAME = r"[A-Za-z_]\w*"
POSE = ("x", "y", "z", "rx", "ry", "rz")  # a pose literal's numbers: metres, a rotation vector (rad)
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")  # a joint list's: rad
NEAR = ("near1", "near2", "near3", "near4", "near5", "near6")  # a qnear list's (the joints of a pose)


@dataclasses.dataclass(frozen=True)
class Signature:
    """A motion function: what it moves by, its options in the order it takes them by position, the speed it runs
    at without ``v=`` (rad/s for movej, m/s otherwise; None: none), and whether CAM posts write it in the shape the
    at-once read reads (``CAM_LINE``)."""

    kind: str
    positional: tuple
    default_speed: str = None
    written: bool = False


MOTIONS = {"movej": Signature(JOINT, ("a", "v", "t", "r"), "1.05", True),
           "movel": Signature(LINEAR, ("a", "v", "t", "r"), "0.25", True),
           "movep": Signature(LINEAR, ("a", "v", "r"), "0.25", True),
           "movec": Signature(CIRCULAR, ("a", "v", "r", "mode"), "0.25")}
STREAMED = ("servoj", "servoc")  # set points streamed to the arm: motions trajcomp does not compensate
DRIVEN = ("speedl", "speedj", "direct_torque")  # the arm moved by a velocity or torque: likewise, listed
CALLS = tuple(MOTIONS) + ("set_tcp",) + STREAMED + DRIVEN  # the calls the reader reads
OPTIONS = ("a", "v", "t", "r")  # the options of a motion a CAM post gives, named or by position
WRITTEN = tuple(f for f, signature in MOTIONS.items() if signature.written)  # the functions of ``CAM_LINE``


def six(blank):
    """Six numbers separated by commas, each a group, ``blank`` the white space allowed around them."""
    return ",".join([blank + "(" + NUMBER + ")" + blank] * 6)


# --- the line-by-line read --------------------------------------------------------------------------------------------
POSE_VALUE = re.compile(r"^\s*p\[" + six(r"\s*") + r"\]\s*$")  # a pose literal, the whole argument or value
LIST_VALUE = re.compile(r"^\s*\[" + six(r"\s*") + r"\]\s*$")  # a six-number list: joints (or data)
POSE_LITERAL = re.compile(r"\bp\[" + six(r"\s*") + r"\]")  # every pose literal of a script
NUMBERS_ONLY = re.compile(r"^\s*p\[[\s\d.eE+,-]*\]\s*$")  # a pose literal of numbers alone: six, or malformed
ASSIGN = re.compile(r"^\s*(?:global\s+|local\s+)?(" + NAME + r")\s*=(?!=)\s*(.+?)\s*$")
DEF = re.compile(r"^\s*def\s+\w+\s*\((.*?)\)\s*:", re.M)  # a function's parameters: known at run time
CALL = re.compile(rf"\b({'|'.join(CALLS)})\s*\(")
INVERSE_KINEMATICS = re.compile(r"^\s*get_inverse_kin\s*\((.*)\)\s*$", re.S)  # get_inverse_kin(pose, qnear=..)
POSE_TRANS = re.compile(r"^\s*pose_trans\s*\((.*)\)\s*$", re.S)  # pose_trans(frame, pose): a pose in a frame
VARIABLE = re.compile(r"^\s*(" + NAME + r")\s*$")
WORD = re.compile(NAME)
# a script has one: a def, a move or a pose literal; or, a script of statements alone (the lines a controller's
# secondary interface or a Script node runs: IO, Modbus, waits), a global or local assignment or a call of the I/O,
# communication or messaging functions of the URScript manual
SIGNS = re.compile(r"(?m)^\s*def\s+\w+\s*\(|\b(?:" + "|".join(MOTIONS) + r")\s*\(|\bp\["
                   r"|^\s*(?:global|local)\s+\w+\s*="
                   r"|\b(?:sleep|sync|halt|textmsg|popup|set_(?:standard_|tool_|configurable_)?(?:digital|analog)_out"
                   r"|(?:modbus|socket|rtde|rpc)_\w+|(?:read|write)_(?:input|output|port)_\w+)\s*\(")

# blocks: a statement ending with ":" opens one up to its ``end``
BLOCK_WORDS = ("def", "sec", "thread", "if", "while", "for")
BLOCK_OPENS = re.compile(INDENT + r"(" + "|".join(BLOCK_WORDS) + r")\b[^\n]*:\s*$", re.M)
BLOCK_CLOSES = re.compile(INDENT + r"(end)\s*$", re.M)
# the lines that change the order a script runs in (`trajcomp.programs.flow.Step`): blocks, their ends, waits
FLOW_LINE = re.compile(INDENT + r"(?:(def|thread|sec|if|elif|while|for)\b(?:[ \t]+(\w+))?[^\n]*:[ \t]*\r?$"
                       r"|(else)[ \t]*:[ \t]*\r?$|(end|break|halt)[ \t]*\r?$|(return)\b"
                       r"|(sleep|sync|stopj|stopl)[ \t]*\()", re.M)
OPENED = {"def": "end", "thread": "end", "sec": "end", "if": "endif", "while": "endloop", "for": "endloop"}
FLOW_KINDS = {"def": "routine", "thread": "routine", "sec": "routine", "if": "if", "elif": "elif", "else": "else",
              "while": "loop", "for": "loop", "break": "exit", "return": "return", "halt": "return"}


# --- the at-once read: the motion lines a CAM post writes, one a line -------------------------------------------------
# ``movel(p[x, y, z, rx, ry, rz], v=0.05, r=0.001)``, ``movej([q1, .., q6], a, v, t, r)``, ``movel(pose_trans(frame,
# p[...]), accel_mss, speed_ms, t=0, r=0.001)``: a written motion to a pose literal, a joint list or pose_trans of a
# variable and a pose literal, its options numbers or variables. Its groups tile the line from its start to the
# call's ")" (so that their offsets are the sums of their lengths), each piece a group.
SLOTS = 4  # options a written line may give
_B = r"[ \t]*"
_OPTION = rf"(?:(,{_B})(?:([{''.join(OPTIONS)}])({_B}={_B}))?(?:({NUMBER})|({NAME}))({_B}))?"  # , name = value
CAM_LINE = re.compile(
    rf"(?m)^({_B})({'|'.join(WRITTEN)})({_B}\({_B})(?:(pose_trans{_B}\({_B})({NAME})({_B},{_B}))?(p?)(\[{_B})"
    + f"({_B},{_B})".join([f"({NUMBER})"] * 6) + rf"({_B}\])(?(4)({_B}\)))({_B})" + _OPTION * SLOTS
    + r"\)[ \t]*(?=[\r\n]|\Z)")
# the names of its groups, in order (0-based, as `re.Match.groups` gives them)
CAM_GROUP = {name: k for k, name in enumerate(
    ["indent", "function", "(", "pose_trans(", "frame", "frame,", "p", "["]
    + [name for k in range(6) for name in ([f"number {k}"] + ([f", {k}"] if k < 5 else []))]
    + ["]", ")", "blanks"]
    + [f"option {slot} {part}" for slot in range(SLOTS)
       for part in (",", "name", "=", "number", "variable", "blanks")])}
# a statement between them that changes nothing the reader carries: blank, a comment (masked), or a call of another
# function than `CALLS` with plain arguments (``set_standard_digital_out(5, 0.083)``, ``sleep(0.5)``), fullmatch
PLAIN = re.compile(rf"[ \t]*(?:({NAME})[ \t]*\([^()\[\]=:\r\n]*\)[ \t]*)?(\r\n|\r|\n|)")
