"""Memory across the stages of a long run: freed memory back to the system, the garbage collector kept off work.

A stage over a million waypoints allocates and frees hundreds of MB of
temporary arrays; glibc's allocator keeps much of it mapped for reuse (its
threshold for returning a block grows with the blocks freed), so the
process would carry it as resident memory into the next stage: 175 MB
after re-timing 1,000,000 waypoints. `release` asks glibc to return it
(``malloc_trim``); where the C library has no such call it does nothing.

A program in a robot language is millions of small objects (targets,
motions, spans) without reference cycles, which Python's cyclic garbage
collector would scan again and again as more are made: 4 s of a 23 s run
of a 100,000-point KRL program. `collection_paused` stops it while they
are made; `end_stage` puts what a stage leaves out of its scans (and out
of the forked workers' scans, which would copy the pages they share)
until the run ends (`kept_apart`).
"""

import contextlib
import ctypes
import functools
import gc


def release():
    """Return the heap memory freed so far to the operating system (glibc), else nothing."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


def end_stage():
    """End a stage of a long run: the memory it freed back to the system (`release`), and every object alive now
    out of the cyclic garbage collector's scans (`gc.freeze`: what a stage leaves lives on; see `kept_apart`)."""
    release()
    gc.freeze()


@contextlib.contextmanager
def kept_apart():
    """A long run: the objects its stages put out of the garbage collector's scans (`end_stage`) are its again
    after the block (`gc.unfreeze`), so that a process serving many runs (a batch worker) collects them."""
    try:
        yield
    finally:
        gc.unfreeze()


@contextlib.contextmanager
def collection_paused():
    """Cyclic garbage collection paused within the block (as it was after it): for code that makes millions of
    objects without cycles (a program's items and spans, the rows of a CSV being split)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


@functools.cache
def _malloc_trim():
    try:
        return ctypes.CDLL(None).malloc_trim  # the C library this process runs on
    except (OSError, AttributeError):  # not glibc: nothing to call
        return None
