"""The two figures nfs compare draws against time: each dwell's gyro bias by turntable
position (nfs.comparison.dwell_traces.DwellBias) and each cycle's heading error
(HeadingTrace), measured beside the model.

Oracles: a run the noise-free model made itself, replayed by that model from the same soak,
is its prediction (every dwell's bias and every cycle's heading error equal to rounding, and
no noise between its twins); on noisy runs, a dwell's bias is the mean of gyro less the
Earth-rate projection over the north finder's dwell, written out; the figures carry a labelled
line per position and run, and are written by write_report.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from nfs.comparison import Comparison, compare
from nfs.comparison.compare_runs import noise_free
from nfs.config.scenario import load_scenario
from nfs.denoise import earth_rate_projection_dph
from nfs.experiment import simulate_run
from nfs.northfind import north_find
from nfs.report.compare_report import plot_dwell_bias, plot_heading_vs_time, write_report


def _runs(inst, seed, temps=(-20.0, 40.0), duration_s=2600.0):
    sc = dataclasses.replace(load_scenario().nominal(), start_temperatures_c=temps,
                             seed=seed, duration_s=duration_s)
    return [simulate_run(inst, c).run for c in sc.conditions()]


@pytest.fixture(scope="module")
def noisy():
    inst = load_scenario().nominal().instrument
    return compare(inst, _runs(inst, seed=5), seed=2)


def test_the_noise_free_models_own_runs_are_its_prediction():
    clean = noise_free(load_scenario().nominal().instrument)
    c = compare(clean, _runs(clean, seed=1), seed=0, start_state=None)
    assert len(c.dwell_biases) == len(c.heading_traces) == 2
    for b, h in zip(c.dwell_biases, c.heading_traces):
        assert b.time_s.size == 4 * 4 and np.all(np.isfinite(b.measured_dph))
        assert np.allclose(b.measured_dph, b.model_dph, rtol=0, atol=1e-9)
        assert b.noise_dph == 0.0 and h.noise_deg == 0.0
        assert h.time_s.size == 4
        assert np.allclose(h.measured_deg, h.model_deg, rtol=0, atol=1e-9)


def test_a_dwell_bias_is_the_mean_of_gyro_less_projection(noisy):
    runs = _runs(load_scenario().nominal().instrument, seed=5)
    b = noisy.dwell_biases[1]
    nf = north_find(runs[1])
    x = np.asarray(runs[1]["gyro_dph"]) - earth_rate_projection_dph(runs[1])
    dwells = [d for c in nf.cycles for d in c.dwells]
    assert np.allclose(b.measured_dph, [x[d.index].mean() for d in dwells], rtol=1e-12)
    assert b.theta_deg.tolist() == pytest.approx([0.0, 90.0, 180.0, 270.0] * 4)
    assert np.array_equal(noisy.heading_traces[1].measured_deg, nf.error_deg)
    # a model that made such runs predicts them within a few of its noise
    for b in noisy.dwell_biases:
        assert 0 < b.noise_dph < 0.01
        assert np.sqrt(np.mean((b.measured_dph - b.model_dph) ** 2)) < 3 * b.noise_dph
    # kept in the comparison's record
    back = Comparison.from_dict(json.loads(json.dumps(noisy.to_dict())))
    assert np.array_equal(back.dwell_biases[0].model_dph, noisy.dwell_biases[0].model_dph)
    assert back.heading_traces[1].noise_deg == noisy.heading_traces[1].noise_deg


def test_figures_are_labelled_and_written(noisy, tmp_path):
    fig = plot_dwell_bias(noisy)
    assert len(fig.axes) == 2
    labels = [a.get_label() for a in fig.axes[0].get_lines() + fig.axes[0].containers]
    for theta in (0, 90, 180, 270):
        assert f"theta = {theta} deg: model" in labels
        assert f"theta = {theta} deg: measured, +-1 sigma of a dwell mean" in labels
    for ax in fig.axes:
        lo, hi = ax.get_ylim()
        assert lo <= 0.0 <= hi and "[deg/h]" in ax.get_ylabel()
    fig = plot_heading_vs_time(noisy)
    assert len(fig.axes) == 2
    assert fig.axes[0].get_ylim() == fig.axes[1].get_ylim()          # one scale for all
    lo, hi = fig.axes[0].get_ylim()
    assert lo == -hi
    labels = [a.get_label() for a in fig.axes[0].get_lines() + fig.axes[0].collections]
    assert {"measured", "model (noise-free prediction)",
            "model +-1 sigma heading noise of a cycle (value in the title)"} <= set(labels)
    assert "[deg]" in fig.axes[0].get_ylabel()


def test_write_report_writes_both_figures(tmp_path):
    inst = load_scenario().nominal().instrument
    c = compare(inst, _runs(inst, seed=6, temps=(10.0,), duration_s=1400.0), seed=0)
    paths = write_report(c, tmp_path)
    for name in ("dwell_bias.png", "heading_vs_time.png"):
        assert tmp_path / "figures" / name in paths
        assert (tmp_path / "figures" / name).read_bytes()[:4] == b"\x89PNG"
        assert f"figures/{name}" in (tmp_path / "report.md").read_text()
