"""Arm configuration data of each robot language, computed from joint angles.

A Cartesian target is reached by several joint solutions; each language
names the one it means with its own flags. All of them follow from the
branch of the arm (`trajcomp.arm.ik.configuration_of`: shoulder front/back of
axis 1, elbow up/down, wrist sign) and the joint angles:

- KUKA S and T (KSS system software manual, "Status" and "Turn"): S bit 0
  = wrist centre behind axis A1 (overhead area); bit 1 = wrist centre in
  front of the line through A2 and A3, in the A1 frame (elbow up in front
  of A1, elbow down overhead); bit 2 = A5 < 0 (wrist negative). T bit i is
  set when axis i+1 < 0.
- ABB confdata (RAPID reference, confdata): cf1, cf4, cf6 = quadrant
  ``floor(q / 90 deg)`` of joints 1, 4, 6; cfx of spherical-wrist arms =
  4 * (wrist centre behind axis 1) + 2 * (wrist centre behind the lower
  arm) + (axis 5 negative), "behind the lower arm" being the complement of
  KUKA's bit 1.
- FANUC CONFIG ``'F/N U/D T/B, t1, t4, t6'``: "F" (flip) when the wrist is
  positive, J5 > 0 (a
  tool pointing down with J4 = 0 is J5 = -90 deg, the common 'N U T'),
  "U" elbow up, "B" wrist centre behind J1; turn numbers
  ``floor((q + 180 deg) / 360 deg)`` of joints 1, 4 and 6.
"""

import numpy as np

from trajcomp.arm.ik import configuration_of
from trajcomp.programs.items import JOINT

# A joint this close to the boundary of its code satisfies both codes (RobotStudio writes J4 = J6 = 0 as
# confdata [0,-1,0,0]; a controller accepts either): declared data are read, and kept, with this slack.
BOUNDARY_TOLERANCE = np.radians(0.5)  # rad
# The motion kinds whose target's configuration data the controller uses (KUKA: Status and Turn only bind
# PTP motions; a LIN or CIRC moves on in the posture the arm is in). Languages not named: every kind.
BINDING_KINDS = {"krl": frozenset({JOINT})}


def _flags(robot, q):
    """Boolean arrays (N,) behind, elbow up and wrist negative of joint vectors q (N, 6)."""
    configs = configuration_of(robot, q)
    behind = np.array([c.shoulder == "back" for c in configs])
    up = np.array([c.elbow == "up" for c in configs])
    negative = np.array([c.wrist == "negative" for c in configs])
    return behind, up, negative


def kuka_status_turn(robot, q):
    """KUKA status and turn ``(S, T)`` of joint vectors q (N, 6), rad: list of int pairs."""
    q = np.atleast_2d(q)
    behind, up, negative = _flags(robot, q)
    status = behind * 1 + (up != behind) * 2 + negative * 4
    turn = (q < -1e-9) @ (1 << np.arange(6))  # a joint written as 0 is not negative
    return [(int(s), int(t)) for s, t in zip(status, turn)]


def abb_confdata(robot, q):
    """ABB confdata ``(cf1, cf4, cf6, cfx)`` of joint vectors q (N, 6), rad: list of int tuples."""
    q = np.atleast_2d(q)
    behind, up, negative = _flags(robot, q)
    quadrant = np.floor(q[:, [0, 3, 5]] / (np.pi / 2) + 1e-9).astype(int)
    cfx = behind * 4 + (up == behind) * 2 + negative * 1
    return [(*map(int, quad), int(x)) for quad, x in zip(quadrant, cfx)]


def fanuc_config(robot, q):
    """FANUC CONFIG ``(flip, elbow, front, t1, t4, t6)`` of joint vectors q (N, 6), rad.

    ``flip`` is ``"F"`` (J5 > 0) or ``"N"``, ``elbow`` ``"U"`` or ``"D"``, ``front``
    ``"T"`` or ``"B"``; t1, t4, t6 are turn numbers (int).
    """
    q = np.atleast_2d(q)
    behind, up, negative = _flags(robot, q)
    turns = np.floor((q[:, [0, 3, 5]] + np.pi) / (2 * np.pi) - 1e-12).astype(int)
    return [
        ("N" if wrist_negative else "F", "U" if elbow_up else "D", "B" if back else "T", *map(int, turn))
        for wrist_negative, elbow_up, back, turn in zip(negative, up, behind, turns)
    ]


BY_FORMAT = {"krl": kuka_status_turn, "rapid": abb_confdata, "fanuc_ls": fanuc_config}


def configuration_for(format_name, robot, q):
    """Configuration data of joint vectors q (N, 6), rad, in a program format's language.

    Returns
    -------
    list of tuple, or None for a format without configuration data (CSV,
    URScript: their joints are written as joints).
    """
    function = BY_FORMAT.get(format_name)
    return None if function is None else function(robot, q)


# Windows are closed intervals that reproduce the encoders' half-open ones to _EDGE: a joint
# on a boundary (J4 = 0, J6 = 180 deg) belongs to exactly one window, as it has one code.
_EDGE = 1e-9  # rad


def binding(program):
    """Whether each target's declared configuration data bind its posture: (N_targets,) bool.

    A target binds if some motion of a kind its language reads configuration
    data for (`BINDING_KINDS`) uses it, as target or via point.
    """
    kinds = BINDING_KINDS.get(program.format)
    table = program.target_table()
    out = np.zeros(len(table.config), dtype=bool)
    motions = program.motion_table()
    use = np.ones(len(motions.kind), dtype=bool) if kinds is None else np.isin(motions.kind, list(kinds))
    for column in (motions.target, motions.via):
        out[column[use & (column >= 0)]] = True
    return out


def written_configuration(format_name, robot, declared, q, tolerance=BOUNDARY_TOLERANCE):
    """The configuration data to write for corrected joints: as declared wherever they still hold.

    Each field the joints still satisfy (within ``tolerance`` of its
    boundary) is kept as the program wrote it; the others are recomputed
    from ``q`` (`configuration_for`). Fields the tool does not own are
    always kept: KUKA Status bits 3-7 (bit 4: taught on an absolutely
    accurate robot) and Turn bits above A6, FANUC turn digits beyond J1, J4,
    J6; ABB cfx changes only with the branch.

    Parameters
    ----------
    format_name : str
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
    computed = configuration_for(format_name, robot, q)
    if computed is None:
        return None
    q = np.atleast_2d(q)
    branch, lower, upper = declared_windows(format_name, declared)
    branch_kept = branch == declared_windows(format_name, computed)[0]
    joint_kept = _satisfied(robot, q, lower, upper, tolerance)
    merge = _MERGE[format_name]
    return [merge(tuple(old), tuple(new), kept, joints) if old else tuple(new)
            for old, new, kept, joints in zip(declared, computed, branch_kept.tolist(), joint_kept)]


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


def _merge_kuka(old, new, branch_kept, joint_kept):
    """S: bits 0-2 from ``new`` if the branch changed; T: the bits of joints out of their window."""
    status = old[0] if branch_kept else (old[0] & ~0b111) | (new[0] & 0b111)
    moved = sum(1 << j for j, kept in enumerate(joint_kept.tolist()) if not kept)
    return (status, (old[1] & ~moved) | (new[1] & moved))


def _merge_abb(old, new, branch_kept, joint_kept):
    """cf1, cf4, cf6 from ``new`` where the joint left its quadrant; cfx if the branch changed."""
    quadrants = tuple(o if kept else n for o, n, kept in zip(old[:3], new[:3], joint_kept[[0, 3, 5]]))
    return (*quadrants, old[3] if branch_kept else new[3], *old[4:])


def _merge_fanuc(old, new, branch_kept, joint_kept):
    """Flip, elbow, front from ``new`` if the branch changed; each turn digit of a joint out of its turn."""
    flags = old[:3] if branch_kept else new[:3]
    turns = tuple(o if kept else n for o, n, kept in zip(old[3:6], new[3:6], joint_kept[[0, 3, 5]]))
    return (*flags, *turns, *old[6:])


_MERGE = {"krl": _merge_kuka, "rapid": _merge_abb, "fanuc_ls": _merge_fanuc}


def _kuka_windows(configs):
    """Branch (M,) and joint windows (M, 6) of KUKA ``(S, T)`` rows: T bit i set means axis i+1 < 0."""
    status, turn = _integers(configs, 0, 2).T
    back = (status & 1) > 0
    up = ((status & 2) > 0) != back
    bits = ((turn[:, None] >> np.arange(6)) & 1) > 0
    lower = np.where(bits, -np.inf, -_EDGE)
    upper = np.where(bits, -2 * _EDGE, np.inf)
    return _branch(back, up, (status & 4) > 0), lower, upper


def _integers(configs, start, stop):
    """Fields ``start:stop`` of configuration rows as an int64 array (M, stop - start), clipped to +-2**40: no
    code that large names a reachable window, and a damaged file's 1e308 stays an unreachable code."""
    limit = 1 << 40
    rows = [[max(-limit, min(limit, int(v))) for v in config[start:stop]] for config in configs]
    return np.array(rows, dtype=np.int64).reshape(-1, stop - start)


def _quadrant_windows(codes, joints, to_lower, to_upper):
    """Windows (M, 6) of ``joints`` from integer codes (M, 3): ``to_lower(code)``, ``to_upper(code)``; others free."""
    lower, upper = np.full((len(codes), 6), -np.inf), np.full((len(codes), 6), np.inf)
    lower[:, joints], upper[:, joints] = to_lower(codes), to_upper(codes)
    return lower, upper


def _abb_windows(configs):
    """Branch and joint windows of ABB confdata rows: joints 1, 4, 6 in quadrants [cf, cf + 1) * 90 deg."""
    values = _integers(configs, 0, 4)
    cfx = values[:, 3]
    back = (cfx & 4) > 0
    up = ((cfx & 2) > 0) == back
    lower, upper = _quadrant_windows(values[:, :3], [0, 3, 5], lambda c: c * np.pi / 2 - _EDGE,
                                     lambda c: (c + 1) * np.pi / 2 - 2 * _EDGE)
    return _branch(back, up, (cfx & 1) > 0), lower, upper


def _fanuc_windows(configs):
    """Branch and joint windows of FANUC CONFIG rows: joints 1, 4, 6 in turn t, ((2t - 1) pi, (2t + 1) pi]."""
    flags = np.array([config[:3] for config in configs], dtype=object).reshape(-1, 3)
    turns = _integers(configs, 3, 6)
    lower, upper = _quadrant_windows(turns, [0, 3, 5], lambda t: (2 * t - 1) * np.pi + _EDGE,
                                     lambda t: (2 * t + 1) * np.pi)
    return _branch(flags[:, 2] == "B", flags[:, 1] == "U", flags[:, 0] == "N"), lower, upper


def _branch(back, up, negative):
    """`trajcomp.arm.ik.Configuration` index (M,) of the flags (M,) bool."""
    return 4 * back.astype(int) + 2 * (~up).astype(int) + negative.astype(int)


WINDOWS_BY_FORMAT = {"krl": _kuka_windows, "rapid": _abb_windows, "fanuc_ls": _fanuc_windows}


def declared_windows(format_name, configs):
    """The branch and joint windows that configuration data declare: the inverse of `configuration_for`.

    Parameters
    ----------
    format_name : str
    configs : sequence of tuple, length N
        Configuration data as read (``()`` where a target has none).

    Returns
    -------
    branch : ndarray of int, shape (N,)
        `Configuration` index 0..7; -1 where nothing is declared.
    lower, upper : ndarray, shape (N, 6)
        Window of each joint, rad (``-inf`` / ``inf`` where free).
    """
    n = len(configs)
    branch = np.full(n, -1)
    lower, upper = np.full((n, 6), -np.inf), np.full((n, 6), np.inf)
    decode = WINDOWS_BY_FORMAT.get(format_name)
    stated = [k for k, config in enumerate(configs) if config]
    if decode is not None and stated:
        branch[stated], lower[stated], upper[stated] = decode([configs[k] for k in stated])
    return branch, lower, upper


def describe(format_name, config):
    """Configuration data as a program of the language writes them (``""`` for none).

    ``("krl", (6, 50))`` -> ``"S 6, T 50"``; RAPID ``"[0,-1,0,1]"``; FANUC ``"N U T, 0, 0, 0"``.
    """
    if not config:
        return ""
    if format_name == "krl":
        return f"S {config[0]}, T {config[1]}"
    if format_name == "fanuc_ls":
        return f"{' '.join(config[:3])}, {', '.join(str(t) for t in config[3:])}"
    return "[" + ",".join(str(v) for v in config) + "]"
