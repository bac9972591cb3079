"""Task-file YAML with line numbers: a loader that remembers where each key and item was written, and a
cursor that walks the parsed data and reports every problem as `file:line: key: what is expected`."""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, NoReturn

import yaml

from lerobot_contrast.contrast.errors import UserError

# No number in a task file is larger than this in its own units: a larger one is a typo (or not finite).
MAX_MAGNITUDE = 1e6


class TaskFileError(UserError):
    """A task file that cannot be used; the message names the file, the line or key, and what is expected."""


class _Map(dict):
    line: int | None = None
    lines: dict[Any, int]


class _Seq(list):
    line: int | None = None
    lines: list[int]


class _LineLoader(yaml.SafeLoader):
    """PyYAML's safe loader, building mappings and lists that remember the line of each key and item."""


def _mapping(loader: _LineLoader, node: yaml.MappingNode) -> _Map:
    loader.flatten_mapping(node)
    out = _Map()
    out.line, out.lines = node.start_mark.line + 1, {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        line = key_node.start_mark.line + 1
        if not isinstance(key, str | int | float | bool):
            raise TaskFileError(f"{loader.name}:{line}: keys must be names, not {type(key).__name__}s")
        if key in out:
            raise TaskFileError(f"{loader.name}:{line}: key {key!r} is given twice in this mapping; keep one")
        out[key] = loader.construct_object(value_node, deep=True)
        out.lines[key] = line
    return out


def _sequence(loader: _LineLoader, node: yaml.SequenceNode) -> _Seq:
    out = _Seq(loader.construct_object(item, deep=True) for item in node.value)
    out.line, out.lines = node.start_mark.line + 1, [item.start_mark.line + 1 for item in node.value]
    return out


_LineLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)
_LineLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, _sequence)


def load_yaml(text: str, source: str) -> Any:
    """Parse YAML text, keeping line numbers; syntax errors become one-line TaskFileErrors."""
    try:
        loader = _LineLoader(text)  # reads the whole text, refusing NUL bytes and other control characters
    except yaml.reader.ReaderError as error:
        line = text.count("\n", 0, error.position) + 1
        raise TaskFileError(
            f"{source}:{line}: invalid YAML: character code {error.character} (a NUL byte or another control "
            "character) is not allowed in a task file; remove it"
        ) from None
    loader.name = source
    try:
        return loader.get_single_data()
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        line = f":{mark.line + 1}" if mark is not None else ""
        raise TaskFileError(f"{source}{line}: invalid YAML: {error.problem or error.context}") from None
    except yaml.YAMLError as error:
        raise TaskFileError(f"{source}: invalid YAML: {' '.join(str(error).split())}") from None
    except RecursionError:
        raise TaskFileError(
            f"{source}: invalid YAML: lists or mappings nested too deeply to read; a task file needs a few levels"
        ) from None
    finally:
        loader.dispose()


@dataclass(frozen=True)
class Node:
    """A value in the task file with where it was written, for error messages."""

    value: Any
    source: str
    path: str = ""
    line: int | None = None

    def fail(self, expected: str) -> NoReturn:
        where = self.source if self.line is None else f"{self.source}:{self.line}"
        raise TaskFileError(f"{where}: {self.path or 'top level'}: {expected}")

    def _child(self, key: Any, value: Any, line: int | None, index: bool = False) -> Node:
        path = f"{self.path}[{key}]" if index else (f"{self.path}.{key}" if self.path else str(key))
        return Node(value, self.source, path, line if line is not None else self.line)

    def get(self, key: str) -> Node | None:
        data = self.mapping()
        if key not in data:
            return None
        return self._child(key, data[key], getattr(data, "lines", {}).get(key))

    def require(self, key: str, expected: str) -> Node:
        child = self.get(key)
        if child is None:
            self.fail(f"missing key {key!r}: {expected}")
        return child

    def items(self) -> list[tuple[str, Node]]:
        data = self.mapping()
        lines = getattr(data, "lines", {})
        out = []
        for key, value in data.items():
            child = self._child(key, value, lines.get(key))
            if not isinstance(key, str):
                child.fail("keys must be names (text), not numbers or booleans")
            out.append((key, child))
        return out

    def elements(self) -> list[Node]:
        data = self.sequence()
        lines = getattr(data, "lines", [None] * len(data))
        return [self._child(i, value, lines[i], index=True) for i, value in enumerate(data)]

    def check_keys(self, allowed: Iterable[str]) -> None:
        allowed = tuple(allowed)
        for key, child in self.items():
            if key not in allowed:
                near = difflib.get_close_matches(key, allowed, n=1)
                hint = f"did you mean {near[0]!r}? " if near else ""
                child.fail(f"unknown key {key!r}; {hint}expected one of: {', '.join(allowed)}")

    def mapping(self) -> dict:
        if not isinstance(self.value, dict):
            self.fail(f"expected a mapping (key: value lines), got {_kind(self.value)}")
        return self.value

    def sequence(self) -> list:
        if not isinstance(self.value, list):
            self.fail(f"expected a list, got {_kind(self.value)}")
        return self.value

    def text(self) -> str:
        if not isinstance(self.value, str) or not self.value.strip():
            self.fail(f"expected non-empty text, got {_kind(self.value)}")
        return self.value

    def texts(self) -> tuple[str, ...]:
        """One text or a non-empty list of texts."""
        if isinstance(self.value, str):
            return (self.text(),)
        if not self.sequence():
            self.fail("expected text or a non-empty list of texts, got an empty list")
        return tuple(item.text() for item in self.elements())

    def number(self, minimum: float | None = None, strict: bool = False) -> float:
        if isinstance(self.value, bool) or not isinstance(self.value, int | float):
            self.fail(f"expected a number, got {_kind(self.value)}")
        value = float(self.value)
        if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
            self.fail(f"expected a number between {-MAX_MAGNITUDE:g} and {MAX_MAGNITUDE:g}, got {value:g}")
        if minimum is not None and (value <= minimum if strict else value < minimum):
            self.fail(f"expected a number {'>' if strict else '>='} {minimum:g}, got {value:g}")
        return value

    def integer(self, minimum: int | None = None) -> int:
        if isinstance(self.value, bool) or not isinstance(self.value, int):
            self.fail(f"expected a whole number, got {_kind(self.value)}")
        if minimum is not None and self.value < minimum:
            self.fail(f"expected a whole number >= {minimum}, got {self.value}")
        return self.value

    def boolean(self) -> bool:
        if not isinstance(self.value, bool):
            self.fail(f"expected true or false, got {_kind(self.value)}")
        return self.value

    def choice(self, options: Iterable[str]) -> str:
        options = tuple(options)
        if self.value not in options:
            self.fail(f"expected one of: {', '.join(options)}; got {_kind(self.value)}")
        return self.value

    def numbers(self, count: tuple[int, ...], what: str) -> tuple[float, ...]:
        """A list of `count` numbers, e.g. [x, y] (`what` says how to write it)."""
        if not isinstance(self.value, list) or len(self.value) not in count:
            self.fail(f"expected {what}, got {_kind(self.value)}")
        return tuple(item.number() for item in self.elements())


def _kind(value: Any) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, int | float):
        return f"{value:g}"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return "a mapping" if isinstance(value, dict) else type(value).__name__
