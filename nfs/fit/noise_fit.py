"""The gyro's noise coefficients from the Allan deviation of the drift residual at rest.

After the drift stage, what the model does not explain of the gyro at rest,

    e(t) = gyro(t) - Earth-rate projection(t) - model drift(t)                    [deg/h]

is the gyro's noise (plus whatever the model lacks).  Its overlapping Allan deviation
(:func:`nfs.noise.allan.allan_deviation`, NIST SP 1065 eq. (11)) is fitted with angle random
walk N, bias instability B and rate random walk K
(:func:`nfs.noise.allan.fit_noise_coefficients`, IEEE Std 952-2020 Annex C).

Gaps: the gyro is not at rest while the turntable moves (5-15 s every dwell of 60-180 s).
Per-dwell Allan deviations stop at half a dwell, too short for the bias-instability floor,
which a 1 Hz gyro of N = 0.0003 deg/sqrt(h) reaches only near tau = 3 min.  So the samples at
rest of each run are concatenated in time order, gaps removed, and the Allan deviation of
that record is computed (one per run, the Allan variances pooled over the runs with the
number of clusters as weights).  Up to a dwell the clusters are those of the continuous
record, except the few that straddle a gap; beyond a dwell the record is the continuous one
with time compressed by dwell / (dwell + move) (about 0.94), whose effect on a flat floor is
nil and on the -1/2 and +1/2 slopes a few per cent.  Per-dwell means instead would keep only
one point per dwell and lose every tau below it.

Noise is not an effect.  What the model lacks would otherwise be read as noise, and the
noise then inflates the floor the model is compared with: a magnetic bias m cos(A - D_mag)
switches with every dwell and puts an Allan bump at the dwell scale that the fit takes for
bias instability; a missing thermal term puts a slow trend in the start-up hour that it
takes for rate random walk.  So the record the noise is read from is (:func:`noise_record`)
the run after its start-up hour (:data:`NOISE_FROM_S`; the whole run when it is shorter
than twice that) with its position harmonics removed, each run's least-squares fit on
[1, cos A, sin A, cos 2A, sin 2A] (A the axis azimuth): five numbers per run of several
thousand samples, which take from a bias instability only its projection on the dwell
pattern (tested: the noise coefficients of a pure noise record come back within their
Allan errors), and take a position-dependent bias whole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..docfields import document_fields
from ..errors import NfsError
from ..noise.allan import allan_deviation, allan_relative_error, fit_noise_coefficients

__all__ = ["NOISE_FROM_S", "GyroNoiseEstimate", "gyro_noise_from_residual", "noise_record"]

#: The noise is read after this time from power-on [s]: the start-up hour, where a missing
#: thermal term lives, is left out.
NOISE_FROM_S = 3600.0


def noise_record(residual_dph: np.ndarray, time_s: np.ndarray, azimuth_deg: np.ndarray,
                 from_s: float = NOISE_FROM_S) -> np.ndarray:
    """The part of one run's residual at rest that is read as noise (module docstring).

    Parameters
    ----------
    residual_dph : ndarray
        e(t) at the samples at rest, in time order [deg/h].
    time_s, azimuth_deg : ndarray
        Their times from power-on [s] and axis azimuths A [deg].
    from_s : float
        Start of the record [s], used when the run lasts at least twice as long.
    """
    e = np.asarray(residual_dph, dtype=float)
    t = np.asarray(time_s, dtype=float)
    a = np.radians(np.asarray(azimuth_deg, dtype=float))
    keep = np.isfinite(e)
    if t.size and t[-1] >= 2.0 * from_s:
        keep &= t >= from_s
    e, a = e[keep], a[keep]
    if e.size < 16:
        return e
    design = np.column_stack([np.ones(e.size), np.cos(a), np.sin(a), np.cos(2 * a),
                              np.sin(2 * a)])
    coef, *_ = np.linalg.lstsq(design, e, rcond=None)
    return e - design @ coef


@document_fields
@dataclass(frozen=True)
class GyroNoiseEstimate:
    """The gyro noise read from the drift residual at rest."""

    arw_deg_per_rth_h: float
    """Angle random walk N [deg/sqrt(h)]."""
    bias_instability_dph: float
    """Bias instability B [deg/h]."""
    rrw_deg_per_h_per_rth_h: float
    """Rate random walk K [deg/h/sqrt(h)]."""
    taus_s: np.ndarray
    """Averaging times of the Allan curve [s]."""
    adev_dph: np.ndarray
    """Pooled overlapping Allan deviation of the residual [deg/h]."""
    adev_rel_err: np.ndarray
    """Approximate relative 1-sigma error of each point [-]."""
    n_samples: int
    """Samples at rest used, over all runs."""
    method: str
    """How the gaps at the moves were handled."""

    def values(self) -> dict[str, float]:
        """{gyro parameter path: fitted value} of N, B and K."""
        return {"gyro.arw_deg_per_rth_h": self.arw_deg_per_rth_h,
                "gyro.bias_instability_dph": self.bias_instability_dph,
                "gyro.rrw_deg_per_h_per_rth_h": self.rrw_deg_per_h_per_rth_h}

    def stderr(self) -> dict[str, float]:
        """{gyro parameter path: approximate standard error}: each value times the relative
        error of the Allan point that sets it (N: the shortest tau; B: the curve's floor; K:
        the longest tau).  A rough figure: the fit pools correlated points."""
        if len(self.adev_rel_err) == 0:
            return {p: math.nan for p in self.values()}
        rel = np.asarray(self.adev_rel_err, dtype=float)
        where = {"gyro.arw_deg_per_rth_h": 0,
                 "gyro.bias_instability_dph": int(np.argmin(self.adev_dph)),
                 "gyro.rrw_deg_per_h_per_rth_h": len(rel) - 1}
        return {p: abs(v) * float(rel[where[p]]) for p, v in self.values().items()}

    def adev_model_dph(self, taus_s: np.ndarray) -> np.ndarray:
        """The fitted curve sqrt((60 N)^2/tau + (0.6643 B)^2 + (K/60)^2 tau/3) [deg/h]."""
        tau = np.asarray(taus_s, dtype=float)
        return np.sqrt((60.0 * self.arw_deg_per_rth_h) ** 2 / tau
                       + (math.sqrt(2 * math.log(2) / math.pi) * self.bias_instability_dph) ** 2
                       + (self.rrw_deg_per_h_per_rth_h / 60.0) ** 2 * tau / 3.0)


def gyro_noise_from_residual(residuals_dph: Sequence[np.ndarray], sample_rate_hz: float, *,
                             max_fraction: float = 0.25) -> GyroNoiseEstimate:
    """Fit N, B, K to the pooled Allan deviation of residual records at rest.

    Parameters
    ----------
    residuals_dph : sequence of ndarray
        One record per run: the residual e(t) of its samples at rest, in time order, gaps
        removed [deg/h] (module docstring).
    sample_rate_hz : float
        Sample rate fs [Hz] of the records.
    max_fraction : float
        Longest averaging time as a fraction of the shortest record (1/4: each run still
        gives at least 3 clusters of two averages).

    Returns
    -------
    GyroNoiseEstimate
    """
    recs = [np.asarray(r, dtype=float) for r in residuals_dph]
    recs = [r[np.isfinite(r)] for r in recs]
    recs = [r for r in recs if r.size >= 16]
    if not recs:
        raise NfsError("gyro noise fit: no run has 16 samples at rest")
    fs = float(sample_rate_hz)
    n_min = min(r.size for r in recs)
    m_max = max(1, int(n_min * max_fraction))
    m = np.unique(np.round(np.geomspace(1, m_max, max(3, int(4 * math.log2(m_max)) + 1))))
    taus = m / fs
    avar = np.zeros(m.size)
    clusters = np.zeros(m.size)
    for r in recs:
        a = allan_deviation(r, fs, taus)
        avar += a.adev ** 2 * a.n_clusters
        clusters += a.n_clusters
    adev = np.sqrt(avar / clusters)
    n_total = int(sum(r.size for r in recs))
    rel = allan_relative_error(n_total, m.astype(np.int64))
    fit = fit_noise_coefficients(taus, adev, adev_rel_err=rel)
    return GyroNoiseEstimate(
        arw_deg_per_rth_h=fit.arw_deg_per_rth_h, bias_instability_dph=fit.bias_instability_dph,
        rrw_deg_per_h_per_rth_h=fit.rrw_deg_per_h_per_rth_h, taus_s=taus, adev_dph=adev,
        adev_rel_err=rel, n_samples=n_total,
        method="samples at rest of each run concatenated (gaps at the moves removed), "
               "overlapping Allan variances pooled over runs by cluster count")
