"""Tests of nfs.denoise.levels: what the scenario reader knows of the wavelets without
PyWavelets.

Oracle: PyWavelets itself, the library the denoiser runs on: the table of filter lengths is
``pywt.Wavelet(name).dec_len`` for every name of ``pywt.wavelist(kind="discrete")``, and the
deepest level of a record is ``pywt.dwt_max_level``.  A record refused at a level by the
checks is refused by the denoiser, with the same message (invariant: one piece of code).
"""

from __future__ import annotations

import numpy as np
import pytest
import pywt

from nfs.denoise.levels import (DEFAULT_WAVELET, FILTER_LENGTHS, check_edge_fit, check_level,
                                level_for_cutoff, max_level)
from nfs.denoise.wavelet import wavelet_denoise
from nfs.errors import InputError


def test_filter_lengths_are_pywavelets_discrete_wavelets():
    names = pywt.wavelist(kind="discrete")
    assert sorted(FILTER_LENGTHS) == sorted(names)
    assert FILTER_LENGTHS == {n: pywt.Wavelet(n).dec_len for n in names}


@pytest.mark.parametrize("filter_length", [2, 4, 6, 8, 16, 62, 102])
def test_max_level_is_pywavelets_dwt_max_level(filter_length):
    n = np.arange(0, 5000)
    ours = [max_level(k, filter_length) for k in n]
    theirs = [pywt.dwt_max_level(int(k), filter_length) for k in n]
    assert ours == theirs


@pytest.mark.parametrize("n", [2, 3, 10, 100, 600, 1800, 5000])
@pytest.mark.parametrize("cutoff_s", [4.0, 64.0, 512.0, 4096.0])
def test_a_record_the_checks_refuse_the_denoiser_refuses_alike(n, cutoff_s):
    def checks():
        level = level_for_cutoff(cutoff_s, 1.0)
        check_level(level, n, DEFAULT_WAVELET, FILTER_LENGTHS[DEFAULT_WAVELET], extended=True)
        check_edge_fit(level, n, None, "auto")

    def denoiser():
        with np.errstate(all="ignore"):
            wavelet_denoise(np.zeros(n), sample_rate_hz=1.0, cutoff_period_s=cutoff_s)

    messages = []
    for run in (checks, denoiser):
        try:
            run()
            messages.append(None)
        except InputError as exc:
            messages.append(str(exc))
    assert messages[0] == messages[1]
