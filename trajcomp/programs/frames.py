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

        A target that states no value: in a language whose targets keep the
        external axes they do not state (`Program.kept_axes`: KRL), the value
        the motions into it leave the track at, the one before them
        (`carried_over`); otherwise none.

        Raises
        ------
        TrajcompError
            A target without a value it states or keeps (named with its file and line).
        """
        index = np.asarray(index, dtype=int)
        axis = None if self.track is None else self.track.index(self.program.track_key)
        if axis is None:
            return np.zeros(len(index))
        values = self._stated(axis)
        missing = ~np.isfinite(values[index])
        if missing.any() and self.program.kept_axes:
            values, why = self.carried_over(values)
            missing = ~np.isfinite(values[index])
        else:
            why = np.full(len(values), "", dtype=object)
        if missing.any():
            field = self.track.written[self.program.track_key]
            first = int(index[np.flatnonzero(missing)[0]])
            kept = (f"; {why[first]}" if why[first] else
                    f"; state {field} in every Cartesian target of a robot on a track")
            raise TrajcompError(
                f"{self.program.name}: {self.program.where(first)} states no {field}: its track position, hence the "
                f"arm's base, is unknown ({int(missing.sum())} target(s) so){kept}")
        return values[index]

    def unplaced(self):
        """``{target index: why}``: the targets the motions use whose track position the program leaves unknown,
        in a language whose controller runs them from where the track stands (`Program.kept_axes`: KRL); empty
        elsewhere, on a fixed base or where every used target's position is known (`carried_over` says why not).
        """
        axis = None if self.track is None else self.track.index(self.program.track_key)
        if axis is None or not self.program.kept_axes:
            return {}
        values, why = self.carried_over(self._stated(axis))
        used = self.program.usage_table().index
        field = self.track.written[self.program.track_key]
        return {int(t): (f"states no {field}, so its track position, hence the arm's base, is unknown"
                         + (f": {why[t]}" if why[t] else ""))
                for t in used[~np.isfinite(values[used])].tolist()}

    def _stated(self, axis):
        """The track position (T,) each of the program's targets states in external axis ``axis`` (NaN: none)."""
        external = self.program.target_table().external
        return np.array([np.nan if e is None or len(e) <= axis else e[axis] for e in external], dtype=float)

    def carried_over(self, values):
        """Each target's track position (T,) where targets keep the value of the motion before, and why not.

        A target without a value of its own gets the one the motion into
        it starts from (the target before's, its own or kept in turn), when
        every motion into it starts from the same value. Unknown (NaN, and
        the reason) where a motion into it starts from a position the
        program does not state (the first motion, one after a position
        computed at run time, after a call or a branch: `Motion.start_why`)
        or its motions start from different values.

        Parameters
        ----------
        values : ndarray, shape (T,)
            Stated values, NaN where a target states none.

        Returns
        -------
        values : ndarray, shape (T,)
        why : ndarray of object, shape (T,)
            ``""`` where known.
        """
        table = self.program.motion_table()
        target = table.target
        named = target >= 0
        value = np.where(named, values[np.maximum(target, 0)], np.nan)
        stated = np.isfinite(value)
        unknown_start = ~named | (table.start_why != "")
        unknown_start[:1] = True
        anchor = np.maximum.accumulate(np.where(stated | unknown_start, np.arange(len(target)), 0))
        kept = np.where(stated[anchor], value[anchor], np.nan)  # the value each motion leaves the track at
        out, why = values.copy(), np.full(len(values), "", dtype=object)
        for t in np.flatnonzero(~np.isfinite(values)).tolist():
            uses = kept[target == t]
            if not len(uses):
                continue
            if np.isnan(uses).any():
                why[t] = ("the controller keeps the track where the motion before leaves it, which starts from a "
                          "position the program does not state here")
            elif np.ptp(uses) > 0:
                why[t] = (f"the controller keeps the track where the motion before leaves it: {uses.min():g} and "
                          f"{uses.max():g} mm on its uses")
            else:
                out[t] = uses[0]
        return out, why

    def carriage_offsets(self, index):
        """``T_base(e)_base(0)`` (N, 4, 4): the arm base at track position 0 seen from the real carriage at each
        target's track position (a translation; identity on a fixed base)."""
        values = self.track_positions(index)
        out = np.tile(np.eye(4), (len(values), 1, 1))
        if self.track is not None:
            out[:, :3, 3] = -self.shift_in_base(values)
        return out

    def written_commands(self, index, T_command):
        """Commands ``T_command`` (N, 4, 4) of targets ``index`` (N,) in the real carriage as they are written.

        ``T_real(e)_controller(e) @ T_command``: the carriage as the controller
        knows it, seen from the real one at each target's track position. The
        controller, placing the arm with its own track, then sends the arm to
        ``T_command`` on the real one. ``T_command`` itself unless a
        calibration identified a track that differs (no product with
        identities: 256 MB at a million targets).
        """
        if self.track is None or not self.track.identified:
            return T_command
        values = self.track_positions(index)
        offsets = np.tile(np.eye(4), (len(index), 1, 1))
        offsets[:, :3, 3] = self.shift_in_base(values, actual=False) - self.shift_in_base(values)
        return offsets @ T_command

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
