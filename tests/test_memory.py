"""Freed heap memory handed back to the operating system (glibc's malloc_trim)."""

import ctypes

import numpy as np
import pytest

from trajcomp.memory import release


def resident_mb():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4096 / 2**20


def glibc():
    try:
        return hasattr(ctypes.CDLL(None), "malloc_trim")
    except OSError:
        return False


@pytest.mark.skipif(not glibc(), reason="needs glibc's malloc_trim and Linux /proc")
def test_memory_freed_between_live_blocks_leaves_the_process():
    big = np.ones(2 * 2**20)
    del big  # a freed 16 MB block raises glibc's mmap threshold: 1 MB blocks now come from the heap
    blocks = [np.ones(2**17) for _ in range(300)]
    kept = blocks[::10]  # alive between the freed ones: the heap cannot shrink from its top
    del blocks
    before = resident_mb()
    release()
    assert before - resident_mb() > 150  # of the 270 MB freed
    assert all(block[0] == 1.0 for block in kept)


def test_release_is_harmless_when_nothing_is_free():
    release()
    release()
