"""The per-target part of the compliance report, at any program size.

Every measure, statistic and flag is computed over all N targets, vectorized
and in chunks of `CHUNK` targets (the kinematic measures need 4x4 link frames
per joint: memory stays flat for millions of targets). The JSON tabulates
every target up to `ROWS` of them. A longer program gets a summarised table
of at most `ROWS` rows: the `WORST` worst places of each measure, then
the flagged targets (failing a per-target criterion) in motion order; the table
says what it holds, and the full per-target data go to a NumPy sidecar
(``<report>.targets.npz``, `full_data`) written with the report.
"""

import dataclasses

import numpy as np

from trajcomp.support.parallel import map_blocks
from trajcomp.report.measures import BRANCH_NAMES, joint_jumps, limit_distances, posture_measures
from trajcomp.arm.transforms import angles_near, matrix_to_pose

CHUNK = 2048  # targets per pass of the kinematic measures
BLOCK = 16 * CHUNK  # targets per task of a process computing the kinematic measures
ROWS = 2000  # every target tabulated up to this many; the rows of a summarised table
WORST = 10  # worst places (local extremes) of each measure in a summarised table

# Per-target measures: unit, which end is the worst, what it is. The sidecar holds each as an (N,) array.
MEASURES = {
    "correction_mm": ("mm", "max", "position correction |command - target|"),
    "correction_deg": ("deg", "max", "orientation correction (rotation angle)"),
    "landing_estimate_mm": ("mm", "max", "landing estimate: held-out error near the target + what the measurements "
                            "could not see at its orientation, tool and posture + convergence"),
    "held_out_mm": ("mm", "max", "held-out error of the model near the target (same mode and interpolator)"),
    "unseen_mm": ("mm", "max", "part of the estimate from parameters the measurements could not see"),
    "orientation_beyond_deg": ("deg", "max", "orientation beyond the measured ones"),
    "convergence_mm": ("mm", "max", "convergence: target to the model's own predicted landing (the model agreeing "
                       "with itself, not an accuracy)"),
    "limit_distance_deg": ("deg", "min", "distance of the nearest joint to its limit"),
    "shoulder_mm": ("mm", "min", "shoulder singularity distance"),
    "elbow_deg": ("deg", "min", "elbow singularity distance"),
    "wrist_deg": ("deg", "min", "wrist singularity distance"),
    "jump_deg": ("deg", "max", "largest joint change from the previous target"),
}
KINEMATIC = ("limit_distance_deg", "shoulder_mm", "elbow_deg", "wrist_deg", "jump_deg")  # from the joints
LANDING = ("landing_estimate_mm", "held_out_mm", "unseen_mm", "orientation_beyond_deg")  # from a model only
FLAGS = ("residual", "outside_grid", "configuration", "joint_limits", "singularity", "orientation", "tool",
         "posture")  # bit k of `flags`


@dataclasses.dataclass(frozen=True)
class TargetMeasures:
    """The measures of all N targets of a run, in motion order.

    Attributes
    ----------
    values : dict of str to ndarray, shape (N,)
        One array per `MEASURES` key, in its unit (the `LANDING` ones only
        for a compensated run).
    branch, branch_planned : ndarray of uint8, shape (N,)
        Branch index of the written and of the planned joints (`BRANCH_NAMES`).
    changed : ndarray of bool, shape (N,)
        Branch changed or a joint turned by half a turn or more.
    """

    values: dict
    branch: np.ndarray
    branch_planned: np.ndarray
    changed: np.ndarray

    def __len__(self):
        return len(self.changed)


def target_measures(report, robot, workers=1):
    """`TargetMeasures` of a `ProgramReport` (N targets) on the nominal ``robot``.

    The kinematic measures are computed in chunks of `CHUNK` targets, a
    `BLOCK` of them by each of ``workers`` processes
    (`trajcomp.support.parallel.map_blocks`); the result does not depend on it.
    """
    n = len(report.labels)
    q, q_planned = np.reshape(report.q, (n, 6)), np.reshape(report.q_planned, (n, 6))
    correction = np.reshape(report.correction, (n, 6))
    values = {"correction_mm": np.linalg.norm(correction[:, :3], axis=1),
              "correction_deg": np.linalg.norm(correction[:, 3:], axis=1)}
    if report.landing is not None:
        values |= {name: np.asarray(report.landing[key], dtype=float).reshape(n) for name, key in zip(
            LANDING, ("estimate_mm", "held_out_mm", "unseen_mm", "orientation_beyond_deg"))}
    values["convergence_mm"] = np.asarray(report.predicted_residual, dtype=float).reshape(n)
    values |= {name: np.empty(n) for name in KINEMATIC}
    branch, branch_planned, changed = np.empty(n, np.uint8), np.empty(n, np.uint8), np.empty(n, bool)
    starts = range(0, n, BLOCK)
    blocks = map_blocks(lambda k: _kinematic_measures(robot, q, q_planned, starts[k], min(starts[k] + BLOCK, n)),
                        len(starts), workers)
    for start, (kinematic, *flags) in zip(starts, blocks):
        part = slice(start, start + len(flags[0]))
        for name, column in zip(KINEMATIC, kinematic):
            values[name][part] = column
        branch[part], branch_planned[part], changed[part] = flags
    return TargetMeasures(values, branch, branch_planned, changed)


def _kinematic_measures(robot, q, q_planned, begin, end):
    """The `KINEMATIC` measures of targets ``begin`` .. ``end`` - 1 of joints q, q_planned (N, 6) rad:
    ``(values (5, B), branch, branch_planned, changed (B,))``, computed `CHUNK` targets at a time."""
    values = np.empty((len(KINEMATIC), end - begin))
    branch, branch_planned, changed = np.empty(end - begin, np.uint8), np.empty(end - begin, np.uint8), \
        np.empty(end - begin, bool)
    for start in range(begin, end, CHUNK):
        part, out = slice(start, min(start + CHUNK, end)), slice(start - begin, min(start + CHUNK, end) - begin)
        jumps = joint_jumps(q[part], q[start - 1] if start else None)
        singular, branch[out], branch_planned[out], changed[out] = posture_measures(robot, q[part], q_planned[part])
        values[:, out] = [np.degrees(limit_distances(robot, q[part]).min(axis=1)), singular["shoulder"],
                          singular["elbow"], singular["wrist"], np.degrees(np.abs(jumps).max(axis=1))]
    return values, branch, branch_planned, changed


def statistics(measures, labels):
    """Distribution of each measure over all targets: min, p5, median, mean, p95, max and the worst target.

    Parameters
    ----------
    measures : TargetMeasures
    labels : Sequence[str]
        Target labels (N,).

    Returns
    -------
    dict of str to dict
        Per `MEASURES` key: ``unit``, ``min``, ``p5``, ``median``, ``mean``,
        ``p95``, ``max``, ``worst`` (1-based index in motion order) and
        ``worst_label``; empty without targets.
    """
    if not len(measures):
        return {}
    out = {}
    for name, (unit, end, _) in _present(measures):
        v = measures.values[name]
        p5, median, p95 = np.percentile(v, [5, 50, 95])
        worst = int(np.argmax(v) if end == "max" else np.argmin(v))
        out[name] = {"unit": unit, "min": float(v.min()), "p5": float(p5), "median": float(median),
                     "mean": float(v.mean()), "p95": float(p95), "max": float(v.max()), "worst": worst + 1,
                     "worst_label": str(labels[worst])}
    return out


def _present(measures):
    """The `MEASURES` items a run has values of."""
    return [(name, spec) for name, spec in MEASURES.items() if name in measures.values]


def flag_bits(masks):
    """The flags (N,) uint8 of failing masks ``{criterion: (N,) bool}``: bit k set where `FLAGS` [k] fails."""
    masks = dict(masks)
    n = len(next(iter(masks.values()))) if masks else 0
    bits = np.zeros(n, np.uint8)
    for k, key in enumerate(FLAGS):
        if key in masks:
            bits |= np.asarray(masks[key], dtype=bool).astype(np.uint8) << k
    return bits


def worst_targets(measures, count=WORST):
    """The ``count`` worst local extremes of each measure, worst first: ``{name: ndarray of int}`` (0-based).

    Only a target worse than the one before it and no better than the one
    after it (the first of a plateau) is a candidate, so the list names
    ``count`` separate places of the program rather than the neighbours of
    one; among equal values the first in motion order wins, so the worst
    target (as numpy's argmax/argmin) is always listed first.
    """
    out = {}
    for name, (_, end, _) in _present(measures):
        v = measures.values[name] if end == "max" else -measures.values[name]
        v = np.nan_to_num(v, nan=np.inf)  # a target without an estimate is among the worst
        padded = np.concatenate(([-np.inf], v, [-np.inf]))
        candidates = np.flatnonzero((v > padded[:-2]) & (v >= padded[2:]))
        top = candidates
        if len(candidates) > count:  # the `count` largest, the first in motion order among equals
            worse = v[candidates]
            threshold = np.partition(worse, len(worse) - count)[len(worse) - count]
            above = candidates[worse > threshold]
            top = np.concatenate((above, candidates[worse == threshold][:count - len(above)]))
        out[name] = top[np.lexsort((top, -v[top]))]
    return out


def table_rows(flags, measures):
    """Which targets the JSON tabulates (ascending 0-based indices) and the table's description.

    All targets up to `ROWS`; beyond, the `worst_targets` of each measure,
    then the flagged targets in motion order, at most `ROWS` rows in all.

    Returns
    -------
    index : ndarray of int
    table : dict
        The document's ``target_table``.
    """
    n, flagged = len(flags), int(np.count_nonzero(flags))
    if n <= ROWS:
        return np.arange(n), {"targets": n, "rows": n, "complete": True, "flagged": flagged, "worst": {},
                              "selection": "every target"}
    worst = worst_targets(measures)
    shown = np.unique(np.concatenate(list(worst.values())))
    extra = np.setdiff1d(np.flatnonzero(flags), shown, assume_unique=True)[:ROWS - len(shown)]
    index = np.union1d(shown, extra)
    listed = int(np.count_nonzero(flags[index]))
    flagged_text = (f"all {flagged} flagged targets" if listed == flagged else
                    f"{listed} of the {flagged} flagged targets (the first in motion order and the worst)")
    selection = (f"{len(index)} of {n} targets: the {WORST} worst places (local extremes) of each measure and "
                 f"{flagged_text} (flagged: failing a per-target criterion); the statistics and the verdict cover all {n}")
    return index, {"targets": n, "rows": len(index), "complete": False, "flagged": flagged,
                   "worst": {name: (k + 1).tolist() for name, k in worst.items()}, "selection": selection}


def _poses(T):
    """Pose rows x, y, z (mm), a, b, c (deg) of matrices (K, 4, 4)."""
    if not len(T):
        return np.zeros((0, 6))
    pose = matrix_to_pose(T)
    pose[:, 3:] = np.degrees(pose[:, 3:])
    return pose


def _round(array, digits):
    return np.round(np.asarray(array, dtype=float), digits).tolist()


def target_json(report, robot, measures, flags, index):
    """The JSON rows (list of dict, schema ``target``) of the targets ``index`` (0-based, ascending)."""
    index = np.asarray(index, dtype=int)
    q = np.reshape(report.q, (-1, 6))
    q_row, previous = q[index], q[np.maximum(index - 1, 0)]
    correction = np.reshape(report.correction, (-1, 6))[index]
    v = {name: values[index] for name, values in measures.values.items()}
    target, command = _poses(report.T_target[index]), _poses(report.T_command[index])
    command[:, 3:] = angles_near(command[:, 3:], target[:, 3:])
    columns = {
        "target": _round(target, 4),
        "command": _round(command, 4),
        "correction_mm": _round(correction[:, :3], 4),
        "correction_deg": _round(correction[:, 3:], 5),
        "correction_norm_mm": _round(v["correction_mm"], 4),
        "correction_norm_deg": _round(v["correction_deg"], 5),
        "convergence_mm": v["convergence_mm"].tolist(),
        "outside_grid": np.asarray(report.outside_grid, dtype=bool)[index].tolist(),
        "joints_deg": _round(np.degrees(q_row), 4),
        "planned_joints_deg": _round(np.degrees(np.reshape(report.q_planned, (-1, 6))[index]), 4),
        "configuration_changed": measures.changed[index].tolist(),
        "limit_distance_deg": _round(np.degrees(limit_distances(robot, q_row)), 3),
        "shoulder_mm": _round(v["shoulder_mm"], 2),
        "elbow_deg": _round(v["elbow_deg"], 3),
        "wrist_deg": _round(v["wrist_deg"], 3),
        "jump_deg": _round(np.degrees(q_row - previous), 3),
    }
    landing = _landing_rows(report, v, index)
    rows = []
    for r, k in enumerate(index.tolist()):
        c = {name: values[r] for name, values in columns.items()}
        rows.append({
            "index": k + 1, "label": str(report.labels[k]), "line": int(report.lines[k]),
            "tool": report.tools[k], "frame": report.frames[k],
            "target": c["target"], "command": c["command"], "correction_mm": c["correction_mm"],
            "correction_deg": c["correction_deg"], "correction_norm_mm": c["correction_norm_mm"],
            "correction_norm_deg": c["correction_norm_deg"], **landing[r], "convergence_mm": c["convergence_mm"],
            "outside_grid": c["outside_grid"], "joints_deg": c["joints_deg"],
            "planned_joints_deg": c["planned_joints_deg"], "posture_source": report.posture_source[k],
            "declared": report.declared[k], "written": report.written[k],
            "branch_planned": BRANCH_NAMES[measures.branch_planned[k]], "branch": BRANCH_NAMES[measures.branch[k]],
            "configuration_changed": c["configuration_changed"], "limit_distance_deg": c["limit_distance_deg"],
            "singularity": {"shoulder_mm": c["shoulder_mm"], "elbow_deg": c["elbow_deg"], "wrist_deg": c["wrist_deg"]},
            "jump_deg": c["jump_deg"],
            "flags": [key for b, key in enumerate(FLAGS) if flags[k] >> b & 1],
        })
    return rows


def _landing_rows(report, values, index):
    """The landing fields of the rows ``index`` (all None without a model), list of dict."""
    keys = ("landing_estimate_mm", "held_out_mm", "unseen_mm", "orientation_beyond_deg", "unmeasured_posture",
            "other_tool")
    if report.landing is None:
        return [dict.fromkeys(keys) for _ in index]
    columns = [*(_round(values[name], 5) for name in LANDING),
               *(np.asarray(report.landing[key], dtype=bool)[index].tolist() for key in keys[4:])]
    return [dict(zip(keys, row)) for row in zip(*columns)]


# What each sidecar array holds (the document's ``full_data.arrays``).
ARRAYS = {
    "line": "(N,) int32: source line of each target, motion order",
    "position_mm": "(N, 3) float32: target position x, y, z, mm, base frame",
    "joints_deg": "(N, 6) float32: written joints, deg",
    **{name: f"(N,) float32: {text}, {unit}" for name, (unit, _, text) in MEASURES.items()},
    "outside_grid": "(N,) bool: target outside the measured grid",
    "configuration_changed": "(N,) bool: branch changed or a joint turned by half a turn",
    "branch": "(N,) uint8: branch of the written joints, index into branch_names",
    "branch_planned": "(N,) uint8: branch of the planned (declared) posture, index into branch_names",
    "branch_names": "(8,) str: shoulder/elbow/wrist branch names",
    "flags": "(N,) uint8: bit k set where the target fails criterion flag_names[k]",
    "flag_names": "(8,) str: the per-target criteria of the flag bits",
}
TIMES = "(M,) float64: time stamp of each waypoint of the re-timed program, s"


def full_data(report, measures, flags, t=None):
    """The sidecar arrays (`ARRAYS`, and ``t_s`` (M,) of a re-timing) of all N targets.

    Returns
    -------
    dict of str to callable
        Each builds its array when called, so that writing the sidecar holds
        one float32 copy at a time (`trajcomp.report.document.npz_bytes`).
    """
    n = len(measures)
    arrays = {
        "line": lambda: np.asarray(report.lines, dtype=np.int32).reshape(n),
        "position_mm": lambda: np.asarray(report.T_target[:, :3, 3], dtype=np.float32),
        "joints_deg": lambda: np.degrees(np.reshape(report.q, (n, 6))).astype(np.float32),
        **{name: (lambda name=name: measures.values[name].astype(np.float32)) for name, _ in _present(measures)},
        "outside_grid": lambda: np.asarray(report.outside_grid, dtype=bool).reshape(n),
        "configuration_changed": lambda: measures.changed,
        "branch": lambda: measures.branch,
        "branch_planned": lambda: measures.branch_planned,
        "branch_names": lambda: np.array(BRANCH_NAMES),
        "flags": lambda: flags,
        "flag_names": lambda: np.array(FLAGS),
    }
    if t is not None:
        arrays["t_s"] = lambda: np.asarray(t, dtype=float)
    return arrays
