"""Universal Robots URScript (.script, .urscript).

Read:
- ``movej``, ``movel``, ``movep``, ``movec`` to a pose literal ``p[x, y, z,
  rx, ry, rz]`` (metres, rotation vector in rad), a joint list ``[q1, ...,
  q6]`` (rad), a variable holding one, ``get_inverse_kin(pose,
  qnear=joints)`` or ``pose_trans(frame, pose)``; speeds ``v=`` (m/s, rad/s
  for movej; UR's defaults 0.25 m/s and 1.05 rad/s when not given) and
  times ``t=``, literal or held by a variable the script assigns once, a
  literal (any other is set at run time: `Motion.speed_why`), and blends
  ``r=`` (m);
- variables ``[global|local] name = p[...]`` / ``= [...]``: a variable is a
  target where a motion uses it (a six-number list only then: gains and
  selection vectors are not points), with PolyScope's pairs ``Waypoint_n_p``
  / ``Waypoint_n_q``: the ``_q`` list (like a ``qnear`` literal or
  variable) holds the joints of the pose and is rewritten with the
  corrected joints;
- frames: the first argument of ``pose_trans`` (a literal or a variable
  holding one, as RoboDK writes ``ref_frame = p[...]`` then
  ``movel(pose_trans(ref_frame, p[...]))``) is the frame of the second,
  like a KUKA base or an ABB work object (`Program.frames`, in the robot
  base frame); a frame the script never assigns (an installation feature
  such as ``Plane_1``) must be given its value;
- ``set_tcp(p[...])`` or a variable holding one: the tool of the following
  motions (before it, the installation TCP: the robot description's tool);
  the same pose set again (PolyScope re-emits it at every Set node) is the
  same tool.
Not compensated, with the reason (`Motion.reason`): poses computed at run
time (pose_add, get_actual_tcp_pose, nested pose_trans ...), variables
assigned anything but a literal, function parameters, variables assigned
only further down, motions after a TCP set at run time, servoj / servoc,
speedl / speedj / direct_torque (the arm moved by a velocity or torque).
A point also used as the frame of ``pose_trans`` (the approach idiom
``movel(pose_trans(pick_p, p[0,0,-0.1,0,0,0]))`` then ``movel(pick_p)``)
stays a point: the offsets from it are computed at run time and move with
it. A six-number list no joint can hold (``Kp = [1000, ...]``) is data.
A motion to a variable the script never assigns is a ReadError.
A pose variable used with two TCPs gets a copy per TCP (``pick_2``,
`trajcomp.formats.uses`), unless its joints are another list's (PolyScope's
``Waypoint_n_q``): then its motions are listed.
PolyScope's program saved beside the script (``name.urp``) is not read
nor written; the report says so (`trajcomp.formats.urscript.polyscope`). Pose
variables named by other statements are `Statement.refs`.
"""

from trajcomp.formats import register_format
from trajcomp.formats.capabilities import BaseFrameOnly, PointCopies, SpeedFields, SpeedUnits, Vendor

register_format(
    "urscript", [".script", ".urscript"],
    f"{__name__}.reader:read",
    f"{__name__}.writer:write",
    Vendor("Universal Robots"),
    SpeedFields(f"{__name__}.speeds:write_speeds", "t=, v="),
    SpeedUnits({"joint": {"rad/s": 1e-6, "s": 1e-4}, "linear": {"mm/s": 1e-3, "s": 1e-4}, "circular": {"mm/s": 1e-3}}),
    BaseFrameOnly(),
    PointCopies(),
)
