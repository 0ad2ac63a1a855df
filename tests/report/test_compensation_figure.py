"""The figure of the drift, its prediction and the residual (drift_vs_compensated.png).

Oracles (invariants of a figure that means what it says): every trace drawn lies within its
panel's limits (none clipped); the residual's limits are symmetric about 0; the legends
stand beside the panels, off the data; the title lies inside the figure.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from nfs.studies.startup_study import run_study
from nfs.compensate.settings import CompensationSettings
from nfs.report.compensation import plot_drift_vs_compensated

@pytest.fixture(scope="module")
def study(small_scenario):
    return run_study(small_scenario, CompensationSettings(methods=("ls",), train_seed=9,
                                                            test_repeats=1, n_jobs=1))


def test_every_trace_shows_and_the_legends_cover_nothing(study):
    fig = plot_drift_vs_compensated(study, best="LS")
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    drift, residual = fig.axes
    for ax in (drift, residual):
        lo, hi = ax.get_ylim()
        for line in ax.get_lines():
            y = np.asarray(line.get_ydata(), dtype=float)
            y = y[np.isfinite(y)]
            assert lo <= y.min() and y.max() <= hi, line.get_label()
        box, leg = ax.get_window_extent(renderer), ax.get_legend().get_window_extent(renderer)
        assert leg.x0 >= box.x1, "the legend stands beside the panel"
    lo, hi = residual.get_ylim()
    assert lo == pytest.approx(-hi)
    labels = [t.get_text() for t in drift.get_legend().get_texts()]
    assert any(lab.startswith("gyro output - Earth rate") for lab in labels)
    assert "LS: predicted drift" in labels
    title = fig._suptitle.get_window_extent(renderer)
    whole = fig.bbox
    assert whole.x0 <= title.x0 and title.x1 <= whole.x1 and title.y1 <= whole.y1
    assert "LS (best row of the table)" in fig.get_suptitle()
