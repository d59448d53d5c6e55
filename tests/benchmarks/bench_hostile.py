"""The hostile model, robot, measurement and layout corpus of issue 26, each case in a process of its own.

Runs every case of tests/hostile_corpus.py (``PER_KIND`` random mutations
per file and operator family, 40 by default, the hand-made cases, and giant
files of ``GIANT`` MB) through every command that reads its kind of file:
each case in a child forked from this process (trajcomp already imported,
as a command's process has it), its peak memory that child's (``wait4``),
its address space capped at 4 GB so that a runaway fails instead of taking
the machine down, killed after 120 s. Prints per kind: cases, command runs,
refused (exit 2), accepted (exit 0 or 1), broken (any other exit, a refusal
not naming the file, an expected refusal missing: `hostile_corpus.violations`),
the slowest command (s) and the largest peak memory (MB), with the cases
that reached them; then every broken case and every case over 5 s or 500 MB.
Targets: 0 broken, every case within 5 s and 500 MB.

    PYTHONPATH=$PWD python tests/benchmarks/bench_hostile.py [PER_KIND [GIANT]]
"""

import os
import pickle
import resource
import signal
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hostile_corpus import KINDS, build_base, cases, run, violations  # noqa: E402

TIMEOUT = 120.0  # s, a child still running is killed and counted broken
ADDRESS_SPACE = 4 << 30  # bytes a child may map
SECONDS, MEGABYTES = 5.0, 500.0  # the bounds per case


def in_child(case, base, folder):
    """Fork a child running ``case``; ``(outcomes or None, seconds, peak MB, status)`` once it ends."""
    read, write = os.pipe()
    start = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child: run, send the outcomes, leave without cleanup
        os.close(read)
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
        try:
            payload = pickle.dumps(run(case, base, folder))
        except BaseException as exc:  # noqa: BLE001 - the runner itself failed: report it
            payload = pickle.dumps(repr(exc))
        with os.fdopen(write, "wb") as handle:
            handle.write(payload)
        os._exit(0)
    os.close(write)
    chunks = []
    with os.fdopen(read, "rb") as handle:
        os.set_blocking(handle.fileno(), False)
        while True:
            done, status, usage = os.wait4(pid, os.WNOHANG)
            try:
                chunk = handle.read()
            except BlockingIOError:
                chunk = None
            if chunk:
                chunks.append(chunk)
            if done:
                break
            if time.perf_counter() - start > TIMEOUT:
                os.kill(pid, signal.SIGKILL)
            time.sleep(0.01)
        rest = handle.read()
        if rest:
            chunks.append(rest)
    seconds = time.perf_counter() - start
    data = b"".join(chunks)
    outcomes = pickle.loads(data) if data else None
    return outcomes, seconds, usage.ru_maxrss / 1024, status


def main(per_kind, giant):
    rows = {kind: {"cases": 0, "runs": 0, "refused": 0, "accepted": 0, "broken": 0, "slowest": (0.0, ""),
                   "peak": (0.0, "")} for kind in KINDS}
    broken, over = [], []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        base = build_base(folder / "base")
        for k, case in enumerate(cases(base, per_kind=per_kind, giant=giant)):
            row = rows[case.kind]
            where = folder / f"case{k}"
            outcomes, seconds, peak, status = in_child(case, base, where)
            row["cases"] += 1
            label = f"{case.kind}: {case.name}"
            if not isinstance(outcomes, list):
                row["broken"] += 1
                broken.append(f"{label}: the child ended with status {status} ({outcomes or 'no outcome'})")
                continue
            slowest = max(outcomes, key=lambda o: o.seconds)
            row["runs"] += len(outcomes)
            row["refused"] += sum(o.code == 2 for o in outcomes)
            row["accepted"] += sum(o.code in (0, 1) for o in outcomes)
            found = violations(case, outcomes, where)
            row["broken"] += bool(found)
            broken += [f"{label}: {line}" for line in found]
            if slowest.seconds > row["slowest"][0]:
                row["slowest"] = (slowest.seconds, f"{label} ({slowest.argv[0]})")
            if peak > row["peak"][0]:
                row["peak"] = (peak, label)
            if slowest.seconds > SECONDS or peak > MEGABYTES:
                over.append(f"{label}: {slowest.argv[0]} {slowest.seconds:.1f} s, peak {peak:.0f} MB")
    print(f"{'kind':13} {'cases':>6} {'runs':>6} {'refused':>8} {'accepted':>9} {'broken':>7} {'slowest s':>10} "
          f"{'peak MB':>8}")
    for kind, row in rows.items():
        print(f"{kind:13} {row['cases']:6d} {row['runs']:6d} {row['refused']:8d} {row['accepted']:9d} "
              f"{row['broken']:7d} {row['slowest'][0]:10.2f} {row['peak'][0]:8.0f}")
    for kind, row in rows.items():
        print(f"  {kind}: slowest {row['slowest'][1]}; largest {row['peak'][1]}")
    for line in broken:
        print("BROKEN", line)
    for line in over:
        print(f"OVER {SECONDS:g} s / {MEGABYTES:g} MB", line)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40, int(sys.argv[2]) if len(sys.argv) > 2 else 100)
