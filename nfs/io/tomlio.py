"""Reading TOML configuration with errors that name the file and the dotted key."""

from __future__ import annotations

import datetime as _dt
import math
import re
import tomllib
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from ..errors import ScenarioError

__all__ = ["load_toml", "check_keys", "number", "integer", "boolean", "string", "number_list",
           "table", "dumps_toml",
           "toml_value", "toml_key", "toml_string"]


def load_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; ScenarioError naming the file on a missing file or a syntax error."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ScenarioError("file not found", file=path) from None
    except IsADirectoryError:
        raise ScenarioError("is a folder, expected a TOML file", file=path) from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"TOML syntax error: {exc}", file=path) from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"not UTF-8 text: {exc}", file=path) from None


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def check_keys(tbl: dict[str, Any], allowed: Iterable[str], prefix: str, file: Any,
               required: Iterable[str] = ()) -> None:
    """Reject unknown keys (naming the key and the allowed ones) and missing required keys."""
    allowed = list(allowed)
    for key in tbl:
        if key not in allowed:
            raise ScenarioError(f"unknown key; allowed keys here: {', '.join(allowed)}",
                                file=file, key=_join(prefix, key))
    for key in required:
        if key not in tbl:
            raise ScenarioError("required key is missing", file=file, key=_join(prefix, key))


_MISSING = object()


def _lookup(tbl: dict[str, Any], key: str, prefix: str, file: Any, default: Any):
    """(dotted name, value); the value is _MISSING when the key is absent and a default is
    given; ScenarioError when a required key (default ``...``) is absent."""
    name = _join(prefix, key)
    if key in tbl:
        return name, tbl[key]
    if default is ...:
        raise ScenarioError("required key is missing", file=file, key=name)
    return name, _MISSING


def table(tbl: dict[str, Any], key: str, prefix: str, file: Any,
          default: dict | None = None) -> dict[str, Any]:
    """A sub-table (ScenarioError if the value is not a table)."""
    if key not in tbl:
        if default is None:
            raise ScenarioError("required table is missing", file=file, key=_join(prefix, key))
        return default
    value = tbl[key]
    if not isinstance(value, dict):
        raise ScenarioError(f"must be a table, got {value!r}", file=file, key=_join(prefix, key))
    return value


def number(tbl: dict[str, Any], key: str, prefix: str, file: Any, default: Any = ...,
           *, minimum: float | None = None, positive: bool = False,
           maximum: float | None = None) -> float:
    """A finite number, optionally bounded; ScenarioError naming the dotted key otherwise."""
    name, value = _lookup(tbl, key, prefix, file, default)
    if value is _MISSING:
        return default
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ScenarioError(f"must be a finite number, got {value!r}", file=file, key=name)
    value = float(value)
    if positive and not value > 0:
        raise ScenarioError(f"must be > 0, got {value!r}", file=file, key=name)
    if minimum is not None and value < minimum:
        raise ScenarioError(f"must be >= {minimum}, got {value!r}", file=file, key=name)
    if maximum is not None and value > maximum:
        raise ScenarioError(f"must be <= {maximum}, got {value!r}", file=file, key=name)
    return value


def integer(tbl: dict[str, Any], key: str, prefix: str, file: Any, default: Any = ...,
            minimum: int | None = None) -> int:
    """An integer (not a bool), optionally ``>= minimum``."""
    name, value = _lookup(tbl, key, prefix, file, default)
    if value is _MISSING:
        return default
    if (isinstance(value, bool) or not isinstance(value, int)
            or (minimum is not None and value < minimum)):
        raise ScenarioError(f"must be an integer{'' if minimum is None else f' >= {minimum}'}"
                            f", got {value!r}", file=file, key=name)
    return value


def boolean(tbl: dict[str, Any], key: str, prefix: str, file: Any,
            default: Any = ...) -> bool:
    """``true`` or ``false``."""
    name, value = _lookup(tbl, key, prefix, file, default)
    if value is _MISSING:
        return default
    if not isinstance(value, bool):
        raise ScenarioError(f"must be true or false, got {value!r}", file=file, key=name)
    return value


def string(tbl: dict[str, Any], key: str, prefix: str, file: Any, default: Any = ...,
           choices: Iterable[str] | None = None) -> str:
    """A string, optionally one of ``choices``."""
    name, value = _lookup(tbl, key, prefix, file, default)
    if value is _MISSING:
        return default
    if not isinstance(value, str):
        raise ScenarioError(f"must be a string, got {value!r}", file=file, key=name)
    if choices is not None and value not in list(choices):
        raise ScenarioError(f"'{value}' is not one of {', '.join(choices)}", file=file, key=name)
    return value


def number_list(tbl: dict[str, Any], key: str, prefix: str, file: Any, default: Any = ...,
                *, nonempty: bool = True) -> tuple[float, ...]:
    """A list of finite numbers (non-empty unless told otherwise)."""
    name, value = _lookup(tbl, key, prefix, file, default)
    if value is _MISSING:
        return default
    if not isinstance(value, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value):
        raise ScenarioError(f"must be a list of numbers, got {value!r}", file=file, key=name)
    if nonempty and not value:
        raise ScenarioError("must not be empty", file=file, key=name)
    return tuple(float(v) for v in value)


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n",
                 "\f": "\\f", "\r": "\\r"}


def toml_string(text: str) -> str:
    """A TOML basic string with every character that needs it escaped."""
    out = []
    for char in text:
        if char in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[char])
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\u{ord(char):04X}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def toml_key(key: str) -> str:
    """A bare key when allowed, else a quoted one."""
    return key if _BARE_KEY.fullmatch(key) else toml_string(key)


def toml_value(value: Any) -> str:
    """One TOML value, inline (arrays and tables on one line); TypeError if not writable.

    Floats are written in their shortest exact form (``repr``), so they read back bitwise.
    """
    if isinstance(value, np.generic):
        value = value.item()
    elif isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, (_dt.datetime, _dt.date, _dt.time)):
        return value.isoformat()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{toml_key(str(k))} = {toml_value(v)}" for k, v in value.items())
        return "{" + (f" {items} " if items else "") + "}"
    raise TypeError(f"cannot write a {type(value).__name__} to TOML")


def dumps_toml(data: dict[str, Any], _prefix: str = "") -> str:
    """Write nested dicts / lists of dicts as TOML.

    Written here because the standard library's tomllib only reads; the package writes
    scenario, instrument and measurement metadata files, whose values are numbers, strings,
    booleans, lists of numbers, inline tables, tables and arrays of tables.
    """
    lines: list[str] = []
    scalars = {k: v for k, v in data.items()
               if not isinstance(v, dict) and not _is_table_array(v)}
    for k, v in scalars.items():
        lines.append(f"{toml_key(k)} = {toml_value(v)}")
    for k, v in data.items():
        name = _join(_prefix, toml_key(k))
        if isinstance(v, dict):
            tables, header = [v], f"[{name}]"
        elif _is_table_array(v):
            tables, header = v, f"[[{name}]]"
        else:
            continue
        for table in tables:
            if lines:
                lines.append("")
            lines.append(header)
            body = dumps_toml(table, name)
            if body:
                lines.append(body)
    return "\n".join(lines).replace("\n\n\n", "\n\n")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)
