"""Blocks of one long program computed on several cores.

A stage that works a block of rows at a time (compensation chunks, the
posture plan's closed-form branches) hands `map_blocks` a function of the
block's index. With more than one worker the blocks are computed by
processes started with ``fork``: they inherit the caller's arrays as they
are (nothing is copied or pickled on the way in) and send each block's
result back, in block order, as it is needed, so only a few results are
held at a time. Where ``fork`` is not available, or the caller is itself a
worker of a pool (a batch's file worker, a Dask worker), the blocks run one
after the other in this process: the results are the same either way.
`meanwhile` gives this process work of its own while a pool's workers
compute. `share_blocks` is for a few costly blocks with small results (a
cross-validation's folds): this process computes blocks too, beside fewer
forked helpers, each process taking the next block no other has taken.
`Workers` is the pool under `map_blocks`, `in_background` and a batch's
files: a worker that dies fails its block at once (`WorkerLost`), one that a
stopping signal killed stops the run as that signal (`Interrupted`), so
that a signal to the process group or to any worker ends the whole run and
no task is lost without an answer.
"""

import atexit
import collections
import contextlib
import ctypes
import multiprocessing
import os
import signal
import threading
import time
from multiprocessing import connection

from trajcomp.errors import TrajcompError
from trajcomp.support.signals import (STOPPING, Interrupted, check, default_from_now, die_by, held,
                                      raise_in_this_process, release_inherited, signal_of)
from trajcomp.support.threads import pin_loaded

_LOOKAHEAD = 2  # blocks a worker may compute ahead of the consumer, each
_MEANWHILE = []  # work for this process while the next pool's workers compute (`meanwhile`)
_PR_SET_PDEATHSIG = 1  # prctl option of <linux/prctl.h>: the signal a process gets when its parent dies
_OPEN = set()  # the `Workers` pools not yet closed
_GRACE = 1.0  # s a worker is given to unwind after SIGTERM before SIGKILL ends it
_LOADAVG = "/proc/loadavg"  # Linux: its 4th field counts the runnable processes, "running/all"


def usable_cores():
    """Cores this process may run on (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def idle_cores():
    """Cores of `usable_cores` that no runnable process of the machine would take from this one now, at least 0.

    From the count of runnable processes in ``/proc/loadavg`` (this one
    included), the least of three readings 5 ms apart so that a process
    running for a moment does not count; where it cannot be read (not
    Linux), every core but this process's is taken as idle.

    Returns
    -------
    int
    """
    readings = []
    for reading in range(3):
        try:
            with open(_LOADAVG) as loadavg:
                readings.append(int(loadavg.read().split()[3].split("/")[0]))
        except (OSError, ValueError, IndexError):
            return usable_cores() - 1
        if reading < 2:
            time.sleep(0.005)
    return max(0, usable_cores() - min(readings))


def map_blocks(function, count, workers=1):
    """``function(k)`` for k = 0 .. count - 1, in order, computed by up to ``workers`` processes.

    Parameters
    ----------
    function : callable
        ``function(k) -> result`` of block k; it may read any data the caller
        holds (a closure). Results must be picklable when ``workers > 1``.
    count : int
        Number of blocks.
    workers : int
        Processes to use; 1 (or a single block) computes in this process.

    Yields
    ------
    The results, in block order. An exception raised by a block is raised
    here, when its result is reached; the workers are then stopped. A
    worker that dies raises `WorkerLost`, or `Interrupted` when a stopping
    signal (SIGINT, SIGTERM, SIGHUP) killed it: the run ends as if this
    process had received it.
    """
    workers = min(workers, count)
    if workers <= 1 or not can_fork():
        yield from map(function, range(count))
        return
    with Workers(function, workers) as pool:
        ahead = count if _MEANWHILE else workers * _LOOKAHEAD  # every block under way while this process is busy
        for k in range(min(ahead, count)):
            pool.submit(k)
        while _MEANWHILE:
            _MEANWHILE.pop(0)()
        for k in range(count):
            if k + ahead < count:
                pool.submit(k + ahead)
            yield pool.result(k)


def share_blocks(function, count, workers=1):
    """``[function(k) for k in range(0, count)]``, computed by this process and up to ``workers - 1`` forked helpers,
    one per core idle now (`idle_cores`).

    Each process takes the next block no other has taken until none is
    left, so a process the machine runs less computes fewer blocks, and
    nothing waits for a helper beyond the one block it is computing. A
    helper costs the pages it writes, which it shares with this process
    until then (calibrating ur10-ipa: 37,000 page faults, 0.15 CPU s, per
    helper), and gains only on a core no other process takes: beside one
    CPU-bound process on two cores, this process and a helper get 4/3 of
    a core, which saves at most a quarter of the blocks' time (ur10-ipa:
    0.3 of 1.2 s), about what the helper costs; on a busier machine it
    only costs. So helpers start on idle cores only. A pool of ``workers`` processes
    (`map_blocks`) would leave this process idle and fork one more.

    Parameters
    ----------
    function : callable
        ``function(k) -> result`` of block k; it may read any data the caller
        holds. Results and errors must be picklable when ``workers > 1``.
    count : int
        Number of blocks.
    workers : int
        Processes computing, this one included; 1 (or a single block)
        computes here only.

    Returns
    -------
    list
        The results, in block order.

    Raises
    ------
    Exception
        What the first failing block (in block order) raised; the other
        processes stop after their block under way.
    """
    helpers = min(workers, count) - 1
    if helpers > 0:
        helpers = min(helpers, idle_cores())
    if helpers <= 0 or not can_fork():
        return [function(k) for k in range(count)]
    context = multiprocessing.get_context("fork")
    taken = context.Value("i", 0)  # the next block no process has taken

    def blocks():
        """``(k, result, error)`` of the blocks this process takes, until none is left or one failed."""
        while True:
            with taken.get_lock():
                k = taken.value
                taken.value += 1
            if k >= count:
                return
            try:
                block = k, function(k), None
            except Exception as error:  # noqa: BLE001 (the caller raises it, in block order)
                with taken.get_lock():
                    taken.value = count  # no process takes another block
                block = k, None, error
            yield block

    def helper(sending, parent):
        init_worker(parent)
        try:
            release_inherited()
            sending.send(list(blocks()))  # at the end: a result sent at once would wait for this process to read it
            default_from_now()
        except KeyboardInterrupt as stop:  # SIGINT, SIGTERM, SIGHUP: die by it, for this process to see
            die_by(signal_of(stop))

    pipes, processes = [], []
    try:
        for _ in range(helpers):
            receiving, sending = context.Pipe(duplex=False)
            processes.append(context.Process(target=helper, args=(sending, os.getpid()), daemon=True))
            with held():  # taken by the helper once it can unwind
                processes[-1].start()
            sending.close()  # the helper's end: closed here, so that a helper that dies shows as end of file
            pipes.append(receiving)
        done = list(blocks())
        for receiving in pipes:
            try:
                done += receiving.recv()
            except EOFError:  # the helper died (killed) before sending its blocks
                pass
    except BaseException:  # Ctrl-C or a failure here: the helpers end now
        for process in processes:
            process.terminate()
        raise
    finally:
        for process in processes:
            process.join()
    codes = sorted({process.exitcode for process in processes} - {0})
    stopped = [-code for code in codes if code is not None and -code in STOPPING]
    if stopped:  # a signal to a helper stops the run as it would this process, also once its blocks were sent
        raise Interrupted(stopped[0])
    done.sort(key=lambda block: block[0])
    for _, _, error in done:
        if error is not None:
            raise error
    if len(done) < count:
        raise WorkerLost(f"a helper process {_death(codes[0])} before sending the blocks it had taken")
    return [result for _, result, _ in done]


@contextlib.contextmanager
def meanwhile(function):
    """Within the block, have ``function()`` run in this process while the workers of a `map_blocks` pool compute.

    For work this process must do anyway that would otherwise hold up the
    run with a core idle, e.g. importing what a later stage needs (scipy,
    0.3 s) while the workers of an earlier one compute; the processes
    forked later inherit it. That pool's blocks are all handed out first,
    so that its workers go on meanwhile. Where no pool starts in the block
    (one process, a short program) the work is not done here: what it
    prepares is then done where it is needed (an import on first use).
    """
    _MEANWHILE.append(function)
    try:
        yield
    finally:
        if function in _MEANWHILE:
            _MEANWHILE.remove(function)


def in_background(function, workers=1):
    """``function()`` computed by a forked process while the caller goes on, when ``workers`` > 1.

    Parameters
    ----------
    function : callable
        ``function() -> result``; it may read any data the caller holds. The
        result must be picklable when ``workers > 1``.
    workers : int
        More than 1: compute in another process, now; else in this
        process, now (raising what ``function`` raises).

    Returns
    -------
    callable
        ``result()``: the result (waiting for it), or the exception
        ``function`` raised in the other process (`WorkerLost` or
        `Interrupted` if it died). A result not asked for is dropped with
        the process when this one ends.
    """
    if workers <= 1 or not can_fork():
        value = function()
        return lambda: value
    pool = Workers(lambda k: function(), 1)
    pool.submit(0)

    def result():
        with pool:
            return pool.result(0)

    return result


class WorkerLost(TrajcompError):
    """A worker process died (killed, out of memory) before sending the result of its block or file."""


class Workers:
    """Forked worker processes computing ``function(k)`` of the blocks handed to them, one block at a time each.

    The workers inherit ``function`` and everything the caller holds (fork).
    A thread of this process takes their results as they come, so that a
    worker never waits for this one to read, and sees at once a worker that
    dies (its process sentinel): its block then fails with `WorkerLost`, or
    every block fails with `Interrupted` when a stopping signal killed it (a
    signal to the process group, or to that worker alone, ends the whole
    run). With ``replace``, a worker that died is replaced and the other
    blocks go on (a batch: one file lost, not the batch); without, every
    block not yet done fails with it. Used as a context manager: on leaving
    it normally the workers end once idle; on an exception (Ctrl-C,
    SIGTERM, a failing block) they are stopped (SIGTERM, then SIGKILL after
    `_GRACE`), so that none is left running.
    """

    def __init__(self, function, workers, replace=False):
        self._function = function  # inherited by each worker, also those that replace dead ones
        self._replace = replace
        self._lock = threading.Condition()
        self._results = {}  # block -> (succeeded, value)
        self._queue = collections.deque()  # blocks handed in, not yet to a worker
        self._busy = {}  # worker process -> its block, or None when idle
        self._connections = {}  # worker process -> its end of the pipe
        self._stopped = None  # the exception that ends every block: a worker stopped by a signal
        self._closing = None  # once closing: whether this process stops the workers (on an exception) or lets them end
        for _ in range(workers):
            self._start_worker()
        _OPEN.add(self)
        self._collector = threading.Thread(target=self._collect, name="trajcomp-workers", daemon=True)
        self._collector.start()

    def submit(self, k):
        """Hand block ``k`` to an idle worker, or queue it for the next one."""
        check()
        with self._lock:
            self._queue.append(k)
            self._dispatch()

    def result(self, k):
        """Block ``k``'s result, waiting for it; what it raised, or how its worker died, is raised here."""
        with self._lock:
            while k not in self._results and self._stopped is None:
                self._lock.wait(0.25)  # a signal to this process is handled between the waits
                check()
            if k not in self._results:
                raise self._stopped
            succeeded, value = self._results.pop(k)
        if not succeeded:
            raise value
        return value

    def __enter__(self):
        return self

    def __exit__(self, kind, error, trace):
        with self._lock:
            self._closing = "stopping" if error is not None else "ending"
            for process in self._busy:
                if error is None:
                    with contextlib.suppress(OSError):
                        self._connections[process].send(None)  # it ends once idle
                else:
                    _signal(process, signal.SIGTERM)  # it unwinds (temporaries removed) and dies
        self._collector.join(_GRACE if error is not None else None)
        if self._collector.is_alive():
            # a signal that interrupted this thread inside the lock can leave it held: kill without it, and never
            # wait for the collector longer than the grace (a daemon thread, gone with the process)
            for process in list(self._busy):
                _signal(process, signal.SIGKILL)
            self._collector.join(_GRACE)
        for receiving in self._connections.values():
            receiving.close()
        _OPEN.discard(self)
        return False

    def _start_worker(self):
        receiving, sending = multiprocessing.get_context("fork").Pipe()
        process = multiprocessing.get_context("fork").Process(  # forked: its arguments are inherited, not pickled
            target=_serve, args=(self._function, sending, os.getpid()), daemon=True)
        with held():  # the worker starts with the stopping signals held: `_serve` takes them once it can unwind
            process.start()
        sending.close()
        self._connections[process] = receiving
        self._busy[process] = None

    def _dispatch(self):
        """Give queued blocks to idle workers (the lock held)."""
        for process, block in self._busy.items():
            if not self._queue:
                return
            if block is None:
                k = self._queue.popleft()
                self._busy[process] = k
                try:
                    self._connections[process].send(k)
                except OSError:  # it died meanwhile: its sentinel tells
                    pass

    def _collect(self):
        """The thread taking results and deaths until every worker has ended."""
        while True:
            with self._lock:
                if not self._busy:
                    return
                waited = {}
                for process in self._busy:
                    waited[self._connections[process]] = waited[process.sentinel] = process
            for ready in connection.wait(list(waited)):
                with self._lock:
                    process = waited[ready]
                    if process in self._busy:
                        self._take(process)
                        if ready == process.sentinel:
                            self._ended(process)
                    self._lock.notify_all()

    def _take(self, process):
        """Read every result ``process`` has sent (the lock held)."""
        receiving = self._connections[process]
        try:
            while receiving.poll():
                k, succeeded, value = receiving.recv()
                self._results[k] = succeeded, value
                self._busy[process] = None
        except (EOFError, OSError):  # it died: its sentinel tells
            return
        self._dispatch()

    def _ended(self, process):
        """A worker's death (the lock held): its block fails, or every block when a signal or this process ended it."""
        process.join()
        k = self._busy.pop(process)
        code = process.exitcode
        if self._closing == "stopping":  # this process's own SIGTERM, or a death that no block waits for now
            return
        if code is not None and -code in STOPPING:  # the whole run stops, by the same signal, also when it came
            # to a worker ending after its last block
            self._stopped = Interrupted(-code)
            os.kill(os.getpid(), -code)
            return
        if self._closing:  # it died ending, its blocks done
            return
        lost = WorkerLost(f"a worker process {_death(code)} before sending its result"
                          + (" (out of memory? the kernel's OOM killer sends SIGKILL)" if code == -signal.SIGKILL else ""))
        if not self._replace:
            self._stopped = lost
            return
        if k is not None:
            self._results[k] = False, lost
        self._start_worker()
        self._dispatch()


@atexit.register  # before multiprocessing's own exit function, registered earlier, terminates the workers
def _close_open_pools():
    """At exit, stop the workers of pools never closed (an `in_background` result not asked for: the run
    failed first) as on an exception: their deaths then stop nothing."""
    for pool in list(_OPEN):
        pool.__exit__(TrajcompError, TrajcompError("exiting"), None)


def _death(code):
    """How a process with exit code ``code`` ended, in words."""
    if code is not None and code < 0:
        return f"was killed by {signal.Signals(-code).name}"
    return f"ended with exit code {code}"


def _signal(process, signum):
    """Send ``signum`` to a worker not yet reaped (its pid is still its own)."""
    with contextlib.suppress(ProcessLookupError):
        os.kill(process.pid, signum)


def _serve(function, connection, parent):
    """A worker's loop: block numbers in, ``(k, succeeded, function(k) or its error)`` out, until None or end of
    file; ``parent`` is the pid of the process that forked it, read before the fork (`init_worker`)."""
    init_worker(parent)
    try:
        release_inherited()
        while True:
            try:
                k = connection.recv()
            except EOFError:
                break
            if k is None:
                break
            try:
                answer = k, True, function(k)
            except Exception as error:  # noqa: BLE001 (the caller raises it, at its block)
                answer = k, False, error
            try:
                connection.send(answer)
            except Exception as error:  # noqa: BLE001 (a result or error that cannot be pickled)
                connection.send((k, False, TrajcompError(f"block {k}: its result cannot be sent back: {error!r}")))
        default_from_now()  # done: a signal in its exit ends it as it is, no exception there
    except KeyboardInterrupt as stop:  # SIGINT, SIGTERM, SIGHUP: unwound; now die by it, for the parent to see
        die_by(signal_of(stop))


def init_worker(parent=None):
    """Initializer of worker processes: one BLAS thread each, they die with their parent, and a stopping signal
    unwinds them, then kills them.

    A worker computes on one BLAS / OpenMP thread unless the user set the
    thread variables (`trajcomp.support.threads.pin_loaded`: a process
    forked from an application that loaded numpy with a thread per core
    would otherwise run that many in each worker). SIGINT, SIGTERM and
    SIGHUP raise `Interrupted` (`trajcomp.support.signals`), so that a
    worker writing files removes its temporaries; `_serve` then ends it by
    the signal, which its parent sees. On Linux the kernel kills a worker
    whose parent dies (``PR_SET_PDEATHSIG``), even by SIGKILL, so that no
    orphan goes on writing outputs; ``parent``, the pid of the process that
    forked this one, read before the fork, tells whether it died before the
    request was made.

    Parameters
    ----------
    parent : int, optional
        The parent's pid as the parent read it; default: this process's
        parent now (a pool's initializer, called at once after the fork).
    """
    pin_loaded()
    raise_in_this_process()
    parent = os.getppid() if parent is None else parent
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # not Linux: workers end when their pipe closes
        return
    if os.getppid() != parent:  # the parent died before the request was made
        os._exit(1)


def can_fork():
    """Whether this process may start forked workers: fork exists and this is not a worker itself."""
    return "fork" in multiprocessing.get_all_start_methods() and not multiprocessing.current_process().daemon
