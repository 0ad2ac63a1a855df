"""The lumped coil wound in layers as a structural alternative (nfs.fit.wound_alternative).

Oracles: the mapping's invariants (the winding holds the lumped outer node's capacity, its
face-to-face conductance starts at the lumped radial link's, the hub keeps the inner node's
capacity and links, thermometers and effects follow their nodes), a file that loads back
without a warning; and, on runs of known units, the choice fit_unit makes: a coil of slow
radial conduction strongly heated at its outer face (the package's default instrument, its
winding's conductivity 0.1 W/(m K), 30 mm high, the electronics' contact 0.3 W/K) is wound,
the drift's cost falling from 12865 to 8295 (measured, seed 11); a unit made by the lumped
preset itself is kept lumped (drift cost 8266 wound against 6172 lumped).
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import pytest

from nfs.config.scenario import load_scenario
from nfs.errors import NfsError
from nfs.experiment import simulate_run
from nfs.fit import fit_unit, set_params, structural_alternatives, write_fitted_model
from nfs.fit.wound_alternative import WOUND_KIND, can_wind, wound_coil, wound_name
from nfs.instrument import Instrument, load_instrument


@pytest.fixture(scope="module")
def lumped():
    return load_instrument("lumped")


def test_the_wound_coil_keeps_what_the_lumped_coil_said(lumped):
    alt = wound_coil(lumped)
    new = alt.instrument
    assert alt.kind == WOUND_KIND and alt.name == wound_name(8) == "the coil in 8 layers"
    coil = new.coil
    assert coil.layers == 8
    assert (new.gyro.coil_outer, new.gyro.coil_inner) == ("coil_8", "coil_1")
    # the winding holds the outer node's capacity and conducts as the radial link did
    assert math.isclose(coil.capacity_j_per_k, 95.0, rel_tol=1e-9)
    assert math.isclose(coil.radial_conductance_w_per_k, 0.25, rel_tol=1e-9)
    assert dict(coil.outer_contacts) == {"electronics": 0.3, "housing": 0.4}
    assert dict(coil.inner_contacts) == {"spool": 3.0}
    nodes = {n.name: n for n in new.own_parts[0]}
    assert "coil_outer" not in nodes and "coil_inner" not in nodes
    assert nodes["spool"].capacity_j_per_k == 190.0
    assert any({l.a, l.b} == {"spool", "housing"} and l.conductance_w_per_k == 0.5
               for l in new.own_parts[1])
    # the coil's heat capacity kept: the lumped two nodes = the winding + its hub
    assert math.isclose(coil.capacity_j_per_k + nodes["spool"].capacity_j_per_k, 285.0)
    assert new.thermometers["fog"].nodes == {"electronics": 0.3, "coil_8": 0.7}
    labels = [e.label for e in new.effects]
    assert "shupe_winding" in labels
    assert not {"shupe_gradient", "shupe_rate", "shupe_stress"} & set(labels)
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # a model we write loads without warnings
        back = Instrument.from_toml_text(new.to_toml())
    assert back.coil == coil
    built = alt.build([2 * v for v in alt.start])
    assert math.isclose(built.coil.height_m, 2 * coil.height_m)
    assert dict(built.coil.outer_contacts) == {"electronics": 0.6, "housing": 0.8}
    for (lo, hi), v in zip(alt.bounds, alt.start):
        assert lo <= v <= hi


def test_only_a_lumped_coil_is_wound(lumped):
    default = load_instrument("default")
    assert can_wind(lumped) and not can_wind(default)
    assert WOUND_KIND in {a.kind for a in structural_alternatives(lumped)}
    assert WOUND_KIND not in {a.kind for a in structural_alternatives(default)}
    with pytest.raises(NfsError, match="wound already"):
        wound_coil(default)


def _runs(truth):
    sc = dataclasses.replace(load_scenario().nominal(), duration_s=5400.0, seed=11)
    return [simulate_run(truth, c).run for c in sc.conditions()]


@pytest.mark.integration      # two fits with refinement on 7 runs of 1.5 h (about 10 s each)
def test_fit_unit_winds_a_layered_coil_and_keeps_a_lumped_one(lumped, tmp_path):
    layered = set_params(load_instrument("default"), {
        "coil.conductivity_w_per_m_k": 0.1, "coil.height_m": 0.03,
        "coil.outer_contacts.electronics": 0.3})
    fr = fit_unit(lumped, _runs(layered), start_state=None)
    assert [s.kind for s in fr.structure.steps][-1:] == [WOUND_KIND], fr.structure.summary()
    assert fr.instrument.coil is not None and "drift agrees" in fr.structure.stopped
    path = write_fitted_model(fr, tmp_path / "wound.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert load_instrument(path).coil == fr.instrument.coil
    assert len(caught) <= 1      # the departures in one line, if any

    own = fit_unit(lumped, _runs(lumped), start_state=None)
    assert WOUND_KIND not in [s.kind for s in own.structure.steps]
    assert own.instrument.coil is None
    assert "not the drift" in own.structure.stopped


def test_a_coil_whose_outer_node_has_only_the_radial_link_is_not_wound(lumped):
    """Oracle: the outer face would be adiabatic: can_wind says no (so fit_unit does not try
    it) and wound_coil refuses in one line."""
    nodes, links = lumped.own_parts
    only_radial = lumped.with_own_parts(nodes, tuple(
        l for l in links if "coil_outer" not in (l.a, l.b) or {l.a, l.b} == {"coil_outer",
                                                                              "coil_inner"}))
    assert not can_wind(only_radial)
    with pytest.raises(NfsError, match="adiabatic"):
        wound_coil(only_radial)
