"""Named parameter paths into an :class:`~nfs.instrument.Instrument`: read and set its numbers.

A path is a dotted name of one number of the instrument, spelled as in its TOML form:

==========================================================  ====================================
path                                                        kind
==========================================================  ====================================
``thermal.nodes.<node>.capacity_j_per_k``                   thermal      C_j [J/K]
``thermal.nodes.<node>.power_w``                            thermal      P_j [W]
``thermal.links.<a>-<b>.conductance_w_per_k``               thermal      G_ab [W/K]
``coil.<conductivity_w_per_m_k|inner_radius_m|...>``        thermal      the wound coil's
``coil.<inner_contacts|outer_contacts>.<node>``             thermal      its faces' G [W/K]
``thermometers.<fog|acc_x|acc_y>.<lag_s|offset_c|...>``     thermometer  tau [s], offset [degC]
``gyro.<bias_dph|scale_factor|...>``                        drift        b [deg/h], ...
``accelerometers.<bias_x_g|bias_y_g|...>``                  accelerometer  [g]
``turntable.<tilt_north_deg|tilt_east_deg>``                turntable    [deg]
``effects.<label>.<param>``                                 the effect's kind (gyro -> drift)
==========================================================  ====================================

A wound coil's layers (``coil_1`` .. ``coil_N``, :mod:`nfs.coil`) and the links it makes are
not paths of their own: they follow the coil's numbers.  A link is named by its two ends in
either order (``coil_outer-coil_inner`` or
``coil_inner-coil_outer``; ``chamber`` is an end like any node).  An effect is named by its
:attr:`~nfs.effects.EffectInstance.label` (``shupe_gradient``,
``acc_bias_temperature:x``, ``tec_power``); only its numeric parameters are paths.

:func:`get_param` reads one number, :func:`set_params` returns a new frozen instrument with
some numbers changed (the original is untouched), :func:`list_params` lists every path and
:func:`expand_paths` expands glob patterns (``thermal.nodes.*.capacity_j_per_k``).  The
simulator draws a unit's parameters through these paths (:mod:`nfs.variability`), the fit
frees them and bounds them (:mod:`nfs.fit.params`).
"""

from __future__ import annotations

import difflib
import fnmatch
from dataclasses import fields, replace
from typing import Iterable, Mapping

from thermal import Link, Network

from .coil import with_coil
from .errors import NfsError

__all__ = ["ParameterError", "PARAM_KINDS", "get_param", "set_params", "list_params",
           "expand_paths", "param_kind", "param_paths", "canonical_path"]

#: The kinds :func:`list_params` can filter on.
PARAM_KINDS = ("thermal", "thermometer", "drift", "accelerometer", "turntable")

#: Dataclass sections of the instrument whose float fields are paths, with their kind.
_SECTIONS = {"gyro": "drift", "accelerometers": "accelerometer", "turntable": "turntable"}
_EFFECT_KIND = {"gyro": "drift", "accelerometer": "accelerometer", "thermal": "thermal",
                "thermometer": "thermometer"}


class ParameterError(NfsError):
    """A parameter path that does not name a number of the instrument."""


# ---------------------------------------------------------------------------------------------
# Listing

def _numeric_fields(obj) -> list[str]:
    return [f.name for f in fields(obj)
            if isinstance(getattr(obj, f.name), (int, float))
            and not isinstance(getattr(obj, f.name), bool)]


def _link_key(link: Link) -> str:
    return f"{link.a}-{link.b}"


def param_paths(inst) -> list[tuple[str, str]]:
    """(path, kind) of every number of ``inst``, in TOML order (kinds: :data:`PARAM_KINDS`)."""
    out: list[tuple[str, str]] = []
    own_nodes, own_links = inst.own_parts
    for node in own_nodes:
        out.append((f"thermal.nodes.{node.name}.capacity_j_per_k", "thermal"))
        out.append((f"thermal.nodes.{node.name}.power_w", "thermal"))
    for link in own_links:
        out.append((f"thermal.links.{_link_key(link)}.conductance_w_per_k", "thermal"))
    if inst.coil is not None:
        out.extend((p, "thermal") for p in inst.coil.paths())
    for name, model in inst.thermometers.items():
        for f in _numeric_fields(model):
            out.append((f"thermometers.{name}.{f}", "thermometer"))
    for section, kind in _SECTIONS.items():
        for f in _numeric_fields(getattr(inst, section)):
            out.append((f"{section}.{f}", kind))
    for e in inst.effects:
        kind = _EFFECT_KIND.get(e.spec.kind)
        if kind is None:
            continue
        for p in e.spec.parameters:
            if p.type is float and e.params.get(p.name) is not None:
                out.append((f"effects.{e.label}.{p.name}", kind))
    return out


def list_params(inst, kind: str | None = None) -> list[str]:
    """Every numeric parameter path of ``inst`` (of one kind of :data:`PARAM_KINDS` if given).

    Kinds: ``thermal`` (nodes, links, thermal effects such as ``tec_power``),
    ``thermometer`` (thermometer fields and thermometer effects), ``drift`` (``gyro.*`` and
    the gyro effects), ``accelerometer`` (``accelerometers.*`` and accelerometer effects),
    ``turntable`` (tilts).
    """
    if kind is not None and kind not in PARAM_KINDS:
        raise ParameterError(f"unknown parameter kind '{kind}'; kinds: {', '.join(PARAM_KINDS)}")
    return [p for p, k in param_paths(inst) if kind is None or k == kind]


def param_kind(inst, path: str) -> str:
    """The kind (:data:`PARAM_KINDS`) of ``path``."""
    path = canonical_path(inst, path)
    for p, k in param_paths(inst):
        if p == path:
            return k
    raise _bad_path(inst, path)  # pragma: no cover  (canonical_path raised already)


def _bad_path(inst, path: str, why: str = "") -> ParameterError:
    valid = list_params(inst)
    close = difflib.get_close_matches(path, valid, n=5, cutoff=0.5)
    if not close:
        head = path.split(".", 1)[0]
        close = [p for p in valid if p.startswith(head + ".")][:5] or valid[:5]
    msg = f"no parameter '{path}' in instrument '{inst.name}'"
    if why:
        msg += f" ({why})"
    return ParameterError(msg + "; close valid paths: " + ", ".join(close)
                          + " (nfs.parameters.list_params lists all)")


def canonical_path(inst, path: str, valid: set[str] | None = None) -> str:
    """``path`` spelled as :func:`list_params` spells it (a link's ends in network order)."""
    if not isinstance(path, str):
        raise ParameterError(f"a parameter path must be a string, got {path!r}")
    if path.startswith("thermal.links.") and path.endswith(".conductance_w_per_k"):
        key = path[len("thermal.links."):-len(".conductance_w_per_k")]
        for link in inst.own_parts[1]:
            if key in (f"{link.a}-{link.b}", f"{link.b}-{link.a}"):
                return f"thermal.links.{_link_key(link)}.conductance_w_per_k"
        raise _bad_path(inst, path, "no such link")
    if valid is None:
        valid = {p for p, _ in param_paths(inst)}
    if path not in valid:
        raise _bad_path(inst, path)
    return path


def expand_paths(inst, patterns: str | Iterable[str]) -> list[str]:
    """Paths matching ``patterns`` (glob: ``*``, ``?``, ``[...]``), in :func:`list_params` order.

    A pattern without a wildcard must name a parameter (a link in either order); a pattern
    that matches nothing is an error, so a typo never silently frees nothing.
    """
    if isinstance(patterns, str):
        patterns = [patterns]
    valid = list_params(inst)
    chosen: set[str] = set()
    for pat in patterns:
        if any(c in pat for c in "*?["):
            hits = fnmatch.filter(valid, pat)
            if not hits:
                raise _bad_path(inst, pat, "the pattern matches no parameter")
            chosen.update(hits)
        else:
            chosen.add(canonical_path(inst, pat))
    return [p for p in valid if p in chosen]


# ---------------------------------------------------------------------------------------------
# Get and set

def get_param(inst, path: str) -> float:
    """The value of parameter ``path`` of ``inst``."""
    path = canonical_path(inst, path)
    parts = path.split(".")
    head = parts[0]
    if head == "thermal":
        if parts[1] == "nodes":
            node = inst.network.nodes[inst.network.index(".".join(parts[2:-1]))]
            return float(getattr(node, parts[-1]))
        key = ".".join(parts[2:-1])
        for link in inst.own_parts[1]:
            if _link_key(link) == key:
                return float(link.conductance_w_per_k)
    elif head == "coil":
        return inst.coil.number(path[len("coil."):])
    elif head == "thermometers":
        return float(getattr(inst.thermometers[parts[1]], parts[2]))
    elif head in _SECTIONS:
        return float(getattr(getattr(inst, head), parts[1]))
    elif head == "effects":
        label, name = path[len("effects."):].rsplit(".", 1)
        return float(inst.effect(label).params[name])
    raise _bad_path(inst, path)  # pragma: no cover


def set_params(inst, values: Mapping[str, float]):
    """A new instrument with the parameters ``values`` ({path: value}) set.

    The original instrument is unchanged (every dataclass is rebuilt with
    :func:`dataclasses.replace`).  Values are not range-checked beyond what the dataclasses
    themselves check (a capacity must stay > 0: :class:`~nfs.errors.ThermalError`).
    """
    node_set: dict[str, dict[str, float]] = {}
    link_set: dict[str, float] = {}
    thermo_set: dict[str, dict[str, float]] = {}
    section_set: dict[str, dict[str, float]] = {}
    effect_set: dict[str, dict[str, float]] = {}
    coil_set: dict[str, float] = {}
    valid = {p for p, _ in param_paths(inst)}
    for raw, value in values.items():
        path = canonical_path(inst, raw, valid)
        v = float(value)
        parts = path.split(".")
        head = parts[0]
        if head == "thermal" and parts[1] == "nodes":
            node_set.setdefault(".".join(parts[2:-1]), {})[parts[-1]] = v
        elif head == "thermal":
            link_set[".".join(parts[2:-1])] = v
        elif head == "coil":
            coil_set[path[len("coil."):]] = v
        elif head == "thermometers":
            thermo_set.setdefault(parts[1], {})[parts[2]] = v
        elif head in _SECTIONS:
            section_set.setdefault(head, {})[parts[1]] = v
        else:
            label, name = path[len("effects."):].rsplit(".", 1)
            effect_set.setdefault(label, {})[name] = v
    changes: dict = {}
    if node_set or link_set or coil_set:
        own_nodes, own_links = inst.own_parts
        nodes = tuple(replace(n, **node_set[n.name]) if n.name in node_set else n
                      for n in own_nodes)
        links = tuple(replace(l, conductance_w_per_k=link_set[_link_key(l)])
                      if _link_key(l) in link_set else l for l in own_links)
        if inst.coil is None:
            changes["network"] = Network(nodes=nodes, links=links)
        else:
            coil = inst.coil.with_numbers(coil_set) if coil_set else inst.coil
            changes["network"] = with_coil(nodes, links, coil)
            changes["coil"] = coil
    if thermo_set:
        changes["thermometers"] = {k: replace(m, **thermo_set[k]) if k in thermo_set else m
                                   for k, m in inst.thermometers.items()}
    for section, kw in section_set.items():
        changes[section] = replace(getattr(inst, section), **kw)
    if effect_set:
        changes["effects"] = tuple(
            replace(e, params={**e.params, **effect_set[e.label]}) if e.label in effect_set
            else e for e in inst.effects)
    return replace(inst, **changes) if changes else inst
