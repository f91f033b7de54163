"""One safe loader for every YAML and JSON input (job files, programs, HMI bodies).

Files and request bodies are untrusted: a 400-byte YAML "billion laughs"
document expands to gigabytes, a 100,000-deep nesting overflows the stack of
a recursive parser, and YAML 1.1 turns ``yes`` into ``True`` and leaves
``1e3`` a string. :func:`parse_document` reads both formats with the same
rules:

- at most ``max_bytes`` bytes (:data:`MAX_DOCUMENT_BYTES` by default),
  UTF-8 text (a leading byte-order mark is accepted);
- nesting at most :data:`MAX_DEPTH` levels of mappings and lists;
- YAML anchors and aliases (``&a``, ``*a``, ``<<: *a``) and explicit tags
  (``!!python/...``, ``!!binary``) are refused;
- a key may appear only once in a mapping;
- plain YAML scalars follow the YAML 1.2 core schema, as JSON does: only
  ``true``/``false`` are booleans, ``null``/``~``/empty is null, ``1e3`` and
  ``.inf`` are floats, and ``yes``, ``on``, ``2024-01-01`` or ``0777``-style
  octals stay what they look like (strings, decimal integers);
- JSON is strict: no ``NaN``/``Infinity`` literals; in both formats a number
  that overflows a float (``1e999``) is refused (YAML's explicit ``.inf`` is
  kept: some fields mean "no limit" by it).

Every refusal is an :class:`~trajkit.errors.InvalidInputError` with one line
that names the source and, for YAML, the line.
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from yaml.composer import Composer
from yaml.constructor import SafeConstructor
from yaml.events import AliasEvent, CollectionStartEvent
from yaml.parser import Parser
from yaml.reader import Reader
from yaml.resolver import BaseResolver
from yaml.scanner import Scanner

from ..errors import InvalidInputError

__all__ = [
    "MAX_DOCUMENT_BYTES",
    "MAX_DEPTH",
    "LineDict",
    "LineList",
    "parse_document",
    "read_document",
    "plain",
    "document_kind",
]

#: Largest accepted document [bytes] (2 MiB); pass ``max_bytes`` to change it.
MAX_DOCUMENT_BYTES = 2 * 1024 * 1024

#: Deepest accepted nesting of mappings and lists.
MAX_DEPTH = 64

Kind = Literal["yaml", "json"]

_SUFFIX_KIND = {".yaml": "yaml", ".yml": "yaml", ".json": "json"}


class LineDict(dict):
    """A mapping that remembers the 1-based line of itself (``line``) and of every key (``key_lines``)."""

    line: int = 0

    def __init__(self, *a: Any, **k: Any) -> None:
        super().__init__(*a, **k)
        self.key_lines: dict = {}


class LineList(list):
    """A list that remembers the 1-based line of itself (``line``) and of every item (``item_lines``)."""

    line: int = 0

    def __init__(self, *a: Any) -> None:
        super().__init__(*a)
        self.item_lines: list = []


def plain(x: Any) -> Any:
    """Return ``x`` with every :class:`LineDict`/:class:`LineList` turned into a plain dict/list."""
    if isinstance(x, dict):
        return {k: plain(v) for k, v in x.items()}
    if isinstance(x, list):
        return [plain(v) for v in x]
    return x


# --------------------------------------------------------------------------- YAML
class _Refused(Exception):
    """A rule of the loader was broken at ``mark`` (raised inside the parser)."""

    def __init__(self, message: str, mark: Any = None) -> None:
        super().__init__(message)
        self.mark = mark


class _CoreResolver(BaseResolver):
    """Implicit tags of the YAML 1.2 core schema (the JSON-compatible one)."""


_CoreResolver.yaml_implicit_resolvers = {}
_CoreResolver.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF"))
_CoreResolver.add_implicit_resolver(
    "tag:yaml.org,2002:int", re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"),
    list("-+0123456789"))
_CoreResolver.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
               r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+0123456789."))
_CoreResolver.add_implicit_resolver(
    "tag:yaml.org,2002:null", re.compile(r"^(?:~|null|Null|NULL|)$"), ["~", "n", "N", ""])

_ALLOWED_TAGS = {
    "tag:yaml.org,2002:str", "tag:yaml.org,2002:int", "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool", "tag:yaml.org,2002:null", "tag:yaml.org,2002:map",
    "tag:yaml.org,2002:seq",
}


class _SafeComposer(Composer):
    """Composer that refuses anchors, aliases, explicit tags and deep nesting."""

    max_depth = MAX_DEPTH

    def compose_node(self, parent: Any, index: Any) -> Any:  # noqa: D401 - PyYAML hook
        event = self.peek_event()
        if isinstance(event, AliasEvent):
            raise _Refused(f"aliases (*{event.anchor}) are not supported", event.start_mark)
        if getattr(event, "anchor", None) is not None:
            raise _Refused(f"anchors (&{event.anchor}) are not supported", event.start_mark)
        tag = getattr(event, "tag", None)
        if tag is not None and tag != "!":
            raise _Refused(f"explicit tags ({tag}) are not supported", event.start_mark)
        if isinstance(event, CollectionStartEvent):
            depth = getattr(self, "_depth", 0) + 1
            if depth > self.max_depth:
                raise _Refused(f"nested deeper than {self.max_depth} levels", event.start_mark)
            self._depth = depth
            try:
                return super().compose_node(parent, index)
            finally:
                self._depth = depth - 1
        return super().compose_node(parent, index)


class _CoreConstructor(SafeConstructor):
    """Constructs core-schema scalars; mappings and lists remember their lines."""

    def construct_yaml_int(self, node: Any) -> int:
        value = self.construct_scalar(node)
        try:
            if value.startswith("0o"):
                return int(value[2:], 8)
            if value.startswith("0x"):
                return int(value[2:], 16)
            return int(value, 10)
        except ValueError:  # e.g. more digits than Python converts
            raise _Refused(f"integer {value[:20]}... is too long", node.start_mark) from None

    def construct_yaml_float(self, node: Any) -> float:
        value = self.construct_scalar(node).lower()
        if value.endswith(".inf"):
            return float("-inf") if value.startswith("-") else float("inf")
        if value == ".nan":
            return float("nan")
        x = float(value)
        if math.isinf(x):  # 1e999: overflow, not the explicit .inf
            raise _Refused(f"number {value[:20]} is out of the range of a float", node.start_mark)
        return x

    def construct_yaml_map(self, node: Any):  # type: ignore[override]
        out = LineDict()
        out.line = node.start_mark.line + 1
        yield out
        for knode, vnode in node.value:
            key = self.construct_object(knode, deep=True)
            try:
                hash(key)
            except TypeError:
                raise _Refused("a mapping key must be a plain value, not a mapping or list",
                               knode.start_mark) from None
            if key in out:
                raise _Refused(f"duplicate key {_short(key)}", knode.start_mark)
            out[key] = self.construct_object(vnode, deep=True)
            out.key_lines[key] = knode.start_mark.line + 1

    def construct_yaml_seq(self, node: Any):  # type: ignore[override]
        out = LineList()
        out.line = node.start_mark.line + 1
        yield out
        for child in node.value:
            out.append(self.construct_object(child, deep=True))
            out.item_lines.append(child.start_mark.line + 1)


_CoreConstructor.yaml_constructors = {}
_CoreConstructor.add_constructor("tag:yaml.org,2002:null", SafeConstructor.construct_yaml_null)
_CoreConstructor.add_constructor("tag:yaml.org,2002:bool", SafeConstructor.construct_yaml_bool)
_CoreConstructor.add_constructor("tag:yaml.org,2002:int", _CoreConstructor.construct_yaml_int)
_CoreConstructor.add_constructor("tag:yaml.org,2002:float", _CoreConstructor.construct_yaml_float)
_CoreConstructor.add_constructor("tag:yaml.org,2002:str", SafeConstructor.construct_yaml_str)
_CoreConstructor.add_constructor("tag:yaml.org,2002:seq", _CoreConstructor.construct_yaml_seq)
_CoreConstructor.add_constructor("tag:yaml.org,2002:map", _CoreConstructor.construct_yaml_map)


class _PyLoader(Reader, Scanner, Parser, _SafeComposer, _CoreConstructor, _CoreResolver):
    """The safe loader on PyYAML's pure-Python scanner and parser."""

    def __init__(self, stream: str) -> None:
        Reader.__init__(self, stream)
        Scanner.__init__(self)
        Parser.__init__(self)
        _SafeComposer.__init__(self)
        _CoreConstructor.__init__(self)
        _CoreResolver.__init__(self)


try:  # libyaml's scanner and parser (about 3x faster); the composer stays ours
    from yaml._yaml import CParser

    class _CLoader(_SafeComposer, _CoreConstructor, _CoreResolver, CParser):
        """The safe loader on libyaml's scanner and parser."""

        def __init__(self, stream: str) -> None:
            CParser.__init__(self, stream)
            _SafeComposer.__init__(self)
            _CoreConstructor.__init__(self)
            _CoreResolver.__init__(self)

    _SafeLoader: type = _CLoader
except ImportError:  # PyYAML built without libyaml
    _SafeLoader = _PyLoader


def _short(value: Any, limit: int = 40) -> str:
    s = repr(value)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _parse_yaml(text: str, source: str, max_depth: int, loader_cls: type | None = None) -> Any:
    loader = (loader_cls or _SafeLoader)(text)
    loader.max_depth = max_depth
    try:
        return loader.get_single_data()
    except _Refused as exc:
        raise InvalidInputError(f"{source}{_at(exc.mark)}: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or " ".join(str(exc).split())[:120]
        raise InvalidInputError(f"{source}{_at(mark)}: not valid YAML: {problem}") from None
    except RecursionError:  # not reached with the depth cap; kept as a guard
        raise InvalidInputError(f"{source}: nested too deeply") from None
    finally:
        loader.dispose()


def _at(mark: Any) -> str:
    return f":{mark.line + 1}" if mark is not None else ""


# --------------------------------------------------------------------------- JSON
_JSON_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)


def _json_depth(raw: bytes) -> int:
    """Deepest nesting of ``[``/``{`` in JSON bytes, ignoring string contents."""
    bare = _JSON_STRING.sub(b'""', raw)
    a = np.frombuffer(bare, dtype=np.uint8)
    step = (np.isin(a, (ord("["), ord("{")))).astype(np.int32) - np.isin(a, (ord("]"), ord("}")))
    return int(np.cumsum(step).max(initial=0))


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not valid JSON")


def _json_float(text: str) -> float:
    x = float(text)
    if math.isinf(x):
        raise ValueError(f"number {text[:20]} is out of the range of a float")
    return x


def _json_object(pairs: list) -> dict:
    out: dict = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"duplicate key {_short(k)}")
        out[k] = v
    return out


def _parse_json(text: str, raw: bytes, source: str, max_depth: int) -> Any:
    if _json_depth(raw) > max_depth:
        raise InvalidInputError(f"{source}: nested deeper than {max_depth} levels")
    try:
        return json.loads(text, object_pairs_hook=_json_object, parse_constant=_refuse_constant,
                          parse_float=_json_float)
    except json.JSONDecodeError as exc:
        raise InvalidInputError(
            f"{source}:{exc.lineno}: not valid JSON: {exc.msg} (column {exc.colno})") from None
    except (ValueError, RecursionError) as exc:
        raise InvalidInputError(f"{source}: not valid JSON: {str(exc)[:120]}") from None


# --------------------------------------------------------------------------- public
def parse_document(data: bytes | str, *, source: str = "<input>", kind: Kind = "yaml",
                   max_bytes: int = MAX_DOCUMENT_BYTES, max_depth: int = MAX_DEPTH) -> Any:
    """Parse one YAML or JSON document under the safe rules of this module.

    Parameters
    ----------
    data : bytes or str
        The document. Bytes must be UTF-8 (an optional byte-order mark is
        dropped).
    source : str
        Name used in error messages (a file name, ``"request body"``).
    kind : {"yaml", "json"}
        Format. YAML mappings and lists come back as :class:`LineDict` and
        :class:`LineList` (plain ``dict``/``list`` subclasses that remember
        their lines); JSON as plain ``dict``/``list``.
    max_bytes : int
        Largest accepted size [bytes].
    max_depth : int
        Deepest accepted nesting of mappings and lists.

    Returns
    -------
    object
        The parsed value (``None`` for an empty YAML document).

    Raises
    ------
    InvalidInputError
        A document that is too large, not UTF-8, nested too deeply, has an
        alias, anchor, explicit tag or duplicate key, or is not valid YAML/JSON.
    """
    if kind not in ("yaml", "json"):
        raise InvalidInputError(f"kind must be 'yaml' or 'json', got {kind!r}")
    if isinstance(data, str):
        raw = data.encode("utf-8", "surrogatepass")
        if len(raw) > max_bytes:
            raise InvalidInputError(f"{source}: larger than {_size(max_bytes)} ({_size(len(raw))})")
        text = data
    elif isinstance(data, (bytes, bytearray, memoryview)):
        raw = bytes(data)
        if len(raw) > max_bytes:
            raise InvalidInputError(f"{source}: larger than {_size(max_bytes)} ({_size(len(raw))})")
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise InvalidInputError(
                f"{source}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start})") from None
    else:
        raise InvalidInputError(f"{source}: expected text or bytes, got {type(data).__name__}")
    if "\x00" in text:
        raise InvalidInputError(f"{source}: not a text document (contains a NUL character)")
    if kind == "json":
        return _parse_json(text, raw, source, max_depth)
    return _parse_yaml(text, source, max_depth)


def document_kind(path: str | os.PathLike) -> Kind:
    """``"yaml"`` or ``"json"`` from a file name's suffix (``.yaml``, ``.yml``, ``.json``)."""
    suffix = Path(path).suffix.lower()
    kind = _SUFFIX_KIND.get(suffix)
    if kind is None:
        raise InvalidInputError(f"{os.fspath(path)}: file name must end in .yaml, .yml or .json")
    return kind  # type: ignore[return-value]


def read_document(path: str | os.PathLike, *, kind: Kind | None = None,
                  max_bytes: int = MAX_DOCUMENT_BYTES, max_depth: int = MAX_DEPTH) -> Any:
    """Read and parse a YAML or JSON file under the rules of :func:`parse_document`.

    ``kind`` defaults to the file's suffix (``.json`` is JSON, anything else YAML).
    The file is read only up to ``max_bytes + 1`` bytes, so a huge file or a
    device cannot exhaust memory.

    Raises
    ------
    InvalidInputError
        See :func:`parse_document`; also a path that is a folder.
    OSError
        The file cannot be opened.
    """
    p = Path(path)
    if kind is None:
        kind = "json" if p.suffix.lower() == ".json" else "yaml"
    if p.is_dir():
        raise InvalidInputError(f"{p}: is a folder, not a file")
    with open(p, "rb") as fh:
        raw = fh.read(max_bytes + 1)
    return parse_document(raw, source=str(p), kind=kind, max_bytes=max_bytes, max_depth=max_depth)


def _size(n: int) -> str:
    if n >= 1024 * 1024:
        return f"{n / (1024 * 1024):.1f} MiB"
    if n >= 1024:
        return f"{n / 1024:.1f} KiB"
    return f"{n} bytes"
