"""Readers of a scenario file's ``[variability]`` and ``[compensation]`` tables and of the
typed values they hold: each value checked and located (file and key) on a fault."""

from __future__ import annotations

import dataclasses
from typing import Any

from ..compensate.features import FeatureError, resolve_features
from ..compensate.catalog import lookup_method
from ..compensate.modes import FeatureModeError, check_features_mode
from ..compensate.settings import PROTOCOLS, CompensationSettings
from ..errors import NfsError, ScenarioError
from ..instrument import Instrument
from ..io.tomlio import boolean, check_keys, integer, number, number_list, string, table
from ..parameters import ParameterError, expand_paths
from ..variability import (CYCLING_SHAPES, NO_VARIABILITY, VARIABILITY_KEYS,
                           VARIABILITY_PRESETS, Variability)

__all__ = ["COMPENSATION_KEYS", "VARIABILITY_TABLE_KEYS", "unit_list", "variability_table",
           "variability_parameters", "compensation_table"]

#: Keys of ``[compensation]``.
COMPENSATION_KEYS = ("methods", "features", "features_mode", "budget", "decimate_s",
                     "cutoff_period_s",
                     "train_seed", "train_repeats", "train_temperatures_c", "test_repeats",
                     "train_units", "test_units", "random_state", "tuner_seeds", "n_jobs",
                     "protocol")
#: Keys of ``[variability]``.
VARIABILITY_TABLE_KEYS = ("preset", *VARIABILITY_KEYS, "parameters")

def unit_list(tbl, key, prefix, file, units):
    """A list of distinct unit indices in 0 .. units-1, or None when absent."""
    if key not in tbl:
        return None
    v = tbl[key]
    name = f"{prefix}.{key}"
    if (not isinstance(v, list) or not v
            or not all(isinstance(u, int) and not isinstance(u, bool) for u in v)):
        raise ScenarioError(f"must be a non-empty list of unit indices, got {v!r}", file=file,
                            key=name)
    bad = [u for u in v if not 0 <= u < units]
    if bad:
        raise ScenarioError(f"unit {bad[0]} is out of range: the scenario has units "
                            f"0..{units - 1} (units = {units})", file=file, key=name)
    if len(set(v)) != len(v):
        raise ScenarioError(f"names a unit twice: {v!r}", file=file, key=name)
    return tuple(v)


def variability_table(d: dict, inst: Instrument, seed: int, file) -> Variability:
    """``[variability]``: its ``preset`` with the values written overriding the preset's.

    ``realistic`` (the default when the table is given): the realistic set; ``custom``:
    nothing varies but what is written; ``none``: no variability at all, the other keys
    checked but not used (a table switched off without deleting it).  No table: ``none``.
    """
    p = "variability"
    if "variability" not in d:
        return NO_VARIABILITY
    tbl = d["variability"]
    if not isinstance(tbl, dict):
        raise ScenarioError(f"must be a table, got {tbl!r}; write [variability] and "
                            f"preset = \"none\", \"custom\" or \"realistic\"", file=file,
                            key=p)
    check_keys(tbl, VARIABILITY_TABLE_KEYS, p, file)
    preset = string(tbl, "preset", p, file, "realistic", choices=tuple(VARIABILITY_PRESETS))
    base = VARIABILITY_PRESETS[preset]
    kw: dict[str, Any] = {"preset": preset}
    for key in VARIABILITY_KEYS:
        default = getattr(base, key)
        if key == "unfinished_soak":
            kw[key] = boolean(tbl, key, p, file, default)
        elif key == "cycling_shape":
            kw[key] = string(tbl, key, p, file, default, choices=CYCLING_SHAPES)
        elif key == "unit_seed":
            kw[key] = integer(tbl, key, p, file, seed, minimum=0)
        elif key == "soak_from_c":
            kw[key] = number(tbl, key, p, file, default, minimum=-273.15)
        elif key in ("soak_h", "chamber_wander_tau_s", "cycling_period_s"):
            kw[key] = number(tbl, key, p, file, default, positive=True)
        else:                                           # standard deviations
            kw[key] = number(tbl, key, p, file, default, minimum=0.0)
    kw["parameters"] = variability_parameters(table(tbl, "parameters", p, file, {}), inst,
                                               file)
    out = Variability(**kw)
    if preset == "none":
        return NO_VARIABILITY
    if preset == "realistic" and out != dataclasses.replace(base, unit_seed=out.unit_seed):
        out = dataclasses.replace(out, preset=f"{preset} (modified)")
    return out


def variability_parameters(tbl: dict, inst: Instrument, file):
    """``[variability.parameters]``: "path or pattern" = relative std, or { std = K }."""
    out = []
    for pattern, v in tbl.items():
        name = f'variability.parameters."{pattern}"'
        if isinstance(v, dict):
            if set(v) != {"std"}:
                raise ScenarioError(
                    "must be a relative standard deviation or { std = value } (quote a "
                    "dotted path: \"effects.shupe_gradient.k_r\" = 0.3)", file=file, key=name)
            std, rel = number(v, "std", name, file, minimum=0.0), False
        else:
            std, rel = number({name: v}, name, "", file, minimum=0.0), True
        try:
            expand_paths(inst, pattern)
        except ParameterError as exc:
            raise ScenarioError(str(exc), file=file, key=name) from None
        out.append((pattern, std, rel))
    return tuple(out)


def compensation_table(tbl: dict, file, units: int = 1) -> Any:
    p = "compensation"
    check_keys(tbl, COMPENSATION_KEYS, p, file)
    d = CompensationSettings()
    methods = tbl.get("methods", list(d.methods))
    if not isinstance(methods, list) or not all(isinstance(m, str) for m in methods):
        raise ScenarioError("must be a list of method names", file=file, key=f"{p}.methods")
    if not methods:
        raise ScenarioError("must name at least one method (nfs table --no-compensation "
                            "gives the uncompensated rows alone)", file=file,
                            key=f"{p}.methods")
    try:
        methods = tuple(lookup_method(m).key for m in methods)
    except NfsError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.methods") from None
    feats = tbl.get("features", list(d.features))
    if isinstance(feats, str):
        feats = [feats]
    if not isinstance(feats, list) or not all(isinstance(f, str) for f in feats):
        raise ScenarioError("must be a feature name or a list of them", file=file,
                            key=f"{p}.features")
    try:
        resolve_features(feats, ["aux_*"])
    except FeatureError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.features") from None
    try:
        mode = check_features_mode(tbl.get("features_mode", d.features_mode), option="")
    except FeatureModeError as exc:
        raise ScenarioError(str(exc), file=file, key=f"{p}.features_mode") from None
    temps = number_list(tbl, "train_temperatures_c", p, file, None)
    n_jobs = tbl.get("n_jobs", d.n_jobs)
    if n_jobs is not None and (isinstance(n_jobs, bool) or not isinstance(n_jobs, int)):
        raise ScenarioError(f"must be an integer, got {n_jobs!r}", file=file, key=f"{p}.n_jobs")
    return CompensationSettings(
        methods=methods, features=tuple(feats), features_mode=mode,
        budget=integer(tbl, "budget", p, file, d.budget, minimum=1),
        decimate_s=number(tbl, "decimate_s", p, file, d.decimate_s, positive=True),
        cutoff_period_s=number(tbl, "cutoff_period_s", p, file, d.cutoff_period_s,
                               positive=True),
        train_seed=integer(tbl, "train_seed", p, file, d.train_seed, minimum=0),
        train_repeats=integer(tbl, "train_repeats", p, file, d.train_repeats, minimum=1),
        train_temperatures_c=temps,
        test_repeats=integer(tbl, "test_repeats", p, file, d.test_repeats, minimum=1),
        train_units=unit_list(tbl, "train_units", p, file, units),
        test_units=unit_list(tbl, "test_units", p, file, units),
        random_state=integer(tbl, "random_state", p, file, d.random_state, minimum=0),
        tuner_seeds=integer(tbl, "tuner_seeds", p, file, d.tuner_seeds, minimum=1),
        n_jobs=n_jobs,
        protocol=string(tbl, "protocol", p, file, d.protocol, choices=PROTOCOLS))


#: Keys a scenario never takes from its base.
