"""Freed memory handed back to the operating system between the stages of a long run.

A stage over a million waypoints allocates and frees hundreds of MB of
temporary arrays; glibc's allocator keeps much of it mapped for reuse (its
threshold for returning a block grows with the blocks freed), so the
process would carry it as resident memory into the next stage: 175 MB
after re-timing 1,000,000 waypoints. `release` asks glibc to return it
(``malloc_trim``); where the C library has no such call it does nothing.
"""

import ctypes
import functools


def release():
    """Return the heap memory freed so far to the operating system (glibc), else nothing."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


@functools.cache
def _malloc_trim():
    try:
        return ctypes.CDLL(None).malloc_trim  # the C library this process runs on
    except (OSError, AttributeError):  # not glibc: nothing to call
        return None
