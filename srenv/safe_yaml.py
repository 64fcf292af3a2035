"""The bounded YAML reader of every config and training file: ``yaml.SafeLoader`` (no Python tags), YAML 1.2
floats, duplicate keys refused, and bounds on bytes, depth and nodes after alias expansion; errors in one line."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from .errors import ConfigError, short_repr
from .input_files import read_regular

# Bounds on what a YAML document may ask of the loader (a config is a few hundred nodes; see
# docs/reliability.md): bytes read, nesting depth, and nodes after alias expansion - a 600-byte "billion
# laughs" document expands to millions of nodes, and anything walking or printing it would do that work.
MAX_YAML_BYTES = 1_000_000
MAX_YAML_DEPTH = 50
MAX_YAML_NODES = 100_000


class _ConfigLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` (no tags that construct Python objects) that also reads ``1e-3`` as a float,
    refuses duplicate mapping keys and bounds the document's expanded size and depth.

    PyYAML follows YAML 1.1, where a float needs a dot (``1.0e-3``), so ``time_step_s: 1e-3`` would arrive
    as the *string* '1e-3' and be refused as "not a number" - a baffling error for a valid value. YAML 1.2
    (and every other tool) reads it as a number; so do we. ``nan``/``inf`` spelt without the dot stay strings.
    A key given twice is an error (YAML 1.2 requires unique keys; PyYAML silently keeps the last one, so
    ``spm: 6`` then ``spm: 30`` would run at 30 without a word).
    """

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._expanded: dict[int, int] = {}  # id(node) -> node count with aliases expanded
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise yaml.composer.ComposerError(None, None, f"nesting deeper than {MAX_YAML_DEPTH} levels",
                                                  self.peek_event().start_mark)
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        size = self._expanded.get(id(node))
        if size is None:
            if isinstance(node, yaml.SequenceNode):
                size = 1 + sum(self._expanded.get(id(c), 1) for c in node.value)
            elif isinstance(node, yaml.MappingNode):
                size = 1 + sum(self._expanded.get(id(k), 1) + self._expanded.get(id(v), 1) for k, v in node.value)
            else:
                size = 1
            self._expanded[id(node)] = size
        if size > MAX_YAML_NODES:
            raise yaml.composer.ComposerError(None, None, f"more than {MAX_YAML_NODES} values once aliases are "
                                              "expanded (an alias bomb?)", node.start_mark)
        return node

    def construct_mapping(self, node: Any, deep: bool = False) -> Any:
        if isinstance(node, yaml.MappingNode):
            seen: set = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge" or not isinstance(key_node, yaml.ScalarNode):
                    continue  # merged keys may be overridden by explicit ones (YAML merge semantics)
                key = self.construct_object(key_node)
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"duplicate key {short_repr(key)}",
                                                            key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


_ConfigLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


_AMBIGUOUS_NUMBER = re.compile(r"^[-+]?(?:0[0-9_]+|[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?|0b[01_]+"
                               r"|[0-9.][0-9.]*_[0-9_.]*(?:[eE][-+]?[0-9]+)?)$")
AMBIGUOUS_WHY = "YAML 1.1 reads 010 as octal 8, 0b10 as binary 2, 1:30 as 90 and 1_0 as 10; YAML 1.2 reads 10 or a string"


def _unambiguous(construct: Any) -> Any:
    """YAML 1.1 reads ``010`` as octal 8, ``0b10`` as 2, ``1:30`` as 90 (base 60) and ``1_0`` as 10; YAML 1.2
    and every other tool read 10 or a string. Neither reading is safe to pick without a word: such a number is refused."""
    def build(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> Any:
        if _AMBIGUOUS_NUMBER.match(node.value):
            raise yaml.constructor.ConstructorError(
                None, None, f"the number {node.value} is ambiguous ({AMBIGUOUS_WHY}): write it without the leading "
                "zero, 0b, colon or underscore, or quote it", node.start_mark)
        return construct(loader, node)
    return build


_ConfigLoader.add_constructor("tag:yaml.org,2002:int", _unambiguous(yaml.SafeLoader.construct_yaml_int))
_ConfigLoader.add_constructor("tag:yaml.org,2002:float", _unambiguous(yaml.SafeLoader.construct_yaml_float))


def _yaml_load(stream: Any) -> Any:
    return yaml.load(stream, Loader=_ConfigLoader)  # a SafeLoader subclass: still no Python tags





_KINDS = ((bool, "a boolean"), (int, "an integer"), (float, "a number"), (str, "a string"), (dict, "a mapping"),
          (list, "a list"), (type(None), "null"))


def yaml_kind(value: Any) -> str:
    """What a YAML value is, in a message's words ("a list", "a mapping", "null", ...): for refusals that name
    the type found beside the type expected."""
    return next((name for cls, name in _KINDS if isinstance(value, cls)), f"a {type(value).__name__}")


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """One line locating a YAML error: 'line L column C: problem' (the full text spans several lines)."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    if mark is None:
        return problem
    return f"line {mark.line + 1} column {mark.column + 1}: {problem}"


def load_yaml_file(path: str | Path, field_name: str) -> Any:
    """Read one YAML file with the bounded, duplicate-refusing safe loader; every problem (unreadable, not a
    regular file, too large, not UTF-8, bad syntax) is one ConfigError naming ``field_name`` and the path."""
    raw = read_regular(path, field_name, "YAML file", MAX_YAML_BYTES)  # a FIFO or a device is refused, not read
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(field_name, str(path), "a UTF-8 text file") from None
    try:
        return _yaml_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(field_name, str(path), f"valid YAML ({_yaml_problem(exc)})") from None
    except RecursionError:
        raise ConfigError(field_name, str(path), "valid YAML (nested too deeply)") from None
