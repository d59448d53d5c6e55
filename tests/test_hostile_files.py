"""Hostile model, robot, measurement and layout files through every command that reads them: refused or accepted,
never a crash.

The corpus is tests/hostile_corpus.py's. Each test runs the hand-made cases
of one kind of file (every one that must be refused states the refusal
expected) and a seeded sample of the random mutations through each command
that reads that kind, in this process; calibrate and retime run only where
the case expects a refusal (on a file they accept they take seconds).
tests/benchmarks/bench_hostile.py runs all of it, each case in a process of
its own, with its time and peak memory.
"""

import pytest

from hostile_corpus import KINDS, build_base, cases, run, violations

MUTATIONS = 2  # random mutations per file and operator family in the suite (the benchmark runs 40)
SLOW = ("calibrate", "retime")  # seconds each on a file they accept


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return build_base(tmp_path_factory.mktemp("hostile-base"))


@pytest.mark.parametrize("kind", KINDS)
def test_hostile_files_are_refused_naming_the_file_or_accepted_never_a_crash(kind, base, tmp_path):
    broken, count = [], 0
    for k, case in enumerate(c for c in cases(base, per_kind=MUTATIONS) if c.kind == kind):
        folder = tmp_path / f"case{k}"
        skip = () if case.refusal else SLOW
        for line in violations(case, run(case, base, folder, skip=skip), folder):
            broken.append(f"{case.name}: {line}")
        count += 1
    assert count > 20
    assert not broken, f"{len(broken)} of {count} {kind} cases broke the contract:\n" + "\n".join(broken)
