"""A program in the order its controller runs it: what can come before each motion.

A reader lists what its program does besides moving as `Step`s, in file
order: routines and their ends, calls, branches (``if`` .. ``elif`` ..
``else`` .. ``endif``), loops (``loop`` .. ``endloop``, ``exit``), labels
and jumps, returns, waits and the settings of the speed state (``set``, a
group such as the TCP speed and the value that statement gives it). Its
motions are the rows of its `trajcomp.programs.tables.MotionTable`, placed
among the steps by file and line. `follow` runs every path the program can
take (a loop any number of times, each branch, a called routine from each
call and back to each) and gives, per motion, the settings that can be in
force when it starts and the motions that can run just before it
(`Reached`); `followed` puts that into the motion table:

- a motion that can be reached from another motion than the one before
  it in the table (after a call, a loop's back jump, a branch, a label),
  or after a call to a routine the read does not include, has no unique
  start: ``start_why`` says why, and re-timing leaves it as written and
  lists it (`trajcomp.timing.moves`);
- a motion after which the program can wait (``WAIT``, ``WaitTime``,
  ``sleep``) ends its blended run there: the controller stops, its zone
  is dropped (an exact stop);
- the speed settings reaching each motion are handed to the language,
  which states the motion's speed from them (the slowest, or set at run
  time where one is `Unknown`).

A call to a routine the read does not include (another file) may move the
arm and change every setting: after it the start and the settings are
`Unknown`. Loops are run zero or more times, so every setting a loop body
makes reaches the motions after the loop and, at its top, its first motion.
Routines are followed context-insensitively: a routine starts with the
settings of all its calls, and returns all it can end with to every call.

A program without any of these steps runs in file order: `needed` tells,
and readers of long CAM programs skip the rest.
"""

import dataclasses

import numpy as np

from trajcomp.programs.items import Statement
from trajcomp.programs.tables import ItemRows

FLOW = frozenset({"routine", "end", "call", "if", "elif", "else", "endif", "loop", "endloop", "exit", "label", "jump",
                  "return", "wait"})
START = "the program's start"


@dataclasses.dataclass(frozen=True)
class Step:
    """One thing a program does besides moving, at ``source``:``line``.

    Attributes
    ----------
    kind : str
        ``"routine"`` (``name``), ``"end"`` (of a routine), ``"call"``
        (``name``; ``value`` why the call is unknown when ``name`` is no
        routine of the steps, None for a built-in that moves nothing and
        sets no speed), ``"if"``, ``"elif"``, ``"else"``, ``"endif"``,
        ``"loop"``, ``"endloop"``, ``"exit"`` (leaves the innermost loop),
        ``"label"`` (``name``), ``"jump"`` (to label ``name``; ``value``
        True if conditional), ``"return"``, ``"wait"`` (the arm stops
        there), ``"set"`` (speed state group ``name`` gets ``value``, any
        hashable the language reads back).
    """

    kind: str
    name: str = ""
    value: object = None
    line: int = 0
    source: int = 0


@dataclasses.dataclass(frozen=True)
class Unknown:
    """A setting or start the program's text does not give: ``why``."""

    why: str


@dataclasses.dataclass(frozen=True)
class Reached:
    """What can be in force when each of M motions starts, per run of R motions no step separates.

    The motions of a run start with the same settings; each but the first
    starts where the motion before it ends.

    Attributes
    ----------
    first : ndarray of int, shape (R,)
        The first motion of each run, ascending (the first is 0).
    settings : list of dict, length R
        Per run, ``{group: frozenset of values}``: every value (or
        `Unknown`) its group can have when its motions start.
    before : list of frozenset, length R
        Per run, the motions (indices) that can run just before its first,
        or why none is known (str: `START`, a call).
    waits : ndarray of bool, shape (M,)
        A wait can follow the motion before the next motion starts.
    """

    first: np.ndarray
    settings: list
    before: list
    waits: np.ndarray

    def rows(self, r):
        """The motions of run ``r``: a slice."""
        return slice(int(self.first[r]), int(self.first[r + 1]) if r + 1 < len(self.first) else len(self.waits))


def needed(steps):
    """True if ``steps`` change the order from the file's: a call (not of a built-in), a branch, a loop, a jump, a
    wait or a second routine."""
    routines = {step.name.lower() for step in steps if step.kind == "routine"}
    if len(routines) > 1:
        return True
    return any(step.kind in FLOW and step.kind not in ("routine", "end", "call")
               or step.kind == "call" and (step.value or step.name.lower() in routines) for step in steps)


class _Graph:
    """The steps and motion runs as nodes, each body's (a routine's or the top level's) successors."""

    def __init__(self, steps, table):
        motions = np.lexsort((table.line, table.source))
        if np.any(np.diff(motions) < 0):
            raise ValueError("motions are not in file order")
        at = np.lexsort(([s.line for s in steps], [s.source for s in steps])) if steps else np.array([], dtype=int)
        steps = [steps[i] for i in at.tolist()]
        keys = np.array([(s.source, s.line) for s in steps], dtype=np.int64).reshape(-1, 2)
        # the motions between two steps are one node: a run (first, last)
        where = np.searchsorted(keys[:, 0] * (1 << 32) + keys[:, 1],
                                table.source.astype(np.int64) * (1 << 32) + table.line, side="right")
        self.nodes = []
        m = 0
        for i, step in enumerate(steps + [None]):
            count = int(np.searchsorted(where, i, side="right")) - m
            if count:
                self.nodes.append(Step("motions", value=(m, m + count - 1)))
                m += count
            if step is not None:
                self.nodes.append(step)
        self.routines = {}  # name -> (entry node, end node)
        bodies, stack, top = [], [], []
        for i, node in enumerate(self.nodes):
            if node.kind == "routine":
                stack.append([i])
            elif node.kind == "end" and stack:
                body = stack.pop() + [i]
                self.routines.setdefault(self.nodes[body[0]].name.lower(), (body[0], i))
                bodies.append(body)
            else:
                (stack[-1] if stack else top).append(i)
        bodies = sorted(bodies + stack)  # in file order; a routine without its end runs to the end of the file
        self.bodies = [top] + bodies if top else bodies
        self.succ = {}
        for body in self.bodies:
            self._link(body)

    def _link(self, body):
        """Successors of the nodes of one body (a list of node indices, a routine's from its entry to its end)."""
        nodes = self.nodes
        kinds = [nodes[n].kind for n in body]
        partner, markers, labels, opened = {}, {}, {}, []
        for p, kind in enumerate(kinds):
            if kind in ("if", "loop"):
                opened.append(p)
                markers[p] = []
            elif kind in ("elif", "else") and opened and kinds[opened[-1]] == "if":
                markers[opened[-1]].append(p)
            elif kind in ("endif", "endloop") and opened:
                partner[opened.pop()] = p
            elif kind == "label":
                labels[nodes[body[p]].name.lower()] = p
        for p in opened:  # not closed: to the end of the body
            partner[p] = len(body) - 1
        owner = {}  # marker -> its if
        for p, found in markers.items():
            for q in found:
                owner[q] = p
        last = len(body) - 1

        def after(p):  # where the flow goes on from p: a branch's end jumps over the other branches to the endif
            q = p + 1
            if q <= last and kinds[q] in ("elif", "else") and q in owner:
                return partner[owner[q]] if owner[q] in partner else last
            return min(q, last) if q <= last else None

        header = {end: p for p, end in partner.items() if kinds[p] == "loop"}  # endloop -> its loop
        loop_of, stack = {}, []  # exit -> its loop
        for p, kind in enumerate(kinds):
            if kind == "loop":
                stack.append(p)
            elif kind == "endloop" and stack:
                stack.pop()
            elif kind == "exit" and stack:
                loop_of[p] = stack[-1]
        for p, kind in enumerate(kinds):
            n = body[p]
            nxt = after(p) if p < last else None
            if kind == "if":
                branch = markers[p][0] if markers[p] else partner.get(p, last)
                out = [nxt, branch]
            elif kind == "elif":
                later = [q for q in markers[owner[p]] if q > p] if p in owner else []
                out = [nxt, later[0] if later else partner.get(owner.get(p), last)]
            elif kind == "loop":
                out = [nxt, after(partner[p]) if partner[p] < last else None]
            elif kind == "endloop":
                out = [header[p]] if p in header else [nxt]
            elif kind == "exit":
                out = [after(partner[loop_of[p]])] if p in loop_of and partner[loop_of[p]] < last else [nxt]
            elif kind == "jump":
                target = labels.get(nodes[n].name.lower())
                out = ([target] if target is not None else [None]) + ([nxt] if nodes[n].value else [])
            elif kind == "return":
                out = [last] if kinds[last] == "end" else [None]
            elif kind == "end":
                out = []
            else:
                out = [nxt]
            self.succ[n] = [body[q] for q in out if q is not None]


def follow(steps, table, initial):
    """Every path through a program: the `Reached` of each of its motions.

    Parameters
    ----------
    steps : sequence of Step
        The program's steps (any order: placed by source and line).
    table : MotionTable
        Its motions, in file order (``line``, ``source``).
    initial : dict
        ``{group: value}`` in force where the program starts (and where a
        routine no one calls starts).

    Returns
    -------
    Reached
    """
    graph = _Graph(list(steps), table)
    nodes, succ = graph.nodes, graph.succ
    groups = sorted(initial)
    state_in = {}
    callers = {}  # routine entry -> the nodes after its calls
    for n, node in enumerate(nodes):
        if node.kind == "call" and node.name.lower() in graph.routines:
            callers.setdefault(graph.routines[node.name.lower()][0], []).append(n)
    start = (tuple(frozenset([initial[g]]) for g in groups), frozenset([START]))
    work = []
    for body in graph.bodies:
        first = body[0]
        if nodes[first].kind != "routine" or first not in callers or body is graph.bodies[0]:
            state_in[first] = start
            work.append(first)
    runs = {n: r for r, n in enumerate(n for n, node in enumerate(nodes) if node.kind == "motions")}
    settings, before = [None] * len(runs), [None] * len(runs)
    waits = np.zeros(len(table), dtype=bool)

    def join(a, b):
        return tuple(x | y for x, y in zip(a[0], b[0])), a[1] | b[1]

    def send(n, state):
        old = state_in.get(n)
        new = state if old is None else join(old, state)
        if new != old:
            state_in[n] = new
            work.append(n)

    while work:
        n = work.pop()
        node, (values, last) = nodes[n], state_in[n]
        kind = node.kind
        if kind == "motions":
            settings[runs[n]], before[runs[n]] = dict(zip(groups, values)), last
            last = frozenset([node.value[1]])
        elif kind == "set":
            values = tuple(frozenset([node.value]) if g == node.name else v for g, v in zip(groups, values))
        elif kind == "wait":
            waits[[m for m in last if isinstance(m, int)]] = True
        elif kind == "call":
            routine = graph.routines.get(node.name.lower())
            if routine is not None:
                send(routine[0], (values, last))
                if routine[1] in state_in:  # what the routine ends with, so far
                    _send_after(n, state_in[routine[1]], succ, send)
                continue
            if node.value:
                why = Unknown(f"after a call to {node.name} (line {node.line}): {node.value}")
                values, last = tuple(frozenset([why]) for _ in groups), frozenset([why.why])
        elif kind == "end":
            entry = next((e for e, end in graph.routines.values() if end == n), None)
            for caller in callers.get(entry, ()):
                _send_after(caller, (values, last), succ, send)
            continue
        for s in succ.get(n, ()):
            send(s, (values, last))
    first = np.array([nodes[n].value[0] for n in runs], dtype=int)
    for r, m in enumerate(first.tolist()):  # a run no path reaches (dead code): as if run in file order
        if settings[r] is None:
            settings[r] = dict(zip(groups, start[0]))
            before[r] = frozenset([m - 1]) if m else start[1]
    return Reached(first, settings, before, waits)


def _send_after(call, state, succ, send):
    """A routine's end ``state`` flows on after its ``call`` node."""
    for s in succ.get(call, ()):
        send(s, state)


def start_reasons(reached, table):
    """Why each motion's start is not unique (``""`` where it is the motion before it in the table), (M,) object.

    Parameters
    ----------
    reached : Reached
    table : MotionTable
    """
    out = np.full(len(table), "", dtype=object)
    for m, before in zip(reached.first.tolist(), reached.before):
        if before == {m - 1}:
            continue
        unknown = sorted(b for b in before if isinstance(b, str) and b != START)
        if unknown:
            out[m] = f"its start is not known: {unknown[0]}"
        elif before == {START}:
            if m:  # a first motion after another one in the file (a routine's, defined above it)
                out[m] = ("where the arm is before it is not known: the first motion of the program, or of a routine "
                          "this file does not call")
        elif len(before) == 1:
            (b,) = before
            out[m] = (f"it starts where the motion at line {int(table.line[b])} ends, not the one before it in the "
                      "file (a call, a loop, a branch or a jump)")
        else:
            lines = sorted(int(table.line[b]) for b in before if isinstance(b, int))
            where = ", ".join(f"line {line}" for line in lines)
            also = " or the program's start" if START in before else ""
            out[m] = (f"its start depends on the path the program takes: the motion before it is at {where}{also} "
                      "(a call, a loop, a branch or a jump)")
    return out


def followed(table, reached, speeds=None):
    """The motion table as its controller runs it (see the module): start reasons, waits' stops, speeds.

    Parameters
    ----------
    table : MotionTable
    reached : Reached
        Of ``table``'s motions (`follow`).
    speeds : callable, optional
        ``speeds(table, reached) -> {column: values (M,)}``: the language's
        speed columns (``speed``, ``speed_unit``, ``speed_why`` ...) from
        the settings reaching each motion; ``spans``: ``(rows (K,), their
        spans (K,))`` of the motions whose spans change.

    Returns
    -------
    MotionTable
    """
    rows = np.arange(len(table))
    columns = {"start_why": start_reasons(reached, table)}
    zone = np.array(table.zone, dtype=float)
    zone[reached.waits] = np.nan
    columns["zone"] = zone
    spans = None
    if speeds is not None:
        columns |= speeds(table, reached)
        spans = columns.pop("spans", None)
    table = table.with_rows(rows, **columns)
    return table if spans is None else table.with_rows(spans[0], spans=spans[1])


def program_followed(program, steps, initial, speeds=None, *, settings=False):
    """``program`` with its motion table as its controller runs it (`followed`), or itself where the steps run
    in file order (`needed`; ``settings``: the speed settings must be followed even so, the language reads
    them only here)."""
    if not (needed(steps) or settings and any(step.kind == "set" for step in steps)):
        return program
    table = program.motion_table()
    table = followed(table, follow(steps, table, initial), speeds)
    if isinstance(program.items, ItemRows):
        return program.replace(items=ItemRows(program.items.statements, table))
    motions = iter(range(len(table)))  # a program of objects stays one
    return program.replace(items=tuple(item if isinstance(item, Statement) else table.motion(next(motions))
                                       for item in program.items))
