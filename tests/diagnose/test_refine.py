"""A thermal structure refined in a chain (nfs.fit.refine).

Oracle: we know the truth's structure.  The runs come from the default instrument whose FOG
thermometer reads 30 % of coil_inner (it sits deeper in the coil than the model says), the
four start temperatures -32, -5, 28 and 54 C, 2 h each, soaked exactly at T0 (and the fit is
told so).  Fitted with the default structure, the FOG thermometer's held-out residual is
more than 2x its floor sqrt(0.01^2 + 0.0625^2 / 12) = 0.0206 K; the refinement adopts a
change of where that thermometer sits (kind ``thermometer``), which brings every
thermometer within 2x, and stops there.  On the default world itself (nothing to change)
no step is taken.
"""

from __future__ import annotations

import dataclasses

import pytest

from nfs.fit.refine import REFINE_FACTOR, fit_unit
from nfs.fit.structure import thermometer_weight
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.config.scenario import load_scenario

TEMPS = (-32.0, -5.0, 28.0, 54.0)


def _runs(inst):
    sc = load_scenario().nominal()
    conds = [dataclasses.replace(c, duration_s=7200.0) for c in sc.conditions()
             if c.start_temperature_c in TEMPS]
    return [simulate_run(inst, c).run for c in conds]


@pytest.mark.slow
def test_thermometer_elsewhere_is_adopted():
    # the two-node coil, where the inner node is a slow part of its own (on a wound coil the
    # inner face and the outer layer follow each other closely, and a thermometer moved
    # between them is fitted as well by a share of the electronics)
    default = load_instrument("lumped")
    inner, outer = default.gyro.coil_inner, default.gyro.coil_outer
    truth = thermometer_weight(default, "fog", inner).build([0.3])
    res = fit_unit(default, _runs(truth), start_state=None, decimate_s=30.0)
    ref = res.structure
    assert ref is not None and ref.steps, ref
    first = ref.steps[0]
    assert first.worst_before > REFINE_FACTOR
    assert "fog thermometer" in first.name
    assert ref.adequacy.worst.ratio <= REFINE_FACTOR, ref.summary()
    assert "within" in ref.stopped
    assert res.initial is default
    assert "structure: " in res.summary()
    # the refined thermometer reads the coil's inner face or another slow node (housing:
    # both lag alike)
    fog = res.instrument.thermometers["fog"].nodes
    assert set(fog) - {"electronics", outer}


def test_nothing_to_refine_on_the_model_s_own_runs():
    default = load_scenario().nominal().instrument
    res = fit_unit(default, _runs(default), start_state=None, decimate_s=30.0)
    assert res.structure is not None and res.structure.steps == ()
    assert res.structure.adequacy.worst.ratio <= REFINE_FACTOR
    assert not any("thermal no generic" in w for w in res.warnings)
