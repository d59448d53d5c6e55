"""YAML documents read with libyaml's safe loader where PyYAML has it, bounded.

PyYAML's pure-Python safe loader takes about 60 ms for a model file and its
robot, libyaml's about 8 ms, at every command's start; both build the same
plain data (mappings, lists, str, numbers, bool, None) and raise
``yaml.YAMLError`` for invalid text.

Things YAML allows are refused, as damage or attack rather than data: a
key given twice in one mapping (YAML keeps the last silently); aliases
that expand to more than `MAX_VALUES` values (an alias shares the value it
names, so a 47 kB file of nested aliases loads as a small graph that is
gigabytes once anything walks it: turning it into an array, or into the
text of an error message); collections nested deeper than `MAX_DEPTH`
(libyaml builds them recursively: 100,000 ``[`` crash the process), found
from the parser's events before anything is built; and integers of more
digits than Python converts (4,300).
"""

import yaml

MAX_BYTES = 2 << 20  # a YAML file of trajcomp's (model, robot, layout) is at most a few hundred kB
MAX_VALUES = 10_000_000  # values (scalars and collections) of a document with its aliases expanded
MAX_DEPTH = 100  # collections nested in one another (trajcomp's files nest at most 6 deep)
_BASE = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_MERGE = "tag:yaml.org,2002:merge"


class _Loader(_BASE):
    """The safe loader, refusing a key given twice in one mapping."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                if key_node.tag == _MERGE or not isinstance(key_node, yaml.ScalarNode):
                    continue
                key = (key_node.tag, key_node.value)
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        "while constructing a mapping", node.start_mark,
                        f"found the key {key_node.value[:100]!r} twice", key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


_Loader.add_constructor("tag:yaml.org,2002:map", _Loader.construct_yaml_map)


def read(path):
    """The text of a YAML file, read as UTF-8; ``yaml.YAMLError`` beyond `MAX_BYTES` (without reading further).

    Raises ``OSError`` and ``UnicodeError`` as reading does. At most
    `MAX_BYTES` are read: a device or a file of gigabytes costs nothing.
    """
    with open(path, "rb") as handle:
        data = handle.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise yaml.YAMLError(f"more than {MAX_BYTES} bytes, beyond any trajcomp file of its kind")
    return data.decode("utf-8")


def load(text):
    """The plain data of a YAML document (str); raises ``yaml.YAMLError``, also for a duplicate key or an alias bomb."""
    try:
        _check_depth(text)
        data = yaml.load(text, Loader=_Loader)
        expanded = _expanded_size(data, {})
    except RecursionError:
        raise yaml.YAMLError("collections nested too deep") from None
    except ValueError as exc:  # an integer of more than 4,300 digits (yaml.YAMLError is no ValueError)
        raise yaml.YAMLError(f"a value cannot be read: {str(exc)[:100]}") from None
    if expanded > MAX_VALUES:
        raise yaml.YAMLError(f"its aliases expand to more than {MAX_VALUES} values: refused as an alias bomb")
    return data


def _check_depth(text):
    """Raise ``yaml.YAMLError`` if collections nest deeper than `MAX_DEPTH` (the parser's events: no recursion)."""
    depth = 0
    try:
        for event in yaml.parse(text, Loader=_BASE):
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_DEPTH:
                    raise yaml.YAMLError(f"collections nested more than {MAX_DEPTH} deep "
                                         f"(line {event.start_mark.line + 1})")
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
    except yaml.MarkedYAMLError as exc:  # newer PyYAML (6.0.4) stops a scan nesting 1,000 deep itself, first
        if "nesting depth" not in str(exc.problem):
            raise
        raise yaml.YAMLError(f"collections nested more than {MAX_DEPTH} deep "
                             f"(line {exc.problem_mark.line + 1})") from None


def shown(value):
    """A YAML value for an error message, at most about 100 characters: a list or mapping by its size only."""
    if isinstance(value, (list, dict)):
        return f"a {'list' if isinstance(value, list) else 'mapping'} of {len(value)} items"
    text = repr(value)
    return text if len(text) <= 100 else text[:100] + "..."


def _expanded_size(value, sizes):
    """Values in ``value`` with every shared (aliased) part counted each time it is used; memoized by identity.

    Stops counting once past `MAX_VALUES` (the answer is then only known to exceed it).
    """
    if not isinstance(value, (dict, list)):
        return 1
    key = id(value)
    if key not in sizes:
        sizes[key] = MAX_VALUES + 1  # a cycle (a collection aliased inside itself) counts as too large
        children = [*value.keys(), *value.values()] if isinstance(value, dict) else value
        total = 1
        for child in children:
            total += _expanded_size(child, sizes)
            if total > MAX_VALUES:
                break
        sizes[key] = total
    return sizes[key]
