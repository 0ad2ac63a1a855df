"""Gyro noise from the Allan deviation of a residual at rest (nfs.fit.noise_fit).

Oracle: the package's own noise generator (nfs.noise.gyro_noise_dph) with N = 0.0003
deg/sqrt(h) and B = 0.002 deg/h, cut into dwells of 150 s with 10 s gaps and concatenated as
the fit does: the fitted N and B come back within 20 %.
"""

import numpy as np
import pytest

from nfs.fit.noise_fit import NOISE_FROM_S, gyro_noise_from_residual, noise_record
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


def _positions(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times [s], axis azimuths [deg] and the at-rest mask of a 4-position schedule of 150 s
    dwells and 10 s moves from power-on."""
    t = np.arange(n, dtype=float)
    k = (np.arange(n) // 160) % 4
    return t, 212.7 + 90.0 * k, (np.arange(n) % 160) < 150


def test_noise_record_leaves_noise_and_takes_a_position_bias():
    """Oracles: a bias that follows the turntable position, c1 cos(A - D) + c2 cos(2A - D2),
    lies in the span noise_record removes, so the record of noise plus that bias equals the
    record of the noise alone (to rounding); and on pure noise (N = 0.0003 deg/sqrt(h),
    B = 0.002 deg/h) the removal takes only the noise's projection on five columns: the
    pooled Allan deviation is that of the same samples without the removal within 5 % at
    every tau.  Without noise_record the magnetic bias raises the Allan deviation at the
    dwell scale (tau 150-450 s) by half or more: what the fit would read as bias
    instability."""
    t, az, rest = _positions(9000)
    late = rest & (t >= NOISE_FROM_S)
    clean, biased, raw, plain = [], [], [], []
    for seed in range(5):
        x = gyro_noise_dph(9000, 1.0, arw_deg_per_rth_h=3e-4, bias_instability_dph=2e-3,
                           rrw_deg_per_h_per_rth_h=0.0, rng=np.random.default_rng(seed))
        m = (x + 0.01 * np.cos(np.radians(az - 120.0))
             + 0.004 * np.cos(np.radians(2 * az - 30.0)))
        clean.append(noise_record(x[rest], t[rest], az[rest]))
        biased.append(noise_record(m[rest], t[rest], az[rest]))
        raw.append(x[late])
        plain.append(m[rest])
        assert clean[-1].size == int(np.sum(late))
        np.testing.assert_allclose(biased[-1], clean[-1], atol=1e-12)
    a_clean = gyro_noise_from_residual(clean, 1.0)
    a_raw = gyro_noise_from_residual(raw, 1.0)
    np.testing.assert_allclose(a_clean.adev_dph, a_raw.adev_dph, rtol=0.05)
    a_plain = gyro_noise_from_residual(plain, 1.0)
    dwell = (a_plain.taus_s >= 150) & (a_plain.taus_s <= 450)
    ref = np.interp(a_plain.taus_s[dwell], a_clean.taus_s, a_clean.adev_dph)
    assert np.all(a_plain.adev_dph[dwell] > 1.5 * ref)
    # a run shorter than twice the start-up hour is read whole
    short = noise_record(np.ones(100), t[:100], az[:100])
    assert short.size == 100 and np.allclose(short, 0.0)
