"""The DWT level of a cutoff period and the span of a record's ends the transform reaches."""

from __future__ import annotations

import math

from ..errors import InputError

__all__ = ["level_for_cutoff", "cutoff_for_level", "edge_span_samples", "positive"]


def positive(name: str, value: float) -> float:
    """``value`` as a finite float > 0, or an InputError naming ``name``."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{name} must be finite and > 0, got {value!r}")
    return value

# --------------------------------------------------------------------------------------------
# level and cutoff


def level_for_cutoff(cutoff_period_s: float, sample_rate_hz: float) -> int:
    """DWT level J whose approximation keeps the periods longer than ``cutoff_period_s``.

    Each DWT level halves the band: the level-J approximation holds frequencies below
    fs / 2^(J+1), i.e. periods longer than 2^(J+1) samples (the dyadic bands of a
    multiresolution analysis: Mallat 2009, *A Wavelet Tour of Signal Processing*, 3rd ed.,
    chapter 7; section not checked). Hence

        J = round(log2(P fs)) - 1,   P: cutoff period [s], fs: sample rate [Hz],

    rounded to the nearest dyadic cutoff on a log scale (P fs = 512 at 1 Hz gives J = 8; the
    band edges of real wavelet filters are not sharp, so the cutoff is nominal).

    Parameters
    ----------
    cutoff_period_s : float
        P, the shortest period the approximation should keep [s].
    sample_rate_hz : float
        fs [Hz].

    Returns
    -------
    int
        J >= 1.

    Raises
    ------
    InputError
        A non-positive or non-finite argument, or P fs < 2^(1.5) (shorter than level 1 cuts).
    """
    p = positive("cutoff_period_s", cutoff_period_s)
    fs = positive("sample_rate_hz", sample_rate_hz)
    samples = p * fs
    if samples < 2.0 ** 1.5:
        raise InputError(f"cutoff_period_s = {p!r} s is {samples:.3g} samples at {fs!r} Hz; "
                         "level 1 already cuts at 4 samples, so the cutoff must be at least "
                         "about 3 samples")
    return max(1, int(round(math.log2(samples))) - 1)


def cutoff_for_level(level: int, sample_rate_hz: float) -> float:
    """The nominal cutoff of level J: 2^(J+1) / fs [s] (inverse of :func:`level_for_cutoff`)."""
    return 2.0 ** (int(level) + 1) / positive("sample_rate_hz", sample_rate_hz)


def edge_span_samples(level: int, filter_length: int) -> int:
    """Samples at each end of a record that boundary effects reach at level J.

        (L - 1)(2^J - 1)

    is the support, in samples of the record, of a level-J wavelet or scaling function of a
    filter of length L (the scaling function of a length-L filter is supported on [0, L - 1]
    at scale 1: Daubechies 1992, *Ten Lectures on Wavelets*, chapter 6; section not checked).
    A sample farther than this from an end is rebuilt only
    from coefficients that never see the extension. At db4 (L = 8), J = 8: 1785 samples.
    """
    return (int(filter_length) - 1) * (2 ** int(level) - 1)
