"""The report draws what the study computed: no second separation, prediction or training.

Oracles: counts (the wavelet separation, a compensator's prediction and the tuned fits are
never called while the report is written, for any file it writes) and equality (the drift
figure's traces are the study's stored separation and predictions, array for array).
"""

from __future__ import annotations

import numpy as np
import pytest

import nfs.denoise
import nfs.report.compensation as report
from nfs.compensate.compensator import DriftCompensator
from nfs.compensate.settings import CompensationSettings
from nfs.studies.startup_study import run_study

@pytest.fixture(scope="module")
def study(small_scenario):
    return run_study(small_scenario, CompensationSettings(methods=("ls", "stepwise"),
                                                            train_seed=9, test_repeats=1,
                                                            n_jobs=1))


def test_write_study_separates_and_predicts_nothing_again(study, tmp_path, monkeypatch):
    calls = []

    def refuse(name):
        def f(*args, **kwargs):
            calls.append(name)
            raise AssertionError(f"the report called {name}")
        return f

    monkeypatch.setattr(report, "separate_drift", refuse("separate_drift"))
    monkeypatch.setattr(nfs.denoise, "separate_drift", refuse("nfs.denoise.separate_drift"))
    monkeypatch.setattr(DriftCompensator, "predict_drift", refuse("predict_drift"))
    table = study.heading_table()
    paths = report.write_study(study, tmp_path, table=table)
    assert calls == []
    assert (tmp_path / "drift_vs_compensated.png").stat().st_size > 0
    assert all(p.exists() for p in paths)


def test_drift_figure_draws_the_stored_arrays(study):
    fig = report.plot_drift_vs_compensated(study, methods=("LS",))
    k = int(np.argmin([s.conditions.start_temperature_c for s in study.test.simulations]))
    top = fig.axes[0].get_lines()
    drawn = {line.get_label(): np.asarray(line.get_ydata()) for line in top}
    sep = study.test_separations[k]
    assert np.array_equal(drawn["thermal drift\n(wavelet-separated) [deg/h]"],
                          np.asarray(sep.drift_dph))
    assert np.array_equal(drawn["LS: predicted drift"],
                          study.results["LS"].predicted_drift_dph[k], equal_nan=True)
