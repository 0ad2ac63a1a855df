"""Exception hierarchy (after python-control's ``exception.py``), and names that moved.

Every error a user can cause by bad input is an :class:`NfsError` whose ``str`` is one line
that locates the fault (file, key, column, row).  The CLI turns it into that line on stderr
and exit code 2, never a traceback.

A package whose public names moved keeps answering for them for one release
(:func:`moved_names`, a PEP 562 module ``__getattr__``) with a :class:`DeprecationWarning`
that names the new home.
"""

from __future__ import annotations

import warnings
from importlib import import_module
from pathlib import Path
from typing import Any, Callable, Mapping

from thermal.errors import ThermalError

__all__ = [
    "NfsError",
    "InputError",
    "MeasurementError",
    "ScenarioError",
    "EffectError",
    "ThermalError",
    "USER_ERRORS",
    "moved_names",
]


class NfsError(Exception):
    """Base class of every error the package raises on purpose."""


class InputError(NfsError):
    """Bad input, located by file, key, column and row where they are known.

    Parameters
    ----------
    message : str
        What is wrong, in one line.
    file : str or Path, optional
        The file that holds the fault.
    key : str, optional
        A TOML key (dotted) that holds the fault.
    column : str, optional
        A CSV column that holds the fault.
    row : int, optional
        The 1-based line number in the file (the header is line 1).
    """

    def __init__(self, message: str, *, file: str | Path | None = None,
                 key: str | None = None, column: str | None = None,
                 row: int | None = None) -> None:
        self.message = message
        self.file = None if file is None else str(file)
        self.key = key
        self.column = column
        self.row = row
        where = []
        if self.file is not None:
            where.append(self.file)
        if key is not None:
            where.append(f"key '{key}'")
        if column is not None:
            where.append(f"column '{column}'")
        if row is not None:
            where.append(f"row {row}")
        prefix = ", ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class MeasurementError(InputError):
    """A measurement file (``nfs-measurement/1``) that cannot be used."""


class ScenarioError(InputError):
    """A scenario or instrument TOML file that cannot be used."""


class EffectError(NfsError):
    """An unknown effect name, a missing or unknown effect parameter, a bad target."""


#: Every error a user's input can cause: the package's own and the thermal network's (the
#: thermal package stands alone and raises its own :class:`thermal.ThermalError`, a
#: ValueError, for a network that is not physical). The CLI prints either as one line.
USER_ERRORS = (NfsError, ThermalError)


def moved_names(package: str, moved: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` that hands over each name of ``moved`` (name
    -> the module that has it now) with a DeprecationWarning, and raises AttributeError for
    any other."""
    def __getattr__(name: str) -> Any:
        module = moved.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        warnings.warn(f"{package}.{name} moved to {module}.{name}; import it from there (the "
                      "old name goes in the next release)", DeprecationWarning, stacklevel=2)
        return getattr(import_module(module), name)
    return __getattr__
