"""Arm configuration data of each robot language, computed from joint angles and read back as joint windows.

A Cartesian target is reached by several joint solutions; each language
names the one it means with its own flags, in its folder's
``configuration.py`` (KUKA Status and Turn: `trajcomp.formats.krl.configuration`;
ABB confdata: `trajcomp.formats.rapid.configuration`; FANUC CONFIG:
`trajcomp.formats.fanuc.configuration`), declared by the language as its
`trajcomp.formats.capabilities.ConfigurationData`, which the functions here
take (None: a language whose targets declare none). Such a module has:

- ``encode(robot, q) -> list of tuple``: the data of joint vectors q (N, 6), rad;
- ``windows(configs) -> (branch (M,), lower (M, 6), upper (M, 6))``: the
  branch and the joint windows that data declare (the inverse of ``encode``);
- ``merge(old, new, branch_kept, joint_kept) -> tuple``: the data to write,
  the fields still satisfied kept as declared (`written_configuration`);
- ``describe(config) -> str``: the data as a program writes them;
- ``BINDING_KINDS`` (optional): the motion kinds the controller reads the
  data for (default: every kind).

All of them follow from the branch of the arm (`trajcomp.arm.ik.branch_index`:
shoulder front/back of axis 1, elbow up/down, wrist sign) and the joint
angles (`flags`). A path's targets mostly share their data: the data are
made into tuples (`distinct_tuples`), read back into windows
(`declared_windows`) and merged (`written_configuration`) once per distinct
value (`distinct_configs`).
"""

import numpy as np

from trajcomp.arm import ik
from trajcomp.arm.kinematics import in_blocks
from trajcomp.formats import capability, registered
from trajcomp.formats.capabilities import ConfigurationData

# A joint this close to the boundary of its code satisfies both codes (RobotStudio writes J4 = J6 = 0 as
# confdata [0,-1,0,0]; a controller accepts either): declared data are read, and kept, with this slack.
BOUNDARY_TOLERANCE = np.radians(0.5)  # rad


def flags(robot, q):
    """Boolean arrays (N,) wrist centre behind axis 1, elbow up and wrist negative of joint vectors q (N, 6), rad."""
    index = ik.branch_index(robot, q)  # `trajcomp.arm.ik_types.Configuration.index`: 4 * back + 2 * down + negative
    return (index & 4) > 0, (index & 2) == 0, (index & 1) > 0


def distinct_tuples(rows, as_tuple=tuple):
    """Rows (N, K) of integers as N tuples, one tuple object per distinct row (``as_tuple(row)``, row a list of int).

    Parameters
    ----------
    rows : ndarray of int, shape (N, K)
    as_tuple : callable
        Makes the tuple of a distinct row (a list of K int).

    Returns
    -------
    list of tuple, length N
    """
    if not len(rows):
        return []
    low = rows.min(axis=0)
    radix = rows.max(axis=0) - low + 1  # each row as one whole number in these radices: a 1-D unique, no row sort
    if np.prod(radix.astype(float)) < 2.0**62:
        place = np.cumprod(np.r_[1, radix])[:-1]
        distinct, row = np.unique((rows - low) @ place, return_inverse=True)
        distinct = low + distinct[:, None] // place % radix
    else:
        distinct, row = np.unique(rows, axis=0, return_inverse=True)
    made = [as_tuple(values) for values in distinct.tolist()]
    return [made[k] for k in row.reshape(-1).tolist()]


def configuration_data(name):
    """The `ConfigurationData` of the language registered as ``name``; None for one whose targets declare none
    (CSV, URScript) or an unknown name (a program built in memory, ``"api"``)."""
    language = registered(name)
    return None if language is None else language.capability(ConfigurationData)


def configuration_for(data, robot, q):
    """Configuration data of joint vectors q (N, 6), rad, in a language's form.

    Parameters
    ----------
    data : ConfigurationData or None
        The language's (`configuration_data`).
    robot : Robot
    q : ndarray, shape (N, 6)

    Returns
    -------
    list of tuple, or None for a language without configuration data (CSV,
    URScript: their joints are written as joints).
    """
    return None if data is None else data.codec().encode(robot, q)


# Windows are closed intervals that reproduce the encoders' half-open ones to EDGE: a joint
# on a boundary (J4 = 0, J6 = 180 deg) belongs to exactly one window, as it has one code.
EDGE = 1e-9  # rad


def binding(program):
    """Whether each target's declared configuration data bind its posture: (N_targets,) bool.

    A target binds if some motion of a kind its language reads configuration
    data for (its module's ``BINDING_KINDS``) uses it, as target or via point.
    """
    data = capability(program, ConfigurationData)
    kinds = None if data is None else getattr(data.codec(), "BINDING_KINDS", None)
    table = program.target_table()
    out = np.zeros(len(table.config), dtype=bool)
    motions = program.motion_table()
    use = np.ones(len(motions.kind), dtype=bool) if kinds is None else np.isin(motions.kind, list(kinds))
    for column in (motions.target, motions.via):
        out[column[use & (column >= 0)]] = True
    return out


def written_configuration(data, robot, declared, q, tolerance=BOUNDARY_TOLERANCE):
    """The configuration data to write for corrected joints: as declared wherever they still hold.

    Each field the joints still satisfy (within ``tolerance`` of its
    boundary) is kept as the program wrote it; the others are recomputed
    from ``q`` (`configuration_for`). Fields the tool does not own are
    always kept: KUKA Status bits 3-7 (bit 4: taught on an absolutely
    accurate robot) and Turn bits above A6, FANUC turn digits beyond J1, J4,
    J6; ABB cfx changes only with the branch.

    Parameters
    ----------
    data : ConfigurationData or None
        The language's (`configuration_data`).
    robot : Robot
    declared : sequence of tuple, length N
        Configuration data as read (``()`` where a target states none: the
        computed ones are returned).
    q : ndarray, shape (N, 6)
        Corrected joints, rad.
    tolerance : float
        Slack of each joint window, rad.

    Returns
    -------
    list of tuple, length N, or None for a language without configuration data.
    """
    computed = configuration_for(data, robot, q)
    if computed is None:
        return None
    q = np.atleast_2d(q)
    old, old_row = distinct_configs(declared)
    new, new_row = distinct_configs(computed)
    old_branch, lower, upper = _windows(data, old)
    branch_kept = old_branch[old_row] == _windows(data, new)[0][new_row]
    # a block of rows at a time: the turns (N, 6, 4) of 100,000 targets are 19 MB
    (joint_kept,) = in_blocks(lambda q, row: (_satisfied(robot, q, lower[row], upper[row], tolerance),), q, old_row)
    # a merge per distinct case (old data, new data, branch kept, a bit per joint kept): a path shares them
    case = ((old_row * len(new) + new_row) * 2 + branch_kept) * 64 + joint_kept @ (1 << np.arange(6))
    _, first, row = np.unique(case, return_index=True, return_inverse=True)
    merge, merged = data.codec().merge, np.empty(len(first), dtype=object)
    for k, at in enumerate(first.tolist()):
        was, data = old[old_row[at]], new[new_row[at]]
        merged[k] = merge(was, data, bool(branch_kept[at]), joint_kept[at]) if was else data
    return merged[row.reshape(-1)].tolist()


def _satisfied(robot, joints, lower, upper, tolerance):
    """(N, 6) bool: each joint of ``joints`` (N, 6) inside its window [lower, upper] (N, 6), or within
    ``tolerance`` of it with no other turn of it inside.

    A controller takes the turn of a joint inside the window its code names;
    only where none is does a joint on the window's boundary stand for it.
    """
    turns = joints[..., None] + 2 * np.pi * np.array([-2, -1, 1, 2])
    reachable = (turns >= robot.q_min[:, None]) & (turns <= robot.q_max[:, None])
    inside = (turns >= (lower - tolerance)[..., None]) & (turns <= (upper + tolerance)[..., None])
    other = np.any(reachable & inside, axis=-1)
    strict = (joints >= lower) & (joints <= upper)
    return strict | ((joints >= lower - tolerance) & (joints <= upper + tolerance) & ~other)


def integer_fields(configs, start, stop):
    """Fields ``start:stop`` of configuration rows as an int64 array (M, stop - start), clipped to +-2**40: no
    code that large names a reachable window, and a damaged file's 1e308 stays an unreachable code."""
    limit = 1 << 40
    rows = [[max(-limit, min(limit, int(v))) for v in config[start:stop]] for config in configs]
    return np.array(rows, dtype=np.int64).reshape(-1, stop - start)


def joint_windows(codes, joints, to_lower, to_upper):
    """Windows (M, 6) of ``joints`` from integer codes (M, 3): ``to_lower(code)``, ``to_upper(code)``; others free."""
    lower, upper = np.full((len(codes), 6), -np.inf), np.full((len(codes), 6), np.inf)
    lower[:, joints], upper[:, joints] = to_lower(codes), to_upper(codes)
    return lower, upper


def branch_index(back, up, negative):
    """`trajcomp.arm.ik.Configuration` index (M,) of the flags (M,) bool."""
    return 4 * back.astype(int) + 2 * (~up).astype(int) + negative.astype(int)


def declared_windows(data, configs):
    """The branch and joint windows that configuration data declare: the inverse of `configuration_for`.

    Parameters
    ----------
    data : ConfigurationData or None
        The language's (`configuration_data`).
    configs : sequence of tuple, length N
        Configuration data as read (``()`` where a target has none).

    Returns
    -------
    branch : ndarray of int, shape (N,)
        `Configuration` index 0..7; -1 where nothing is declared.
    lower, upper : ndarray, shape (N, 6)
        Window of each joint, rad (``-inf`` / ``inf`` where free).
    """
    distinct, row = distinct_configs(configs)
    branch, lower, upper = _windows(data, distinct)
    return branch[row], lower[row], upper[row]


def distinct_configs(configs):
    """The distinct configuration data among ``configs`` and where each one is: ``(values, row)``.

    A path's targets mostly share one tuple object each (`distinct_tuples`):
    they are told apart by identity first, then by value.

    Parameters
    ----------
    configs : sequence of tuple, length N
        Configuration data (``()`` or None where a target has none).

    Returns
    -------
    values : list of tuple
        Each distinct value once, ``()`` first.
    row : ndarray of int, shape (N,)
        Index of each one's value in ``values``.
    """
    identity = np.fromiter(map(id, configs), dtype=np.int64, count=len(configs))  # all alive in configs: distinct
    _, first, row = np.unique(identity, return_index=True, return_inverse=True)
    distinct = {(): 0}
    value = np.fromiter((distinct.setdefault(tuple(configs[k] or ()), len(distinct)) for k in first.tolist()),
                        dtype=np.int64, count=len(first))
    return list(distinct), value[row.reshape(-1)]


def _windows(data, distinct):
    """`declared_windows` of distinct configuration data, ``distinct[0]`` being ``()``: branch (M,), lower and
    upper (M, 6)."""
    branch = np.full(len(distinct), -1)
    lower, upper = np.full((len(distinct), 6), -np.inf), np.full((len(distinct), 6), np.inf)
    if data is not None and len(distinct) > 1:
        branch[1:], lower[1:], upper[1:] = data.codec().windows(distinct[1:])
    return branch, lower, upper


def describe(data, config):
    """Configuration data as a program of the language (its `ConfigurationData`, or None) writes them (``""`` for
    none): ``"S 6, T 50"`` in KRL."""
    if not config:
        return ""
    return data.codec().describe(config) if data is not None else "[" + ",".join(str(v) for v in config) + "]"
