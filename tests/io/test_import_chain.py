"""An imported chamber log, and a run with missing samples, go through the unit's chain as
the run they came from.

Oracles: the same two simulated runs (T0 = -20 and 30 C, tests/io/chamber_logs.py) as the
simulator wrote them, beside

- the same runs written as three-file chamber logs and imported: they differ only by the
  resampling of the thermometers (within a quantum of 0.0625 K) and the chamber (exact on
  its piecewise-linear program);
- the same runs with 30 gyro, FOG-thermometer and accelerometer samples each made missing
  (NaN, as ``--allow-nan`` reads them): every consumer leaves them out;

so the fit lands on the same parameters (within a fifth of their standard errors, or
1e-3 relative), the comparison says the same of every channel, and the diagnosis gives the
same answer with the same leading candidates.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from chamber_logs import simulate, write_log

import nfs


def _chain(runs):
    chain = nfs.UnitChain("default", runs)
    return chain.fit(), chain.compare(), chain.diagnose()


@pytest.fixture(scope="module")
def native(tmp_path_factory):
    folder = tmp_path_factory.mktemp("native")
    runs = [simulate(folder, t0) for t0 in (-20.0, 30.0)]
    return runs, _chain(runs)


def _same_answers(got, want):
    (fit_g, cmp_g, dia_g), (fit_w, cmp_w, dia_w) = got, want
    assert fit_g.params.keys() == fit_w.params.keys()
    for p, value in fit_w.params.items():
        shift = abs(fit_g.params[p] - value)
        # the thermometers are resampled from their own clocks: a fraction of an error bar
        assert shift <= 0.5 * fit_w.stderr[p] or shift <= 1e-3 * abs(value), \
            (p, value, fit_g.params[p], fit_w.stderr[p])
    assert {k: s.consistent for k, s in cmp_g.summaries.items()} == \
        {k: s.consistent for k, s in cmp_w.summaries.items()}
    assert (dia_g.answer.kind, dia_g.answer.labels) == (dia_w.answer.kind, dia_w.answer.labels)
    # the candidates that stand (the order of those that do not is noise)
    assert [(s.effect, s.target) for s in dia_g.diagnosis.ranking if s.significant] == \
        [(s.effect, s.target) for s in dia_w.diagnosis.ranking if s.significant]
    assert (dia_g.diagnosis.ranking[0].effect, dia_g.diagnosis.ranking[0].target) == \
        (dia_w.diagnosis.ranking[0].effect, dia_w.diagnosis.ranking[0].target)


@pytest.mark.integration
def test_imported_logs_fit_compare_and_diagnose_as_the_native_runs(native, tmp_path):
    runs, answers = native
    imported = [nfs.import_log(write_log(run, tmp_path / f"log_{i}"))
                for i, run in enumerate(runs)]
    _same_answers(_chain(imported), answers)


@pytest.mark.integration
def test_missing_samples_are_left_out_by_every_step(native):
    runs, answers = native
    rng = np.random.default_rng(0)
    holed = []
    for run in runs:
        columns = dict(run.columns)
        for name in ("gyro_dph", "temp_fog_c", "acc_x_g"):
            values = columns[name].copy()
            values[rng.choice(values.size, 30, replace=False)] = np.nan
            columns[name] = values
        holed.append(dataclasses.replace(run, columns=columns))
    _same_answers(_chain(holed), answers)
