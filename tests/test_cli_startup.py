"""Start-up: a sub-command's ``--help`` builds its parser without loading numpy or the library behind it.

Wall time is what the user feels (tests/benchmarks/bench_startup.py prints it
per command; issue 25's bound is 0.15 s), but on a shared machine it is no
assertion; what makes it is: the parsers take their choices and defaults
from the option modules (`trajcomp.timing.options`, `trajcomp.compensation.options`,
`trajcomp.model.options`, `trajcomp.calibration.options`, `trajcomp.calibration.profiles`)
and the format registry (without importing a plugin), and the command modules import the rest when they run.
"""

import json
import subprocess
import sys

import pytest
from conftest import install_plugin

from trajcomp import formats
from trajcomp.formats.capabilities import SpeedFields, Vendor
from trajcomp.cli import main
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


def test_the_help_names_the_registrys_languages_and_imports_no_plugin(monkeypatch, tmp_path, capsys):
    """A language registered as a folder registers it is in the help texts at once; a plugin is not imported."""
    (tmp_path / "heavy_plugin.py").write_text("raise RuntimeError('a help text imported the plugin')\n")
    install_plugin(monkeypatch, tmp_path, "heavy", "heavy_plugin")  # also restores the registry afterwards
    formats.register_format("sixth", [".six", ".sx"], "sixth.reader:read", "sixth.writer:write", Vendor("Maker"),
                            SpeedFields("sixth.speeds:write_speeds", "TIME="))
    shown = {}
    for name in ("compensate", "convert", "retime"):
        with pytest.raises(SystemExit):
            main([name, "--help"])
        shown[name] = " ".join(capsys.readouterr().out.split())
    assert "Languages: csv (.csv), fanuc_ls (FANUC .ls), krl (KUKA .src)" in shown["compensate"]
    for name in ("compensate", "convert"):
        assert "sixth (Maker .six .sx), urscript (Universal Robots .script .urscript), and the plugins'" in shown[name]
    assert "--to FORMAT write the corrected program in this language instead (csv, fanuc_ls, krl, rapid, sixth, " \
        "urscript or a plugin's)" in shown["compensate"]
    assert "configuration data (in fanuc_ls, krl, rapid) are computed" in shown["convert"]  # sixth declares none
    assert ("(csv (the t column), fanuc_ls (msec, sec, mm/sec), krl ($VEL.CP, BAS(#VEL_PTP, %)), rapid (\\T, \\V of "
            "the speeddata), sixth (TIME=), urscript (t=, v=), and plugins that declare them)") in shown["retime"]
    assert not formats._PLUGINS["loaded"] and "heavy_plugin" not in sys.modules
