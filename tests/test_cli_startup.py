"""Start-up: a sub-command's ``--help`` builds its parser without loading numpy or the library behind it.

Wall time is what the user feels (tests/benchmarks/bench_startup.py prints it
per command; issue 25's bound is 0.15 s), but on a shared machine it is no
assertion; what makes it is: the parsers take their choices and defaults
from the option modules (`trajcomp.timing.options`, `trajcomp.compensation.options`,
`trajcomp.model.options`, `trajcomp.calibration.options`, `trajcomp.calibration.profiles`)
and the format registry, and the command modules import the rest when they run.
"""

import json
import subprocess
import sys

from trajcomp.commands import COMMANDS

HEAVY = ("numpy", "scipy", "ruckig", "matplotlib", "yaml")  # what a run needs and a --help does not
PROBE = """
import json, sys
from trajcomp.cli import main
loaded = {}
for name in sys.argv[1:]:
    try:
        main([name, "--help"])
    except SystemExit:
        pass
    loaded[name] = sorted(m for m in sys.modules if m.split(".")[0] in %r)
print(json.dumps(loaded))
""" % (HEAVY,)


def test_no_subcommands_help_imports_numpy_or_the_library_behind_it():
    """Each command's --help in turn, in one process: the heavy modules loaded after each (none)."""
    done = subprocess.run([sys.executable, "-c", PROBE, *COMMANDS], capture_output=True, text=True, check=True)
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert loaded == {name: [] for name in COMMANDS}
    for name in COMMANDS:
        assert f"usage: trajcomp {name}" in done.stdout

