"""A stopping signal ends a run promptly and whole, wherever it lands; a worker that dies fails its work, never hangs.

The runs are real ``trajcomp`` processes in a process group of their own,
as a CI runner or a terminal starts them (tests/signal_runs.py); a handful
of moments here, hundreds in tests/benchmarks/bench_signals.py.
"""

import contextlib
import dataclasses
import json
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.signal_runs import STOPPING, long_program, run_stopped
from trajcomp.jobs.batch import ERROR, FileResult, _end_starting, _stopping_nanny, run_batch
from trajcomp.support.parallel import WorkerLost, Workers, in_background, map_blocks, share_blocks
from trajcomp.support.signals import Interrupted, held, raised

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups, /proc and fork")
SLACK = 4.0  # s from the signal to the end allowed here, on a loaded CI machine (the benchmark holds 2 s)


@pytest.fixture(scope="module")
def program(tmp_path_factory):
    return long_program(tmp_path_factory.mktemp("signals") / "long.csv", 4000)


def _compensate(program, kuka_model, *extra):
    return ["compensate", str(program), "--model", str(kuka_model), "-o", "long.out.csv", "--jobs", "2", *extra]


@pytest.mark.parametrize("signum, target, delay", [
    (signal.SIGTERM, "group", 0.9),  # reading and compensating: the pool's workers die with the group
    (signal.SIGINT, "group", 1.8),
    (signal.SIGHUP, "main", 1.3),
    (signal.SIGTERM, "worker", 0.0),  # the first worker the run starts, as it starts
])
def test_a_stopping_signal_ends_a_compensation_with_its_code_and_nothing_written(
        program, kuka_model, tmp_path, signum, target, delay):
    outcome = run_stopped(_compensate(program, kuka_model), tmp_path, signum, delay, target)
    assert outcome.problems(signum, lambda files: files == ["long.out.csv"], deadline=SLACK) == [], outcome


def test_a_worker_killed_by_sigkill_fails_the_run_with_exit_2_naming_it(program, kuka_model, tmp_path):
    outcome = run_stopped(_compensate(program, kuka_model), tmp_path, signal.SIGKILL, 0.0, "worker")
    assert outcome.code == 2 and "killed by SIGKILL" in outcome.stderr and "Traceback" not in outcome.stderr
    assert outcome.files == [] and outcome.left_running == []


def _batch(tmp_path, count=4, targets=1500):
    cam = tmp_path / "cam"
    cam.mkdir()
    for k in range(count):
        long_program(cam / f"p{k}.csv", targets)
    return cam


def test_a_signal_to_a_batch_group_ends_it_with_the_files_done_whole_and_no_summary(kuka_model, tmp_path):
    cam = _batch(tmp_path)
    command = ["compensate", "cam", "--model", str(kuka_model), "-o", "out", "--jobs", "2"]
    outcome = run_stopped(command, tmp_path, signal.SIGTERM, 2.5, "group")
    finished = {f"out/p{k}.csv" for k in range(4)} | {"out/summary.json"}
    assert outcome.problems(signal.SIGTERM, lambda files: set(files) == finished,
                            lambda files: set(files) < finished - {"out/summary.json"}, deadline=SLACK) == []
    for name in outcome.files:  # a program written before the signal is whole (the summary: all were, in time)
        if name.endswith(".csv"):
            assert len((tmp_path / name).read_text().splitlines()) == 1501
    assert cam.exists()


def test_a_sighup_to_a_dask_batch_group_ends_it_quietly_with_no_process_left(kuka_model, tmp_path):
    pytest.importorskip("dask.distributed")
    _batch(tmp_path, count=2, targets=4000)  # still computing at 5 s on an idle machine (1,500 were done by then)
    command = ["compensate", "cam", "--model", str(kuka_model), "-o", "out", "--jobs", "2", "--scheduler", "local"]
    outcome = run_stopped(command, tmp_path, signal.SIGHUP, 5.0, "group")  # the cluster computing
    finished = {f"out/p{k}.csv" for k in range(2)} | {"out/summary.json"}
    assert outcome.problems(signal.SIGHUP, lambda files: set(files) == finished,
                            lambda files: set(files) < finished - {"out/summary.json"}, deadline=SLACK) == []
    assert "warning" not in outcome.stderr  # neither Dask's INFO records nor its complaints on the way down


def test_a_batch_worker_killed_by_sigkill_fails_its_file_and_the_batch_writes_its_summary(kuka_model, tmp_path):
    _batch(tmp_path, count=3, targets=3000)
    command = ["compensate", "cam", "--model", str(kuka_model), "-o", "out", "--jobs", "2"]
    outcome = run_stopped(command, tmp_path, signal.SIGKILL, 0.5, "worker")  # one under way with a file
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    statuses = sorted(entry["status"] for entry in summary["files"])
    assert outcome.code == 2 and statuses.count("error") == 1 and len(statuses) == 3, outcome
    (lost,) = [entry for entry in summary["files"] if entry["status"] == "error"]
    assert "killed by SIGKILL" in lost["message"] and lost["outputs"] == []
    assert not (tmp_path / "out" / os.path.basename(lost["input"])).exists()
    assert outcome.left_running == []


def _kill_own(signum):
    def block(k):
        if k == 3:
            os.kill(os.getpid(), signum)
            time.sleep(10)
        return k
    return block


def test_a_block_whose_worker_dies_raises_worker_lost_at_once():
    start = time.monotonic()
    with pytest.raises(WorkerLost, match="killed by SIGKILL"):
        list(map_blocks(_kill_own(signal.SIGKILL), 8, 2))
    assert time.monotonic() - start < 5 and multiprocessing.active_children() == []


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_a_stopping_signal_to_one_worker_stops_this_process_as_that_signal(signum):
    with raised(), pytest.raises(Interrupted) as stop:
        list(map_blocks(_kill_own(signum), 8, 2))
        time.sleep(5)  # the signal comes back to this process
    assert stop.value.signum == signum and stop.value.exit_code == STOPPING[signum]
    assert multiprocessing.active_children() == []


def test_a_signal_to_a_worker_ending_after_its_last_block_still_stops_this_process():
    def block(k):  # the worker then lingers in its exit for 2 s, as a loaded machine lets it
        multiprocessing.util.Finalize(None, time.sleep, args=(2.0,), exitpriority=0)
        return os.getpid()

    with raised(), pytest.raises(Interrupted) as stop:
        with Workers(block, 1) as pool:
            pool.submit(0)
            worker = pool.result(0)
            threading.Timer(0.3, os.kill, (worker, signal.SIGHUP)).start()  # as the pool closes
        time.sleep(5)
    assert stop.value.signum == signal.SIGHUP


def test_a_background_worker_stopped_by_a_signal_stops_this_process_while_it_computes():
    with raised(), pytest.raises(Interrupted) as stop:
        later = in_background(lambda: _kill_own(signal.SIGTERM)(3), 2)
        time.sleep(5)  # this process computing its own part: the signal interrupts it
        later()
    assert stop.value.signum == signal.SIGTERM


def test_a_shared_blocks_helper_stopped_by_a_signal_stops_the_run(monkeypatch):
    monkeypatch.setattr("trajcomp.support.parallel.idle_cores", lambda: 1)
    helper = []

    def block(k):
        if os.getpid() != parent and not helper:
            helper.append(k)
            os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.2)
        return k

    parent = os.getpid()
    with raised(), pytest.raises(Interrupted) as stop:
        share_blocks(block, 4, 2)
    assert stop.value.signum == signal.SIGTERM


def test_a_batch_file_whose_worker_dies_is_an_error_and_the_others_are_done(tmp_path):
    def job(path, output):
        if path.name == "b":
            os.kill(os.getpid(), signal.SIGKILL)
        return FileResult(str(path), outputs=(str(output),))

    names = ["a", "b", "c", "d"]
    results = run_batch(job, [tmp_path / n for n in names], [tmp_path / "out" / n for n in names], jobs=2)
    assert [r.status for r in results] == ["pass", ERROR, "pass", "pass"]
    assert "killed by SIGKILL" in results[1].message and multiprocessing.active_children() == []


def test_a_worker_whose_parent_died_before_it_asked_to_die_with_it_ends(tmp_path):
    """The parent's pid is read before the fork: a parent that died in the gap is seen, no orphan writes."""
    marker = tmp_path / "orphan-wrote"
    script = (
        "import os, threading, time\n"
        "from trajcomp.support import parallel\n"
        "parallel.pin_loaded = lambda: time.sleep(0.5)  # widen the gap between the fork and the request\n"
        "threading.Timer(0.2, lambda: os._exit(0)).start()  # the parent dies in it\n"
        f"list(parallel.map_blocks(lambda k: open({str(marker)!r}, 'w').write('x'), 2, 2))\n"
    )
    subprocess.run([sys.executable, "-c", script], env=dict(os.environ, PYTHONPATH=os.getcwd()), timeout=60)
    time.sleep(1.5)
    assert not marker.exists()


def test_a_stopping_signal_while_matplotlib_loads_is_taken_after_it(tmp_path):
    """Raised into the initialisation of one of its C extensions, it aborted the interpreter (exit 134)."""
    script = (
        "import os, signal, sys, threading\n"
        "from trajcomp.support.signals import Interrupted, held, raised\n"
        "from trajcomp.report.plots import pyplot\n"
        "threading.Timer(float(sys.argv[1]), lambda: os.kill(os.getpid(), signal.SIGTERM)).start()\n"
        "with raised():\n"
        "    try:\n"
        "        pyplot(); import time; time.sleep(5)\n"
        "    except Interrupted as stop:\n"
        "        sys.exit(stop.exit_code)\n"
    )
    for delay in (0.02, 0.1, 0.3):
        done = subprocess.run([sys.executable, "-c", script, str(delay)], capture_output=True, text=True, timeout=60,
                              env=dict(os.environ, PYTHONPATH=os.getcwd()))
        assert done.returncode == 143 and "Fatal" not in done.stderr and "Traceback" not in done.stderr, done.stderr


@pytest.mark.parametrize("entry", ["trajcomp", "trajcomp.cli"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_the_command_lines_imports_ends_the_run_with_its_code(entry, signum):
    """The earliest moment trajcomp's code runs: a SIGINT there was a KeyboardInterrupt traceback out of an
    import (bench_signals.py's one broken run in 100), a SIGTERM a kill without a word. Sent as `trajcomp.commands`
    is imported, by the program's own entries (the console script runs ``trajcomp.__main__``)."""
    script = (
        "import os, runpy, signal, sys\n"
        "signum = int(sys.argv[2])\n"
        "class SignalOnImport:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'trajcomp.commands':\n"
        "            os.kill(os.getpid(), signum)\n"
        "sys.meta_path.insert(0, SignalOnImport())\n"
        "entry, sys.argv = sys.argv[1], ['trajcomp', 'robots']\n"
        "runpy.run_module(entry, run_name='__main__', alter_sys=True)\n"
    )
    done = subprocess.run([sys.executable, "-c", script, entry, str(int(signum))], capture_output=True, text=True,
                          timeout=60, env=dict(os.environ, PYTHONPATH=os.getcwd()))
    assert done.returncode == STOPPING[signum], done.stderr
    assert "Traceback" not in done.stderr and "what was not finished was not written" in done.stderr
    assert not done.stdout  # the command did not run


@pytest.mark.parametrize("entry", ["trajcomp", "trajcomp.cli"])
def test_a_signal_as_python_m_imports_the_package_ends_the_run_with_its_code(entry, tmp_path):
    """``python -m trajcomp[.cli]`` imports the package first: its imports (logging, the errors) are held too."""
    (tmp_path / "sitecustomize.py").write_text(
        "import os, signal, sys\n"
        "class SignalOnImport:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'trajcomp.errors':\n"
        "            os.kill(os.getpid(), signal.SIGINT)\n"
        "sys.meta_path.insert(0, SignalOnImport())\n")
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-m", entry, "robots"], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, PYTHONPATH=f"{tmp_path}{os.pathsep}{root}"))
    assert done.returncode == 130 and "Traceback" not in done.stderr, done.stderr
    assert not done.stdout


def test_a_signal_held_while_another_thread_runs_is_raised_after_the_block():
    """The kernel gives a process's signal to a thread not blocking it: the hold must not depend on the mask."""
    import threading

    other = threading.Event()
    thread = threading.Thread(target=other.wait)
    thread.start()
    reached = []
    try:
        with raised(), pytest.raises(Interrupted) as stop:
            with held():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.3)  # the handler runs here, in the main thread
                reached.append(True)
    finally:
        other.set()
        thread.join()
    assert reached and stop.value.signum == signal.SIGTERM


def test_a_stop_raised_where_python_ignores_it_is_raised_again_at_once(capsys):
    """A signal whose handler runs in a weak reference's callback (an import's module lock has one) or a
    destructor: Python printed the Interrupted as "Exception ignored" and the run went on to its next check."""
    import weakref

    class Thing:
        pass

    thing = Thing()
    reference = weakref.ref(thing, lambda ref: time.sleep(0.5))  # the signal comes during the callback
    start = time.monotonic()
    with raised(), pytest.raises(Interrupted) as stop:
        threading.Timer(0.1, os.kill, (os.getpid(), signal.SIGTERM)).start()
        del thing
        time.sleep(3)
    assert stop.value.signum == signal.SIGTERM and time.monotonic() - start < 1.5 and reference() is None
    assert "Exception ignored" not in capsys.readouterr().err


def test_a_signal_the_process_ignores_stays_ignored():
    """``nohup trajcomp ...`` ignores SIGHUP; a shell's background job, SIGINT."""
    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with raised():
            os.kill(os.getpid(), signal.SIGHUP)
            time.sleep(0.2)
    finally:
        signal.signal(signal.SIGHUP, previous)


def test_a_stop_that_became_another_exception_on_its_way_exits_with_the_signal_code(monkeypatch, capsys):
    """Raised into a C extension's initialisation, Interrupted comes out as ImportError: the run stopped all the same."""
    import trajcomp.commands.robots as robots
    from trajcomp.cli import main

    def run(args):
        try:
            os.kill(os.getpid(), signal.SIGHUP)
            time.sleep(1)
        except Interrupted as stop:
            raise ImportError("initialization failed") from stop

    monkeypatch.setattr(robots, "run", run)
    assert main(["robots"]) == 129
    assert "terminated (SIGHUP)" in capsys.readouterr().err


def test_a_background_result_never_asked_for_does_not_change_the_exit_code(tmp_path):
    """The run failed before asking for it: at exit its worker is stopped, and its death stops nothing."""
    script = (
        "import sys, time\n"
        "from trajcomp.support.parallel import in_background\n"
        "from trajcomp.support.signals import raised\n"
        "with raised():\n"
        "    later = in_background(lambda: time.sleep(30), 2)\n"
        "    time.sleep(0.3)\n"
        "sys.exit(2)\n"
    )
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, PYTHONPATH=os.getcwd()))
    assert done.returncode == 2 and time.monotonic() - start < 10, done.stderr


def _unless_hung(function, *args, seconds=120, **kwargs):
    """``function(*args, **kwargs)`` run in a thread: its value, or a failed test once it has run ``seconds`` s."""
    ended = []
    thread = threading.Thread(target=lambda: ended.append(function(*args, **kwargs)), daemon=True)
    thread.start()
    thread.join(seconds)
    assert ended, f"{function.__name__} hung"
    return ended[0]


def test_a_dask_batch_file_whose_worker_dies_each_time_is_an_error_and_the_others_are_done(tmp_path):
    """Each restart slower than Dask's lost-worker timeout, as on a loaded machine (15 s there, 10 ms here): the
    cluster closed the nannies restarting their workers, and the batch waited forever for the files left."""
    dask = pytest.importorskip("dask")
    pytest.importorskip("dask.distributed")

    def job(path, output):  # defined here: Dask sends it by value
        import os as here
        import signal as signals

        if path.name == "b":
            here.kill(here.getpid(), signals.SIGKILL)
        return FileResult(str(path), outputs=(str(output),))

    names = ["a", "b", "c"]
    with dask.config.set({"distributed.deploy.lost-worker-timeout": "10ms"}):
        results = _unless_hung(run_batch, job, [tmp_path / n for n in names], [tmp_path / "out" / n for n in names],
                               jobs=2, scheduler="local")
    assert [r.status for r in results] == ["pass", ERROR, "pass"]
    assert "Dask worker died" in results[1].message


def test_a_local_dask_cluster_left_without_workers_fails_the_files_not_done(tmp_path, monkeypatch):
    """A worker that died and whose restart failed (its nanny closed): nothing would ever run the files left."""
    pytest.importorskip("dask.distributed")
    from distributed.nanny import WorkerProcess

    start = WorkerProcess.start

    async def once(self):  # a nanny's first start of its worker process; the restart fails
        if getattr(self, "started", False):
            raise OSError("no restart here")
        self.started = True
        return await start(self)

    monkeypatch.setattr(WorkerProcess, "start", once)

    def job(path, output):
        import os as here
        import signal as signals

        if path.name == "b":
            here.kill(here.getpid(), signals.SIGKILL)
        return FileResult(str(path), outputs=(str(output),))

    names = ["a", "b", "c"]
    results = _unless_hung(run_batch, job, [tmp_path / n for n in names], [tmp_path / "out" / n for n in names],
                           jobs=1, scheduler="local")
    assert [r.status for r in results][1:] == [ERROR, ERROR] and results[0].status in ("pass", ERROR)
    assert all("no worker left" in r.message for r in results if r.status == ERROR)


def test_a_local_dask_cluster_that_failed_to_start_as_the_run_stopped_stops_it(tmp_path, monkeypatch):
    """A SIGINT to the group killed a starting worker, and the run said exit 2 'did not start' (bench_signals)."""
    pytest.importorskip("dask.distributed")

    def starting(**options):  # the signal came as the cluster started; its exception did not reach this thread
        with contextlib.suppress(Interrupted):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        raise RuntimeError("StoppingNanny failed to start.")

    monkeypatch.setattr("dask.distributed.LocalCluster", starting)
    with raised(), pytest.raises(Interrupted) as stop:
        run_batch(None, [tmp_path / "a"], [tmp_path / "out" / "a"], scheduler="local")
    assert stop.value.signum == signal.SIGINT


def test_a_process_spawned_with_sigint_blocked_is_ended_by_it_as_it_imports_trajcomp(capfd):
    """A local Dask cluster's worker starts so: a SIGINT while it started was its KeyboardInterrupt traceback (and an
    exit 1 that its nanny took for a failed start: the run's exit 2, not 130)."""
    from multiprocessing import resource_tracker

    from trajcomp.support.signals import spawned

    worker = multiprocessing.get_context("spawn").Process(target=spawned)  # its unpickling imports trajcomp

    def start():  # as the cluster's loop thread starts its workers, multiprocessing's resource tracker started
        resource_tracker.ensure_running()  # (its start unblocks SIGINT and SIGTERM in the thread starting it)
        signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGINT])
        worker.start()
        os.kill(worker.pid, signal.SIGINT)

    starter = threading.Thread(target=start)
    starter.start()
    starter.join()
    worker.join(60)
    assert worker.exitcode == -signal.SIGINT and "Traceback" not in capfd.readouterr().err


class _Nanny:
    """What a Dask nanny is to `_stopping_nanny`: its status, and what it does when its worker's process ends
    (restart it)."""

    status = dataclasses.make_dataclass("Status", ["name"])("running")

    def __init__(self):
        self.restarted = []

    def _on_worker_exit_sync(self, exitcode):
        self.restarted.append(exitcode)


def test_a_dask_worker_ended_by_a_stopping_signal_stops_the_run_and_no_worker_restarts_after():
    pytest.importorskip("dask.distributed")
    nanny = _stopping_nanny(_Nanny, [])()
    nanny._on_worker_exit_sync(-signal.SIGKILL)  # the OOM killer: restarted, the run goes on
    with raised(), pytest.raises(Interrupted) as stop:
        nanny._on_worker_exit_sync(-signal.SIGHUP)
        time.sleep(5)
    assert stop.value.signum == signal.SIGHUP and nanny.restarted == [-signal.SIGKILL]
    with raised(), pytest.raises(Interrupted):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        finally:
            nanny._on_worker_exit_sync(1)  # a worker ending as the run stops: no other started
    assert nanny.restarted == [-signal.SIGKILL]


def test_the_dask_workers_still_starting_as_the_run_stops_are_ended():
    """Left, one outlived the run and printed its own traceback, reading its start from the run gone."""
    starting, running = (subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"]) for _ in range(2))
    nannies = [SimpleNamespace(process=SimpleNamespace(status=SimpleNamespace(name=status), process=process))
               for status, process in (("starting", starting), ("running", running))]
    _end_starting(nannies)
    assert starting.wait(10) == -signal.SIGKILL and running.poll() is None
    running.kill()
    running.wait()


def test_the_resource_tracker_a_dask_batch_shares_outlives_a_sighup_to_the_group():
    code = ("import os, signal, time\n"
            "from multiprocessing import resource_tracker\n"
            "from trajcomp.jobs.batch import _start_resource_tracker\n"
            "_start_resource_tracker()\n"
            "tracker = resource_tracker._resource_tracker._pid\n"
            "os.kill(tracker, signal.SIGHUP)\n"
            "time.sleep(0.3)\n"
            "print(os.waitpid(tracker, os.WNOHANG))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2])))
    assert done.stdout.strip() == "(0, 0)", done.stderr  # still running


def test_what_a_run_killed_while_committing_leaves_hidden_the_next_run_cleans(kuka_model, tmp_path):
    """A run killed (SIGKILL, no unwinding) at each rename or link of its commit of a KRL pair and its report
    leaves hidden temporaries, backups or a journal; the next run (later: they are aged here) leaves only the set
    it writes, whole (its pair reads). A stopping signal unwinds and leaves nothing: see test_atomic. The output
    named relative to the working folder, as users name it: the strays were kept then (their folder compared
    unresolved with the resolved one)."""
    weld = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"
    for file in weld.iterdir():
        (tmp_path / file.name).write_bytes(file.read_bytes())
    arguments = ["compensate", "weld.src", "--model", str(kuka_model), "-o", "out/weld.src", "--report", "out/r.json",
                 "--retime", "none"]  # the commit is the same re-timed or not
    script = (
        "import os, signal, sys\n"
        "k, calls = int(sys.argv[1]), []\n"
        "def killing(real):\n"
        "    def call(*args, **kwargs):\n"
        "        calls.append(real)\n"
        "        if len(calls) == k and os.path.basename(str(args[-1])).startswith(('weld', 'r.', '.')):\n"
        "            os.kill(os.getpid(), signal.SIGKILL)\n"
        "        return real(*args, **kwargs)\n"
        "    return call\n"
        "os.replace, os.link, os.rename, os.unlink = map(killing, (os.replace, os.link, os.rename, os.unlink))\n"
        "from trajcomp.cli import main\n"
        "sys.exit(main(sys.argv[2:]))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    (tmp_path / "out").mkdir()
    left_hidden = 0
    for k in range(1, 13, 2):  # the k-th call: a backup's link, the journal's rename, a file's, a backup's unlink
        subprocess.run([sys.executable, "-c", script, str(k), *arguments], cwd=tmp_path, env=env, timeout=120,
                       capture_output=True)
        hidden = [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".")]
        left_hidden += bool(hidden)
        for path in hidden:
            os.utime(path, (0, 0))  # the next run comes later
        done = subprocess.run([sys.executable, "-m", "trajcomp.cli", *arguments], cwd=tmp_path, env=env,
                              timeout=120, capture_output=True, text=True)
        assert done.returncode in (0, 1), done.stderr
        assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["r.html", "r.json", "weld.dat", "weld.src"], k
        from trajcomp import formats

        assert len(formats.read(tmp_path / "out" / "weld.src").targets) == 5
    assert left_hidden >= 3  # the kills did fall inside commits
