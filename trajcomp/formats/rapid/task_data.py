"""The speeddata and num of a RAPID task: where the other modules of a module's task declare one, and where a
module's statements may change one (`trajcomp.formats.rapid.reader._Reader.constant`)."""

import re
from pathlib import Path

from trajcomp.errors import ReadError
from trajcomp.formats.rapid import grammar
from trajcomp.formats.text import Lines, mask, read_source


def may_change(text, key):
    """Whether a statement's masked line ``text`` that names datum ``key`` (lower case) may change it: any
    statement but a motion (which reads its speed data), a declaration, and an assignment of another datum (which
    reads it) may (a routine call may take it as an INOUT, VAR or PERS argument)."""
    assigned = grammar.ASSIGNMENT.match(text)
    return not (grammar.STARTS_MOTION.match(text) or grammar.STARTS_DECLARATION.match(text)
                or assigned and assigned.group(1).lower() != key)


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


class TaskData:
    """The speeddata and num the other modules of a module's task declare, read as the controller sees them.

    Parameters
    ----------
    path : Path
        The module read (not searched).
    folders : sequence of Path
        The task's folders (a backup's PROGMOD and SYSMOD), missing ones skipped.
    extensions : sequence of str
        The modules' extensions, lower case with the dot.
    """

    def __init__(self, path, folders, extensions):
        self.path, self.folders, self.extensions = Path(path), list(folders), set(extensions)
        self._modules, self._declared, self._changed, self._unknown = None, None, {}, None

    def modules(self):
        """``(file, masked text, Lines)`` of each other module of the task, read once (an unreadable one skipped)."""
        if self._modules is None:
            self._modules = []
            for folder in self.folders:
                for file in sorted(folder.iterdir()) if folder.is_dir() else ():
                    if file != self.path and file.suffix.lower() in self.extensions and file.is_file():
                        try:
                            masked = mask(read_source(file).text, "!")
                        except ReadError:
                            continue
                        self._modules.append((file, masked, Lines(masked)))
        return self._modules

    def declared(self, key):
        """The declarations of datum ``key`` (lower case) the module sees in the other modules of its task (not
        LOCAL, not a routine's own data): list of ``(file, line, storage, type, value)``, storage upper case, type
        lower case, value its text ('' if none)."""
        if self._declared is None:
            self._declared = {}
            for file, masked, lines in self.modules():
                routines = [(m.start(), m.re is grammar.ROUTINE_OPENS) for pattern in (grammar.ROUTINE_OPENS,
                                                                                     grammar.ROUTINE_CLOSES)
                            for m in pattern.finditer(masked) if "MODULE" not in m.group(1).upper()]
                routines.sort()
                for m in grammar.TASK_SPEED.finditer(masked):
                    inside = [opens for at, opens in routines if at < m.start()]
                    d = grammar.SPEED_DECLARATION.match(masked, m.start())
                    if d is None or (inside and inside[-1]):
                        continue
                    self._declared.setdefault(d.group(3).lower(), []).append(
                        (file, lines.number(d.start(1)), d.group(1).upper(), d.group(2).lower(),
                         (d.group(4) or "").strip()))
        return self._declared.get(key, [])

    def unknown_call(self, masked, lines):
        """``"name (file:line)"`` of the first call, in the module read (``masked``, its `Lines`) or another of
        its task, of a routine no module of the task declares (`unknown_calls`: it may change any datum the
        module sees), or ``""``."""
        if self._unknown is None:
            texts = [(self.path, masked, lines), *self.modules()]
            routines = {m.group(1).lower() for _, text, _ in texts for m in grammar.ROUTINE_NAME_LINE.finditer(text)}
            self._unknown = next((f"{name} ({file.name}:{lines_of.number(at)})" for file, text, lines_of in texts
                                  for name, at in unknown_calls(text, routines)), "")
        return self._unknown

    def changed(self, key):
        """``"file:line"`` of the first statement of another module of the task that may change datum ``key``
        (`may_change`), or ``""``."""
        if key not in self._changed:
            self._changed[key] = next((f"{file.name}:{line}" for file, masked, lines in self.modules()
                                       if (line := changed_at(masked, lines, key))), "")
        return self._changed[key]
