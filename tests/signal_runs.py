"""Runs of the ``trajcomp`` command stopped by a signal at a chosen moment, and what each left behind.

Shared by tests/support/test_signals.py (a handful of moments) and
tests/benchmarks/bench_signals.py (hundreds). A run is started in a process
group of its own, as a CI job or a terminal starts it; after ``delay``
seconds a signal goes to the group, to the main process or to one of its
worker processes; the run must then end within `DEADLINE` with the
signal's code (or have finished before it, whole), leaving no process of the
group running and no file under a real name that a finished run would not
have written, and no temporary when a stopping signal let it unwind.
"""

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEADLINE = 2.0  # s from the signal to the run's end
STOPPING = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}


def long_program(path, targets):
    """A KR6 CSV program of ``targets`` LIN motions on a smooth closed curve in front of the arm (mm, deg)."""
    k = np.arange(targets)
    xyz = np.column_stack([400 + 80 * np.sin(k / 50), -50 + 80 * np.cos(k / 70), 650 + 60 * np.sin(k / 90)])
    lines = ["x,y,z,a,b,c,motion,speed,zone"]
    lines += [f"{x:.3f},{y:.3f},{z:.3f},0,90,0,LIN,100,1" for x, y, z in xyz]
    path.write_text("\n".join(lines) + "\n")
    return path


@dataclasses.dataclass
class Outcome:
    """What one stopped run did: its exit code, how long it took to end after the signal, what it left."""

    code: object  # int, or "hang" when it outlived the deadline (then killed)
    seconds: float
    left_running: list
    files: list
    stderr: str
    sent_to: str

    def problems(self, signum, finished, stopped=lambda files: not files, deadline=DEADLINE):
        """What breaks the promise, in words (empty: none).

        ``finished(files)`` tells whether ``files`` are what a finished run
        writes, ``stopped(files)`` what a stopped run may leave (default:
        nothing).
        """
        found = []
        if self.code == "hang" or self.seconds > deadline:
            found.append(f"ended {self.seconds:.2f} s after the signal ({self.code})")
        if self.left_running:
            found.append(f"processes left running: {self.left_running}")
        if "Traceback" in self.stderr or "Fatal Python error" in self.stderr:
            found.append("a traceback: " + self.stderr[-300:])
        if self.code in (0, 1):  # it finished before the signal came
            if not finished(self.files):
                found.append(f"finished with {self.code} but wrote {self.files}")
        elif self.code == -signum and (not self.files or finished(self.files)):
            pass  # killed by it before its handlers were set or after they were put back: the shell reports 128 + n
        elif self.code != STOPPING[signum]:
            found.append(f"exit {self.code}, not {STOPPING[signum]}: {self.stderr[-300:]}")
        elif not stopped(self.files):
            found.append(f"stopped but left {self.files}")
        return found


def run_stopped(command, folder, signum, delay, target="group"):
    """Run ``trajcomp command`` in ``folder``; ``delay`` s after its start send ``signum`` to ``target``.

    ``target``: ``"group"`` (its process group), ``"main"`` or ``"worker"``
    (a child of the main process, ``delay`` s after the first one started,
    or the next one it starts).
    Files the run was given are left out of `Outcome.files` (those present
    before it started).
    """
    before = set(_files(folder))
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    process = subprocess.Popen([sys.executable, "-m", "trajcomp.cli", *command], cwd=folder, env=env,
                               start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    started = time.monotonic()
    if target == "worker":  # the delay counts from its first worker's start
        while not _children(process.pid) and process.poll() is None:
            time.sleep(0.01)
    time.sleep(delay)
    sent_to = target
    try:
        if target == "group":
            os.killpg(process.pid, signum)
        elif target == "main":
            os.kill(process.pid, signum)
        else:  # a worker of the main process, or the next one it starts
            children = _executed(_children(process.pid), process.pid)
            while not children and process.poll() is None:
                time.sleep(0.01)
                children = _executed(_children(process.pid), process.pid)
            sent_to = f"worker after {time.monotonic() - started:.2f} s" if children else "none (ended)"
            if children:
                os.kill(children[0], signum)
    except ProcessLookupError:
        pass
    sent = time.monotonic()
    try:
        _, stderr = process.communicate(timeout=DEADLINE + (60 if signum == signal.SIGKILL else 3))
        code = process.returncode
    except subprocess.TimeoutExpired:
        code = "hang"
        os.killpg(process.pid, signal.SIGKILL)
        _, stderr = process.communicate()
    seconds = time.monotonic() - sent
    left = _group(process.pid)
    if left:
        os.killpg(process.pid, signal.SIGKILL)
    files = sorted(set(_files(folder)) - before)
    return Outcome(code, seconds, left, files, stderr, sent_to)


def _files(folder):
    return [str(p.relative_to(folder)) for p in Path(folder).rglob("*") if p.is_file()]


def _children(pid):
    """The worker processes of process ``pid``, started by any of its threads (a Dask nanny's thread): its
    children but multiprocessing's resource tracker (a Dask batch's), which is no worker and ignores the
    stopping signals by design (they are left to its users)."""
    children = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    children.sort()
    return [child for child in children if b"resource_tracker" not in _command(child)]


def _executed(children, pid):
    """``children`` of process ``pid`` once each runs its own program: one that is still a copy of the run about to
    execute its program (the thread of the run that started it waits for that: state D, vfork) is waited for, up to
    0.5 s; those that become multiprocessing's resource tracker are left out (a forked worker never executes another
    program, and its thread goes on at once)."""
    deadline = time.monotonic() + 0.5
    while _starting(pid) & set(children) and time.monotonic() < deadline:
        time.sleep(0.01)
    return [child for child in children if b"resource_tracker" not in _command(child)]


def _starting(pid):
    """The children of process ``pid`` that a thread of it waits for (state D), as one waits for a vfork child to
    execute its program."""
    starting = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            if (task / "stat").read_text().rsplit(")", 1)[1].split()[0] == "D":
                starting.update(int(c) for c in (task / "children").read_text().split())
        except OSError:
            pass
    return starting


def _command(pid):
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def _has_memory(pid):
    """Whether process ``pid`` still has its memory: one that is ending has released it (an empty command line)
    and runs no more of its code."""
    return bool(_command(pid))


def _group(pgid):
    """Processes of process group ``pgid`` still running (zombies and those already ending not counted)."""
    left = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z" and _has_memory(entry.name):
            left.append(int(entry.name))
    return left
