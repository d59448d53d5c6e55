"""The commands of the README and of the docs pages it links, and every ``--help`` example, run as written;
the outputs they show are what the commands print.

Rules (the README's "Set up" section points here):

- README: every fenced block tagged ``sh`` holds console commands. They run
  in order, top to bottom, as one terminal session that starts at the root of
  a clone: a temporary folder holding a copy of ``examples/``, beside a link
  ``shared`` to the real data folder next to this repository when there is
  one. ``cd`` carries over to later commands and files stay. A line ending in
  ``\\`` continues on the next, ``#`` starts a comment, ``A && B`` runs A then
  B. Any other fenced block is shown output; a ``trajcomp`` command in one
  fails `test_readme_commands_are_in_sh_blocks` (tag that block ``sh``).
- How: ``cd DIR`` moves the session; a plain ``trajcomp ...`` runs
  ``trajcomp.cli.main`` in this process (the code of this checkout); any
  other command runs in bash, with ``trajcomp`` and ``python`` on the PATH
  running this checkout's code.
- ``--help``: the lines under ``example:`` of every sub-command run in the
  order of ``trajcomp.cli.COMMANDS``, as another session from the root of
  another such clone.
- Docs pages: the pages under ``docs/`` the README lists (list items that
  start with a link to one), in that order, continue the README's session:
  their ``sh`` blocks run after the README's, in the same folder, with the
  files it made.
- Shown output: a fenced block whose info string is ``text output`` (the
  language, then the word ``output``, then optional ``abs=X`` and
  ``rel=Y``: the tolerance of its numbers, default exact) shows what the
  last command run before it printed (stdout and stderr). Each of its lines
  must match a line of that output, in order, other lines of the output
  between them allowed; in a line, ``...`` stands for any text, runs of
  spaces for any run of spaces, and each number for a number within
  ``abs + rel * |shown|`` of it; a line that is only ``...`` stands for
  any lines. Any other block that is not ``sh`` is illustration, not
  compared.
- A ``python`` block whose first line is ``# examples/NAME.py...`` shows that
  file whole, as it is (`test_shown_example_files_are_the_files`): the
  commands that run it run what the page shows.
- Not run: a command starting with one of `NOT_RUN` (installing, the test
  suite itself, CI, the benchmarks); in ``A && B`` only that part is left
  out. A command naming a path under ``shared/data/`` skips when that path
  is absent, saying where those data come from (`REAL_DATA_SOURCES`), and
  so does the output block shown after it.
- Every other command must exit 0; a failure names the README line (or the
  sub-command) and the command, with the end of its output.

Each command is one test item. An item run alone first runs the commands
before it, so any selection works; after a failure the rest of that session
is skipped. The test workers share one session of each kind (its folder, its
state and each command's outcome on disk, under a lock): whichever worker
reaches an item first runs the commands up to it, once for all workers.
"""

import argparse
import contextlib
import dataclasses
import fcntl
import importlib
import io
import json
import logging
import os
import re
import shlex
import shutil
import subprocess
import sys
import traceback
from pathlib import Path

import pytest
from conftest import DATA_HOME, REAL_DATA_SOURCES

from trajcomp.cli import COMMANDS, main

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"

NOT_RUN = (
    "pip install",  # changes the environment; the test runs the code of this checkout
    "python -m pytest",  # the test suite itself
    ".ci/run",  # the test suite from a clean checkout
    "python tests/benchmarks/",  # minutes of work, not part of the test run
)
COMMAND_LANGUAGES = {"sh"}
REAL_DATA = re.compile(r"[^\s=,]*shared/data/[^\s,]*")
FENCE = re.compile(r"^\s*```\s*(\S*)(.*)")
DOCS_LINK = re.compile(r"^\s*[-*]\s+\[[^\]]*\]\((docs/[\w./-]+\.md)\)", re.MULTILINE)
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
CONTINUED = "\\"
COMMENT = re.compile(r"(^|\s)#.*")
TRAJCOMP_LINE = re.compile(r"^\s*(\$\s*)?trajcomp\s")
SHELL_SYNTAX = re.compile(r"[|<>;&`$()*?]")
TIMEOUT = 300  # s, per shell command


@dataclasses.dataclass(frozen=True)
class Command:
    """One command line as the docs show it: where it is written and its text; or, with ``shown``, an output
    block: the lines the command before it prints, and the tolerance of their numbers."""

    where: str
    text: str
    shown: tuple = None
    tolerance: tuple = (0.0, 0.0)  # (abs, rel)

    def __str__(self):
        return f"{self.where}: `{self.text}`"


def fenced_blocks(path):
    """``(language, [(line number, text), ...])`` of every fenced block of a Markdown file."""
    return [(language, lines) for language, _, lines in _blocks(path)]


def _blocks(path):
    """``(language, the rest of the info string, [(line number, text), ...])`` of every fenced block."""
    blocks, current = [], None
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        fence = FENCE.match(line)
        if fence and current is None:
            current = (fence.group(1), fence.group(2).split(), [])
        elif fence:
            blocks.append(current)
            current = None
        elif current is not None:
            current[2].append((number, line))
    return blocks


def readme_commands(path=README):
    """The commands of the ``sh`` blocks, continued lines joined, comments dropped, and the output blocks."""
    commands = []
    for language, info, lines in _blocks(path):
        if language not in COMMAND_LANGUAGES:
            if info[:1] == ["output"]:
                options = dict(word.split("=", 1) for word in info[1:])
                commands.append(Command(f"{path.name}:{lines[0][0] - 1 if lines else 0}", "(shown output)",
                                        tuple(text for _, text in lines),
                                        (float(options.get("abs", 0)), float(options.get("rel", 0)))))
            continue
        pending = None
        for number, line in lines:
            text = COMMENT.sub("", line).strip()
            if pending is None and not text:
                continue
            start, before = pending or (number, "")
            joined = f"{before} {text.removesuffix(CONTINUED).strip()}".strip()
            pending = (start, joined) if text.endswith(CONTINUED) else None
            if pending is None:
                commands.append(Command(f"{path.name}:{start}", joined))
    return commands


def docs_pages(path=README):
    """The pages under docs/ a Markdown file lists (a list item starting with a link to one), in that order."""
    return [REPO / link for link in dict.fromkeys(DOCS_LINK.findall(path.read_text(encoding="utf-8")))
            if (REPO / link).is_file()]


def session_commands():
    """The README's commands, then those of the docs pages it links, one session."""
    commands = readme_commands()
    for page in docs_pages():
        commands += [dataclasses.replace(c, where=f"docs/{c.where}") for c in readme_commands(page)]
    return commands


def line_pattern(shown):
    """A regex of a shown output line (numbers captured, ``...`` any text, spaces any spaces) and its numbers."""
    pattern, numbers, at = "", [], 0
    for m in re.finditer(rf"\.\.\.|{NUMBER.pattern}|\s+", shown.strip()):
        pattern += re.escape(shown.strip()[at:m.start()])
        token = m.group()
        if token == "...":
            pattern += ".*?"
        elif token.isspace():
            pattern += r"\s+"
        else:
            pattern += f"({NUMBER.pattern})"
            numbers.append(float(token))
        at = m.end()
    pattern += re.escape(shown.strip()[at:])
    return re.compile(pattern), numbers


def output_mismatch(shown, output, tolerance):
    """The first shown line no output line matches, in order, within the tolerance (None when all do)."""
    absolute, relative = tolerance
    lines = output.splitlines()
    at = 0
    for text in shown:
        if not text.strip() or text.strip() == "...":
            continue
        pattern, expected = line_pattern(text)
        for k in range(at, len(lines)):
            m = pattern.fullmatch(lines[k].strip())
            if m and all(abs(float(got) - want) <= absolute + relative * abs(want)
                         for got, want in zip(m.groups(), expected)):
                at = k + 1
                break
        else:
            near = [line for line in lines if pattern.fullmatch(line.strip())]
            return text + (f"\n  printed: {near[0]}" if near else "\n  (no printed line of that form)")
    return None


def help_examples():
    """``{sub-command: [example command lines]}`` from each parser's epilog, in the order of COMMANDS."""
    sub = argparse.ArgumentParser(prog="trajcomp").add_subparsers()
    examples = {}
    for name in COMMANDS:
        importlib.import_module(f"trajcomp.commands.{name}").add_parser(sub)
        shown = re.search(r"^examples?:\n((?:[ \t]+\S.*\n?)*)", sub.choices[name].epilog or "", re.MULTILINE)
        examples[name] = [line.strip() for line in (shown.group(1) if shown else "").splitlines() if line.strip()]
    return examples


class Session:
    """One terminal session over a list of commands in a temporary clone, shared by every process that opens it.

    The clone, the session's state and each command's outcome live in
    ``root``; `run_through` takes a lock on them, so processes that open
    the same root (the test workers) continue one session and never run a
    command twice.
    """

    def __init__(self, root, commands):
        self.root = root
        self.commands = commands
        root.mkdir(parents=True, exist_ok=True)
        bin_dir = root / "bin"
        self.env = dict(
            os.environ,
            PATH=os.pathsep.join([str(bin_dir), str(Path(sys.executable).parent), os.environ.get("PATH", "")]),
            PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
        )
        with self._locked():
            if (root / "state.json").exists():
                return
            self.cwd = root / "clone"
            self.next, self.failed, self.outcomes = 0, None, {}
            self.output, self.skipped = "", None  # the last command's output; why it was not run
            shutil.copytree(REPO / "examples", self.cwd / "examples")
            if (REPO.parent / "shared").is_dir():
                (root / "shared").symlink_to(REPO.parent / "shared")
            bin_dir.mkdir()
            shim = bin_dir / "trajcomp"
            shim.write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} -m trajcomp.cli "$@"\n')
            shim.chmod(0o755)
            self._save()

    @contextlib.contextmanager
    def _locked(self):
        """Hold the session's lock (blocking while another process runs its commands); its state loaded."""
        with open(self.root / "lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                if (self.root / "state.json").exists():
                    state = json.loads((self.root / "state.json").read_text())
                    self.cwd = Path(state.pop("cwd"))
                    self.outcomes = {int(k): v for k, v in state.pop("outcomes").items()}
                    vars(self).update(state)
                yield
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    def _save(self):
        state = dict(cwd=str(self.cwd), next=self.next, failed=self.failed, outcomes=self.outcomes,
                     output=self.output, skipped=self.skipped)
        (self.root / "state.json").write_text(json.dumps(state))

    def run_through(self, index):
        """Run the commands up to ``index`` not yet run; the skip reason of the last one, or None.

        Raises
        ------
        pytest.fail.Exception
            Command ``index`` failed (its message, whichever process ran it).
        pytest.skip.Exception
            A command before it failed.
        """
        with self._locked():
            try:
                while self.next <= index:
                    self.outcomes[self.next] = self._outcome(self.commands[self.next])
                    self.next += 1
            finally:
                self._save()
        kind, text = self.outcomes[index]
        if kind == "fail":
            pytest.fail(text, pytrace=False)
        if kind == "after failure":
            pytest.skip(text)
        return text

    def _outcome(self, command):
        """``(kind, text)`` of running ``command``: ``("ran", skip reason or None)``, ``("fail", message)`` or
        ``("after failure", reason)``."""
        if self.failed is not None:
            return "after failure", f"not run: {self.failed} failed before"
        try:
            return "ran", self.run(command)
        except pytest.fail.Exception as failure:
            self.failed = command.where
            return "fail", str(failure)
        except Exception:
            self.failed = command.where
            return "fail", f"{command} raised:\n{traceback.format_exc()}"

    def run(self, command):
        """Run one command in the session's folder (or compare a shown output); the reason it is not, or None."""
        if command.shown is not None:
            if self.skipped:
                return f"{command.where}: the output of a command not run: {self.skipped}"
            wrong = output_mismatch(command.shown, self.output, command.tolerance)
            if wrong:
                pytest.fail(f"{command.where}: the shown output is not what the command before it printed "
                            f"(tolerance abs {command.tolerance[0]:g}, rel {command.tolerance[1]:g}); first line "
                            f"not matched:\n  shown:   {wrong}\n--- printed:\n{self.output[-3000:]}", pytrace=False)
            return None
        self.skipped = None
        parts = [p for p in re.split(r"\s+&&\s+", command.text) if not p.startswith(NOT_RUN)]
        if not parts:
            return f"{command}: not run in tests (it starts with one of {', '.join(NOT_RUN)})"
        for path in REAL_DATA.findall(command.text):
            if not (self.cwd / path).exists():
                folder = path.split("shared/data/", 1)[1].split("/")[0]
                source = REAL_DATA_SOURCES.get(folder, "real data not described in tests/test_docs.py")
                self.skipped = (f"{command}: needs the real data {path}, absent: {source}, in {DATA_HOME}")
                return self.skipped
        for part in parts:
            words = shlex.split(part)
            if words[0] == "cd" and len(words) == 2:
                if not (self.cwd / words[1]).is_dir():
                    pytest.fail(f"{command}: no folder {words[1]} in {self.cwd}", pytrace=False)
                self.cwd = (self.cwd / words[1]).resolve()
                continue
            plain_trajcomp = words[0] == "trajcomp" and not SHELL_SYNTAX.search(part)
            code, output = self.trajcomp(words[1:]) if plain_trajcomp else self.shell(part)
            self.output = output
            if code != 0:
                tail = "\n".join(output.strip().splitlines()[-15:])
                pytest.fail(f"{command} exited {code} in {self.cwd}:\n{tail}", pytrace=False)
        return None

    def trajcomp(self, argv):
        """``(exit code, output)`` of the CLI run in this process, in the session's folder.

        The same ``main`` as the console script, without its start-up cost
        (about a second of imports per command).
        """
        output = io.StringIO()
        previous = Path.cwd()
        os.chdir(self.cwd)
        warnings = logging.StreamHandler(output)  # the console script's warnings on stderr (the root logger
        warnings.setFormatter(logging.Formatter("trajcomp: warning: %(message)s"))  # has pytest's handlers)
        warnings.setLevel(logging.WARNING)
        logging.getLogger().addHandler(warnings)
        try:
            with contextlib.redirect_stdout(output), contextlib.redirect_stderr(output):
                code = main(argv)
        except SystemExit as exc:  # argparse: bad usage
            code = exc.code
        except Exception:  # a traceback: the console script would exit 1 with it
            code = 1
            output.write(traceback.format_exc())
        finally:
            logging.getLogger().removeHandler(warnings)
            os.chdir(previous)
        return code, output.getvalue()

    def shell(self, text):
        """``(exit code, output)`` of a shell command in the session's folder."""
        done = subprocess.run(["bash", "-c", text], cwd=self.cwd, env=self.env, capture_output=True, text=True,
                              timeout=TIMEOUT)
        return done.returncode, done.stdout + done.stderr


README_COMMANDS = session_commands()
HELP_EXAMPLES = [
    Command(f"trajcomp {name} --help, example {k}", text)
    for name, lines in help_examples().items()
    for k, text in enumerate(lines, start=1)
]


def shared_folder(tmp_path_factory, name):
    """A folder ``name`` of this test run, the same for every test worker (the workers' base folders share
    their parent, which is the run's own)."""
    base = tmp_path_factory.getbasetemp()
    return (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / name


@pytest.fixture(scope="module")
def readme_session(tmp_path_factory):
    return Session(shared_folder(tmp_path_factory, "readme-session"), README_COMMANDS)


@pytest.fixture(scope="module")
def help_session(tmp_path_factory):
    return Session(shared_folder(tmp_path_factory, "help-session"), HELP_EXAMPLES)


@pytest.mark.parametrize("index", range(len(README_COMMANDS)), ids=[c.where for c in README_COMMANDS])
def test_readme_command_runs_as_written(readme_session, index):
    reason = readme_session.run_through(index)
    if reason:
        pytest.skip(reason)


@pytest.mark.parametrize("index", range(len(HELP_EXAMPLES)), ids=[c.where for c in HELP_EXAMPLES])
def test_help_example_runs_as_written(help_session, index):
    reason = help_session.run_through(index)
    if reason:
        pytest.skip(reason)


def test_every_command_shows_an_example():
    assert [name for name, lines in help_examples().items() if not lines] == []


def test_readme_commands_are_in_sh_blocks():
    hidden = [
        f"{page.name}:{number}: {text.strip()}"
        for page in (README, *docs_pages())
        for language, lines in fenced_blocks(page)
        if language not in COMMAND_LANGUAGES
        for number, text in lines
        if TRAJCOMP_LINE.match(text)
    ]
    assert not hidden, "trajcomp commands in a block not tagged sh (the docs test would not run them):\n" + "\n".join(hidden)


def test_readme_keeps_the_set_up_commands():
    texts = {c.text for c in README_COMMANDS}
    assert {"pip install -e . && trajcomp demo", 'pip install -e ".[test]" && python -m pytest'} <= texts


def test_extraction_joins_continued_lines_and_drops_comments(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(
        "text\n```sh\n# a comment\ntrajcomp plan --robot ur10 \\\n  --step 100 -o plan.csv   # plan it\n"
        "cd tour\n```\n```text\ntrajcomp: error: shown output\n```\n"
    )
    assert readme_commands(readme) == [
        Command("README.md:4", "trajcomp plan --robot ur10 --step 100 -o plan.csv"),
        Command("README.md:6", "cd tour"),
    ]


def test_a_failing_command_is_named_by_its_line(tmp_path):
    session = Session(tmp_path, [
        Command("README.md:3", "mkdir -p tour && cd tour"),
        Command("README.md:4", "trajcomp validate model.yaml validation.csv --tolerance 0.05"),
        Command("README.md:5", "trajcomp robots"),
    ])
    assert session.run_through(0) is None and session.cwd.name == "tour"
    with pytest.raises(pytest.fail.Exception, match=r"README.md:4: `trajcomp validate model.yaml .*` exited 2 in .*tour"):
        session.run_through(1)
    with pytest.raises(pytest.skip.Exception, match="not run: README.md:4 failed before"):
        session.run_through(2)


def test_install_test_and_benchmark_commands_and_absent_data_are_skipped_by_rule(tmp_path):
    session = Session(tmp_path, [
        Command("README.md:1", 'pip install -e ".[test]" && python -m pytest'),
        Command("README.md:2", "python tests/benchmarks/bench_demo.py"),
        Command("README.md:3", "trajcomp calibrate ../shared/data/no-such-set/grid.csv --robot ur5 -o m.yaml"),
        Command("README.md:4", "pip install -e . && trajcomp robots > robots.txt"),
    ])
    assert "not run in tests" in session.run_through(0)
    assert "not run in tests" in session.run_through(1)
    assert ("needs the real data ../shared/data/no-such-set/grid.csv, absent: real data not described"
            in session.run_through(2))
    assert session.run_through(3) is None  # the trajcomp part ran, through the shell
    assert "ur10" in (session.cwd / "robots.txt").read_text()


def test_a_shown_output_is_compared_with_what_the_command_before_it_printed(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("```sh\necho 'rms 0.0071 mm, 5,892 points'; echo extra; echo 'cycle time 9.180 s'\n```\n"
                      "```text output abs=0.0005\nrms 0.007 mm, 5,892 points\n...\ncycle  time 9.18... s\n```\n"
                      "```text output\nrms 0.006 mm, 5,892 points\n```\n")
    commands = readme_commands(readme)
    assert [c.shown is not None for c in commands] == [False, True, True] and commands[1].tolerance == (0.0005, 0.0)
    session = Session(tmp_path, commands)
    assert session.run_through(1) is None  # within 0.0005; "..." any lines or text; spaces any spaces
    with pytest.raises(pytest.fail.Exception, match=r"README.md:9: the shown output is not what .*\n  shown:   rms "
                                                    r"0.006 mm, 5,892 points\n  printed: rms 0.0071 mm"):
        session.run_through(2)  # exact by default: a stale figure fails


def test_the_output_of_a_command_that_needs_absent_data_is_skipped_with_where_the_data_come_from(tmp_path):
    session = Session(tmp_path, [
        Command("README.md:1", "trajcomp calibrate ../shared/data/ur10-ipa/none.csv --robot ur10 -o m.yaml"),
        Command("README.md:2", "(shown output)", ("identified 25 parameters",)),
    ])
    assert "christianlandgraf/ipa-robot-accuracy" in session.run_through(0)
    assert "the output of a command not run" in session.run_through(1)


def test_the_docs_pages_the_readme_links_continue_its_session():
    pages = docs_pages()
    assert all(page.parent == REPO / "docs" for page in pages)
    where = [c.where for c in README_COMMANDS]
    readme_last = max(k for k, w in enumerate(where) if w.startswith("README.md:"))
    assert all(not w.startswith("README.md:") for w in where[readme_last + 1:])


def test_shown_example_files_are_the_files():
    shown = [(page, lines) for page in (README, *docs_pages()) for language, lines in fenced_blocks(page)
             if language == "python" and lines and re.match(r"# examples/\S+\.py", lines[0][1])]
    for page, lines in shown:
        name = re.match(r"# (examples/\S+\.py)", lines[0][1]).group(1)
        assert "\n".join(text for _, text in lines) + "\n" == (REPO / name).read_text(), f"{page.name}:{lines[0][0]}"
    assert any(page == README for page, _ in shown)


def test_sessions_opened_on_one_folder_continue_one_session_and_run_each_command_once(tmp_path):
    commands = [Command("README.md:1", "mkdir -p tour && cd tour"), Command("README.md:2", "echo ran >> log.txt"),
                Command("README.md:3", "echo ran >> log.txt"), Command("README.md:4", "false")]
    first, second = Session(tmp_path / "s", commands), Session(tmp_path / "s", commands)
    assert second.run_through(2) is None  # runs 0-2, in the folder the first one made
    assert first.run_through(1) is None and first.cwd == second.cwd  # already run: its outcome, nothing again
    assert (first.cwd / "log.txt").read_text() == "ran\nran\n"
    with pytest.raises(pytest.fail.Exception, match=r"README.md:4: `false` exited 1"):
        first.run_through(3)
    with pytest.raises(pytest.fail.Exception, match=r"README.md:4: `false` exited 1"):
        second.run_through(3)  # the failure the first one met
