"""Tools and user frames of a program: names to values, and targets in the robot base frame.

Frame values are T_world_frame and tool values T_flange_tool (mm); the base
is placed in the world by the robot's ``T_world_base``, and on a track
(`trajcomp.arm.track`) each target's base is the carriage frame at the
track position the target states: the arm part of a target is in that
frame. A frame or tool the
program uses must be defined in the program or supplied by the caller; a
missing one is an error, never a guess. Frame ``None`` is the base, tool
``None`` the robot description's tool.
"""

import numpy as np

from trajcomp.errors import TrajcompError
from trajcomp.programs.tables import rows_of, value_codes
from trajcomp.arm.transforms import invert


class FrameTable:
    """Values of the tools and frames a program uses: its own, then the caller's.

    Parameters
    ----------
    program : Program
    robot : Robot or None
        Places the base in the world and gives the default tool (identity without).
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        T_flange_tool and T_world_frame (mm) the program uses but does not define.
    """

    def __init__(self, program, robot=None, tools=None, frames=None):
        self.program = program
        self.tools = {**(tools or {}), **program.tools}
        self.frames = {**(frames or {}), **program.frames}
        self.T_base_world = invert(robot.T_world_base) if robot is not None else np.eye(4)
        self.default_tool = robot.T_flange_tool if robot is not None else np.eye(4)
        self.track = robot.track if robot is not None else None

    def tool(self, name):
        """T_flange_tool (4, 4) of a tool name (None: the robot's tool)."""
        return self.default_tool if name is None else self._lookup(self.tools, name, "tool", "--tool")

    def frame(self, name):
        """T_base_frame (4, 4) of a frame name (None: the base)."""
        return np.eye(4) if name is None else self.T_base_world @ self._lookup(self.frames, name, "frame", "--frame")

    def _lookup(self, values, name, what, option):
        if name not in values:
            raise TrajcompError(
                f"{self.program.name}: {what} {name!r} is used but not defined in the program; "
                f"give its value (e.g. {option} {name}=x,y,z,a,b,c in mm and deg)"
            )
        return values[name]

    def targets_in_base(self, index):
        """Targets ``index`` (N,) as used by the motions, in the base frame.

        Returns
        -------
        T_base_frame, T_flange_tool, T_base_tcp : ndarray, shape (N, 4, 4)
            Each target's user frame, tool and pose, mm.
        """
        used = self.program.usage_table()
        row = np.searchsorted(used.index, index)
        T_base_frame = _values(used.frame[row], self.frame)
        T_flange_tool = _values(used.tool[row], self.tool)
        poses = rows_of(self.program.target_table().pose, index)
        if self.track is not None:  # each target's arm base: the carriage where its track position puts it
            T_base_frame = self.carriage_offsets(index) @ T_base_frame
        return T_base_frame, T_flange_tool, poses if _is_base(T_base_frame) else T_base_frame @ poses

    def track_positions(self, index):
        """The track positions (N,), mm, targets ``index`` (N,) state in the field the robot's track names for the
        program's language; zeros on a fixed base or for a language the track names no field of.

        Raises
        ------
        TrajcompError
            A target that states no value in that field.
        """
        index = np.asarray(index, dtype=int)
        axis = None if self.track is None else self.track.index(self.program.format)
        if axis is None:
            return np.zeros(len(index))
        external = self.program.target_table().external
        values = np.array([np.nan if external[i] is None or len(external[i]) <= axis else external[i][axis]
                           for i in index.tolist()], dtype=float).reshape(-1)
        missing = np.flatnonzero(~np.isfinite(values))
        if missing.size:
            field = self.track.written[self.program.format]
            raise TrajcompError(
                f"{self.program.name}: {self.program.where(int(index[missing[0]]))} states no {field}: its track "
                f"position, hence the arm's base, is unknown ({missing.size} target(s) so); state {field} in every "
                "Cartesian target of a robot on a track")
        return values

    def carriage_offsets(self, index):
        """``T_base(e)_base(0)`` (N, 4, 4): the arm base at track position 0 seen from the real carriage at each
        target's track position (a translation; identity on a fixed base)."""
        values = self.track_positions(index)
        out = np.tile(np.eye(4), (len(values), 1, 1))
        if self.track is not None:
            out[:, :3, 3] = -self.shift_in_base(values)
        return out

    def command_offsets(self, index):
        """``T_real(e)_controller(e)`` (N, 4, 4): the carriage as the controller knows it, seen from the real one
        at each target's track position (identity unless a calibration identified a track that differs).

        A command ``T`` in the real carriage is written ``command_offsets @ T`` in it: the controller, placing the
        arm with its own track, then sends the arm to ``T`` on the real one.
        """
        out = np.tile(np.eye(4), (len(index), 1, 1))
        if self.track is not None and self.track.identified:
            values = self.track_positions(index)
            out[:, :3, 3] = self.shift_in_base(values, actual=False) - self.shift_in_base(values)
        return out

    def shift_in_base(self, values, actual=True):
        """The carriage's translations (N, 3), mm, at track positions ``values`` (N,), in the base frame at 0 (on
        the real track, or the controller's: `trajcomp.arm.track.Track.shift`)."""
        return self.track.shift(values, actual) @ self.T_base_world[:3, :3].T


def in_frames(T_base_frame, T_base_pose):
    """Poses (N, 4, 4) given in the base frame, expressed in their user frames ``T_base_frame`` (N, 4, 4), mm."""
    return T_base_pose if _is_base(T_base_frame) else invert(T_base_frame) @ T_base_pose


def _is_base(T_base_frame):
    """Whether every frame of a stack (N, 4, 4) is the base itself (no transform to apply)."""
    return bool(len(T_base_frame)) and np.array_equal(T_base_frame, np.broadcast_to(np.eye(4), T_base_frame.shape))


def _values(names, value):
    """``value(name)`` (4, 4) of each of N names, stacked (N, 4, 4): looked up once per distinct name.

    A read-only view of one matrix when every name is the same (no copy per row).
    """
    codes, distinct = value_codes(names)
    values = np.array([value(name) for name in distinct]).reshape(-1, 4, 4)
    return np.broadcast_to(values[0], (len(names), 4, 4)) if len(distinct) == 1 else values[codes]


def tool_groups(tools):
    """``[(tool (4, 4), rows)]``: the distinct tools of a stack (n, 4, 4) and the rows using each."""
    if not len(tools) or np.all(tools == tools[0]):
        return [(tools[0], np.arange(len(tools)))] if len(tools) else []
    unique, group = np.unique(tools.reshape(len(tools), 16), axis=0, return_inverse=True)
    return [(tool.reshape(4, 4), np.flatnonzero(group.ravel() == g)) for g, tool in enumerate(unique)]
