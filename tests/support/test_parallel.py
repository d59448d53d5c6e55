"""Blocks on several cores: the same results in the same order as one process, errors named as there."""

import multiprocessing
import os

import numpy as np
import pytest

import trajcomp.compensation.target_correction as compensation
import trajcomp.compensation.posture as posture
from trajcomp import formats
from trajcomp.compensation.target_correction import compensate
from trajcomp.errors import IKError
from trajcomp.support import parallel
from trajcomp.support.parallel import in_background, map_blocks, meanwhile, share_blocks, usable_cores
from trajcomp.compensation.posture import planned_joints
from trajcomp.arm.robot import load_robot
from tests.compensation.test_compensate import cell, targets_in_cube  # noqa: F401 (fixture)

pytestmark = pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="needs fork")


def test_blocks_come_back_in_order_with_the_serial_values():
    data = np.random.default_rng(0).normal(size=(50, 3))  # read by the workers from the caller's memory
    serial = list(map_blocks(lambda k: (k, data[k].sum()), 50, 1))
    for workers in (2, 3):
        assert list(map_blocks(lambda k: (k, data[k].sum()), 50, workers)) == serial
    assert [k for k, _ in serial] == list(range(50))


def test_work_meanwhile_runs_here_once_while_the_workers_compute():
    import time

    busy = []

    def work():
        start = time.monotonic()
        time.sleep(1.0)
        busy.append((os.getpid(), start, time.monotonic()))

    with meanwhile(work):
        results = list(map_blocks(lambda k: (k, os.getpid(), time.sleep(0.05) or time.monotonic()), 6, 2))
        assert list(map_blocks(lambda k: k, 3, 2)) == [0, 1, 2]  # a second pool: the work is done
    ((pid, start, end),) = busy
    assert pid == os.getpid() and [k for k, *_ in results] == list(range(6))
    assert all(worker != pid for _, worker, _ in results)
    assert all(start < finished < end for *_, finished in results)  # every block computed while this one worked


def test_work_meanwhile_is_dropped_where_no_pool_starts():
    ran = []
    with meanwhile(lambda: ran.append(1)):
        assert list(map_blocks(lambda k: k, 3, 1)) == [0, 1, 2]  # one process: the blocks run here, in turn
        assert list(map_blocks(lambda k: k, 1, 2)) == [0]  # one block: no pool either
    assert list(map_blocks(lambda k: k, 3, 2)) == [0, 1, 2]  # after the block
    assert ran == []


def test_blocks_run_in_other_processes_only_when_asked():
    assert set(map_blocks(lambda k: os.getpid(), 6, 1)) == {os.getpid()}
    assert os.getpid() not in set(map_blocks(lambda k: os.getpid(), 6, 2))
    assert list(map_blocks(lambda k: os.getpid(), 1, 4)) == [os.getpid()]  # one block: no process started
    assert list(map_blocks(lambda k: k, 0, 2)) == []


def test_an_error_in_a_block_is_raised_with_its_message():
    def block(k):
        if k == 5:
            raise IKError(f"block {k}: target unreachable")
        return k

    results = map_blocks(block, 9, 2)
    assert [next(results) for _ in range(5)] == [0, 1, 2, 3, 4]
    with pytest.raises(IKError, match="block 5: target unreachable"):
        next(results)


def _pids_of_blocks(_):
    return sorted(set(map_blocks(lambda k: os.getpid(), 4, 2))), os.getpid()


def test_a_pool_worker_computes_its_blocks_itself():
    """A daemonic worker cannot start processes: its blocks run inline instead of failing."""
    with multiprocessing.get_context("fork").Pool(1) as pool:
        pids, worker = pool.map(_pids_of_blocks, [0])[0]
    assert pids == [worker]


def test_usable_cores_is_this_process_affinity():
    assert usable_cores() == len(os.sched_getaffinity(0)) >= 1


def test_compensation_on_two_processes_equals_one(cell, monkeypatch):  # noqa: F811
    monkeypatch.setattr(compensation, "CHUNK", 16)
    targets = targets_in_cube(cell.robot, 100, 4)
    one, two = compensate(cell.model, targets, workers=1), compensate(cell.model, targets, workers=2)
    for name in ("T_command", "q", "correction", "residual", "outside"):
        np.testing.assert_array_equal(getattr(two, name), getattr(one, name))


def test_compensation_failure_on_two_processes_names_targets_as_one(cell, monkeypatch):  # noqa: F811
    targets = targets_in_cube(cell.robot, 30, 2)
    targets[[12, 23], :3, 3] = [[3000.0, 0.0, 500.0], [0.0, -2500.0, 900.0]]
    names = [f"prog.csv line {k + 2}" for k in range(30)]
    with pytest.raises(IKError) as one:
        compensate(cell.model, targets, label="prog.csv", names=names)
    monkeypatch.setattr(compensation, "CHUNK", 6)
    with pytest.raises(IKError) as two:
        compensate(cell.model, targets, label="prog.csv", names=names, workers=2)
    assert str(two.value) == str(one.value)


def test_posture_plan_on_two_processes_equals_one(tmp_path, monkeypatch):
    """Undeclared runs chained across blocks, and declared joints, give the same plan on two processes."""
    monkeypatch.setattr(posture, "BLOCK", 7)
    t = np.linspace(0.0, 4.0 * np.pi, 60)
    rows = [f"{550 + 80 * np.cos(a):.3f},{150 + 80 * np.sin(a):.3f},{550 + 5 * a:.3f},0,90,0,LIN,50,1,,,,,,"
            for a in t]
    rows[30] = "600,100,600,0,90,0,PTP,50,,0,-90,90,-90,-90,0"  # a declared posture in the middle
    program = tmp_path / "helix.csv"
    program.write_text("x,y,z,a,b,c,motion,speed,zone,j1,j2,j3,j4,j5,j6\n" + "\n".join(rows) + "\n")
    read = formats.read(program)
    robot = load_robot("ur10")
    one, two = planned_joints(read, robot, workers=1), planned_joints(read, robot, workers=2)
    np.testing.assert_array_equal(two.q, one.q)
    assert two.source == one.source and one.source[30] == "joints" and one.source[0] == "home"


def test_an_unreachable_target_stops_the_plan_alike_and_leaves_no_worker(tmp_path, monkeypatch):
    monkeypatch.setattr(posture, "BLOCK", 7)
    rows = [f"{550 + k:.3f},150,550,0,90,0,LIN,50,1" for k in range(40)]
    rows[25] = "5000,150,550,0,90,0,LIN,50,1"  # out of reach, in the fourth block
    program = tmp_path / "far.csv"
    program.write_text("x,y,z,a,b,c,motion,speed,zone\n" + "\n".join(rows) + "\n")
    read, robot = formats.read(program), load_robot("ur10")
    messages = []
    for workers in (1, 2):
        with pytest.raises(IKError, match="cannot reach") as error:
            planned_joints(read, robot, workers=workers)
        messages.append(str(error.value))
        assert multiprocessing.active_children() == []
    assert messages[0] == messages[1] and "far.csv:27" in messages[0]


def test_a_background_result_comes_from_another_process_only_when_asked_for_one():
    data = np.arange(10.0)
    later = in_background(lambda: (os.getpid(), data.sum()), 2)
    pid, total = later()
    assert pid != os.getpid() and total == 45.0 and multiprocessing.active_children() == []
    assert in_background(lambda: os.getpid(), 1)() == os.getpid()

    def fails():
        raise IKError("before: unreachable")

    with pytest.raises(IKError, match="before: unreachable"):
        in_background(fails, 2)()
    with pytest.raises(IKError, match="before: unreachable"):
        in_background(fails, 1)  # computed at once in this process


def test_pool_workers_die_with_their_parent_even_when_it_is_killed(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    script = (
        "import os, time\n"
        "from concurrent.futures import ProcessPoolExecutor\n"
        "from trajcomp.support.parallel import init_worker\n"
        "pool = ProcessPoolExecutor(2, initializer=init_worker)\n"
        "print(pool.submit(os.getpid).result(), flush=True)\n"
        "pool.submit(time.sleep, 60); pool.submit(time.sleep, 60)\n"
        "time.sleep(60)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    worker = int(parent.stdout.readline())
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and _alive(worker):
        time.sleep(0.05)
    assert not _alive(worker)


def _alive(pid):
    """Whether process ``pid`` runs (a zombie, dead but not yet reaped, does not count)."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.parametrize("user_setting, threads", [(None, 1), ("2", 2)])
def test_workers_forked_from_an_application_compute_on_one_blas_thread_unless_the_user_says(user_setting, threads):
    """An application (no thread variables) loaded numpy with two BLAS threads: each worker computes on one."""
    import subprocess
    import sys

    code = ("import numpy, threadpoolctl\nthreadpoolctl.threadpool_limits(2)\n"
            "from trajcomp.support.parallel import map_blocks\n"
            "print(sorted({p['num_threads'] for k in map_blocks(lambda k: threadpoolctl.threadpool_info(), 2, 2)"
            " for p in k if p['user_api'] == 'blas'}))")
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                             "MKL_NUM_THREADS")}
    if user_setting is not None:
        env.update(OPENBLAS_NUM_THREADS=user_setting)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert done.stdout.strip() == str([threads])


def test_shared_blocks_come_back_in_order_computed_here_and_in_a_helper(monkeypatch):
    import time

    monkeypatch.setattr(parallel, "idle_cores", lambda: 1)  # whatever else runs on the machine now

    data = np.random.default_rng(1).normal(size=(8, 3))
    serial = share_blocks(lambda k: (k, data[k].sum(), os.getpid()), 8, 1)
    assert [(k, total) for k, total, _ in serial] == [(k, data[k].sum()) for k in range(8)]
    assert {pid for *_, pid in serial} == {os.getpid()}
    shared = share_blocks(lambda k: (k, data[k].sum(), time.sleep(0.05) or os.getpid()), 8, 2)
    assert [(k, total) for k, total, _ in shared] == [(k, data[k].sum()) for k in range(8)]
    assert len({pid for *_, pid in shared}) == 2 and os.getpid() in {pid for *_, pid in shared}  # both took blocks
    assert share_blocks(lambda k: os.getpid(), 1, 4) == [os.getpid()]  # one block: no helper started
    assert share_blocks(lambda k: k, 0, 2) == []


def test_shared_blocks_raise_the_first_failing_block_error_and_stop_taking_blocks(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "idle_cores", lambda: 1)
    def block(k):
        tmp_path.joinpath(str(k)).touch()  # the blocks begun, in whichever process
        if k in (3, 5):
            raise IKError(f"block {k}: target unreachable")
        return k

    with pytest.raises(IKError, match="block 3: target unreachable"):
        share_blocks(block, 40, 2)
    assert len(list(tmp_path.iterdir())) < 10  # the processes stopped taking blocks after the failure


def test_shared_blocks_go_on_here_while_a_helper_gets_no_cpu(monkeypatch):
    import signal
    import threading
    import time

    monkeypatch.setattr(parallel, "idle_cores", lambda: 1)

    parent = os.getpid()

    def block(k):
        if os.getpid() != parent:
            os.kill(os.getpid(), signal.SIGSTOP)  # a helper the machine does not run (until resumed below)
        time.sleep(0.01)
        return k, os.getpid()

    def resume():
        for process in multiprocessing.active_children():
            os.kill(process.pid, signal.SIGCONT)

    timer = threading.Timer(1.0, resume)
    timer.start()
    results = share_blocks(block, 40, 2)
    timer.join()
    assert [k for k, _ in results] == list(range(40))
    assert sum(pid == parent for _, pid in results) >= 39  # the helper's one block waited for it, no other


def test_shared_blocks_start_helpers_on_idle_cores_only(monkeypatch):
    monkeypatch.setattr(parallel, "idle_cores", lambda: 0)
    assert set(share_blocks(lambda k: os.getpid(), 6, 2)) == {os.getpid()}
    monkeypatch.setattr(parallel, "idle_cores", lambda: 1)
    assert len(set(share_blocks(lambda k: __import__("time").sleep(0.05) or os.getpid(), 6, 4))) == 2  # one helper


def test_idle_cores_counts_the_runnable_processes(monkeypatch, tmp_path):
    loadavg = tmp_path / "loadavg"
    monkeypatch.setattr(parallel, "_LOADAVG", str(loadavg))
    monkeypatch.setattr(parallel, "usable_cores", lambda: 4)
    loadavg.write_text("0.50 0.40 0.30 3/200 999\n")  # this process and two others
    assert parallel.idle_cores() == 1
    loadavg.write_text("9.50 9.40 9.30 9/200 999\n")
    assert parallel.idle_cores() == 0
    monkeypatch.setattr(parallel, "_LOADAVG", str(tmp_path / "absent"))  # not Linux: every other core
    assert parallel.idle_cores() == 3
