"""Reading a scenario file loads neither the learners (scikit-learn) nor the wavelet
denoiser (PyWavelets): they are needed to train and to separate the drift, not to check the
names and values of a file.

Oracle: the modules a fresh interpreter holds after :func:`nfs.load_scenario` (a subprocess,
so that the test does not depend on what earlier tests imported).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path


ROOT = Path(__file__).resolve().parents[2]

#: What a scenario's reader must not load: the learners and scikit-learn, the denoiser and
#: PyWavelets (the light level arithmetic of nfs.denoise.levels is allowed).
HEAVY = ("sklearn", "pywt", "nfs.learners", "nfs.denoise.wavelet", "nfs.denoise.drift",
         "nfs.denoise.thresholds")


def test_reading_a_scenario_loads_no_learner_and_no_pywavelets():
    code = ("import json, sys, nfs; nfs.load_scenario(); "
            f"heavy = {HEAVY!r}; "
            "print(json.dumps(sorted(m for m in sys.modules "
            "if any(m == h or m.startswith(h + '.') for h in heavy))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout
    assert json.loads(out) == []
