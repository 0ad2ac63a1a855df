"""The DWT level of a cutoff period, the span of a record's ends the transform reaches, and
whether a record is long enough for a level: all without PyWavelets.

What a scenario file's reader checks of the drift separation (a cutoff the shortest run can
be separated at) it checks here, by the same functions the denoiser
(:func:`nfs.denoise.wavelet.wavelet_denoise`) uses, with the wavelets known by their filter
lengths (:data:`FILTER_LENGTHS`) rather than by importing PyWavelets.
"""

from __future__ import annotations

import math
import numbers

from ..errors import InputError

__all__ = ["level_for_cutoff", "cutoff_for_level", "edge_span_samples", "positive",
           "DEFAULT_WAVELET", "FILTER_LENGTHS", "max_level", "check_level", "check_edge_fit"]

#: The wavelet of the drift separation and of :func:`nfs.denoise.wavelet.wavelet_denoise`
#: unless another is given: Daubechies' db4 (the FOG start-up paper).
DEFAULT_WAVELET = "db4"

#: Orders (p, q) of PyWavelets' biorthogonal wavelets bior p.q and rbio p.q.
_BIOR_ORDERS = ((1, 1), (1, 3), (1, 5), (2, 2), (2, 4), (2, 6), (2, 8), (3, 1), (3, 3), (3, 5),
                (3, 7), (3, 9), (4, 4), (5, 5), (6, 8))

#: Decomposition filter length L [taps] of every discrete wavelet of PyWavelets, by name
#: (``pywt.Wavelet(name).dec_len``; the names are ``pywt.wavelist(kind="discrete")``): dbN
#: and symN have 2N taps, coifN 6N (Daubechies 1992, *Ten Lectures on Wavelets*, sections
#: 6.4 and 8.2; sections not checked), bior/rbio p.q 2q + 2 (2q for p = 1, PyWavelets'
#: zero-padded filters), dmey 62.  tests/denoise/test_denoise_levels.py checks the table
#: against PyWavelets itself, names and lengths.
FILTER_LENGTHS: dict[str, int] = {
    "haar": 2, "dmey": 62,
    **{f"db{n}": 2 * n for n in range(1, 39)},
    **{f"sym{n}": 2 * n for n in range(2, 21)},
    **{f"coif{n}": 6 * n for n in range(1, 18)},
    **{f"{family}{p}.{q}": 2 * q + (0 if p == 1 else 2)
       for family in ("bior", "rbio") for p, q in _BIOR_ORDERS},
}


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


def max_level(n_samples: int, filter_length: int) -> int:
    """The deepest useful DWT level of a record of ``n_samples`` samples with a filter of
    ``filter_length`` taps: floor(log2(n / (L - 1))), 0 when n < L - 1 (the level at which
    the record becomes shorter than the filter; PyWavelets' ``dwt_max_level``, to which
    tests/denoise/test_denoise_levels.py holds it), in integers."""
    n, span = int(n_samples), int(filter_length) - 1
    return 0 if n < span else (n // span).bit_length() - 1


def check_level(level: int, n_samples: int, wavelet: str, filter_length: int, *,
                extended: bool) -> None:
    """An InputError unless a record of ``n_samples`` samples reaches DWT level ``level``
    with ``wavelet`` (its filter of ``filter_length`` taps): the record as transformed, with
    its smooth extension of :func:`edge_span_samples` at each end when ``extended``, must
    hold (L - 1) 2^J samples or more (:func:`max_level`)."""
    n = int(n_samples)
    n_transformed = n + 2 * min(edge_span_samples(level, filter_length), n - 1) \
        if extended else n
    deepest = max_level(n_transformed, filter_length)
    if level > deepest:
        need = (filter_length - 1) * 2 ** level
        raise InputError(f"level {level} needs a transformed record of at least {need} "
                         f"samples with {wavelet} (filter length {filter_length}); this one "
                         f"has {n_transformed} (max level {deepest})")


def check_edge_fit(level: int, n_samples: int, edge_fit_samples: int | None,
                   edge_fit_degree) -> tuple[int, int | str]:
    """The window [samples] and the degree of the polynomial fitted at each end of a record
    of ``n_samples`` samples for its smooth extension at level J = ``level`` (window
    min(n, 2^J) unless ``edge_fit_samples`` is given; degree ``"auto"`` or an integer >= 0),
    or an InputError when the degree is neither or the window too short for it (3 samples
    for ``"auto"``, degree + 1 otherwise)."""
    window = min(int(n_samples), 2 ** level if edge_fit_samples is None
                 else int(edge_fit_samples))
    degree = edge_fit_degree
    if degree != "auto":
        if isinstance(degree, bool) or not isinstance(degree, numbers.Integral) or degree < 0:
            raise InputError(f'edge_fit_degree must be "auto" or an integer >= 0, '
                             f"got {degree!r}")
        degree = int(degree)
    if window < (3 if degree == "auto" else degree + 1):
        raise InputError(f"edge fit of degree {degree} needs more samples than "
                         f"edge_fit_samples = {window}")
    return window, degree
