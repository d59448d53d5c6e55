"""The floor plan: each wing imports only the wings below it.

Read from the source (every ``import`` and ``from ... import`` statement,
lazy ones inside functions included), not from what happens to be loaded.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "trajcomp"
# wing (a folder, or a module at the top): the wings (and top-level modules) it may import besides itself, errors
# and support
BELOW = {
    "support": set(),
    "arm": set(),
    "programs": {"arm"},
    "formats": {"arm", "programs"},
    "model": {"arm"},
    "timing": {"arm", "programs", "formats"},
    "report": {"arm", "model"},
    "compensation": {"arm", "programs", "formats", "model", "timing", "report"},
    "calibration": {"arm", "model"},
    "jobs": {"arm", "programs", "formats", "model", "timing", "compensation", "report"},
    "paper_protocol": {"arm", "programs", "formats", "model", "compensation", "calibration", "jobs"},
    "api": {"arm", "programs", "formats", "model", "timing", "compensation", "report", "jobs"},
    "commands": {"arm", "programs", "formats", "model", "timing", "compensation", "report", "calibration", "jobs",
                 "paper_protocol"},
    "cli": {"commands"},
}
# a module that sits higher than its wing: the calibration and validation reports read a calibration's run
ABOVE_ITS_WING = {"report/calibration.py": {"calibration"}}
ALWAYS = {"errors", "support", "__init__"}


def _imported_wings(path):
    """The first names below ``trajcomp`` of every module ``path`` imports (set of str): a wing, a top-level
    module, or ``__init__`` for a name of the package itself."""
    wings = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            parts = node.module.split(".")
            if parts[0] == "trajcomp" and len(parts) > 1:
                wings.add(parts[1])
            elif parts[0] == "trajcomp":
                wings |= {a.name if _is_module(a.name) else "__init__" for a in node.names}
        elif isinstance(node, ast.Import):
            wings |= {a.name.split(".")[1] for a in node.names if a.name.startswith("trajcomp.")}
    return wings


def _is_module(name):
    """Whether ``trajcomp.<name>`` is a wing or a top-level module."""
    return (PACKAGE / name / "__init__.py").exists() or (PACKAGE / f"{name}.py").exists()


def _imported_modules(path, lazy):
    """The dotted names of the modules ``path`` imports (set of str); a name a package imports on first use
    (``lazy``: {package: {name: module}}) counts as its module."""
    modules = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            modules.add(node.module)
            modules |= {f"{node.module}.{lazy.get(node.module, {}).get(a.name, a.name)}" for a in node.names}
        elif isinstance(node, ast.Import):
            modules |= {a.name for a in node.names}
    return modules


def _modules(wing):
    """The source files of a wing (a folder) or of a top-level module."""
    folder = PACKAGE / wing
    return sorted(folder.rglob("*.py")) if folder.is_dir() else [PACKAGE / f"{wing}.py"]


@pytest.mark.parametrize("wing", sorted(BELOW))
def test_a_wing_imports_only_the_wings_below_it(wing):
    allowed = BELOW[wing] | ALWAYS | {wing}
    reached = {}
    for path in _modules(wing):
        name = str(path.relative_to(PACKAGE))
        reached[name] = _imported_wings(path) - allowed - ABOVE_ITS_WING.get(name, set())
    assert not {name: sorted(wings) for name, wings in reached.items() if wings}


def test_every_wing_and_top_level_module_has_its_floor():
    """A new wing or module at the top is placed in the floor plan, never left unchecked."""
    names = {path.stem if path.is_file() else path.name for path in PACKAGE.iterdir()
             if (path.suffix == ".py" and path.stem not in ("__init__", "__main__"))
             or (path / "__init__.py").exists()}
    assert names - ALWAYS == set(BELOW) - ALWAYS
    assert set(ABOVE_ITS_WING) <= {str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")}


def test_the_program_side_never_imports_the_calibration_report():
    """The one module of the report wing above the calibration stays out of a compensation's imports."""
    from trajcomp.report import _MODULES as REPORT_NAMES

    program_side = ("programs", "formats", "timing", "compensation", "jobs", "api")
    importers = {str(path.relative_to(PACKAGE)) for wing in program_side for path in _modules(wing)
                 if "trajcomp.report.calibration" in _imported_modules(path, {"trajcomp.report": REPORT_NAMES})}
    assert not importers


def test_the_tests_mirror_the_wings():
    """A test folder is named after the wing it tests (or the plugins); the project's own tests stay at the top."""
    folders = {path.name for path in Path(__file__).parent.iterdir()
               if path.is_dir() and path.name not in ("data", "benchmarks", "__pycache__")}
    wings = {path.name for path in PACKAGE.iterdir() if (path / "__init__.py").exists()}
    assert folders <= wings | {"plugins"} and {"arm", "model", "calibration", "formats", "timing"} <= folders


def test_a_programs_route_to_the_written_file_never_enters_the_commands():
    """The API, the batch workers and the plugins run the library's pipeline; only the CLI imports commands."""
    importers = {str(path.relative_to(PACKAGE)) for path in PACKAGE.rglob("*.py")
                 if "commands" in _imported_wings(path) and path.parent.name != "commands"}
    assert importers == {"cli.py"}


def _calls(path, owner, names):
    """The lines of ``path`` calling ``owner.<name>`` or a name imported as it, for ``names`` (list of int)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    imported = {a.asname or a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                and node.module == f"trajcomp.{owner}" for a in node.names if a.name in names}
    return [node.lineno for node in ast.walk(tree) if isinstance(node, ast.Call)
            and (isinstance(node.func, ast.Attribute) and node.func.attr in names
                 and isinstance(node.func.value, ast.Name) and node.func.value.id == owner
                 or isinstance(node.func, ast.Name) and node.func.id in imported)]


def test_the_jobs_sit_above_the_stages_and_alone_write_programs():
    """The stages never import the jobs wing; the faces (the CLI's commands, the API, the demo) never write a
    program file themselves: a program's route to the file written is a job's (compensate, retime, convert)."""
    stages = ("programs", "formats", "timing", "compensation", "report", "model", "arm")
    assert all("jobs" not in BELOW[stage] for stage in stages)
    assert {"compensation", "timing", "report"} <= BELOW["jobs"]
    writers = {str(path.relative_to(PACKAGE)): lines for path in PACKAGE.rglob("*.py")
               if path.parent.name not in ("formats", "jobs") and path.parent.parent.name != "formats"
               and (lines := _calls(path, "formats", {"write"}))}
    assert not writers
