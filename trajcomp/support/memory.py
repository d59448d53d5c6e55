"""Memory across the stages of a long run: freed memory back to the system, the garbage collector kept off work.

A stage over a million waypoints allocates and frees hundreds of MB of
temporary arrays; glibc's allocator keeps much of it mapped for reuse (its
threshold for returning a block grows with the blocks freed), so the
process would carry it as resident memory into the next stage: 175 MB
after re-timing 1,000,000 waypoints. `release` asks glibc to return it
(``malloc_trim``); where the C library has no such call it does nothing.
A run that ends with its process may rather keep what it frees
(`keep_freed_blocks`): a block freed and made again comes back without
page faults.

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


M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3  # mallopt parameters of glibc's <malloc.h>
KEPT_BLOCK = 32 * 2**20  # bytes: glibc's largest mmap threshold on 64 bits; smaller blocks are kept by the heap


def release():
    """Return the heap memory freed so far to the operating system (glibc), else nothing."""
    trim = _c_function("malloc_trim")
    if trim is not None:
        trim(0)


def keep_freed_blocks():
    """From now on, freed blocks of up to `KEPT_BLOCK` stay in this process's heap for the next allocations (glibc),
    instead of going back to the system and coming again as fresh pages; where the C library has no ``mallopt``,
    nothing.

    For a process that ends with its run, whose arrays of a few MB come and
    go thousands of times: calibrating ur10-ipa (Jacobians and normal
    equations of 5,892 rows and 720 spline terms) spent 0.8 of its 6 CPU s
    in page faults, 0.3 s so, for 216 -> 220 MB peak resident memory.
    """
    mallopt = _c_function("mallopt")
    if mallopt is not None:
        mallopt(M_MMAP_THRESHOLD, KEPT_BLOCK)
        mallopt(M_TRIM_THRESHOLD, 2**30)  # the heap's free top is returned beyond 1 GiB only


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
def _c_function(name):
    """The function ``name`` of the C library this process runs on, or None where it has none (not glibc)."""
    try:
        return getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError):
        return None
