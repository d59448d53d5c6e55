"""The format registry: lookup, lazy built-ins, entry-point plugins."""

import re
import sys
from importlib.metadata import EntryPoint

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.formats.capabilities import ConfigurationData, SpeedFields
from trajcomp.errors import ReadError, TrajcompError
from trajcomp.programs.program import Program


def test_lookup_by_extension_and_name():
    assert formats.find_format("a/b/PROG.SRC").name == "krl"
    assert formats.find_format("x.mod").name == "rapid"
    assert formats.find_format("x.ls").name == "fanuc_ls"
    assert formats.find_format("x.script").name == "urscript"
    assert formats.find_format("x.txt", format="csv").name == "csv"


def test_unknown_extension_and_name():
    with pytest.raises(TrajcompError, match=r"unknown program extension '\.xyz'.*\.src"):
        formats.find_format("p.xyz")
    with pytest.raises(TrajcompError, match="unknown program format 'nope'"):
        formats.find_format(format="nope")


def test_missing_file_is_a_read_error(tmp_path):
    with pytest.raises(ReadError, match="no such file"):
        formats.read(tmp_path / "none.src")


def test_builtin_format_readers_and_writers_are_imported_lazily():
    """The registry (and the CLI's help) loads each language's folder, which only registers it: no reader, writer
    or numpy is imported until a program is read or written."""
    code = (
        "import sys, trajcomp.formats, trajcomp.cli; "
        "print(sorted(m for m in sys.modules if m.startswith('trajcomp.formats.') and m.count('.') > 2), "
        "'numpy' in sys.modules)"
    )
    import subprocess

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[] False"


@pytest.fixture
def plugins(monkeypatch, tmp_path):
    """Entry points of a working and a broken plugin, and a clean registry."""
    module = tmp_path / "toyformat.py"
    module.write_text(
        "from trajcomp.formats import register_format\n"
        "from trajcomp.programs.program import Program\n"
        "def read(path):\n"
        "    return Program('toy', 'toy', (), ())\n"
        "def write(program, path):\n"
        "    return {path: b'toy\\n'}\n"
        "register_format('toy', ['.toy'], read, write)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    points = [
        EntryPoint("toy", "toyformat", formats.ENTRY_POINT_GROUP),
        EntryPoint("broken", "no_such_module_for_trajcomp", formats.ENTRY_POINT_GROUP),
    ]
    monkeypatch.setattr(formats, "entry_points", lambda group: points if group == formats.ENTRY_POINT_GROUP else [])
    monkeypatch.setattr(formats, "_FORMATS", dict(formats._FORMATS))
    monkeypatch.setattr(formats, "_PLUGINS", {"loaded": False, "failed": {}})
    yield
    sys.modules.pop("toyformat", None)


def test_plugin_formats_are_found_through_entry_points(plugins, tmp_path):
    assert not formats._PLUGINS["loaded"]
    formats.find_format("x.src")  # a built-in lookup does not load plugins
    assert not formats._PLUGINS["loaded"]
    fmt = formats.find_format("data.toy")
    assert fmt.name == "toy" and fmt.source == "plugin toyformat"
    (tmp_path / "a.toy").write_text("")
    assert isinstance(formats.read(tmp_path / "a.toy"), Program)
    formats.write(tmp_path / "b.toy", formats.read(tmp_path / "a.toy"))
    assert (tmp_path / "b.toy").read_bytes() == b"toy\n"


def test_broken_plugin_is_named_in_the_error(plugins):
    with pytest.raises(TrajcompError, match=r"plugins that failed to import: broken \(no_such_module"):
        formats.find_format("x.unknown")
    assert "broken" in formats.plugin_failures()
    assert "toy" in [f.name for f in formats.formats()]


def test_mask_blanks_comments_and_string_contents_keeping_offsets():
    from trajcomp.formats.text import mask

    text = 'LIN P1 ; go "fast"\r\nMSG="a;b" ; c\nX="ab\ncd'
    assert mask(text, ";") == 'LIN P1 ' + " " * 11 + '\r\nMSG="   " ' + " " * 3 + '\nX="  \n  '
    assert mask("a // b\n// c", "//") == "a     \n    "


def _masked_by_pattern(text, comment, quote):
    """The reference: one pattern of a string (to its closing quote or the end) or a comment, left to right; a
    carriage return alone made a line feed."""
    def blanked(m):
        if m.group(1) is None:
            return " " * len(m.group(0))
        return quote + re.sub(r"[^\r\n]", " ", m.group(1)) + m.group(0)[1 + len(m.group(1)):]

    q, c = re.escape(quote), re.escape(comment)
    return re.sub(f"{q}([^{q}]*)(?:{q}|\\Z)|{c}[^\r\n]*", blanked, re.sub("\r(?!\n)", "\n", text))


@pytest.mark.parametrize("comment", [";", "!", "//"])
def test_mask_of_random_texts_is_the_patterns(comment):
    from trajcomp.formats.text import mask

    rng = np.random.default_rng(11)
    alphabet = ['"', "'", ";", "!", "/", "\n", "\r", "\r\n", "a", " ", "é", "Ω"]
    for _ in range(400):
        text = "".join(rng.choice(alphabet, size=int(rng.integers(0, 40))).tolist())
        for quote in ('"', "'"):
            assert mask(text, comment, quote) == _masked_by_pattern(text, comment, quote), (text, quote)


@pytest.mark.parametrize("language", formats.BUILT_IN)
def test_a_built_in_language_is_one_folder_that_registers_its_own_modules(language):
    """Adding a language is a folder and a line in BUILT_IN: its reader, writer, speed fields and configuration
    data (where it has some) are modules of its folder, registered from there, with the hooks' names."""
    import importlib

    package = f"trajcomp.formats.{language}"
    (fmt,) = [f for f in formats.formats() if f.reader.startswith(package + ".")]
    for face, ref in (("reader", fmt.reader), ("writer", fmt.writer), ("speeds", fmt.capability(SpeedFields).write)):
        module, function = ref.split(":")
        assert module == f"{package}.{face}" and callable(getattr(importlib.import_module(module), function))
    if fmt.capability(ConfigurationData) is not None:
        data = fmt.capability(ConfigurationData).codec()
        assert data.__name__ == f"{package}.configuration"
        assert all(callable(getattr(data, hook)) for hook in ("encode", "windows", "merge", "describe"))
