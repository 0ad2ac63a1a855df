"""The registry of named physical effects (docs/effects.md; the names are a contract).

One registry maps each effect name to its function, its kind and the parameters it needs
(after PyWavelets' ``thresholding_options`` and pvlib's required-key sets per model).  The
simulator, the fit and the diagnosis all look effects up here, and a user's own effect is
registered exactly like a built-in one::

    from nfs.effects import Parameter, register_effect

    @register_effect("coil_stress_hysteresis", kind="gyro",
                     parameters=[Parameter("k", "deg/h per K", "gain")])
    def coil_stress_hysteresis(ctx, *, k):
        '''Rate error k (T_coil - T_coil(0)) [deg/h]. ...'''
        return k * (ctx.coil_c - ctx.coil_c[0])

A parameter the effect is not linear in (a time constant, an angle) carries the values the
diagnosis tries for it: ``Parameter("tau", "s", "time constant", grid=(30.0, 120.0, 480.0))``.

Such a file is named in a scenario (``effects_files = ["my_effects.py"]``, run only when the
user trusts it: ``--trust-effects``) or exposed as an
entry point in the group ``nfs.effects``.

Kinds and call signatures
-------------------------
``gyro``
    ``f(ctx: EffectContext, **params) -> ndarray`` rate error [deg/h] added to the FOG output.
``accelerometer``
    ``f(ctx: EffectContext, axis: str, **params) -> ndarray`` error [g] added to axis ``x``/``y``.
``thermal``
    ``f(time_s, temperature_c, moving, **params) -> power [W]`` added at the node ``node``;
    ``temperature_c`` is that node's temperature.  Called per sample with scalars when
    ``state_dependent``, else once with arrays.
``thermometer``
    ``f(reading_c, time_s, **params) -> ndarray`` transforms one thermometer reading.
``geometry``
    ``f(geom: Geometry, **params) -> Geometry`` changes where the sensors point (the
    turntable's true angle, the platform tilt, the gyro's input axis): applied before the
    Earth-rate and gravity projections (:mod:`nfs.effects.geometry`).
``null``
    contributes nothing (the explicit null effect, for ablation).
"""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import dataclass, field, replace as replace_fields
from importlib import metadata
from pathlib import Path
from typing import Any, Callable

from ..errors import EffectError, NfsError

__all__ = [
    "KINDS",
    "SHAPE_UNITS",
    "Parameter",
    "EffectSpec",
    "EffectInstance",
    "register_effect",
    "get_effect",
    "available_effects",
    "load_effects_file",
    "make_effect",
]

#: The kinds of effect, i.e. which part of the instrument an effect acts on.
KINDS = ("gyro", "accelerometer", "thermal", "thermometer", "geometry", "null")

ENTRY_POINT_GROUP = "nfs.effects"

#: Units that make a float parameter a shape (the effect is not linear in it): a time
#: constant [s], a temperature period [K], an angle [deg] or [rad].
SHAPE_UNITS = ("s", "K", "deg", "rad")


@dataclass(frozen=True)
class Parameter:
    """One parameter of an effect."""

    name: str
    """Name as written in scenario files (docs/effects.md spelling)."""
    unit: str
    """Unit, e.g. ``deg/h/K``; ``""`` for names and dimensionless numbers."""
    description: str
    """What it is."""
    default: Any = None
    """Default value; ``None`` means required (unless ``optional``)."""
    type: type = float
    """``float`` for numbers, ``int`` for counts (a coil's layers; never fitted), ``str`` for
    names (nodes, channels, axes, a winding pattern), ``tuple`` for a list of numbers (one per
    turntable position, say; ``bounds`` apply to each)."""
    optional: bool = False
    """True when ``None`` is a legal value (the effect then uses its own default target)."""
    shape: bool = False
    """True when the effect is not linear in this parameter although its unit does not say so
    (a time constant [s], a period [K] or an angle are shapes by their unit): a fit or a
    diagnosis holds it at its value, or chooses it on its ``grid``, instead of solving for
    it as a linear coefficient."""
    bounds: tuple[float, float] | None = None
    """Closed interval (low, high) of the values where the effect is physical; a value
    outside raises :class:`~nfs.errors.EffectError` on construction.  None: unbounded."""
    constant: bool = False
    """True for a constant of the design or its materials that a data sheet gives (a
    fibre's index and dn/dT, a coil's length and diameter): units of one design share it,
    so a unit's scatter (:mod:`nfs.variability`) leaves it alone and a fit holds it unless
    named."""
    grid: tuple[float, ...] | None = None
    """Shape parameters only (:attr:`nonlinear`): the values [in ``unit``] at which the
    diagnosis (:mod:`nfs.diagnose`) tries the effect, the best one then refined by least
    squares (inside ``bounds``; a time constant [s] or period [K] without bounds from a
    fifth of the smallest value to five times the largest); its test pays for the choice
    (Bonferroni over the grid's points).  Each value lies inside ``bounds``.  None: the
    diagnosis holds the parameter at its ``default``, and a shape parameter with neither is
    not tried.  E.g. ``Parameter("tau", "s", "time constant", grid=(60.0, 300.0, 1200.0))``."""

    @property
    def required(self) -> bool:
        """True when a scenario must give this parameter."""
        return self.default is None and not self.optional

    @property
    def nonlinear(self) -> bool:
        """True for a shape parameter: a float the effect is not linear in, by its unit
        (:data:`SHAPE_UNITS`) or by ``shape=True``."""
        return self.type is float and (self.shape or self.unit in SHAPE_UNITS)


@dataclass(frozen=True)
class EffectSpec:
    """A registered effect: its name, kind, function and parameters."""

    name: str
    """The registry name (docs/effects.md)."""
    kind: str
    """One of :data:`KINDS`."""
    function: Callable[..., Any]
    """The plain function implementing the effect (its docstring holds the physics)."""
    parameters: tuple[Parameter, ...]
    """Parameters, in the order of docs/effects.md."""
    target: str | None = None
    """Name of the parameter that says where the effect acts (node, axis, thermometer,
    channel), or None."""
    state_dependent: bool = False
    """Thermal effects only: True when the power depends on the node temperature."""
    check: Callable[[dict[str, Any]], None] | None = None
    """Checks the resolved parameters together (a bound on a combination of them) and
    raises EffectError with a one-line message; None: the per-parameter checks suffice."""

    @property
    def summary(self) -> str:
        """First line of the function's docstring."""
        doc = (self.function.__doc__ or "").strip()
        return doc.splitlines()[0] if doc else ""

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise EffectError(
            f"effect '{self.name}' has no parameter '{name}'; its parameters: "
            + ", ".join(p.name for p in self.parameters))

    def resolve(self, params: dict[str, Any], *, where: str = "") -> dict[str, Any]:
        """Check ``params`` against the declared parameters and fill in defaults.

        Raises EffectError naming the unknown or missing parameter and listing the valid ones.
        """
        prefix = f"{where}: " if where else ""
        names = [p.name for p in self.parameters]
        for key in params:
            if key not in names:
                raise EffectError(
                    f"{prefix}effect '{self.name}' has no parameter '{key}'; allowed: "
                    + (", ".join(names) or "(none)"))
        out: dict[str, Any] = {}
        for p in self.parameters:
            if p.name in params:
                value = params[p.name]
                if value is None and p.optional:
                    out[p.name] = None
                    continue
                if p.type is float:
                    if isinstance(value, bool) or not isinstance(value, (int, float)):
                        raise EffectError(f"{prefix}effect '{self.name}' parameter "
                                          f"'{p.name}' must be a number [{p.unit}], got {value!r}")
                    value = float(value)
                    if p.bounds is not None and not p.bounds[0] <= value <= p.bounds[1]:
                        lo, hi = p.bounds
                        raise EffectError(
                            f"{prefix}effect '{self.name}' parameter '{p.name}' = {value:g} "
                            f"[{p.unit}] is outside [{lo:.6g}, {hi:.6g}] ({p.description})")
                elif p.type is int:
                    value = self._count(p, value, prefix)
                elif p.type is str and not isinstance(value, str):
                    raise EffectError(f"{prefix}effect '{self.name}' parameter '{p.name}' "
                                      f"must be a name (string), got {value!r}")
                elif p.type is tuple:
                    value = self._number_list(p, value, prefix)
                out[p.name] = value
            elif p.required:
                raise EffectError(f"{prefix}effect '{self.name}' needs parameter '{p.name}' "
                                  f"[{p.unit}] ({p.description})")
            else:
                out[p.name] = p.default
        if self.check is not None:
            try:
                self.check(out)
            except EffectError as exc:
                raise EffectError(f"{prefix}effect '{self.name}': {exc}") from None
        return out

    def _count(self, p: Parameter, value: Any, prefix: str) -> int:
        """A whole number (an int, or a float with no fraction) inside ``p.bounds``."""
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not float(value).is_integer()):
            raise EffectError(f"{prefix}effect '{self.name}' parameter '{p.name}' must be a "
                              f"whole number, got {value!r}")
        value = int(value)
        if p.bounds is not None and not p.bounds[0] <= value <= p.bounds[1]:
            lo, hi = p.bounds
            raise EffectError(f"{prefix}effect '{self.name}' parameter '{p.name}' = {value} "
                              f"is outside [{lo:g}, {hi:g}] ({p.description})")
        return value

    def _number_list(self, p: Parameter, value: Any, prefix: str) -> tuple[float, ...]:
        """A list of numbers as a tuple of floats, each inside ``p.bounds``."""
        if not isinstance(value, (list, tuple)) or any(
                isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
            raise EffectError(f"{prefix}effect '{self.name}' parameter '{p.name}' must be a "
                              f"list of numbers [{p.unit}], got {value!r}")
        out = tuple(float(v) for v in value)
        if p.bounds is not None:
            lo, hi = p.bounds
            for i, v in enumerate(out):
                if not lo <= v <= hi:
                    raise EffectError(
                        f"{prefix}effect '{self.name}' parameter '{p.name}[{i}]' = {v:g} "
                        f"[{p.unit}] is outside [{lo:.6g}, {hi:.6g}] ({p.description})")
        return out


@dataclass(frozen=True)
class EffectInstance:
    """An effect switched on in an instrument, with its resolved parameters."""

    spec: EffectSpec
    """The registered effect."""
    params: dict[str, Any] = field(default_factory=dict)
    """Resolved parameters (defaults filled in)."""

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def target_value(self) -> Any:
        """The value of the target parameter (a node, axis, thermometer or channel), or None."""
        return None if self.spec.target is None else self.params.get(self.spec.target)

    @property
    def label(self) -> str:
        """``name`` or ``name:target``: how the contribution is labelled in results."""
        t = self.target_value
        return self.name if t is None else f"{self.name}:{t}"

    def to_dict(self) -> dict[str, Any]:
        """The scenario-file form: ``{"name": ..., **params}`` without None values."""
        out: dict[str, Any] = {"name": self.name}
        out.update({k: list(v) if isinstance(v, tuple) else v
                    for k, v in self.params.items() if v is not None})
        return out


_REGISTRY: dict[str, EffectSpec] = {}
_entry_points_loaded = False


def register_effect(name: str, *, kind: str, parameters: list[Parameter] | tuple = (),
                    target: str | None = None, state_dependent: bool = False,
                    check: Callable[[dict[str, Any]], None] | None = None,
                    replace: bool = False) -> Callable[[Callable], Callable]:
    """Decorator that registers ``function`` under ``name``.

    Parameters
    ----------
    name : str
        Registry name; must be new unless ``replace``.
    kind : str
        One of :data:`KINDS`.
    parameters : list of Parameter
        What the effect needs, with units; a shape parameter's ``grid`` (the values the
        diagnosis tries) is checked here against its bounds.
    target : str, optional
        Name of the parameter that says where the effect acts.
    state_dependent : bool
        Thermal effects: the power depends on the node temperature (evaluated per sample,
        with a float temperature, or with an array of the temperatures of runs simulated
        together: the function must give the same value for a float and for the same
        number in an array).
    check : callable, optional
        ``check(params)`` raises EffectError when the parameters are unphysical together.
    replace : bool
        Allow re-registering an existing name (for reloading a user's file).
    """
    if kind not in KINDS:
        raise EffectError(f"effect '{name}': kind '{kind}' is not one of {', '.join(KINDS)}")
    params = tuple(_with_checked_grid(name, p) for p in parameters)
    if target is not None and target not in [p.name for p in params]:
        raise EffectError(f"effect '{name}': target '{target}' is not one of its parameters")

    def decorator(function: Callable) -> Callable:
        old = _REGISTRY.get(name)
        same_origin = old is not None and (
            (old.function.__module__, old.function.__qualname__)
            == (function.__module__, function.__qualname__))
        if old is not None and not (replace or same_origin):
            raise EffectError(f"an effect named '{name}' is registered already")
        _REGISTRY[name] = EffectSpec(name=name, kind=kind, function=function,
                                     parameters=params, target=target,
                                     state_dependent=state_dependent, check=check)
        return function

    return decorator


def _with_checked_grid(effect: str, p: Parameter) -> Parameter:
    """``p`` with its grid as a tuple of floats; EffectError when the grid is empty, not
    numbers, outside ``p.bounds`` or on a parameter the effect is linear in."""
    if p.grid is None:
        return p
    where = f"effect '{effect}' parameter '{p.name}'"
    if not p.nonlinear:
        raise EffectError(f"{where}: a grid is for a shape parameter (unit "
                          f"{', '.join(SHAPE_UNITS)} or shape=True); unit '{p.unit}' makes "
                          "it a linear coefficient, which the diagnosis solves for")
    if not isinstance(p.grid, (list, tuple)) or not p.grid or any(
            isinstance(v, bool) or not isinstance(v, (int, float)) for v in p.grid):
        raise EffectError(f"{where}: grid must be a non-empty tuple of numbers [{p.unit}], "
                          f"got {p.grid!r}")
    grid = tuple(float(v) for v in p.grid)
    if p.bounds is not None:
        lo, hi = p.bounds
        outside = [v for v in grid if not lo <= v <= hi]
        if outside:
            raise EffectError(f"{where}: grid value(s) {', '.join(f'{v:g}' for v in outside)} "
                              f"[{p.unit}] outside its bounds [{lo:.6g}, {hi:.6g}]")
    return replace_fields(p, grid=grid)


def _load_entry_points() -> None:
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            ep.load()  # importing the module runs its @register_effect decorators
        except Exception as exc:  # a broken plug-in must not break the built-ins
            raise EffectError(f"entry point '{ep.name}' in group '{ENTRY_POINT_GROUP}' "
                              f"failed to load: {exc}") from exc


def available_effects(kind: str | None = None) -> list[str]:
    """Sorted names of the registered effects (of one kind if given)."""
    _load_entry_points()
    return sorted(n for n, s in _REGISTRY.items() if kind is None or s.kind == kind)


def get_effect(name: str) -> EffectSpec:
    """The effect registered under ``name``; EffectError listing the valid names if none."""
    if name not in _REGISTRY:
        _load_entry_points()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise EffectError(f"unknown effect '{name}'; valid names: "
                          + ", ".join(available_effects())) from None


def make_effect(name: str, params: dict[str, Any] | None = None, *,
                where: str = "") -> EffectInstance:
    """Look up ``name`` and resolve ``params`` into an :class:`EffectInstance`."""
    spec = get_effect(name)
    return EffectInstance(spec=spec, params=spec.resolve(dict(params or {}), where=where))


def load_effects_file(path: str | Path) -> None:
    """Execute a user's Python file whose ``@register_effect`` decorators add effects."""
    path = Path(path)
    if not path.is_file():
        raise EffectError(f"{path}: effects file not found")
    module_name = f"nfs_user_effects_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise EffectError(f"{path}: cannot load as a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except NfsError:
        raise
    except Exception as exc:
        raise EffectError(f"{path}: {type(exc).__name__}: {exc}") from exc
