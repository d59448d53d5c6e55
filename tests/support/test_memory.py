"""Freed heap memory handed back to the operating system (glibc's malloc_trim)."""

import ctypes

import numpy as np
import pytest

from trajcomp.support.memory import release


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


def test_collection_is_paused_within_the_block_and_as_it_was_after():
    import gc

    from trajcomp.support.memory import collection_paused

    assert gc.isenabled()
    with collection_paused():
        assert not gc.isenabled()
        with collection_paused():
            assert not gc.isenabled()
        assert not gc.isenabled()  # the outer block still pauses it
    assert gc.isenabled()
    with pytest.raises(ValueError), collection_paused():
        raise ValueError
    assert gc.isenabled()


def test_a_compensate_run_leaves_nothing_out_of_the_collectors_scans(tmp_path, kuka_model, monkeypatch):
    """Its stages freeze what they leave (gc.freeze); a process serving many runs gets it all back after each."""
    import gc
    import shutil
    from pathlib import Path

    from trajcomp.support import memory
    from trajcomp.cli import main

    frozen = []

    def end_stage():
        memory.end_stage()
        frozen.append(gc.get_freeze_count())

    monkeypatch.setattr("trajcomp.jobs.pipeline.end_stage", end_stage)
    kuka = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"
    for name in ("weld.src", "weld.dat"):
        shutil.copy(kuka / name, tmp_path / name)
    assert main(["compensate", str(tmp_path / "weld.src"), "--model", str(kuka_model),
                 "-o", str(tmp_path / "out.src")]) == 0
    assert len(frozen) == 5 and min(frozen) > 0  # each stage left its objects out of the scans
    assert gc.get_freeze_count() == 0  # and the run gave them back
