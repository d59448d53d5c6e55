"""Every path a program can take, run the way its controller runs it: the reference of the control-flow tests.

Independent of trajcomp's reading: each test turns its program's lines into
`Op`s with its own patterns, and `visits` runs the ops as a controller
would, taking every branch both ways, every loop 0, 1 and 2 times, every
conditional jump both ways, calls into routines and back. At each motion it
records what is in force (the speed settings), the motion that ran just
before and whether a wait came between: the slowest programmed speed that
can reach a motion is the least over its visits, the start positions it can
have are its visits' previous motions.
"""

import dataclasses

LOOPS = 2  # a loop body or a backward jump is run at most this many times on a path


@dataclasses.dataclass(frozen=True)
class Op:
    """``kind``: routine (name), end, call (name), if, else, endif, loop, endloop, exit, label (name), jump (name,
    conditional), wait, set (name: group, value), motion (name: a key naming the motion), return."""

    kind: str
    name: str = ""
    value: object = None


@dataclasses.dataclass(frozen=True)
class Visit:
    settings: tuple  # ((group, value), ...) sorted
    before: str  # key of the motion that ran just before ("" at the program's start)
    waited: bool  # a wait came between that motion and this one

    def setting(self, group):
        return dict(self.settings).get(group)


def _structure(ops):
    """Matching partners (if -> else/endif, else -> endif, loop <-> endloop, routine -> end), labels, routines'
    entries."""
    partner, stack, labels, routines = {}, [], {}, {}
    for i, op in enumerate(ops):
        if op.kind in ("if", "loop", "routine"):
            stack.append(i)
            if op.kind == "routine":
                routines[op.name.lower()] = i
        elif op.kind == "else":
            partner[stack[-1]] = i
            stack[-1] = i
        elif op.kind in ("endif", "endloop", "end") and stack:
            opened = stack.pop()
            partner[opened] = i
            if op.kind == "endloop":
                partner[i] = opened
        elif op.kind == "label":
            labels[op.name.lower()] = i
    return partner, labels, routines


def visits(ops, entry, initial):
    """``{(motion key, path): Visit}`` over every path from routine ``entry`` (or op 0 if None), settings
    ``initial`` ({group: value}) in force at the start.

    ``path`` is the decisions taken so far, each ``(n, choice)`` at the n-th op that is not a ``set``: the same
    path in a program that differs only by its speed settings (a re-timed one) has the same key.
    """
    partner, labels, routines = _structure(ops)
    place, count = [], 0
    for op in ops:
        place.append(count)
        count += op.kind != "set"
    start = routines[entry.lower()] + 1 if entry else 0
    out = {}
    todo = [(start, (), tuple(sorted(initial.items())), "", False, (), ())]
    while todo:
        pc, calls, settings, before, waited, counts, path = todo.pop()
        if pc >= len(ops):
            continue
        op = ops[pc]

        def go(to, settings=settings, before=before, waited=waited, calls=calls, counts=counts, choice=None):
            todo.append((to, calls, settings, before, waited, counts,
                         path if choice is None else path + ((place[pc], choice),)))

        def counted(n):
            return tuple(sorted({**dict(counts), pc: n}.items()))

        if op.kind == "motion":
            out[(op.name, path)] = Visit(settings, before, waited)
            go(pc + 1, before=op.name, waited=False)
        elif op.kind == "set":
            go(pc + 1, settings=tuple(sorted({**dict(settings), op.name: op.value}.items())))
        elif op.kind == "wait":
            go(pc + 1, waited=True)
        elif op.kind == "if":
            go(pc + 1, choice=True)
            go(partner[pc] + 1, choice=False)  # past the else (into its branch) or the endif
        elif op.kind == "else":  # the end of the then-branch: over the else-branch
            go(partner[pc] + 1)
        elif op.kind == "loop":
            go(pc + 1, choice=True)  # into the body
            go(partner[pc] + 1, choice=False)  # past it
        elif op.kind == "endloop":
            done = dict(counts).get(pc, 0)
            if done < LOOPS:
                go(partner[pc] + 1, counts=counted(done + 1), choice=True)
            go(pc + 1, choice=False)
        elif op.kind == "exit":
            end, depth = pc, 0
            while True:
                end += 1
                if ops[end].kind == "loop":
                    depth += 1
                elif ops[end].kind == "endloop":
                    if depth == 0:
                        break
                    depth -= 1
            go(end + 1)
        elif op.kind == "jump":
            target = labels[op.name.lower()]
            done = dict(counts).get(pc, 0)
            if target > pc or done < LOOPS:
                go(target + 1, counts=counted(done + 1), choice=True)
            if op.value:
                go(pc + 1, choice=False)
        elif op.kind == "call":
            if op.name.lower() in routines:
                go(routines[op.name.lower()] + 1, calls=calls + (pc + 1,))
            else:
                go(pc + 1)
        elif op.kind in ("end", "return"):
            if calls:
                go(calls[-1], calls=calls[:-1])
        elif op.kind == "routine":  # a routine defined inside another, reached in sequence: over it
            go(partner.get(pc, len(ops)) + 1)
        else:  # label, endif
            go(pc + 1)
    return out


def by_motion(visited):
    """``{motion key: [Visit, ...]}`` of `visits`' result: every path's visits of each motion."""
    out = {}
    for (key, _), visit in visited.items():
        out.setdefault(key, []).append(visit)
    return out


def slowest(visits_of, group):
    """The least value of ``group`` over a motion's visits (None if one has none)."""
    values = [visit.setting(group) for visit in visits_of]
    return None if any(v is None for v in values) else min(values)
