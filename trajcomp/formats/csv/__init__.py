"""Program CSV (docs/conventions.md): one target per row, TCP poses in the robot base frame.

Columns ``x,y,z,a,b,c`` (mm, deg; A, B, C intrinsic Z-Y'-X''), optional
``motion`` (PTP | LIN), ``speed`` (mm/s), ``zone`` (mm), ``j1..j6`` (deg)
and ``t`` (s, written by re-timing). A row with empty pose fields and
joints is a joint target. ``#`` lines are comments. Any other column (an
id, a comment) is kept as it is, except a name close to a known one (``xx``,
``speeed``: a typo would silently drop data) and a column given twice.
A pose or joint group given in part, and a file without target rows, are
refused too.

CSV programs are CAM paths of up to millions of rows, so they are read and
written as columns, a block of rows at a time (`Program.from_tables`): no
object per row. Writing a program read from CSV keeps every column, row and
byte; the edited rows get their new pose and, where the program knows their
joints, ``j1..j6`` (added as columns when the file has none); `with_times`
sets the ``t`` column.
"""

from trajcomp.formats import register_format
from trajcomp.formats.capabilities import BaseFrameOnly, RowBlocks, SpeedFields, SpeedUnits

register_format(
    "csv", [".csv"],
    f"{__name__}.reader:read",
    f"{__name__}.writer:write",
    RowBlocks(f"{__name__}.reader:read", f"{__name__}.writer:write"),
    SpeedFields(f"{__name__}.speeds:write_speeds", "the t column", timed_rows=True),
    SpeedUnits({"joint": {"mm/s": 1e-3}, "linear": {"mm/s": 1e-3}, "circular": {"mm/s": 1e-3}}),
    BaseFrameOnly(),
)
