"""YAML read with libyaml gives what PyYAML's pure-Python safe loader gives, and fails alike."""

from pathlib import Path

import pytest
import yaml

import trajcomp
from trajcomp.support import yaml_text

FILES = sorted((Path(trajcomp.__file__).parent / "arm" / "robots").glob("*.yaml")) + sorted(
    (Path(__file__).resolve().parents[1] / "examples" / "columns").glob("*.yaml"))


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_shipped_files_read_as_the_reference_loader_reads_them(path):
    text = path.read_text(encoding="utf-8")
    assert yaml_text.load(text) == yaml.safe_load(text)


def test_plain_types_only_and_the_same_error_class():
    text = "a: 1.5e-3\nb: [yes, no, ~, '07']\nc: {d: -0.0}\n"
    assert yaml_text.load(text) == yaml.safe_load(text) == {"a": 0.0015, "b": [True, False, None, "07"],
                                                          "c": {"d": -0.0}}
    for bad in ("a: [1, 2", "!!python/object:os.system {}"):
        with pytest.raises(yaml.YAMLError):
            yaml_text.load(bad)
