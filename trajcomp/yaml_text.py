"""YAML documents read with libyaml's safe loader where PyYAML has it.

PyYAML's pure-Python safe loader takes about 60 ms for a model file and its
robot, libyaml's about 8 ms, at every command's start; both build the same
plain data (mappings, lists, str, numbers, bool, None) and raise
``yaml.YAMLError`` for invalid text.
"""

import yaml

_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def load(text):
    """The plain data of a YAML document (str); raises ``yaml.YAMLError``."""
    return yaml.load(text, Loader=_LOADER)
