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
"""

import contextlib
import ctypes
import multiprocessing
import os
import signal
import time

from trajcomp.errors import TrajcompError
from trajcomp.support.threads import pin_loaded

_TASK = None  # the function of the pool being started, inherited by its forked workers
_LOOKAHEAD = 2  # blocks a worker may compute ahead of the consumer, each
_MEANWHILE = []  # work for this process while the next pool's workers compute (`meanwhile`)
_PR_SET_PDEATHSIG = 1  # prctl option of <linux/prctl.h>: the signal a process gets when its parent dies
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
    here, when its result is reached; the blocks not yet started are
    dropped, and the workers end once the few under way have.
    """
    workers = min(workers, count)
    if workers <= 1 or not _can_fork():
        yield from map(function, range(count))
        return
    global _TASK
    _TASK = function
    try:
        pool = multiprocessing.get_context("fork").Pool(workers, init_worker)  # they start here, with it
    finally:
        _TASK = None
    try:
        ahead = count if _MEANWHILE else workers * _LOOKAHEAD  # every block under way while this process is busy
        pending = []
        for k in range(count):
            pending.append(pool.apply_async(_run, (k,)))
            if len(pending) > ahead:
                yield pending.pop(0).get()
        while _MEANWHILE:
            _MEANWHILE.pop(0)()
        for result in pending:
            yield result.get()
    finally:  # also when a block failed or the caller stopped: the few blocks under way end, then the workers
        pool.close()  # (Pool.terminate can hang on its task thread; at most workers * _LOOKAHEAD blocks wait)
        pool.join()


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
    if helpers <= 0 or not _can_fork():
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

    def helper(sending):
        init_worker()
        sending.send(list(blocks()))  # at the end: a result sent at once would wait for this process to read it

    pipes, processes = [], []
    try:
        for _ in range(helpers):
            receiving, sending = context.Pipe(duplex=False)
            processes.append(context.Process(target=helper, args=(sending,), daemon=True))
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
    done.sort(key=lambda block: block[0])
    for _, _, error in done:
        if error is not None:
            raise error
    if len(done) < count:
        codes = sorted({process.exitcode for process in processes} - {0})
        raise TrajcompError(f"a helper process ended (exit code {codes}) before sending the blocks it had taken")
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
        ``function`` raised in the other process.
    """
    if workers <= 1 or not _can_fork():
        value = function()
        return lambda: value
    global _TASK
    _TASK = lambda k: function()  # noqa: E731 (the forked process's task)
    try:
        pool = multiprocessing.get_context("fork").Pool(1, init_worker)
    finally:
        _TASK = None
    pending = pool.apply_async(_run, (0,))
    pool.close()

    def result():
        try:
            return pending.get()
        finally:
            pool.join()

    return result


def init_worker():
    """Initializer of worker processes: one BLAS thread each, they die with their parent, and Ctrl-C is the
    parent's to handle.

    A worker computes on one BLAS / OpenMP thread unless the user set the
    thread variables (`trajcomp.support.threads.pin_loaded`: a process
    forked from an application that loaded numpy with a thread per core
    would otherwise run that many in each worker). Ctrl-C reaches the whole process group; the parent stops the workers,
    which do not report it themselves. SIGTERM gets its default action back
    (a forked worker inherits the parent's handler). On Linux the kernel
    kills a worker whose parent dies (``PR_SET_PDEATHSIG``), even by
    SIGKILL, so that no orphan goes on writing outputs.
    """
    pin_loaded()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    parent = os.getppid()
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):  # not Linux: workers end when their task queue closes
        return
    if os.getppid() != parent:  # the parent died before the request was made
        os._exit(1)


def _run(k):
    return _TASK(k)


def _can_fork():
    """Whether this process may start forked workers: fork exists and this is not a daemonic pool worker."""
    return "fork" in multiprocessing.get_all_start_methods() and not multiprocessing.current_process().daemon
