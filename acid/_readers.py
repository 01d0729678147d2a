"""Reading TOML and JSON files a user hands to acid: bounded size, bounded depth, one line.

Every reader of a TOML or JSON file (params.json, econ parameters, plant configurations,
sweep specifications, FMU maps, ``summary.json``) goes through :func:`load_toml` or
:func:`load_json`. They refuse, with one line naming the file (and the key where there is
one), a file larger than ``max_bytes`` (checked before it is read), text that is not UTF-8,
syntax errors, nesting deeper than ``max_depth`` (refused while scanning, before the parser
recurses; dotted TOML keys are checked on the parsed tree) and a top level of the wrong
kind. What a reader then does with the values is its own business.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from acid.errors import AcidError, ConfigError, DataError

#: largest TOML / JSON file acid reads, bytes (acid's own files are a few kB; a summary.json
#: of a long reproduce run well under 1 MB)
MAX_BYTES = 16 * 1024 * 1024
#: deepest nesting of tables / arrays (acid's files nest at most 5 levels)
MAX_DEPTH = 32


def read_text(path: str | os.PathLike, what: str = "file", error: type[AcidError] = DataError,
              max_bytes: int = MAX_BYTES, kind: str = "text") -> str:
    """The UTF-8 text of ``path``, refused (``error``, one line) when it is missing, not a
    file, larger than ``max_bytes`` or not UTF-8."""
    path = Path(path)
    if not path.is_file():
        raise error(f"{path}: {what} not found" if not path.exists()
                    else f"{path}: {what} is not a file")
    try:
        with open(path, "rb") as fh:
            raw = fh.read(max_bytes + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read {what} ({exc.strerror or type(exc).__name__})") \
            from None
    if len(raw) > max_bytes:
        raise error(f"{path}: {what} is larger than {max_bytes // (1024 * 1024)} MB")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not valid {kind} (not UTF-8 text at byte {exc.start})") from None


def nesting_depth(text: str, toml: bool = False) -> int:
    """Deepest bracket nesting (``[``/``{``) of JSON or TOML text, strings and (TOML)
    comments skipped; a linear scan, so it cannot recurse."""
    depth = deepest = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == '"' or (toml and c == "'"):
            triple = toml and text.startswith(c * 3, i)
            end = c * 3 if triple else c
            i += len(end)
            while i < n and not text.startswith(end, i):
                if c == '"' and text[i] == "\\":
                    i += 1
                elif not triple and text[i] == "\n":
                    break
                i += 1
            i += len(end)
            continue
        if toml and c == "#":
            nl = text.find("\n", i)
            i = n if nl < 0 else nl + 1
            continue
        if c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


def _first_line(exc: BaseException) -> str:
    text = str(exc).splitlines()
    return text[0] if text and text[0] else type(exc).__name__


def _check_depth(text: str, path: Path, what: str, error, max_depth: int, toml: bool) -> None:
    d = nesting_depth(text, toml=toml)
    if d > max_depth:
        raise error(f"{path}: {what} nests {d} levels deep (at most {max_depth})")


def check_tree(obj, source: str, error: type[AcidError] = DataError,
               max_depth: int = MAX_DEPTH, finite: bool = False) -> None:
    """Refuse a parsed tree nested deeper than ``max_depth`` (dotted TOML keys nest without
    brackets), or holding NaN or an infinity when ``finite`` (JSON has no such numbers),
    naming the first key path that does; iterative."""
    stack = [(obj, "", 0)]
    while stack:
        node, where, depth = stack.pop()
        if depth > max_depth:
            raise error(f"{source}: {where or 'the top level'} nests deeper than {max_depth} "
                        "levels")
        if finite and isinstance(node, float) and not math.isfinite(node):
            raise error(f"{source}: {where or 'the top level'} = {node} is a non-finite "
                        "number (JSON has no NaN or infinity)")
        if isinstance(node, dict):
            stack.extend((v, f"{where}.{k}" if where else str(k), depth + 1)
                         for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(node))


def load_json(path: str | os.PathLike, what: str = "JSON file",
              error: type[AcidError] = DataError, max_bytes: int = MAX_BYTES,
              max_depth: int = MAX_DEPTH, top: type | None = dict):
    """Parse a JSON file (see the module docstring); ``top`` the required type of the top
    level (None: any). NaN and infinities are refused, naming their key (not JSON)."""
    path = Path(path)
    text = read_text(path, what, error, max_bytes, "JSON")
    _check_depth(text, path, what, error, max_depth, toml=False)

    try:
        obj = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise error(f"{path}: not valid JSON ({_first_line(exc)})") from None
    check_tree(obj, str(path), error, max_depth, finite=True)
    if top is not None and not isinstance(obj, top):
        kind = {dict: "object", list: "array"}.get(top, top.__name__)
        raise error(f"{path}: {what} must be a JSON {kind} at the top level, got "
                    f"{_kind(obj)}")
    return obj


def load_toml(path: str | os.PathLike, what: str = "TOML file",
              error: type[AcidError] = ConfigError, max_bytes: int = MAX_BYTES,
              max_depth: int = MAX_DEPTH) -> dict:
    """Parse a TOML file (see the module docstring)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python < 3.11
        import tomli as tomllib
    path = Path(path)
    text = read_text(path, what, error, max_bytes, "TOML")
    _check_depth(text, path, what, error, max_depth, toml=True)
    try:
        d = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError, RecursionError) as exc:
        raise error(f"{path}: not valid TOML ({_first_line(exc)})") from None
    check_tree(d, str(path), error, max_depth)
    return d


def _kind(value) -> str:
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, bool):
        return "a boolean"
    if value is None:
        return "null"
    return "a number" if isinstance(value, (int, float)) else type(value).__name__


__all__ = ["load_json", "load_toml", "read_text", "nesting_depth", "check_tree", "MAX_BYTES",
           "MAX_DEPTH"]
