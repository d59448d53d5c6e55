"""A trajcomp format plugin: ``.pts`` point lists (one motion per line).

Each line is ``PTP|LIN x y z a b c`` (mm, deg, robot base frame, the robot's
tool); ``#`` starts a comment line, kept in place. Installing this package
(``pip install -e plugins/trajcomp-points``) registers the format through the
``trajcomp.formats`` entry point; `trajcomp formats` then lists it and
`trajcomp compensate` / `trajcomp convert` accept ``.pts`` files.
"""

from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats import register_format
from trajcomp.programs.program import JOINT, LINEAR, Motion, Program, Statement, Target
from trajcomp.arm.transforms import matrix_to_pose, pose_to_matrix

KINDS = {"PTP": JOINT, "LIN": LINEAR}


def read(path):
    """Read a ``.pts`` file into a Program; malformed lines raise ReadError with file:line."""
    path = Path(path)
    items, targets = [], []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        words = line.split()
        if not words or words[0].startswith("#"):
            items.append(Statement(number, line))
            continue
        if words[0] not in KINDS or len(words) != 7:
            raise ReadError(f"{path}:{number}: expected PTP|LIN x y z a b c, got {line.strip()!r}")
        try:
            pose = np.array([float(w) for w in words[1:]])
        except ValueError:
            raise ReadError(f"{path}:{number}: not a number in {line.strip()!r}") from None
        pose[3:] = np.radians(pose[3:])
        targets.append(Target(name="", line=number, pose=pose_to_matrix(pose)))
        items.append(Motion(KINDS[words[0]], target=len(targets) - 1, line=number, text=line.strip()))
    return Program("points", path.stem, tuple(items), tuple(targets))


def write(program, path):
    """``{path: bytes}`` of the program as a point list (base-frame poses, 3 decimals)."""
    names = {kind: name for name, kind in KINDS.items()}
    lines = []
    for item in program.items:
        if isinstance(item, Statement):
            lines.append(item.text if item.text.lstrip().startswith("#") or not item.text.strip() else f"# {item.text}")
        elif item.target is None:
            lines.append(f"# not converted: {item.text}")
        else:
            pose = matrix_to_pose(program.targets[item.target].pose)
            pose[3:] = np.degrees(pose[3:])
            lines.append(" ".join([names.get(item.kind, "LIN")] + [f"{v:.3f}" for v in pose]))
    return {Path(path): ("\n".join(lines) + "\n").encode("utf-8")}


register_format("points", (".pts",), read, write)
