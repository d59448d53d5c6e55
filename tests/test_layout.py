"""The floor plan: each wing imports only the wings below it.

Read from the source (every ``import`` and ``from ... import`` statement,
lazy ones inside functions included), not from what happens to be loaded.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "trajcomp"
# wing: the wings (and top-level modules) it may import besides itself, errors and support
BELOW = {
    "support": set(),
    "arm": set(),
    "programs": {"arm"},
    "formats": {"arm", "programs"},
    "model": {"arm"},
    "timing": {"arm", "programs", "formats"},
    "compensation": {"arm", "programs", "formats", "model", "timing", "report"},
    "calibration": {"arm", "model"},
}
ALWAYS = {"errors", "support", "__init__"}


def _imported_wings(path):
    """The first names below ``trajcomp`` of every module ``path`` imports (set of str)."""
    wings = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            parts = node.module.split(".")
            if parts[0] == "trajcomp":
                wings.add(parts[1] if len(parts) > 1 else "__init__")
        elif isinstance(node, ast.Import):
            wings |= {a.name.split(".")[1] for a in node.names if a.name.startswith("trajcomp.")}
    return wings


@pytest.mark.parametrize("wing", sorted(BELOW))
def test_a_wing_imports_only_the_wings_below_it(wing):
    allowed = BELOW[wing] | ALWAYS | {wing}
    reached = {str(path.relative_to(PACKAGE)): _imported_wings(path) - allowed
               for path in sorted((PACKAGE / wing).rglob("*.py"))}
    assert not {name: sorted(wings) for name, wings in reached.items() if wings}


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

