"""The instrument: thermal network, sensors, turntable, thermometers and its effect list.

An instrument is described by a TOML file (the built-in preset ``default`` lives in
``nfs/presets/default_instrument.toml``; ``nfs preset default`` prints it for a user to copy
and edit).  :func:`instrument_from_dict` turns the parsed TOML into frozen dataclasses and
checks every key, naming the file and the dotted key of any fault.
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from thermal import Link, Network, Node

from .coil import WoundCoil, coil_from_dict, own_parts, with_coil
from .constants import T_REF_C
from .effects import CoilLayout, EffectInstance, check_geometry, make_effect
from .effects.thermometer import THERMOMETERS
from .errors import EffectError, ScenarioError, ThermalError
from .io.tomlio import (check_keys, dumps_toml, load_toml, number, string, table)
from .io.unit_files import check_values_as_declared, drawn_unit_entry
from .ranges import check, deferred_warnings, warn_unusual
from .sensors import ThermometerModel

__all__ = [
    "GyroModel", "AccelerometerModel", "TurntableModel", "AuxChannel", "Instrument",
    "instrument_from_dict", "load_instrument", "preset_names", "preset_path",
    "CHAMBER",
]

#: Name of the chamber boundary in thermal links.
CHAMBER = "chamber"


@dataclass(frozen=True)
class GyroModel:
    """The FOG: where its coil and source sit in the network, constant bias and noise."""

    coil_outer: str
    """Node of the coil's outer layers."""
    coil_inner: str
    """Node of the coil's inner layers and spool."""
    source: str
    """Node of the light source, TEC and FOG electronics."""
    bias_dph: float = 0.0
    """Constant bias b [deg/h] (cancels in multiposition north finding)."""
    scale_factor: float = 1.0
    """K0, scale factor of the output (1: the output is calibrated in deg/h)."""
    arw_deg_per_rth_h: float = 0.0005
    """N, angle random walk [deg/sqrt(h)] (0.0003-0.001)."""
    bias_instability_dph: float = 0.003
    """B, bias instability [deg/h] (0.002-0.005)."""
    rrw_deg_per_h_per_rth_h: float = 0.0
    """K, rate random walk [deg/h/sqrt(h)]."""


@dataclass(frozen=True)
class AccelerometerModel:
    """The two quartz flexure accelerometers (docs/physics.md section 4)."""

    x_node: str
    """Node of QFA x."""
    y_node: str
    """Node of QFA y."""
    noise_ug_per_rth_hz: float = 20.0
    """White noise density [ug/sqrt(Hz)]."""
    bias_x_g: float = 0.0
    """Constant bias of QFA x [g]."""
    bias_y_g: float = 0.0
    """Constant bias of QFA y [g]."""

    @property
    def nodes(self) -> dict[str, str]:
        """Axis -> node."""
        return {"x": self.x_node, "y": self.y_node}


@dataclass(frozen=True)
class TurntableModel:
    """Tilt of the turntable axis (docs/physics.md section 4)."""

    tilt_north_deg: float = 0.0
    """alpha_N, tilt toward north [deg]."""
    tilt_east_deg: float = 0.0
    """alpha_E, tilt toward east [deg]."""


@dataclass(frozen=True)
class AuxChannel:
    """An auxiliary electrical channel ``aux_*`` (Tao et al.'s (2019) oscillator voltage, a TEC
    drive).

    value = offset + gain * source(t) + white noise + random walk, where source is the total
    power of a node (``power:NODE`` [W]) or a node temperature (``temperature:NODE`` [degC]).
    """

    name: str
    """Column name, ``aux_<what>_<unit>``."""
    source: str
    """``power:NODE`` or ``temperature:NODE``."""
    gain: float = 1.0
    """Channel units per source unit."""
    offset: float = 0.0
    """Channel units."""
    noise: float = 0.0
    """White noise standard deviation per sample [channel units]."""
    walk_per_rth_s: float = 0.0
    """Random-walk intensity [channel units / sqrt(s)] (an electrical drift that no
    thermometer sees)."""

    @property
    def kind(self) -> str:
        return self.source.split(":", 1)[0]

    @property
    def node(self) -> str:
        return self.source.split(":", 1)[1]


@dataclass(frozen=True)
class Instrument:
    """A north finding system: network, sensors, thermometers, aux channels and effects."""

    name: str
    """Name (free text)."""
    network: Network
    """The lumped thermal network (nodes, links; the chamber is ``chamber``)."""
    gyro: GyroModel
    """The FOG."""
    accelerometers: AccelerometerModel
    """The QFAs."""
    turntable: TurntableModel
    """The turntable."""
    thermometers: dict[str, ThermometerModel]
    """``fog``, ``acc_x``, ``acc_y`` -> thermometer."""
    effects: tuple[EffectInstance, ...] = ()
    """The effects this instrument has, in order."""
    aux: tuple[AuxChannel, ...] = ()
    """Auxiliary channels written to the measurement."""
    t_ref_c: float = T_REF_C
    """T_ref of the effect library [degC]."""
    description: str = ""
    """Free text, e.g. where the values come from."""
    coil: WoundCoil | None = None
    """The wound coil (``[coil]``), whose layers ``coil_1`` .. ``coil_N`` are nodes of
    :attr:`network`; None: the coil is the two lumped nodes of ``[gyro]``."""

    @property
    def coil_layout(self) -> CoilLayout | None:
        """Where the wound coil's layers sit (for ``shupe_winding``); None when lumped."""
        return None if self.coil is None else self.coil.layout

    @property
    def target_nodes(self) -> tuple[str, ...]:
        """The nodes an effect can be put at by a diagnosis or a rival: every node but the
        interior layers of a wound coil, which is one body whose faces (its innermost and
        outermost layers) are where heat arrives and a thermometer could sit."""
        if self.coil is None:
            return self.network.node_names
        inner = set(self.coil.layer_names[1:-1])
        return tuple(n for n in self.network.node_names if n not in inner)

    def with_own_parts(self, nodes, links) -> "Instrument":
        """A copy whose ``[thermal]`` nodes and links are ``nodes`` and ``links`` (the wound
        coil, if any, added to them as :func:`nfs.coil.with_coil` does)."""
        if self.coil is None:
            return replace(self, network=Network(nodes=tuple(nodes), links=tuple(links)))
        return replace(self, network=with_coil(tuple(nodes), tuple(links), self.coil))

    @functools.cached_property
    def own_parts(self) -> tuple[tuple[Node, ...], tuple[Link, ...]]:
        """(nodes, links) of ``[thermal]``: :attr:`network` without the wound coil's layers
        and the links it makes (a link of ``[thermal]`` to a layer is its own)."""
        if self.coil is None:
            return self.network.nodes, self.network.links
        return own_parts(self.network, self.coil)

    def with_effects(self, effects) -> "Instrument":
        """A copy with another effect list (checked against this instrument)."""
        out = replace(self, effects=tuple(effects))
        check_effect_targets(out, file=None)
        return out

    def effect(self, label: str) -> EffectInstance:
        """The effect with this label (``name`` or ``name:target``)."""
        for e in self.effects:
            if label in (e.label, e.name):
                return e
        raise EffectError(f"instrument '{self.name}' has no effect '{label}'; it has: "
                          + ", ".join(e.label for e in self.effects))

    def to_dict(self) -> dict[str, Any]:
        """The TOML form (inverse of :func:`instrument_from_dict`)."""
        own_nodes, own_links = self.own_parts
        nodes = {n.name: {"capacity_j_per_k": n.capacity_j_per_k, "power_w": n.power_w}
                 for n in own_nodes}
        links = [{"between": [l.a, l.b], "conductance_w_per_k": l.conductance_w_per_k}
                 for l in own_links]
        out: dict[str, Any] = {"name": self.name}
        if self.description:
            out["description"] = self.description
        out["t_ref_c"] = self.t_ref_c
        out["thermal"] = {"nodes": nodes, "links": links}
        if self.coil is not None:
            out["coil"] = self.coil.to_dict()
        out["gyro"] = dict(vars(self.gyro))
        out["accelerometers"] = dict(vars(self.accelerometers))
        out["turntable"] = dict(vars(self.turntable))
        out["thermometers"] = {k: dict(vars(v)) for k, v in self.thermometers.items()}
        if self.aux:
            out["aux"] = [dict(vars(a)) for a in self.aux]
        if self.effects:
            out["effects"] = [e.to_dict() for e in self.effects]
        return out

    def to_toml(self) -> str:
        """TOML text that :func:`load_instrument` reads back to an equal instrument."""
        return dumps_toml(self.to_dict()) + "\n"

    @classmethod
    def from_toml_text(cls, text: str, file: Any = None) -> "Instrument":
        """The instrument of TOML ``text`` (what :meth:`to_toml` wrote), checked as a file
        is (:func:`instrument_from_dict`); ``file`` names it in messages."""
        return instrument_from_dict(tomllib.loads(text), file)


_TOP_KEYS = ("name", "description", "t_ref_c", "thermal", "coil", "gyro", "accelerometers",
             "turntable", "thermometers", "aux", "effects", "fit")
_GYRO_KEYS = tuple(GyroModel.__dataclass_fields__)
_ACC_KEYS = tuple(AccelerometerModel.__dataclass_fields__)
_TT_KEYS = tuple(TurntableModel.__dataclass_fields__)
_THERMO_KEYS = tuple(ThermometerModel.__dataclass_fields__)
_AUX_KEYS = tuple(AuxChannel.__dataclass_fields__)


def _network(tbl: dict, prefix: str, file: Any, coil: WoundCoil | None = None) -> Network:
    """The ``[thermal]`` table's network, with the wound ``coil``'s layers when given (its
    links may then name the layers)."""
    check_keys(tbl, ("nodes", "links"), prefix, file, required=("nodes", "links"))
    nodes_tbl = table(tbl, "nodes", prefix, file)
    nodes = []
    for name, spec in nodes_tbl.items():
        p = f"{prefix}.nodes.{name}"
        if not isinstance(spec, dict):
            raise ScenarioError("must be a table", file=file, key=p)
        check_keys(spec, ("capacity_j_per_k", "power_w"), p, file)
        cap = number(spec, "capacity_j_per_k", p, file, positive=True)
        nodes.append(Node(name=name, capacity_j_per_k=cap,
                          power_w=number(spec, "power_w", p, file, 0.0)))
    if not nodes:
        raise ScenarioError("must name at least one node", file=file, key=f"{prefix}.nodes")
    links_val = tbl["links"]
    if not isinstance(links_val, list):
        raise ScenarioError("must be an array of tables [[...links]]", file=file,
                            key=f"{prefix}.links")
    links = []
    for i, spec in enumerate(links_val):
        p = f"{prefix}.links[{i}]"
        if not isinstance(spec, dict):
            raise ScenarioError("must be a table", file=file, key=p)
        check_keys(spec, ("between", "conductance_w_per_k"), p, file,
                   required=("between", "conductance_w_per_k"))
        between = spec["between"]
        if (not isinstance(between, list) or len(between) != 2
                or not all(isinstance(b, str) for b in between)):
            raise ScenarioError(f"must be two node names, got {between!r}", file=file,
                                key=f"{p}.between")
        g = number(spec, "conductance_w_per_k", p, file, minimum=0.0)
        links.append(Link(a=between[0], b=between[1], conductance_w_per_k=g))
    try:
        if coil is not None:
            return with_coil(tuple(nodes), tuple(links), coil)
        return Network(nodes=tuple(nodes), links=tuple(links))
    except ThermalError as exc:
        raise ScenarioError(str(exc), file=file, key=prefix) from None


def _node_ref(network: Network, node: str, key: str, file: Any) -> str:
    if node not in network.node_names:
        raise ScenarioError(f"unknown node '{node}'; nodes: {', '.join(network.node_names)}",
                            file=file, key=key)
    return node


def _dataclass_numbers(cls, tbl: dict, prefix: str, file: Any, names: dict[str, str],
                       network: Network) -> Any:
    """Build a dataclass from a table whose fields are numbers, except ``names`` (node refs)."""
    check_keys(tbl, cls.__dataclass_fields__, prefix, file, required=tuple(names))
    kwargs = {}
    for fname, f in cls.__dataclass_fields__.items():
        if fname in names:
            kwargs[fname] = _node_ref(network, string(tbl, fname, prefix, file),
                                      f"{prefix}.{fname}", file)
        elif fname in tbl:
            nonneg = fname.startswith(("arw", "bias_instability", "rrw", "noise"))
            kwargs[fname] = number(tbl, fname, prefix, file, minimum=0.0 if nonneg else None)
    return cls(**kwargs)


def _thermometers(tbl: dict, network: Network, file: Any) -> dict[str, ThermometerModel]:
    check_keys(tbl, THERMOMETERS, "thermometers", file, required=THERMOMETERS)
    out = {}
    for name in THERMOMETERS:
        p = f"thermometers.{name}"
        spec = table(tbl, name, "thermometers", file)
        check_keys(spec, _THERMO_KEYS, p, file, required=("nodes",))
        nodes = spec["nodes"]
        if isinstance(nodes, str):
            nodes = {nodes: 1.0}
        if not isinstance(nodes, dict) or not nodes:
            raise ScenarioError("must be a node name or a table node = weight", file=file,
                                key=f"{p}.nodes")
        weights = {}
        for node, w in nodes.items():
            _node_ref(network, node, f"{p}.nodes", file)
            weights[node] = number(nodes, node, f"{p}.nodes", file, positive=True)
        out[name] = ThermometerModel(
            nodes=weights,
            lag_s=number(spec, "lag_s", p, file, 20.0, minimum=0.0),
            offset_c=number(spec, "offset_c", p, file, 0.0),
            noise_c=number(spec, "noise_c", p, file, 0.01, minimum=0.0),
            quantum_c=_kelvin_step(spec, "quantum_c", p, file, 0.0625))
    return out


def _kelvin_step(spec: dict, key: str, prefix: str, file: Any, default: float) -> float:
    """A thermometer's resolution [K]: 0 (none) up to 1 K; a larger value is refused as a
    unit mistake (a quartz or platinum sensor of a north finder resolves 1/16 K or better:
    62.5 is 0.0625 K written in mK)."""
    value = number(spec, key, prefix, file, default, minimum=0.0)
    if value > 1.0:
        raise ScenarioError(f"{value!r} K is not a plausible thermometer resolution (at most "
                            f"1 K); was it given in mK? (e.g. 0.0625 for 1/16 K)",
                            file=file, key=f"{prefix}.{key}")
    return value


def parse_aux(val: Any, network: Network, file: Any) -> tuple[AuxChannel, ...]:
    """An ``[[aux]]`` array (an instrument's, or the channels a scenario adds): each table a
    channel ``aux_*`` reading ``power:NODE`` [W] or ``temperature:NODE`` [degC] of
    ``network`` through a gain, an offset, white noise and a random walk; a ScenarioError
    names ``file`` and the dotted key of any fault."""
    if not isinstance(val, list):
        raise ScenarioError("must be an array of tables [[aux]]", file=file, key="aux")
    out = []
    for i, spec in enumerate(val):
        p = f"aux[{i}]"
        if not isinstance(spec, dict):
            raise ScenarioError("must be a table", file=file, key=p)
        check_keys(spec, _AUX_KEYS, p, file, required=("name", "source"))
        name = string(spec, "name", p, file)
        if not name.startswith("aux_"):
            raise ScenarioError(f"an aux channel's name must start with 'aux_', got '{name}'",
                                file=file, key=f"{p}.name")
        source = string(spec, "source", p, file)
        kind, _, node = source.partition(":")
        if kind not in ("power", "temperature"):
            raise ScenarioError(f"must be 'power:NODE' or 'temperature:NODE', got '{source}'",
                                file=file, key=f"{p}.source")
        _node_ref(network, node, f"{p}.source", file)
        out.append(AuxChannel(
            name=name, source=source, gain=number(spec, "gain", p, file, 1.0),
            offset=number(spec, "offset", p, file, 0.0),
            noise=number(spec, "noise", p, file, 0.0, minimum=0.0),
            walk_per_rth_s=number(spec, "walk_per_rth_s", p, file, 0.0, minimum=0.0)))
    return tuple(out)


def parse_effects(val: Any, file: Any, key: str = "effects") -> tuple[EffectInstance, ...]:
    """An ``[[effects]]`` array: each table has ``name`` and the effect's parameters."""
    if not isinstance(val, list):
        raise ScenarioError("must be an array of tables [[effects]]", file=file, key=key)
    out = []
    for i, spec in enumerate(val):
        p = f"{key}[{i}]"
        if not isinstance(spec, dict):
            raise ScenarioError("must be a table", file=file, key=p)
        name = string(spec, "name", p, file)
        params = {k: v for k, v in spec.items() if k != "name"}
        try:
            out.append(make_effect(name, params))
        except EffectError as exc:
            raise ScenarioError(str(exc), file=file, key=p) from None
    return tuple(out)


def check_effect_targets(inst: Instrument, file: Any) -> None:
    """Every node, axis and thermometer an effect of ``inst`` names must exist; a channel
    must be an ``aux_*`` name; the effects' geometry must suit the turntable's tilts [deg]
    (:func:`nfs.effects.check_geometry`).  A ScenarioError names ``file`` and the effect;
    with ``file`` None (an instrument built in code) the EffectError itself is raised.

    A channel need not be declared under ``[[aux]]``: an effect may read a measured column
    that the model does not simulate (a fitted ``aux_linear`` on a recorded current).  Such
    an instrument loads, fits and diagnoses against measured runs; simulating it raises
    (:func:`nfs.experiment.simulate_run`).
    """
    aux_names = [a.name for a in inst.aux]
    for i, e in enumerate(inst.effects):
        where = f"effects[{i}] ({e.name})"
        try:
            check_geometry([e], None, inst.turntable.tilt_north_deg,
                           inst.turntable.tilt_east_deg)
        except EffectError as exc:
            if file is None:
                raise
            raise ScenarioError(str(exc), file=file, key=where) from None
        for p in e.spec.parameters:
            v = e.params.get(p.name)
            if v is None or p.type is not str:
                continue
            if p.name == "channel" and isinstance(v, str) and v.startswith("aux_"):
                continue
            valid = {"node": inst.network.node_names, "axis": ("x", "y"),
                     "thermometer": tuple(THERMOMETERS), "channel": aux_names}.get(p.name)
            if valid is not None and v not in valid:
                msg = (f"effect '{e.name}': unknown {p.name} '{v}'; valid: "
                       + (", ".join(valid) or "(none)")
                       + (" or any measured aux_* column" if p.name == "channel" else ""))
                if file is None:
                    raise EffectError(msg)
                raise ScenarioError(msg, file=file, key=where)


def _check_winding(inst: Instrument, file: Any) -> None:
    """A ``shupe_winding`` of a wound coil must be that coil: its mean diameter D between
    the winding's inner and outer diameters, its fibre filling the winding's volume at a
    pitch a fibre has (``limits.fibre_pitch_mm``, ``limits.layer_pitch_mm`` of
    :mod:`nfs.ranges`)."""
    if inst.coil is None:
        return
    coil = inst.coil
    for i, e in enumerate(inst.effects):
        if e.name != "shupe_winding":
            continue
        where = f"effects[{i}] (shupe_winding)"
        d = e.params["D"]
        lo, hi = 2.0 * coil.inner_radius_m, 2.0 * coil.outer_radius_m
        if not lo <= d <= hi:
            raise ScenarioError(f"D = {d:g} m is not the wound coil's mean diameter: the "
                                f"[coil] winding spans {lo:g}-{hi:g} m (r_i + r_o = "
                                f"{coil.mean_diameter_m:g} m)", file=file, key=f"{where}.D")
        volume = coil.capacity_j_per_k / coil.heat_capacity_j_per_m3_k
        check("limits.fibre_pitch_mm", 1e3 * float(np.sqrt(volume / e.params["L"])),
              file=file, key=f"{where}.L", error=ScenarioError)
        check("limits.layer_pitch_mm",
              1e3 * (coil.outer_radius_m - coil.inner_radius_m) / e.params["N_opt"],
              file=file, key=f"{where}.N_opt", error=ScenarioError)


def check_heating(network: Network, file: Any, effects=()) -> None:
    """The steady-state rise dT [K] of every node above the chamber under the nodes'
    constant powers P [W] and the ``effects``' constant heat sources (G dT = P, G the
    conductances [W/K], the chamber as ground) against ``limits.steady_rise_k`` of
    :mod:`nfs.ranges`; a powered part without a thermal path to the chamber would heat
    without bound.  A ScenarioError names ``file`` and the node."""
    names = list(network.node_names)
    idx = {n: i for i, n in enumerate(names)}
    n = len(names)
    g = np.zeros((n, n))
    for link in network.links:
        ends = [idx[e] for e in (link.a, link.b) if e != CHAMBER]
        c = link.conductance_w_per_k
        for i in ends:
            g[i, i] += c
        if len(ends) == 2:
            g[ends[0], ends[1]] -= c
            g[ends[1], ends[0]] -= c
    power = np.array([node.power_w for node in network.nodes])
    for e in effects:
        if e.name == "heat_source" and e.params.get("node") in idx:
            power[idx[e.params["node"]]] += float(e.params["power"])
    # nodes with a path of non-zero conductance to the chamber
    grounded = np.zeros(n, bool)
    for link in network.links:
        if CHAMBER in (link.a, link.b) and link.conductance_w_per_k > 0:
            grounded[[idx[e] for e in (link.a, link.b) if e != CHAMBER]] = True
    changed = True
    while changed:
        changed = False
        for link in network.links:
            if CHAMBER in (link.a, link.b) or link.conductance_w_per_k <= 0:
                continue
            a, b = idx[link.a], idx[link.b]
            if grounded[a] != grounded[b]:
                grounded[[a, b]] = True
                changed = True
    floating = [names[i] for i in range(n) if not grounded[i] and power[i] != 0.0]
    if floating:
        raise ScenarioError(f"node '{floating[0]}' dissipates {power[idx[floating[0]]]:g} W "
                            "but has no thermal path to the chamber: it would heat without "
                            "bound (add a link towards 'chamber')", file=file,
                            key=f"thermal.nodes.{floating[0]}")
    on = np.flatnonzero(grounded)
    if on.size == 0:
        return
    rise = np.linalg.solve(g[np.ix_(on, on)], power[on])
    worst = int(np.argmax(np.abs(rise)))
    check("limits.steady_rise_k", float(rise[worst]), file=file,
          key=f"thermal.nodes.{names[on[worst]]}", error=ScenarioError)


def instrument_from_dict(d: dict[str, Any], file: Any = None, *,
                         drawn: dict | None = None) -> Instrument:
    """Build an :class:`Instrument` from its TOML form, checking every key and every value
    against its range (:mod:`nfs.ranges`: impossible values refused, unusual ones warned;
    ``drawn``: the manifest's record of a drawn unit's file, whose unusual values are said
    in one line, :func:`nfs.io.unit_files.check_values_as_declared`)."""
    with deferred_warnings():
        return _instrument_from_dict(d, file, drawn)


def _instrument_from_dict(d: dict[str, Any], file: Any, drawn: dict | None = None
                          ) -> Instrument:
    check_keys(d, _TOP_KEYS, "", file, required=("thermal", "gyro", "accelerometers",
                                                  "thermometers"))
    thermal_tbl = table(d, "thermal", "", file)
    gyro_tbl = table(d, "gyro", "", file)
    coil = None
    if "coil" in d:
        nodes_tbl = thermal_tbl.get("nodes")
        coil = coil_from_dict(table(d, "coil", "", file), file,
                              tuple(nodes_tbl) if isinstance(nodes_tbl, dict) else ())
    network = _network(thermal_tbl, "thermal", file, coil)
    if coil is not None:
        # the coil's nodes in [gyro] are its innermost and outermost layers unless named
        gyro_tbl = {"coil_outer": coil.layer_names[-1], "coil_inner": coil.layer_names[0],
                    **gyro_tbl}
    gyro = _dataclass_numbers(GyroModel, gyro_tbl, "gyro", file,
                              {"coil_outer": "", "coil_inner": "", "source": ""}, network)
    acc = _dataclass_numbers(AccelerometerModel, table(d, "accelerometers", "", file),
                             "accelerometers", file, {"x_node": "", "y_node": ""}, network)
    tt = _dataclass_numbers(TurntableModel, table(d, "turntable", "", file, {}), "turntable",
                            file, {}, network)
    thermo = _thermometers(table(d, "thermometers", "", file), network, file)
    aux = parse_aux(d.get("aux", []), network, file)
    effects = parse_effects(d.get("effects", []), file)
    inst = Instrument(name=string(d, "name", "", file, "instrument"), network=network,
                      gyro=gyro, accelerometers=acc, turntable=tt, thermometers=thermo,
                      effects=effects, aux=aux, t_ref_c=number(d, "t_ref_c", "", file, T_REF_C),
                      description=string(d, "description", "", file, ""), coil=coil)
    check_effect_targets(inst, file)
    check_values_as_declared(d, file, drawn)
    _check_winding(inst, file)
    check_heating(network, file, inst.effects)
    return inst


def preset_names() -> list[str]:
    """Names of the built-in instrument presets."""
    root = resources.files("nfs") / "presets"
    return sorted(p.name[: -len("_instrument.toml")] for p in root.iterdir()
                  if p.name.endswith("_instrument.toml"))


def preset_path(name: str) -> Path:
    """Path of a built-in instrument preset."""
    if name not in preset_names():
        raise ScenarioError(f"unknown instrument preset '{name}'; presets: "
                            + ", ".join(preset_names()))
    return Path(str(resources.files("nfs") / "presets" / f"{name}_instrument.toml"))


def load_instrument(name_or_path: str | Path, base: Path | None = None) -> Instrument:
    """A preset by name, or an instrument TOML file (relative to ``base``; a drawn unit's
    file, :mod:`nfs.io.unit_files`, warns in one line)."""
    s = str(name_or_path)
    if not s.endswith(".toml") and "/" not in s and "\\" not in s:
        path = preset_path(s)
    else:
        path = Path(s)
        if base is not None and not path.is_absolute():
            path = base / path
    with deferred_warnings():
        inst = instrument_from_dict(load_toml(path), file=path, drawn=drawn_unit_entry(path))
        return _own_name(inst, path)


def _own_name(inst: Instrument, path: Path) -> Instrument:
    """A copy of a built-in preset keeps the preset's ``name`` (``nfs preset default >
    my.toml``), and every later report would compare 'default' with 'default': such a file
    is named after itself (``my``), with one warning line saying how to choose."""
    if inst.name not in preset_names():
        return inst
    try:
        if path.resolve() == preset_path(inst.name).resolve():
            return inst
    except OSError:
        pass
    warn_unusual(f"name = \"{inst.name}\" is the built-in preset's; this instrument is called "
                 f"'{path.stem}' (write name = \"...\" to choose)", file=path, key="name",
                 once=("name", str(path)))
    return replace(inst, name=path.stem)
