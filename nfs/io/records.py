"""Results as JSON: every field of a frozen result, written and read back by its type.

The results a unit's chain hands from step to step (the fit, the comparison, the diagnosis,
the settlement of a tie, the design: :mod:`nfs.unit`) are frozen dataclasses.  Each one's
``to_dict`` / ``from_dict`` is :func:`encode` / :func:`decode` of its fields, read from the
type annotations, so the JSON schema is the class itself and nothing parses prose:

- numbers as JSON numbers; a non-finite float as the string ``"inf"``, ``"-inf"`` or
  ``"nan"`` (JSON has none, and an infinite standard error means "not identifiable");
- NumPy arrays as nested lists (read back as float arrays);
- tuples and lists as lists; a dict with non-string keys (a start temperature, a pair of
  rival indices) with the key written as text (``"20.0"``, ``"0,1"``);
- an object with ``to_toml()`` (an :class:`~nfs.instrument.Instrument`) as its TOML text (the
  file ``nfs fit`` writes), read back by its class's ``from_toml_text``;
- a field marked ``field(metadata={"record": False})`` (a trace kept for a figure, which
  the inputs reproduce) is left out and read back as its default (an empty array);
- a nested result as an object that names its class (``"record"``), with the properties
  its class lists in ``DERIVED`` (an answer, a ratio) written beside its fields for a reader
  and recomputed when read; where the annotation does not say which result (``Any``), that
  name is looked up in :data:`RECORDS` (only classes registered with :func:`record`: reading
  a file never imports or runs anything it names).

Nothing is pickled: a results file is data, safe to read from anywhere.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
import warnings
from typing import Any, Union

import numpy as np

from ..errors import NfsError
from ..ranges import RangeWarning

__all__ = ["RECORDS", "record", "encode", "decode", "to_record", "from_record", "RecordError"]

#: Result classes that may appear where an annotation says ``Any``, by class name.
RECORDS: dict[str, type] = {}


class RecordError(NfsError):
    """A results file whose content does not match its result's fields."""


def record(cls: type) -> type:
    """Register a dataclass so that it can be read back where a field is ``Any``."""
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"{cls.__name__} is not a dataclass")
    RECORDS[cls.__name__] = cls
    return cls


def _hints(cls: type) -> dict[str, Any]:
    """The resolved annotations of a result's fields."""
    try:
        return typing.get_type_hints(cls)
    except NameError as exc:      # an annotation only a type checker sees
        raise RecordError(f"{cls.__name__}: a field's type cannot be read ({exc})") from None


def _key(k: Any) -> str:
    if isinstance(k, tuple):
        return ",".join(str(x) for x in k)
    return str(k)


def _float(x: float) -> float | str:
    x = float(x)
    if math.isfinite(x):
        return x
    return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")


def encode(value: Any, tag: bool = False) -> Any:
    """``value`` as JSON-ready data (module docstring); ``tag``: name a dataclass's class."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, np.bool_):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        return _float(value)
    if hasattr(value, "to_toml") and hasattr(type(value), "from_toml_text"):
        return {"toml": value.to_toml()}
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            return [encode(x) for x in value.tolist()] if value.ndim else _float(value)
        return value.tolist()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out = {f.name: encode(getattr(value, f.name), True)
               for f in dataclasses.fields(value) if f.init and f.metadata.get("record", True)}
        # what a reader wants beside the fields (a property: an answer, a ratio), written for
        # reading and recomputed, not read, by decode
        out.update({k: encode(getattr(value, k), True) for k in getattr(value, "DERIVED", ())})
        return {"record": type(value).__name__, **out} if tag else out
    if isinstance(value, dict):
        return {_key(k): encode(v, True) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [encode(v, True) for v in value]
    raise TypeError(f"cannot write {type(value).__name__} as JSON")


def decode(data: Any, hint: Any, where: str = "") -> Any:
    """Read ``data`` (written by :func:`encode`) back as type ``hint``."""
    try:
        return _decode(data, hint, where or getattr(hint, "__name__", "value"))
    except RecordError:
        raise
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        raise RecordError(f"{where or hint}: {exc}") from None


def _decode(data: Any, hint: Any, where: str) -> Any:
    if hint is Any or hint is object:
        return _untyped(data, where)
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (Union, types.UnionType):
        if data is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _decode(data, a, where)
            except (TypeError, ValueError, KeyError, AttributeError, RecordError) as exc:
                errors.append(str(exc))
        raise RecordError(f"{where}: none of {hint} fits ({'; '.join(errors)})")
    if data is None:
        return None
    if hint is float:
        return float(data)          # "inf", "-inf" and "nan" read as floats
    if hint is int:
        return int(data)
    if hint in (str, bool):
        if not isinstance(data, hint):
            raise RecordError(f"{where}: expected {hint.__name__}, got {type(data).__name__}")
        return data
    if hint is np.ndarray:
        return np.asarray(_floats(data), dtype=float)
    if isinstance(hint, type) and hasattr(hint, "from_toml_text"):
        with warnings.catch_warnings():
            # the result that wrote this instrument reported its unusual values when it was
            # made (a fit's departures from the typical ranges are in its own record); read
            # back, it is not a user's input: the hard limits still apply, the notes do not
            warnings.simplefilter("ignore", RangeWarning)
            return hint.from_toml_text(data["toml"], where)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(x, args[0], f"{where}[{i}]") for i, x in enumerate(data))
        if args:
            return tuple(_decode(x, a, f"{where}[{i}]") for i, (x, a) in
                         enumerate(zip(data, args)))
        return tuple(_untyped(x, where) for x in data)
    if origin is list or hint is list:
        a = args[0] if args else Any
        return [_decode(x, a, f"{where}[{i}]") for i, x in enumerate(data)]
    if origin is dict or hint is dict:
        kt, vt = args if args else (str, Any)
        return {_read_key(k, kt): _decode(v, vt, f"{where}.{k}") for k, v in data.items()}
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return _dataclass(data, hint, where)
    if isinstance(hint, str):
        raise RecordError(f"{where}: unresolved annotation {hint!r}")
    raise RecordError(f"{where}: cannot read a {hint}")


def _floats(data: Any) -> Any:
    if isinstance(data, list):
        return [_floats(x) for x in data]
    return float(data)


def _read_key(k: str, kt: Any) -> Any:
    if kt is float:
        return float(k)
    if kt is int:
        return int(k)
    if typing.get_origin(kt) is tuple:
        return tuple(int(x) for x in k.split(","))
    return k


def _untyped(data: Any, where: str) -> Any:
    """A value whose annotation is ``Any``: a tagged record, or plain JSON data."""
    if isinstance(data, dict):
        name = data.get("record")
        if isinstance(name, str):
            cls = RECORDS.get(name)
            if cls is None:
                raise RecordError(f"{where}: unknown record {name!r} (known: "
                                  f"{', '.join(sorted(RECORDS))})")
            return _dataclass({k: v for k, v in data.items() if k != "record"}, cls, where)
        return {k: _untyped(v, f"{where}.{k}") for k, v in data.items()}
    if isinstance(data, list):
        return [_untyped(v, where) for v in data]
    return data


def _dataclass(data: Any, cls: type, where: str) -> Any:
    if not isinstance(data, dict):
        raise RecordError(f"{where}: expected an object for {cls.__name__}, got "
                          f"{type(data).__name__}")
    hints = _hints(cls)
    known = {f.name: f for f in dataclasses.fields(cls)
             if f.init and f.metadata.get("record", True)}
    skipped = {f.name: f for f in dataclasses.fields(cls)
               if f.init and not f.metadata.get("record", True)}
    unknown = sorted(set(data) - set(known) - {"record", "schema"}
                     - set(getattr(cls, "DERIVED", ())))
    if unknown:
        raise RecordError(f"{where}: unknown key(s) {', '.join(unknown)} for {cls.__name__}")
    kwargs = {}
    for name, f in known.items():
        if name in data:
            kwargs[name] = _decode(data[name], hints[name], f"{where}.{name}")
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise RecordError(f"{where}: missing key {name!r} for {cls.__name__}")
    for name, f in skipped.items():
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            # a trace left out of the record: an empty one
            kwargs[name] = np.zeros(0) if hints[name] is np.ndarray else None
    return cls(**kwargs)


def to_record(obj: Any, schema: str) -> dict[str, Any]:
    """A result as the JSON object its ``to_dict`` returns: ``{"schema": schema, fields}``."""
    return {"schema": schema, **encode(obj)}


def from_record(cls: type, data: Any, schema: str, where: str = "") -> Any:
    """The result of class ``cls`` from :func:`to_record`'s object, its schema checked."""
    where = where or cls.__name__
    if not isinstance(data, dict):
        raise RecordError(f"{where}: expected a JSON object written by {cls.__name__}.to_dict")
    found = data.get("schema", schema)
    if found != schema:
        raise RecordError(f"{where}: schema {found!r}, expected {schema!r}")
    return decode(data, cls, where)
