"""The speeddata and num of a RAPID task: where the other modules of a module's task declare one, where a
module's statements may change one, and whether the controller's other tasks may change a PERS they share
(`trajcomp.formats.rapid.reader._Reader.constant`)."""

import re
from pathlib import Path

from trajcomp.errors import ReadError
from trajcomp.formats.rapid import grammar
from trajcomp.formats.text import Lines, mask, read_source


def may_change(text, key):
    """Whether a statement's masked line ``text`` that names datum ``key`` (lower case) may change it: any
    statement but a motion (which reads its speed data), a declaration, an assignment of another datum (which
    reads it) and an instruction that changes none of its arguments (`grammar.STRAIGHT`: VelSet, AccSet,
    WaitTime ...) may (a routine call may take it as an INOUT, VAR or PERS argument)."""
    assigned = grammar.ASSIGNMENT.match(text)
    instruction = grammar.INSTRUCTION.match(text)
    return not (grammar.STARTS_MOTION.match(text) or grammar.STARTS_DECLARATION.match(text)
                or assigned and assigned.group(1).lower() != key
                or instruction and instruction.group(1).lower() in grammar.STRAIGHT)


def changed_at(masked, lines, key, parts=None):
    """The number of the first line of ``masked`` (``parts``: its ``(start, end)`` offsets looked at; default all)
    whose statement may change datum ``key`` (`may_change`); 0 if none."""
    named = re.compile(r"\b" + re.escape(key) + r"\b", re.I)
    for start, end in [(0, len(masked))] if parts is None else parts:
        for m in named.finditer(masked, start, end):
            line = lines.number(m.start())
            text = masked[lines.starts[line - 1]:lines.starts[line] if line < len(lines.starts) else len(masked)]
            if may_change(text.rstrip("\r\n"), key):
                return line
    return 0


# a statement calling a routine by its name (the name first, then ';', blanks or an optional argument), or by a
# name computed at run time (%"name"%)
_CALL = re.compile(r"^[ \t]*(?:([A-Za-z]\w*)[ \t]*(?:;|[ \t]|\\)|(%))", re.M)
_NOT_ROUTINES = grammar.BUILT_IN | grammar.NOT_CALLS | set(grammar.FLOW_STEPS) | {
    w.lower() for w in (*grammar.PREFIXES, *grammar.STORAGES, *grammar.ROUTINES, "THEN", "DO", "TO", "FROM", "STEP")}


def unknown_calls(masked, routines):
    """``(name, offset)`` of the statements of ``masked`` that call a routine not among ``routines`` (lower
    names): a built-in instruction trajcomp does not know, or a routine of a module the folder lacks."""
    for m in _CALL.finditer(masked):
        name = m.group(1) or m.group(2)
        line = masked[m.start():masked.find("\n", m.start()) % (len(masked) + 1)]
        if name.lower() not in routines and name.lower() not in _NOT_ROUTINES \
                and not (grammar.ASSIGNMENT.match(line) or grammar.STARTS_MOTION.match(line)):
            yield name, m.start()


_TASK_FOLDER = re.compile(r"TASK\d+", re.I)  # a backup's RAPID/TASKn


def task_folders(path):
    """The folders of a module's task and those of the controller's other tasks.

    A module of a backup (``RAPID/TASKn/PROGMOD`` or ``SYSMOD``) is in the
    task of its ``TASKn``, whose modules lie in its PROGMOD and SYSMOD, and
    the backup holds every other task of the controller as another
    ``RAPID/TASKn``; a module elsewhere is in the task of its folder, and
    the controller's other tasks are not known.

    Returns
    -------
    folders : list of Path
        The task's folders (some may be missing).
    other_tasks : dict or None
        ``{name: folders}`` of the backup's other tasks; None outside a backup.
    """
    folder = Path(path).parent
    if folder.name.upper() not in ("PROGMOD", "SYSMOD"):
        return [folder], None
    task = folder.parent
    folders = [task / "PROGMOD", task / "SYSMOD"]
    if not (_TASK_FOLDER.fullmatch(task.name) and task.parent.name.upper() == "RAPID"):
        return folders, None
    return folders, {other.name: [other / "PROGMOD", other / "SYSMOD"] for other in sorted(task.parent.iterdir())
                     if other != task and other.is_dir() and _TASK_FOLDER.fullmatch(other.name)}


def shared_by_tasks(declaration):
    """Whether a `grammar.SPEED_DECLARATION` match declares a PERS every task of the controller that declares it
    shares: one without LOCAL (its module's own) or TASK (its task's own) before it."""
    prefixes = declaration.string[declaration.start():declaration.start(1)]
    return declaration.group(1).upper() == "PERS" and not re.search(r"\b(?:LOCAL|TASK)\b", prefixes, re.I)


def _modules(folders, extensions, skip):
    """``(file, masked text, Lines)`` of each module in ``folders`` but ``skip`` (an unreadable one left out)."""
    modules = []
    for folder in folders:
        for file in sorted(folder.iterdir()) if folder.is_dir() else ():
            if file != skip and file.suffix.lower() in extensions and file.is_file():
                try:
                    masked = mask(read_source(file).text, "!")
                except ReadError:
                    continue
                modules.append((file, masked, Lines(masked)))
    return modules


def _declarations(modules):
    """The speeddata and num ``modules`` (`_modules`) declare for their task (not LOCAL, not a routine's own data):
    ``{lower name: [(file, line, storage, type, value, shared)]}``, storage upper case, type lower case, value its
    text ('' if none), shared `shared_by_tasks`."""
    declared = {}
    for file, masked, lines in modules:
        routines = sorted((m.start(), m.re is grammar.ROUTINE_OPENS) for pattern in (grammar.ROUTINE_OPENS,
                                                                                   grammar.ROUTINE_CLOSES)
                          for m in pattern.finditer(masked) if "MODULE" not in m.group(1).upper())
        for m in grammar.TASK_SPEED.finditer(masked):
            inside = [opens for at, opens in routines if at < m.start()]
            d = grammar.SPEED_DECLARATION.match(masked, m.start())
            if d is None or (inside and inside[-1]):
                continue
            declared.setdefault(d.group(3).lower(), []).append(
                (file, lines.number(d.start(1)), d.group(1).upper(), d.group(2).lower(), (d.group(4) or "").strip(),
                 shared_by_tasks(d)))
    return declared


def _first_unknown_call(modules):
    """``"name (file:line)"`` of the first call in ``modules`` (``(file, masked text, Lines)`` of one task) of a
    routine none of them declares (`unknown_calls`), or ``""``."""
    routines = {m.group(1).lower() for _, text, _ in modules for m in grammar.ROUTINE_NAME_LINE.finditer(text)}
    return next((f"{name} ({file.name}:{lines.number(at)})" for file, text, lines in modules
                 for name, at in unknown_calls(text, routines)), "")


def _first_change(modules, key):
    """``"file:line"`` of the first statement of ``modules`` that may change datum ``key`` (`may_change`), or
    ``""``."""
    return next((f"{file.name}:{line}" for file, masked, lines in modules if (line := changed_at(masked, lines, key))),
                "")


class TaskData:
    """The speeddata and num the other modules of a module's task, and the controller's other tasks, declare and
    may change, read as the controller sees them.

    Parameters
    ----------
    path : Path
        The module read (not searched).
    folders : sequence of Path
        The task's folders (a backup's PROGMOD and SYSMOD), missing ones skipped.
    extensions : sequence of str
        The modules' extensions, lower case with the dot.
    other_tasks : dict or None, optional
        ``{name: folders}`` of every other task of the controller (a
        backup's other ``RAPID/TASKn``); None (default): not known, as for
        a module outside a backup.
    """

    def __init__(self, path, folders, extensions, other_tasks=None):
        self.path, self.folders, self.extensions = Path(path), list(folders), set(extensions)
        self.other_tasks = other_tasks
        self._modules, self._declared, self._changed, self._unknown, self._others = None, None, {}, None, None

    def modules(self):
        """``(file, masked text, Lines)`` of each other module of the task, read once (an unreadable one skipped)."""
        if self._modules is None:
            self._modules = _modules(self.folders, self.extensions, self.path)
        return self._modules

    def declared(self, key):
        """The declarations of datum ``key`` (lower case) the module sees in the other modules of its task (not
        LOCAL, not a routine's own data): list of ``(file, line, storage, type, value, shared)`` (`_declarations`)."""
        if self._declared is None:
            self._declared = _declarations(self.modules())
        return self._declared.get(key, [])

    def unknown_call(self, masked, lines):
        """``"name (file:line)"`` of the first call, in the module read (``masked``, its `Lines`) or another of
        its task, of a routine no module of the task declares (`unknown_calls`: it may change any datum the
        module sees), or ``""``."""
        if self._unknown is None:
            self._unknown = _first_unknown_call([(self.path, masked, lines), *self.modules()])
        return self._unknown

    def changed(self, key):
        """``"file:line"`` of the first statement of another module of the task that may change datum ``key``
        (`may_change`), or ``""``."""
        if key not in self._changed:
            self._changed[key] = _first_change(self.modules(), key)
        return self._changed[key]

    def other_tasks_change(self, key, value):
        """Why another task of the controller may give PERS ``key`` (lower case; shared by every task declaring
        it, `shared_by_tasks`), declared here with ``value``, another value, or ``""`` if none can.

        A PERS's value in a module is the one saved last, and every task
        declaring it reads and writes that one datum: it holds its value
        only where every task of the controller is read (a backup's
        ``RAPID/TASKn``) and none declares it with another value, names it
        in a statement that may change it (`may_change`), or calls a routine
        no module of its task declares (a module loaded at run time may
        change it). The other tasks of a module outside a backup are not
        known: it may change there.
        """
        if self.other_tasks is None:
            return ("the controller's other tasks share it and are not read (the module is not in a backup's "
                    "RAPID/TASKn folders)")
        if self._others is None:
            self._others = [(name, _modules(folders, self.extensions, self.path))
                            for name, folders in self.other_tasks.items()]
        stated = re.sub(r"\s+", "", value).lower()
        for task, modules in self._others:
            for file, at, storage, _, other, shared in _declarations(modules).get(key, []):
                if shared and other and re.sub(r"\s+", "", other).lower() != stated:
                    return (f"task {task} declares it {other} ({file.name}:{at}): its value is that of the task "
                            "loaded first")
            if changed := _first_change(modules, key):
                return f"task {task} may change it ({changed})"
            if called := _first_unknown_call(modules):
                return (f"task {task} calls {called}, a routine no module of its task declares, which may "
                        "change it")
        return ""
