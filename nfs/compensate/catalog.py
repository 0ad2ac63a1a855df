"""The names of the compensation methods, known without building one.

What a scenario's reader needs to check ``[compensation] methods`` (is the name a method,
its key, is it tuned, the default rows): the registered methods (:data:`METHODS`, filled by
:func:`nfs.compensate.registry.register_method`) and the built-in ones by name
(:data:`BUILTIN`), so that reading a scenario imports neither scikit-learn nor the learners
(:mod:`~nfs.compensate.methods` builds them, and registers them when it is imported; a test
holds :data:`BUILTIN` equal to what it registers).  Methods a package exposes as an entry
point in the group :data:`ENTRY_POINT_GROUP` are loaded on the first look-up that misses.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import metadata
from typing import Any, Callable

from ..errors import NfsError

__all__ = ["MethodError", "MethodSpec", "METHODS", "BUILTIN", "OTHER_GROUP",
           "ENTRY_POINT_GROUP", "MethodName", "find_method", "lookup_method",
           "known_methods", "table_methods", "load_entry_points"]

#: Figure panel of a method registered without a ``group``.
OTHER_GROUP = "other methods"

#: Entry-point group whose modules register methods when imported.
ENTRY_POINT_GROUP = "nfs.compensation_methods"


class MethodError(NfsError):
    """An unknown compensation method, or one registered wrongly."""


@dataclass(frozen=True)
class MethodSpec:
    """A compensation method: a table row and how to build its estimator."""

    name: str
    """Row label in the tables (e.g. ``SSA-SVR``)."""
    key: str
    """Command-line key (e.g. ``ssa-svr``)."""
    tuned: bool
    """True when hyperparameters are searched with a budget of evaluations (its ``fit``
    takes the validation groups: whole start-ups left out)."""
    build: Callable[..., Any]
    """build(budget=, random_state=, n_jobs=) -> unfitted estimator."""
    reference: str
    """Where the method comes from."""
    max_samples: int | None = None
    """Training samples at most (every k-th sample is kept above it, k = ceil(n /
    max_samples)): for the models whose searches cost O(n^2) (SVR) or O(n^3) (RVR) per fit;
    stated in the table notes."""
    tuner: str | None = None
    """The tuner of a tuned method (``grid``, ``pso``, ...)."""
    cost: float = 1.0
    """Cost of one training [s of CPU, default scenario, measured one training at a time on
    one thread of a loaded 2-core machine: only their order matters] (the study dispatches
    the costliest first, so that its workers finish together)."""
    group: str = OTHER_GROUP
    """Panel of the table's figure the row is drawn in."""
    table: bool = True
    """A row of every table whose settings name no methods (:func:`table_methods`)."""
    model_classes: tuple[type, ...] = ()
    """Classes other than the package's own estimators that the fitted estimator holds,
    which a model file may then name and read back (:mod:`~nfs.compensate.model_file`)."""

    @property
    def seeded(self) -> bool:
        """True when training depends on the random_state through a tuner's draws (a grid
        search draws nothing)."""
        return self.tuner is not None and self.tuner != "grid"


#: Every registered method by key, in registration order (the table's order).
METHODS: dict[str, MethodSpec] = {}


@dataclass(frozen=True)
class MethodName:
    """What a name says of a method without building it."""

    key: str
    """Command-line key (``ssa-svr``)."""
    name: str
    """Row label (``SSA-SVR``)."""
    tuned: bool
    """Its hyperparameters are searched (it has a tuner)."""
    table: bool = True
    """A row of a table whose settings name no methods."""


#: The methods of the seed papers (:mod:`~nfs.compensate.methods`), in their table order.
BUILTIN: dict[str, MethodName] = {m.key: m for m in (
    MethodName("ls", "LS", False), MethodName("stepwise", "stepwise", False),
    MethodName("bp", "BP", False), MethodName("rbf", "RBF", False),
    MethodName("lssvm", "LSSVM", False), MethodName("ir-lssvm", "IR-LSSVM", False),
    MethodName("svr-grid", "SVR (grid)", True), MethodName("pso-svr", "PSO-SVR", True),
    MethodName("gwo-svr", "GWO-SVR", True), MethodName("ssa-svr", "SSA-SVR", True),
    MethodName("hho-rvr", "HHO-RVR", True), MethodName("tpe-svr", "TPE-SVR", True, False))}

_entry_points_loaded = False


def load_entry_points() -> None:
    """Import, once, the modules that register methods through an entry point."""
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            ep.load()        # importing the module runs its register_method calls
        except Exception as exc:  # a broken plug-in must not pass for a missing method
            raise MethodError(f"entry point '{ep.name}' in group '{ENTRY_POINT_GROUP}' "
                              f"failed to load: {exc}") from exc


def find_method(name: Any) -> MethodSpec | None:
    """The registered method of key or row label ``name``, or None."""
    if not isinstance(name, str):
        return None
    spec = METHODS.get(name) or METHODS.get(name.lower())
    return spec or next((m for m in METHODS.values() if m.name == name), None)


def _names() -> dict[str, MethodName]:
    """Every known method by key: the built-in ones, then the registered ones (a
    registration replaces a built-in's entry)."""
    out = dict(BUILTIN)
    for k, m in METHODS.items():
        out[k] = MethodName(m.key, m.name, m.tuned, m.table)
    return out


def lookup_method(name: str) -> MethodName:
    """A method by key or row label, known without building it; MethodError listing the
    known ones."""
    for attempt in range(2):
        if isinstance(name, str):
            names = _names()
            hit = names.get(name) or names.get(name.lower()) or next(
                (m for m in names.values() if m.name == name), None)
            if hit is not None:
                return hit
        if attempt == 0:
            load_entry_points()
    raise MethodError(f"unknown compensation method '{name}'; methods: "
                      + ", ".join(known_methods()))


def known_methods() -> list[str]:
    """The keys of every known method, the built-in ones first."""
    load_entry_points()
    return list(_names())


def table_methods() -> tuple[str, ...]:
    """The keys of the rows of a table whose settings name no methods, in order: every
    method known with ``table=True``."""
    load_entry_points()
    return tuple(k for k, m in _names().items() if m.table)
