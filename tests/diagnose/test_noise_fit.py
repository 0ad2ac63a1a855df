"""Gyro noise from the Allan deviation of a residual at rest (nfs.diagnose.noise_fit).

Oracle: the package's own noise generator (nfs.noise.gyro_noise_dph) with N = 0.0003
deg/sqrt(h) and B = 0.002 deg/h, cut into dwells of 150 s with 10 s gaps and concatenated as
the fit does: the fitted N and B come back within 20 %.
"""

import numpy as np
import pytest

from nfs.diagnose.noise_fit import gyro_noise_from_residual
from nfs.errors import NfsError
from nfs.noise import gyro_noise_dph


def test_recovers_arw_and_bias_instability():
    recs = []
    for seed in range(5):
        x = gyro_noise_dph(9000, 1.0, arw_deg_per_rth_h=3e-4, bias_instability_dph=2e-3,
                           rrw_deg_per_h_per_rth_h=0.0, rng=np.random.default_rng(seed))
        at_rest = (np.arange(9000) % 160) < 150
        recs.append(x[at_rest])
    est = gyro_noise_from_residual(recs, 1.0)
    assert est.arw_deg_per_rth_h == pytest.approx(3e-4, rel=0.2)
    assert est.bias_instability_dph == pytest.approx(2e-3, rel=0.2)
    assert est.n_samples == sum(r.size for r in recs)
    assert np.all(np.diff(est.taus_s) > 0) and est.adev_dph.shape == est.taus_s.shape
    # the fitted curve passes through the measured one at short tau (white noise)
    assert est.adev_model_dph(est.taus_s[:1])[0] == pytest.approx(est.adev_dph[0], rel=0.05)


def test_too_short():
    with pytest.raises(NfsError, match="16 samples"):
        gyro_noise_from_residual([np.zeros(5)], 1.0)
