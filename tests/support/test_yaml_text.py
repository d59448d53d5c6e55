"""YAML read with libyaml gives what PyYAML's pure-Python safe loader gives, and fails alike."""

from pathlib import Path

import pytest
import yaml

import trajcomp
from trajcomp.support import yaml_text

FILES = sorted((Path(trajcomp.__file__).parent / "arm" / "robots").glob("*.yaml")) + sorted(
    (Path(__file__).resolve().parents[2] / "examples" / "columns").glob("*.yaml"))


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


@pytest.mark.parametrize("text", ["[" * 100_000 + "]" * 100_000, "- " * 100_000 + "1", "{a: " * 2000 + "1" + "}" * 2000])
def test_collections_nested_beyond_the_bound_are_refused_before_libyaml_builds_them(text):
    # 100,000 '[' were a segmentation fault in libyaml's recursive composer (exit 139, no message)
    with pytest.raises(yaml.YAMLError, match=r"nested more than 100 deep \(line 1\)"):
        yaml_text.load(text)


def test_collections_nested_to_the_bound_are_read():
    text = "b: " + "[" * 99 + "1" + "]" * 99  # the document's mapping and 99 lists: 100 deep
    nested = yaml_text.load(text)["b"]
    for _ in range(99):
        assert len(nested) == 1
        nested = nested[0]
    assert nested == 1


def test_an_integer_of_more_digits_than_python_converts_is_a_yaml_error():
    with pytest.raises(yaml.YAMLError, match=r"a value cannot be read: Exceeds the limit \(4300 digits\)"):
        yaml_text.load("delta: " + "9" * 5000)  # was a ValueError: an internal error, exit 3
