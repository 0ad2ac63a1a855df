"""An imported chamber log goes through the unit's chain as the run it came from.

Oracle: the same two simulated runs (T0 = -20 and 30 C), once as the simulator wrote them and
once written as three-file chamber logs (tests/io/chamber_logs.py) and imported: the imported
runs differ only by the resampling of the thermometers (within a quantum of 0.0625 K) and
the chamber (exact on its ramp), so the fit lands on the same parameters (within a small
fraction of their standard errors), the comparison says the same of every channel, and the
diagnosis gives the same answer.
"""

from __future__ import annotations

import numpy as np
import pytest

import nfs

from chamber_logs import simulate, write_log


@pytest.mark.integration
def test_imported_logs_fit_compare_and_diagnose_as_the_native_runs(tmp_path):
    native = [simulate(tmp_path, t0) for t0 in (-20.0, 30.0)]
    imported = [nfs.import_log(write_log(run, tmp_path / f"log_{i}"))
                for i, run in enumerate(native)]
    answers = []
    for runs in (native, imported):
        chain = nfs.UnitChain("default", runs)
        fit = chain.fit()
        comparison = chain.compare()
        finding = chain.diagnose()
        answers.append((fit, comparison, finding))
    (fit_n, cmp_n, dia_n), (fit_i, cmp_i, dia_i) = answers
    assert fit_i.params.keys() == fit_n.params.keys()
    for p, value in fit_n.params.items():
        sigma = fit_n.stderr[p]
        assert abs(fit_i.params[p] - value) <= 0.2 * sigma or \
            abs(fit_i.params[p] - value) <= 1e-3 * abs(value), (p, value, fit_i.params[p], sigma)
    assert [cmp_i.summaries[k].consistent for k in cmp_n.summaries] == \
        [cmp_n.summaries[k].consistent for k in cmp_n.summaries]
    assert (dia_i.answer.kind, dia_i.answer.labels) == (dia_n.answer.kind, dia_n.answer.labels)
    ranks = [[(s.effect, s.target) for s in d.diagnosis.ranking[:3]] for d in (dia_n, dia_i)]
    assert ranks[0] == ranks[1]
    assert np.isfinite([fit_i.rms_after[c] for c in fit_i.rms_after]).all()
