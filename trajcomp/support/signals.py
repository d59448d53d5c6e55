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

import _thread
import contextlib
import functools
import os
import signal
import sys
import threading
import time

STOPPING = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
_STOPPED = []  # the signal that stopped this process's run, once raised (a second one is not raised again)
_HELD = [0]  # how deep within `held` this process is, then the signal that came meanwhile, if one did
_STARTING = {}  # from `hold_from_start` to `raised`: each stopping signal's handler before, and "came": the first


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
    """The handler: raise `Interrupted` the first time, unless held (then at the end of `held`); later signals
    find the run already unwinding."""
    if _STOPPED:
        return
    if _HELD[0]:
        _HELD[1:] = _HELD[1:] or [signum]
        return
    _STOPPED.append(signum)
    raise Interrupted(signum)


def check():
    """Raise `Interrupted` if a stopping signal came and its exception was lost on the way.

    The handler runs wherever the main thread is; where it is running an
    at-fork callback, a destructor or a weak reference's callback, Python
    ignores the exception (`raised` then sends the signal again). The
    places that start work or write call this, so that such a run stops
    there at the latest.
    """
    if _STOPPED and not _HELD[0]:
        raise Interrupted(_STOPPED[0])


def stopped():
    """The `Interrupted` of the stopping signal this process's run received, or None.

    An exception that a signal's `Interrupted` became on its way (an
    ImportError when it was raised into a C extension's initialisation) is
    told apart by it: the run stopped, it did not fail.
    """
    return Interrupted(_STOPPED[0]) if _STOPPED else None


def hold_from_start():
    """Keep each of `STOPPING` that comes before the run begins (`raised`), which then raises it (`check`).

    Called by the program's first line (``python -m trajcomp``, the
    console script, ``python -m trajcomp.cli``), never on a library's
    import: a signal during the command line's imports ends the run with
    its code and message, not with a traceback out of an import. Before
    that line (the interpreter's own start-up) Python's defaults hold.
    """
    if threading.current_thread() is not threading.main_thread() or spawned():  # a worker's start: not the program's
        return
    for signum in STOPPING:
        handler = signal.getsignal(signum)
        if handler not in (signal.SIG_IGN, _keep):
            _STARTING[signum] = handler
            signal.signal(signum, _keep)


def _keep(signum, frame):
    """`hold_from_start`'s handler: the first signal kept for `raised`."""
    _STARTING.setdefault("came", signum)


@contextlib.contextmanager
def raised():
    """Within the block, each of `STOPPING` raises `Interrupted` in the main thread (the handlers restored after).

    A signal this process ignores (``nohup`` ignores SIGHUP, a shell's
    background job SIGINT) stays ignored. One that came while the program
    started (`hold_from_start`) is raised by the block's first `check`. Elsewhere than in the main thread,
    where no handler can be set, the block runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _STOPPED.clear()
    previous = {signum: _STARTING.pop(signum, signal.getsignal(signum)) for signum in STOPPING}
    for signum, handler in previous.items():
        if handler is not signal.SIG_IGN:
            signal.signal(signum, _raise)
    if "came" in _STARTING:  # a signal during the program's start (`hold_from_start`): raised by the first `check`
        _STOPPED.append(_STARTING.pop("came"))
    unraisable = sys.unraisablehook
    sys.unraisablehook = functools.partial(_raise_lost, unraisable)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        sys.unraisablehook = unraisable
        _STOPPED.clear()


def _raise_lost(hook, unraisable):
    """``sys.unraisablehook`` within `raised` (``hook`` the one before): an `Interrupted` that Python could not raise
    where the signal came, and ignored, is raised again a moment later where the main thread then is.

    The handler runs wherever the main thread is, a weak reference's
    callback or a destructor included (an import's module lock has such a
    callback, the garbage collector runs destructors anywhere): Python
    printed the exception there ("Exception ignored in") and went on, and
    the run went on until its next `check`. Here the signal is sent again
    to the main thread 10 ms later, from a new thread (started without
    waiting for it: the handler run within this hook would be lost the
    same way), as if it came then; nothing is printed. Any other exception
    goes to ``hook``.
    """
    if not isinstance(unraisable.exc_value, Interrupted):
        hook(unraisable)
        return
    _STOPPED.clear()
    _thread.start_new_thread(_send_later, (threading.main_thread().ident, unraisable.exc_value.signum))


def _send_later(thread, signum):
    time.sleep(0.01)
    signal.pthread_kill(thread, signum)


def raise_in_this_process():
    """Have each of `STOPPING` this process does not ignore raise `Interrupted` from now on (a worker's start)."""
    _STOPPED.clear()
    for signum in STOPPING:
        if signal.getsignal(signum) is not signal.SIG_IGN:
            signal.signal(signum, _raise)


@contextlib.contextmanager
def held():
    """`STOPPING` held back during the block and raised after it.

    For a block that must not be cut: the renames of a set of files, or the
    import of a C extension (an exception raised into one's initialisation
    aborts the interpreter, exit 134). Held twice: by the signal mask of
    this thread (where signal masks exist), and by `_raise`, which the
    interpreter runs in the main thread even when another thread took the
    signal. A process forked within the block inherits it held, until
    `release_inherited`. In a thread other than the main one (a pool's
    collector starting a worker), only its mask holds them.
    """
    main = threading.current_thread() is threading.main_thread()  # another thread's hold is its mask only
    _HELD[0] += main
    try:
        before = signal.pthread_sigmask(signal.SIG_BLOCK, STOPPING)
    except (AttributeError, OSError):
        before = None
    try:
        yield
    finally:
        if before is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, before)  # a signal that waited in the mask is handled here
        _HELD[0] -= main
        if main:
            _raise_held()


def release_inherited():
    """In a process forked within `held`: hold no more, raising `Interrupted` for a signal that came meanwhile."""
    _HELD[0] = 0
    try:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPPING)
    except (AttributeError, OSError):
        pass
    _raise_held()


def _raise_held():
    if not _HELD[0] and _HELD[1:]:
        signum = _HELD.pop()
        if not _STOPPED:
            _STOPPED.append(signum)
            raise Interrupted(signum)


def spawned():
    """Whether this process is one that multiprocessing spawned (a local Dask cluster's worker): it runs the parent's
    main module too (as ``__mp_main__``) before its work, and is no program of its own."""
    return "--multiprocessing-fork" in getattr(sys, "orig_argv", ())


def release_in_spawned():
    """In a process that multiprocessing spawned with SIGINT blocked (a local Dask cluster's worker,
    `trajcomp.jobs.batch`): each of `STOPPING` ends it by its default action from now on, one that came meanwhile
    now.

    Called by the package's first lines, the earliest trajcomp's code runs
    there (the spawned process imports its parent's main module before it
    unpickles its work). Any other process (not spawned, or spawned with
    SIGINT unblocked, as multiprocessing starts its processes) is left as
    it is.
    """
    if not spawned():
        return
    try:
        if signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, []):
            return
    except (AttributeError, OSError):
        return
    default_from_now()
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPPING)


def default_from_now():
    """Have each of `STOPPING` end this process by its default action from now on (a worker whose work is done:
    a signal in its exit is no exception there, and its parent sees it killed by that signal)."""
    for signum in STOPPING:
        if signal.getsignal(signum) is not signal.SIG_IGN:
            signal.signal(signum, signal.SIG_DFL)


def die_by(signum):
    """End this process as ``signum``'s default action does (its parent sees it killed by that signal)."""
    signal.signal(signum, signal.SIG_DFL)
    try:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [signum])
    except (AttributeError, OSError):
        pass
    os.kill(os.getpid(), signum)
    os._exit(128 + signum)  # where the signal did not end it (not POSIX)
