"""PolyScope's program (.urp) beside a URScript file: what trajcomp does with it.

PolyScope saves a program as ``name.urp`` (gzip-compressed XML: the
program tree, each waypoint stored as its joint angles with the
controller's own calibrated kinematics) and generates ``name.script``
from it, the script the controller runs. trajcomp corrects the script;
it does not write the .urp: a waypoint there is joint angles under the
kinematics of that arm's calibration, which trajcomp does not hold, so
the corrected poses cannot be put into it exactly. Opening the .urp in
PolyScope and saving it regenerates the script from the uncorrected
waypoints: the correction is then lost. The program's report says so.
"""

from pathlib import Path

SUFFIX = ".urp"


def urp_beside(script_path):
    """The PolyScope program saved with a script (same name, ``.urp``, any case), or None."""
    script_path = Path(script_path)
    try:
        names = [p for p in script_path.parent.iterdir() if p.suffix.lower() == SUFFIX]
    except OSError:
        return None
    return next((p for p in names if p.stem == script_path.stem), None)


def notes(script_path):
    """The report's note on the .urp beside ``script_path`` (a tuple of one str, or empty)."""
    urp = urp_beside(script_path)
    if urp is None:
        return ()
    return (f"{urp.name} beside {Path(script_path).name} is PolyScope's program, from which the controller "
            f"generates the script: trajcomp corrects the script only, {urp.name} is not corrected (its waypoints "
            "are joint angles under the arm's own calibrated kinematics); run the corrected script, and do not open "
            f"and save {urp.name} over it (nor a copy of it beside the output): PolyScope would regenerate the "
            "script from the uncorrected waypoints",)
