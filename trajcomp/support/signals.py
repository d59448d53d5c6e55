"""The signals that stop a run (SIGINT, SIGTERM, SIGHUP): raised where the run is, held back where it must not be.

Each of them is raised as an exception in the process's main thread
(`Interrupted`, a KeyboardInterrupt, as Ctrl-C is), once (the signals that
follow, e.g. a process group's signal resent by a worker's death, find the
run already unwinding and are dropped), so that the run unwinds
as after Ctrl-C: temporaries removed, nothing half-written. The command line
turns it into the shells' exit code of the signal (130, 143, 129); a worker
process that receives one unwinds the same way and then dies by the signal,
so that the process that started it sees which one it was
(`trajcomp.support.parallel`). `held` defers them over a block that must not
be cut (the renames of a set, the loading of a C extension).
"""

import contextlib
import os
import signal
import threading

STOPPING = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
_STOPPED = []  # the signal that stopped this process's run, once raised (a second one is not raised again)


class Interrupted(KeyboardInterrupt):
    """The run was stopped by ``signum`` (SIGINT, SIGTERM or SIGHUP)."""

    def __init__(self, signum=signal.SIGINT):
        super().__init__(signum)
        self.signum = signum

    def __str__(self):
        return f"stopped by {self.name}"

    @property
    def exit_code(self):
        """128 + the signal's number, as shells report a process that signal stopped (130, 143, 129)."""
        return 128 + self.signum

    @property
    def name(self):
        """The signal's name, e.g. ``"SIGTERM"``."""
        return signal.Signals(self.signum).name


def signal_of(interruption):
    """The signal number a KeyboardInterrupt stands for: its own, or SIGINT for Python's Ctrl-C."""
    return getattr(interruption, "signum", signal.SIGINT)


def _raise(signum, frame):
    """The handler: raise `Interrupted` the first time; later signals find the run already unwinding."""
    if not _STOPPED:
        _STOPPED.append(signum)
        raise Interrupted(signum)


@contextlib.contextmanager
def raised():
    """Within the block, each of `STOPPING` raises `Interrupted` in the main thread (the handlers restored after).

    Elsewhere than in the main thread, where no handler can be set, the block
    runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.signal(signum, _raise) for signum in STOPPING}
    _STOPPED.clear()
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        _STOPPED.clear()


def raise_in_this_process():
    """Have each of `STOPPING` raise `Interrupted` from now on (a worker process's start)."""
    _STOPPED.clear()
    for signum in STOPPING:
        signal.signal(signum, _raise)


@contextlib.contextmanager
def held():
    """`STOPPING` held back during the block and delivered after it (where signal masks exist).

    For a block that must not be cut: the renames of a set of files, or the
    import of a C extension (an exception raised into one's initialisation
    aborts the interpreter, exit 134).
    """
    try:
        before = signal.pthread_sigmask(signal.SIG_BLOCK, STOPPING)
    except (AttributeError, OSError):
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def die_by(signum):
    """End this process as ``signum``'s default action does (its parent sees it killed by that signal)."""
    signal.signal(signum, signal.SIG_DFL)
    try:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [signum])
    except (AttributeError, OSError):
        pass
    os.kill(os.getpid(), signum)
    os._exit(128 + signum)  # where the signal did not end it (not POSIX)
