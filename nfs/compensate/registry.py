"""The registry of compensation methods: a key -> how to build its estimator, and its row.

In the shape of the tuners' registry (:mod:`nfs.learners.tuners.registry`) and the effects'
(:mod:`nfs.effects.registry`): :data:`METHODS` maps each key to its :class:`MethodSpec`,
:func:`register_method` adds one, :func:`get_method` looks one up by key or row label (an
unknown name is one line that lists the known ones).  The methods of the seed papers
(:mod:`~nfs.compensate.methods`) are registered exactly as a user's own, and everything that
enumerates methods reads this registry: a scenario's ``[compensation] methods``, the rows of
a table whose settings name none (:func:`table_methods`), the studies, ``nfs train
--method``, and the model files (the classes a method lists in ``model_classes`` are the
ones a file may hold beside the package's own).

A user's own method, a scikit-learn regressor on the thermometer features (drift [deg/h]
from the features of :mod:`~nfs.compensate.features`)::

    from sklearn.linear_model import Ridge
    from sklearn.pipeline import Pipeline, make_pipeline
    from sklearn.preprocessing import StandardScaler
    from nfs.compensate import register_method

    register_method("ridge", make_pipeline(StandardScaler(), Ridge(alpha=1e-3)),
                    name="Ridge", reference="ridge regression on the features",
                    model_classes=(Pipeline, StandardScaler, Ridge))

The estimator is cloned for every training, and a ``random_state`` it leaves at None is set
to the study's seed (a table is reproducible only when every draw is seeded).  A factory
does as well, as a decorator::

    @register_method("mlp", name="MLP", model_classes=(Pipeline, StandardScaler, MLPRegressor))
    def mlp(*, random_state):
        return make_pipeline(StandardScaler(), MLPRegressor((20,), random_state=random_state))

called with those of ``budget`` (evaluations of a tuned method's validation error),
``random_state`` (the study's seed) and ``n_jobs`` (parallel evaluations inside one
training) it names.  The estimator's ``fit(X, y)`` gets the training samples (and
``groups=``, one per start temperature of the training start-ups,
:attr:`~nfs.compensate.dataset.DriftDataset.validation_groups`, when the method has a
``tuner``); its ``predict(X)`` gives the drift [deg/h].

Where a method runs: the studies hand the :class:`MethodSpec` itself to their worker
processes (pickled, a factory defined in a script by value), so a method registered in the
Python session trains there too.  A new process (the ``nfs`` command, a sweep's Dask
workers) knows the built-in methods and those a package exposes as an entry point in the
group ``nfs.compensation_methods`` (a module whose import registers them), loaded on the
first look-up that misses.
"""

from __future__ import annotations

import inspect
import sys
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from sklearn.base import BaseEstimator, clone

from .catalog import (METHODS, OTHER_GROUP, MethodError, MethodSpec, find_method,
                      load_entry_points)

__all__ = ["BUILD_ARGUMENTS", "register_method", "unregister_method", "get_method",
           "available_methods", "model_classes", "class_path"]

#: What a method's factory may ask for, by keyword.
BUILD_ARGUMENTS = ("budget", "random_state", "n_jobs")



@dataclass(frozen=True)
class _Factory:
    """A factory called with the build arguments it names (pickles as its function)."""

    function: Callable[..., Any]
    takes: tuple[str, ...]

    def __call__(self, *, budget: int, random_state: int, n_jobs: int | None):
        given = {"budget": budget, "random_state": random_state, "n_jobs": n_jobs}
        return self.function(**{k: given[k] for k in self.takes})


@dataclass(frozen=True)
class _Prototype:
    """An unfitted estimator cloned for each training, its unset random states seeded."""

    estimator: Any

    def __call__(self, *, budget: int, random_state: int, n_jobs: int | None):
        est = clone(self.estimator)
        unset = {k: random_state for k, v in est.get_params(deep=True).items()
                 if (k == "random_state" or k.endswith("__random_state")) and v is None}
        return est.set_params(**unset) if unset else est




def register_method(key: str, build: Any = None, *, name: str | None = None,
                    reference: str = "", tuner: str | None = None,
                    max_samples: int | None = None, cost: float = 1.0,
                    group: str = OTHER_GROUP, table: bool = True,
                    model_classes: Sequence[type] = (), replace: bool = False):
    """Register a compensation method under ``key`` (a decorator when ``build`` is omitted).

    Parameters
    ----------
    key : str
        Command-line and scenario key: lower case, no spaces (``ridge``).
    build : callable or estimator
        A factory of the unfitted estimator, called with those of ``budget``,
        ``random_state`` and ``n_jobs`` it names; or an unfitted scikit-learn estimator,
        cloned for each training (a ``random_state`` left at None set to the study's seed).
        The estimator maps the features (n_samples, n_features) to the drift [deg/h].
    name : str, optional
        Row label in the tables (default: ``key``).
    reference : str
        Where the method comes from.
    tuner : str, optional
        The search of a tuned method (``grid``, ``ssa``, ...): its ``fit`` is given the
        validation groups (``groups=``, whole start-ups left out), and a tuner other than
        ``grid`` is trained with every tuner seed of the settings.
    max_samples : int, optional
        Training samples at most (every k-th kept above it).
    cost : float
        Relative cost of one training [s]: the studies start the costliest first.
    group : str
        Panel of the table's figure.
    table : bool
        A row of every table whose settings name no methods.
    model_classes : sequence of type
        scikit-learn estimator classes, beside the package's own, that the fitted estimator
        holds: a model file may then hold them (without them, saving says in one line which
        class it cannot write).
    replace : bool
        Replace a method registered under ``key`` already (else that is an error).

    Returns
    -------
    MethodSpec, or the decorator (which returns the function unchanged)
    """
    if build is None:
        def decorator(function: Callable[..., Any]) -> Callable[..., Any]:
            register_method(key, function, name=name, reference=reference, tuner=tuner,
                            max_samples=max_samples, cost=cost, group=group, table=table,
                            model_classes=model_classes, replace=replace)
            return function
        return decorator
    if not isinstance(key, str) or not key or key != key.lower() or any(
            c.isspace() for c in key):
        raise MethodError(f"method key {key!r}: lower case, no spaces (e.g. 'ridge')")
    name = key if name is None else name
    if not isinstance(name, str) or not name.strip():
        raise MethodError(f"method '{key}': name must be a row label, got {name!r}")
    if tuner is not None and not (isinstance(tuner, str) and tuner):
        raise MethodError(f"method '{key}': tuner must be a tuner's name or None, got "
                          f"{tuner!r}")
    if isinstance(cost, bool) or not isinstance(cost, (int, float)) or not cost >= 0.0:
        raise MethodError(f"method '{key}': cost must be a number >= 0 [s], got {cost!r}")
    _check_free(key, name, replace)
    spec = MethodSpec(name=name, key=key, tuned=tuner is not None,
                      build=_builder(key, build), reference=reference,
                      max_samples=_max_samples(key, max_samples), tuner=tuner,
                      cost=float(cost), group=group, table=bool(table),
                      model_classes=_classes(key, model_classes))
    METHODS[key] = spec
    return spec


def _check_free(key: str, name: str, replace: bool) -> None:
    """MethodError when ``key`` or ``name`` is taken (by ``key`` itself unless ``replace``)."""
    for other in METHODS.values():
        taken = {other.key, other.name.lower()} & {key, name.lower()}
        if not taken:
            continue
        if other.key == key and replace:
            continue
        raise MethodError(f"a compensation method '{taken.pop()}' is registered already "
                          f"(key '{other.key}', row '{other.name}')"
                          + ("; replace=True replaces it" if other.key == key else ""))


def _builder(key: str, build: Any) -> Callable[..., Any]:
    """``build`` as a callable of (budget, random_state, n_jobs), checked."""
    if isinstance(build, BaseEstimator) or (hasattr(build, "fit") and
                                            hasattr(build, "get_params") and
                                            not isinstance(build, type)):
        return _Prototype(build)
    if not callable(build):
        raise MethodError(f"method '{key}': build must be a factory or an unfitted "
                          f"estimator, got {type(build).__name__}")
    try:
        params = list(inspect.signature(build).parameters.values())
    except (TypeError, ValueError):
        return _Factory(build, BUILD_ARGUMENTS)
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return _Factory(build, BUILD_ARGUMENTS)
    needs = [p.name for p in params if p.default is p.empty and p.kind is not p.VAR_POSITIONAL
             and p.name not in BUILD_ARGUMENTS]
    if needs:
        raise MethodError(f"method '{key}': its factory needs {', '.join(needs)}; a factory "
                          f"is given only {', '.join(BUILD_ARGUMENTS)}")
    return _Factory(build, tuple(a for a in BUILD_ARGUMENTS if a in {p.name for p in params}))


def _max_samples(key: str, value: int | None) -> int | None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                              or value < 1):
        raise MethodError(f"method '{key}': max_samples must be an integer >= 1 or None, "
                          f"got {value!r}")
    return value


def _classes(key: str, classes: Sequence[type]) -> tuple[type, ...]:
    out = tuple(classes)
    for cls in out:
        if not (isinstance(cls, type) and issubclass(cls, BaseEstimator)):
            raise MethodError(f"method '{key}': model_classes holds {cls!r}, not a "
                              "scikit-learn estimator class")
    return out


def unregister_method(key: str) -> MethodSpec:
    """Remove the method registered under ``key`` and return it (MethodError if none)."""
    spec = get_method(key)
    del METHODS[spec.key]
    return spec


def get_method(name: str) -> MethodSpec:
    """A method by key (``ssa-svr``) or row label (``SSA-SVR``); error listing the valid ones."""
    spec = find_method(name)
    if spec is None:
        load_entry_points()
        spec = find_method(name)
    if spec is None:
        raise MethodError(f"unknown compensation method '{name}'; methods: "
                          + ", ".join(available_methods()))
    return spec


def available_methods() -> list[str]:
    """The keys of every registered method, in registration order."""
    load_entry_points()
    return list(METHODS)


def class_path(cls: type) -> str:
    """The name a model file gives a registered class: its shortest public path among the
    modules imported already (``sklearn.linear_model.Ridge``), else module and qualified
    name."""
    parts = cls.__module__.split(".")
    for k in range(1, len(parts)):
        module = sys.modules.get(".".join(parts[:k]))
        if module is not None and vars(module).get(cls.__qualname__) is cls:
            return f"{'.'.join(parts[:k])}.{cls.__qualname__}"
    return f"{cls.__module__}.{cls.__qualname__}"


def model_classes() -> dict[str, type]:
    """The classes the registered methods list in ``model_classes``, by
    :func:`class_path`."""
    load_entry_points()
    return {class_path(cls): cls for m in METHODS.values() for cls in m.model_classes}
