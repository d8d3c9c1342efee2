"""The one YAML loader of the package: every configuration, mission and world file is read through it.

PyYAML's ``safe_load`` builds no Python objects, but it still expands aliases (a "billion laughs"
file of a few hundred bytes takes gigabytes), silently keeps the last of two equal keys, recurses
once per nesting level (RecursionError) and reads any file, binary or UTF-16 (UnicodeDecodeError).
:func:`load_yaml_file` refuses all of those with one :class:`YamlFileError` line naming the file
(and the line, for a problem inside the document):

- files larger than ``MAX_FILE_BYTES`` (1 MiB) are not read;
- the text must be UTF-8 without NUL bytes (binary files, UTF-16 and UTF-32 are refused);
- anchors/aliases (``&a`` ... ``*a``) are refused: configuration files have no use for them;
- a key given twice in one mapping is refused with the key and both lines;
- nesting deeper than ``MAX_DEPTH`` levels is refused.

:func:`load_yaml_text` applies the same rules to a YAML text held in memory (a RunMission goal's
``mission_yaml``): no module parses YAML any other way. :func:`short_repr` is how a problem message
quotes a value: at most ``QUOTE_CHARS`` characters, control characters escaped.
"""
import os
import reprlib
from pathlib import Path
from typing import Any

import yaml
from yaml.composer import Composer
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.events import AliasEvent
from yaml.nodes import MappingNode

MAX_FILE_BYTES = 1 << 20
MAX_DEPTH = 32
QUOTE_CHARS = 60


class YamlFileError(ValueError):
    """A YAML file that cannot be used; the message is one line that names the file."""


_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = QUOTE_CHARS
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict, _REPR.maxset = 3, 8, 8, 4, 8


def short_repr(value, limit: int = QUOTE_CHARS) -> str:
    """How a message quotes a value: its repr (control characters escaped, as repr does) cut to about
    `limit` characters; a cut string says its length. Built from pieces (reprlib), so that quoting a
    huge value costs no more than quoting a small one."""
    if isinstance(value, str):
        text = repr(value[:limit])
        if len(value) <= limit and len(text) <= limit + 2:
            return text
        return f"{text[:limit]}... ({len(value)} characters)"
    text = _REPR.repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _line(mark) -> str:
    return f"line {mark.line + 1}" if mark is not None else "unknown line"


class _BoundedLoader(yaml.SafeLoader):
    """SafeLoader without aliases, duplicate keys or deep nesting."""

    def __init__(self, stream):
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent, index):
        if self.check_event(AliasEvent):
            event = self.peek_event()
            raise YamlFileError(f"{_line(event.start_mark)}: alias *{event.anchor} refused "
                                "(anchors and aliases are not allowed in these files)")
        event = self.peek_event()
        if getattr(event, "anchor", None) is not None:
            raise YamlFileError(f"{_line(event.start_mark)}: anchor &{event.anchor} refused "
                                "(anchors and aliases are not allowed in these files)")
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise YamlFileError(f"{_line(event.start_mark)}: nested deeper than {MAX_DEPTH} levels")
            return Composer.compose_node(self, parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):
        if isinstance(node, MappingNode):
            seen = {}
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    hash(key)
                except TypeError:
                    raise ConstructorError(None, None, "found an unhashable key", key_node.start_mark) from None
                if key in seen:
                    raise YamlFileError(f"{_line(key_node.start_mark)}: duplicate key {key!r} "
                                        f"(first given on {_line(seen[key])})")
                seen[key] = key_node.start_mark
        return SafeConstructor.construct_mapping(self, node, deep=deep)


_BoundedLoader.add_constructor("tag:yaml.org,2002:map", _BoundedLoader.construct_yaml_map)


def _decode(data: bytes, source: str) -> str:
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise YamlFileError(f"{source}: not UTF-8 text (a UTF-16/UTF-32 byte-order mark); save it as UTF-8")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise YamlFileError(f"{source}: not a text file (NUL byte at offset {nul})")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise YamlFileError(f"{source}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})") \
            from None


def load_yaml_text(text: str, source: str = "<text>", max_bytes: int = MAX_FILE_BYTES) -> Any:
    """The document of a YAML text (None when empty); YamlFileError naming source on any problem
    (a text over max_bytes is refused unparsed)."""
    if len(text) > max_bytes or len(text.encode("utf-8", "surrogatepass")) > max_bytes:
        raise YamlFileError(f"{source}: larger than {max_bytes} bytes")
    if "\x00" in text:
        raise YamlFileError(f"{source}: not a text file (NUL character)")
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except YamlFileError as exc:
        raise YamlFileError(f"{source}: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        where = f"{_line(mark)}, column {mark.column + 1}: " if mark is not None else ""
        raise YamlFileError(f"{source}: not valid YAML: {where}{problem}") from None
    except RecursionError:  # not reached with MAX_DEPTH, kept as a last guard
        raise YamlFileError(f"{source}: nested too deeply") from None
    finally:
        loader.dispose()


def load_yaml_file(path, max_bytes: int = MAX_FILE_BYTES) -> Any:
    """The document of a YAML file (None when empty); YamlFileError naming the file on any problem
    (a file over max_bytes is not read), FileNotFoundError (an OSError) when it does not exist."""
    path = Path(os.path.expanduser(str(path)))
    source = str(path)
    if not path.exists():
        raise FileNotFoundError(2, "no such file", source)
    if path.is_dir():
        raise YamlFileError(f"{source}: is a folder, not a YAML file")
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as exc:
        raise YamlFileError(f"{source}: cannot read: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise YamlFileError(f"{source}: larger than {max_bytes} bytes ({max_bytes // 1024} KiB): "
                            "not a configuration file")
    return load_yaml_text(_decode(data, source), source, max_bytes)
