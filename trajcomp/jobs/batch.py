"""Batch runs: many program files through one job, in parallel, a failing file never stopping the others.

A job is a picklable callable ``job(input: Path, output: Path) -> FileResult``
(e.g. `trajcomp.jobs.pipeline.CompensationJob`). `run_batch` runs it over
the files inline, in a local process pool (``jobs`` > 1) or on a Dask
distributed cluster (``scheduler``: an address, or ``"local"`` for a local
cluster), and turns every error of one file into that file's result.
`run_programs` is a whole batch as ``trajcomp compensate`` and the API run
it: the files named by paths, folders and patterns, their outputs, the
files of one task together, the summary.
"""

import atexit
import contextlib
import dataclasses
import glob
import json
import logging
import os
import signal
import threading
import time
from pathlib import Path

from trajcomp import __version__, formats
from trajcomp.support import crash
from trajcomp.support.atomic import refuse_inputs, write_atomic
from trajcomp.errors import TrajcompError
from trajcomp.support.parallel import WorkerLost, Workers, can_fork
from trajcomp.support.progress import progress
from trajcomp.support.signals import STOPPING, held, stopped

log = logging.getLogger(__name__)

PASS, FAIL, ERROR, CRASH = "pass", "fail", "error", "crash"
EXIT_CODES = {PASS: 0, FAIL: 1, ERROR: 2, CRASH: crash.EXIT_CODE}  # a crash is a bug: neither success nor bad input
SUMMARY_SCHEMA = "trajcomp-batch/1"
RESTARTS_WAITED = "1000 days"  # a local Dask cluster's lost-worker timeout: its nannies restart workers however slowly


@dataclasses.dataclass(frozen=True)
class FileResult:
    """What a job did with one file.

    Attributes
    ----------
    input : str
    outputs : tuple of str
        Files written (empty when nothing was).
    status : {"pass", "fail", "error", "crash"}
        Done; done but failing its verdict or tolerance; refused (bad input,
        nothing written); an internal error (a bug).
    message : str
        Why it failed, was refused or crashed.
    lines : tuple of str
        The run's report lines.
    """

    input: str
    outputs: tuple = ()
    status: str = PASS
    message: str = ""
    lines: tuple = ()


def expand_inputs(patterns):
    """Program files named by paths, folders and glob patterns, in order, once each.

    A folder gives its program files and those of its subfolders (hidden
    ones left out): a controller backup keeps its layout (a RAPID task's
    PROGMOD and SYSMOD, a KUKA backup's R1/Program).

    Returns
    -------
    list of (Path, PurePath)
        Each file, and where it is written under the output folder: its
        path under the folder named, else its name.

    Raises
    ------
    TrajcompError
        A pattern that matches no program file, naming it.
    """
    extensions = {e for f in formats.formats() for e in f.extensions}
    found, seen = [], set()
    for pattern in patterns:
        path = Path(pattern)
        if path.is_dir():
            matches = [(p, p.relative_to(path)) for p in sorted(path.rglob("*"))
                       if p.is_file() and p.suffix.lower() in extensions
                       and not any(part.startswith(".") for part in p.relative_to(path).parts)]
        elif is_pattern(pattern):
            matches = [(p, Path(p.name)) for p in sorted(map(Path, glob.glob(pattern)))
                       if p.is_file() and p.suffix.lower() in extensions]
        else:
            matches = [(path, Path(path.name))]
        if not matches:
            raise TrajcompError(f"{pattern}: no program file ({', '.join(sorted(extensions))})")
        found += [(p, relative) for p, relative in matches if p not in seen]
        seen.update(p for p, _ in matches)
    return found


def is_pattern(text):
    """Whether ``text`` is a glob pattern: it has ``*``, ``?`` or ``[`` and names no existing file (``prog[1].csv``)."""
    return glob.has_magic(text) and not Path(text).exists()


def output_paths(inputs, out_dir, suffix=None):
    """``out_dir / relative`` of every input (Path list), its extension replaced by ``suffix`` when given.

    Every per-program output (the program, its report under a report
    folder) lies at that relative path, so that the input folders are
    mirrored and two programs of the same name in two folders stay apart.

    Parameters
    ----------
    inputs : sequence of (Path, PurePath)
        As `expand_inputs` gives them.
    out_dir : str or Path
    suffix : str, optional
        The extension of another language written (``--to``).

    Raises
    ------
    TrajcompError
        Two inputs written to the same file (their outputs would collide,
        also when only their extensions tell them apart), or ``out_dir`` is
        a file.
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise TrajcompError(f"{out_dir}: with several programs, -o names a folder, and this is a file")
    seen, outputs = {}, []
    for path, relative in inputs:
        relative = relative.with_suffix(suffix) if suffix else relative
        key = relative.as_posix().lower()  # one file where case is not told apart (Windows, macOS, controllers)
        if key in seen:
            raise TrajcompError(f"{seen[key]} and {path} would both be written to {out_dir / relative}")
        seen[key] = path
        outputs.append(out_dir / relative)
    return outputs


def run_one(job, path, output):
    """``job(path, output)`` with every exception turned into the file's result.

    ``path`` and ``output`` are one file each, or tuples of the files of
    one task compensated together (`trajcomp.formats.task.groups`).
    """
    try:
        return job(*((tuple(map(Path, p)) if isinstance(p, tuple) else Path(p)) for p in (path, output)))
    except TrajcompError as exc:
        return FileResult(named(path), status=ERROR, message=str(exc))
    except Exception as exc:  # one file's bug must not stop the batch; it is reported as a crash
        if stopped() is not None:  # a signal's exception that became another on its way: the batch stops
            raise stopped() from exc
        return FileResult(named(path), status=CRASH, message=crash.bug_message(exc, crash.save_traceback(exc)))


def named(path):
    """A batch input for its result: a file, or the files of one task joined by ``" + "``."""
    return " + ".join(map(str, path)) if isinstance(path, tuple) else str(path)


def run_batch(job, inputs, outputs, *, jobs=1, scheduler=None, done=None):
    """Run ``job`` over the files, each result in input order.

    Parameters
    ----------
    job : callable
        Picklable ``job(input, output) -> FileResult``.
    inputs, outputs : sequence of Path
    jobs : int
        Worker processes (local pool, or local Dask cluster).
    scheduler : str, optional
        Dask scheduler address, or ``"local"`` for a local cluster of
        ``jobs`` workers; default: no Dask.
    done : callable, optional
        ``done(result)`` as each file finishes (e.g. a progress bar's update).

    A local pool's worker that dies (the OOM killer) fails its file
    (``error``) and is replaced; one stopped by SIGINT, SIGTERM or SIGHUP
    stops the batch as that signal would (`trajcomp.support.parallel.Workers`),
    as do those signals sent to this process: the files under way unwind
    (nothing half-written) and no summary is written.

    Returns
    -------
    list of FileResult
    """
    done = done or (lambda result: None)
    if scheduler is not None:
        return _on_dask(job, inputs, outputs, jobs, scheduler, done)
    if jobs <= 1 or len(inputs) <= 1 or not can_fork():
        results = (run_one(job, i, o) for i, o in zip(inputs, outputs))
        return [_reported(result, done) for result in results]
    results = []
    with Workers(lambda k: run_one(job, inputs[k], outputs[k]), min(jobs, len(inputs)), replace=True) as pool:
        for k in range(len(inputs)):
            pool.submit(k)
        for k in range(len(inputs)):
            try:
                result = pool.result(k)
            except WorkerLost as lost:  # killed (the OOM killer): this file failed, the others go on
                result = FileResult(named(inputs[k]), status=ERROR, message=f"{lost}; it was not compensated")
            results.append(_reported(result, done))
    return results


def _reported(result, done):
    done(result)
    return result


def _on_dask(job, inputs, outputs, jobs, scheduler, done):
    """`run_batch` on a Dask cluster: its scheduler's address, or ``"local"`` for a local cluster of ``jobs``
    workers.

    Each result is gathered as its file is done (kept on its worker, a
    worker that died later lost it: computed again). A local cluster's
    nanny restarts a worker that died for as long as its start takes (Dask
    closes a nanny whose worker is not back within its lost-worker timeout,
    15 s, that a loaded machine's start exceeds: then no worker was left and
    the batch waited forever); once none is left (a restart failed), the
    files not done are errors.
    """
    try:
        import dask
        from dask.distributed import Client, KilledWorker, LocalCluster, Nanny, as_completed
    except ImportError as exc:
        raise TrajcompError(
            f"--scheduler needs Dask distributed ({exc}); install it with: pip install 'trajcomp[cluster]'"
        ) from exc
    if scheduler == "local":
        _start_resource_tracker()
    cluster, nannies = None, []
    try:
        with contextlib.ExitStack() as local:
            if scheduler == "local":
                local.enter_context(dask.config.set({"distributed.deploy.lost-worker-timeout": RESTARTS_WAITED}))
                try:
                    # no dashboard; the scheduler's HTTP server (its metrics) on any free port: on Dask's 8787, a
                    # second batch at once warned on stderr that the port was taken
                    cluster = LocalCluster(n_workers=max(jobs, 1), threads_per_worker=1, dashboard_address=None,
                                           scheduler_kwargs={"dashboard_address": ":0"},
                                           worker_class=_stopping_nanny(Nanny, nannies), preload=["trajcomp"])
                except RuntimeError as exc:  # "Nanny failed to start": a worker process died as it started
                    if stopped() is not None:  # by the stopping signal that stopped the run (sent to the group)
                        raise stopped() from exc
                    raise TrajcompError(f"--scheduler local: the local Dask cluster did not start ({exc}: a worker "
                                        "process died as it started)") from exc
            with Client(cluster if cluster is not None else scheduler, timeout="20s") as client:
                futures = client.map(run_one, [job] * len(inputs), inputs, outputs, pure=False)
                where = {future.key: k for k, future in enumerate(futures)}
                results = [None] * len(futures)
                finished = as_completed(futures, with_results=True, raise_errors=False)
                while not finished.is_empty():
                    if not finished.has_ready() and cluster is not None and not _workers_coming(cluster):
                        for k in (k for k, result in enumerate(results) if result is None):
                            results[k] = FileResult(named(inputs[k]), status=ERROR,
                                                    message="the local Dask cluster has no worker left (a restart "
                                                    "failed); it was not compensated")
                            done(results[k])
                        break
                    for future, result in finished.next_batch(block=False):
                        k = where[future.key]
                        results[k] = _dask_result(result, inputs[k], KilledWorker)
                        done(results[k])
                    time.sleep(0.05)
            if cluster is not None:
                _close_local(cluster)
        return results
    except OSError as exc:
        raise TrajcompError(f"--scheduler {scheduler}: cannot reach the Dask scheduler: {exc}") from exc
    except KeyboardInterrupt:  # a stopping signal: no close of a local cluster, here or by Dask's exit function
        # (on an error, that function closes it)
        if scheduler == "local":
            from distributed.deploy.spec import close_clusters

            atexit.unregister(close_clusters)  # it would wait up to 10 s and print a traceback
            _end_starting(nannies)
        raise


def _dask_result(result, path, killed_worker):
    """A file's `FileResult` from what Dask's ``as_completed(with_results=True, raise_errors=False)`` gave for it:
    its result, or its error, ``(type, exception, traceback)`` (a cancellation: the exception alone).

    A `killed_worker` error (Dask's KilledWorker: its worker died each time
    Dask tried it, as the OOM killer does) fails this file; any other is
    raised.
    """
    if isinstance(result, FileResult):
        return result
    error = result if isinstance(result, BaseException) else result[1]
    if not isinstance(error, killed_worker):
        raise error
    return FileResult(named(path), status=ERROR,
                      message=f"its Dask worker died each time it was tried ({error}); it was not compensated")


def _workers_coming(cluster):
    """Whether a local Dask cluster has a nanny that runs its worker or restarts it (not one closed or failed)."""
    return any(nanny.status.name in ("init", "created", "starting", "running")
               for nanny in list(cluster.workers.values()))


def _stopping_nanny(nanny_base, nannies):
    """The nanny class of a local Dask cluster (a ``nanny_base``, Dask's Nanny): a stopping signal that ends one of
    its workers stops the whole run as that signal; each nanny started is appended to ``nannies``.

    SIGTERM and SIGHUP end a worker process by their default action, SIGINT
    too once trajcomp's package is imported there (it is the cluster's
    preload, if nothing imported it before; Python's own handler would print
    a KeyboardInterrupt traceback): the worker starts with SIGINT blocked
    (the nanny blocks it in the cluster's event-loop thread, whose threads
    start the processes and pass them their mask), and one that came
    meanwhile ends it then (`trajcomp.support.signals.release_in_spawned`).
    Its nanny, in the run's process, sees the worker killed by a stopping
    signal and sends it to
    the run's main thread, which stops as if it had received it; the
    worker is not restarted, nor is any started once the run stopped (a
    process started as the run ends would print its own traceback, reading
    its start from a parent gone: `_end_starting`). A worker its nanny
    ends at the batch's end stops nothing. Multiprocessing's resource
    tracker is started before (`_start_resource_tracker`): its start
    unblocks SIGINT in the thread that starts it. Defined here,
    with Dask imported.
    """
    from distributed.core import Status

    class StoppingNanny(nanny_base):
        async def start_unsafe(self):
            signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGINT])  # the cluster's loop thread: no handler there
            nannies.append(self)
            return await super().start_unsafe()

        async def instantiate(self):
            if stopped() is not None:  # the run stops: no worker is started
                return Status.failed
            return await super().instantiate()

        def _on_worker_exit_sync(self, exitcode):
            if -exitcode in STOPPING and self.status.name not in ("closing", "closing_gracefully", "closed"):
                signal.pthread_kill(threading.main_thread().ident, -exitcode)
            elif stopped() is None:
                super()._on_worker_exit_sync(exitcode)

    return StoppingNanny


def _end_starting(nannies):
    """Kill (SIGKILL) the worker processes of ``nannies`` that are still starting, as the run stops.

    Such a process has run nothing; left, it would outlive the run for a
    moment and print a traceback, reading its start from the run gone. A
    start under way whose process is not there yet is waited for, up to
    0.5 s in all (once the run stopped, no nanny begins one:
    `_stopping_nanny`).
    """
    deadline = time.monotonic() + 0.5
    while nannies and time.monotonic() < deadline:
        for nanny in list(nannies):
            worker = nanny.process
            if worker is None or worker.status.name not in ("init", "starting"):
                nannies.remove(nanny)
            elif worker.process is not None and worker.process.pid is not None:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(worker.process.pid, signal.SIGKILL)
                nannies.remove(nanny)
        time.sleep(0.01)


def _start_resource_tracker():
    """Start multiprocessing's resource tracker, which a local Dask cluster's processes share, deaf to the stopping
    signals.

    It ignores SIGINT and SIGTERM itself, not SIGHUP: killed by a SIGHUP to
    the process group, a new one is started for the next semaphore, which
    prints a KeyError traceback for each semaphore released that it never
    saw, and outlives the run. Started here with the signals held
    (`trajcomp.support.signals.held`), it keeps them blocked for good (a
    signal mask is inherited); a signal to this process meanwhile is raised
    after. It ends when the last process of the run closes its pipe. It
    cleans up the semaphores of a run a signal stopped without saying so
    (its "leaked semaphore objects" warning, given to it as a ``-W`` option:
    the run reports the stop).
    """
    import sys
    from multiprocessing import resource_tracker

    quiet = "ignore::UserWarning:multiprocessing.resource_tracker"
    sys.warnoptions.append(quiet)  # the tracker is started with this process's -W options
    try:
        with held():
            resource_tracker.ensure_running()
    finally:
        sys.warnoptions.remove(quiet)


def _close_local(cluster):
    """Close a local Dask cluster whose work is done; a failure of Dask's own clean-up is logged, not raised.

    A nanny still restarting a worker that died (the OOM killer) can fail
    the close ("can only join a started process"): the results are in by
    then, and the processes go with the cluster. A run that a stopping
    signal stopped does not close it (a second or more): its worker
    processes end when this one does (they watch a pipe from it).
    """
    try:
        cluster.close()
    except (AssertionError, RuntimeError, OSError, TimeoutError) as exc:
        log.warning("the local Dask cluster did not close cleanly (%s); its results are complete", exc)


def result_line(result):
    """A file's line in the batch's list: ``PASS  a/weld.src``, ``ERROR a/bad.csv:3: x: not a number``.

    A message that starts by naming the file (by its name, as a reader names
    it) names it by its path in the batch instead of repeating it.
    """
    name = Path(result.input.split(" + ")[0]).name
    message = result.message
    if message.startswith(f"{result.input}:"):
        return f"{result.status.upper():5} {message}"
    if message.startswith(f"{name}:") and " + " not in result.input:
        return f"{result.status.upper():5} {result.input}{message[len(name):]}"
    return f"{result.status.upper():5} {result.input}" + (f": {message}" if message else "")


def exit_code(results):
    """The batch's exit code: the worst of its files' (crash 3, error 2, fail 1, pass 0)."""
    return max((EXIT_CODES[r.status] for r in results), default=0)


def write_summary(path, results, **context):
    """Write the batch summary JSON (schema ``trajcomp-batch/1``) atomically.

    ``context`` (model, mode, options) is recorded as given.
    """
    counts = {status: sum(r.status == status for r in results) for status in EXIT_CODES}
    document = {
        "schema": SUMMARY_SCHEMA,
        "trajcomp": __version__,
        **context,
        "exit_code": exit_code(results),
        "counts": counts,
        "files": [
            {"input": r.input, "outputs": list(r.outputs), "status": r.status, "message": r.message}
            for r in results
        ],
    }
    write_atomic(path, json.dumps(document, indent=2) + "\n")


def run_programs(job, programs, out_dir, *, to_format=None, in_place=False, models=(), report=None, summary=None,
                 jobs=1, scheduler=None, show_progress=False, **context):
    """Run ``job`` over the program files named by ``programs``, each into ``out_dir``, and write the summary.

    The batch of ``trajcomp compensate`` and of `trajcomp.api.filter_programs`.
    The inputs are expanded (`expand_inputs`) and mirrored under ``out_dir``
    (`output_paths`); an output that would replace an input (unless
    ``in_place``) or a model file is refused, and so is a summary that would
    replace any of them; the files of one task that share points run as one
    program (`trajcomp.formats.task.groups`; not when converting); folders
    made for files that were not written are removed.

    Parameters
    ----------
    job : callable
        ``job(input, output) -> FileResult``, picklable for ``jobs`` > 1.
    programs : sequence of str or Path
        Files, folders or glob patterns.
    out_dir : str or Path
        The folder written into.
    to_format : str, optional
        The language written (its first extension replaces the inputs').
    in_place : bool
        Allow an output to replace its input.
    models : sequence of Path
        The model's files: never replaced.
    report : str or Path, optional
        The folder of the per-program reports (mirrored as the outputs are).
    summary : str or Path, optional
        The summary JSON; default ``out_dir / "summary.json"``.
    jobs, scheduler
        As `run_batch`.
    show_progress : bool
        A bar over the files on a terminal.
    **context
        Recorded in the summary (`write_summary`).

    Returns
    -------
    results : list of FileResult
        In input order, a task's files as one.
    summary : Path
        The summary written.
    """
    from trajcomp.formats.task import groups as task_groups

    found = expand_inputs(programs)
    suffix = formats.find_format(format=to_format).extensions[0] if to_format else None
    outputs = output_paths(found, out_dir, suffix)
    inputs = [path for path, _ in found]
    summary = Path(summary) if summary else Path(out_dir) / "summary.json"
    refuse_inputs(outputs, [*([] if in_place else inputs), *models],
                  "give -o another folder than the programs' (or --in-place to replace them)")
    refuse_inputs([summary], [*inputs, *models, *outputs], "give --summary another name")
    reports = [Path(report) / path.relative_to(out_dir) for path in outputs] if report else []
    made = make_folders(dict.fromkeys(path.parent for path in [*outputs, *reports]))  # a backup's layout is kept
    try:
        # the files of one task that share points run as one program (a shared point corrected once)
        tasks = task_groups(inputs) if not to_format else [[k] for k in range(len(inputs))]
        inputs = [inputs[g[0]] if len(g) == 1 else tuple(inputs[k] for k in g) for g in tasks]
        outputs = [outputs[g[0]] if len(g) == 1 else tuple(outputs[k] for k in g) for g in tasks]
        with progress(len(inputs), desc="compensate", unit="file", enabled=show_progress) as bar:
            results = run_batch(job, inputs, outputs, jobs=jobs, scheduler=scheduler,
                                done=lambda result: bar.update(1))
        write_summary(summary, results, **context, jobs=jobs, scheduler=scheduler)
    finally:
        remove_empty(made)  # the folders of refused files (or of all, when stopped before the summary)
    return results, summary


def make_folders(folders):
    """Make the folders (Paths) that do not exist, parents first; the ones made, deepest first."""
    made = []
    for folder in folders:
        missing = [p for p in (folder, *folder.parents) if not p.exists()]
        folder.mkdir(parents=True, exist_ok=True)
        made += missing
    return sorted(set(made), key=lambda p: len(p.parts), reverse=True)


def remove_empty(folders):
    """Remove those of the folders (deepest first) left empty: a batch leaves no folder for a file it refused."""
    for folder in folders:
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
