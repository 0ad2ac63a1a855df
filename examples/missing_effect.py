"""Which physical effect is my model missing?  A worked example of fit -> compare -> diagnose.

The "measurements" come from an instrument that has an effect the default model lacks: a
magnetic (Faraday) bias that follows the turntable position, m cos(A - D_mag) with
m = 0.012 deg/h, D_mag = 30 deg (effects.md, ``magnetic``).  The default model is put beside
them, the comparison says where it fails, the diagnosis names the missing effect, and adding
it makes the residual fall.

Run as ``python examples/missing_effect.py [OUT_DIR]``; the same steps from the command line::

    nfs simulate hidden.toml -o runs/            # (here: made in Python below)
    nfs compare runs/ --model default -o report/
    nfs diagnose runs/ --model default --json diag.json
    nfs diagnose runs/ --model default --apply magnetic -o fitted2.toml
    nfs compare runs/ --model fitted2.toml -o report2/
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

from nfs.diagnose import apply_candidate, compare, diagnose
from nfs.effects import make_effect
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument
from nfs.io.scenario import load_scenario

HIDDEN = {"name": "magnetic", "m": 0.012, "D_mag": 30.0}


def measurements(seed: int = 21):
    """Seven start-ups (seed 004's temperatures) of an instrument with the hidden effect."""
    model = load_instrument("default")
    params = {k: v for k, v in HIDDEN.items() if k != "name"}
    truth = model.with_effects(list(model.effects) + [make_effect(HIDDEN["name"], params)])
    sc = dataclasses.replace(load_scenario(), seed=seed)
    return model, [simulate_run(truth, c).run for c in sc.conditions()]


def main(out_dir: str | Path | None = None) -> dict:
    out = Path(out_dir or tempfile.mkdtemp(prefix="nfs_missing_effect_"))
    model, runs = measurements()

    before = compare(model, runs)
    gyro = before.summaries["gyro_drift_dph"]
    print("1. the default model beside the measurements:")
    print("   " + gyro.sentence)

    d = diagnose(model, runs)
    top = d.ranking[0]
    print("2. diagnosis: " + d.verdict)
    print(f"   top candidate: {top.effect} (CV drift RMS {top.cv_rms_before:.4f} -> "
          f"{top.cv_rms_after:.4f} deg/h)")

    new, fit, report = apply_candidate(model, runs, top.effect, top.target)
    after = compare(new, runs)
    print(f"3. with {top.effect} added and refitted: "
          + ", ".join(f"{k} = {v:.4g}" for k, v in fit.params.items() if "magnetic" in k))
    print("   " + after.summaries["gyro_drift_dph"].sentence)
    rms_b, floor = gyro.stages["all"]
    rms_a, _ = after.summaries["gyro_drift_dph"].stages["all"]
    return {"top": top.effect, "significant": [s.effect for s in d.significant],
            "rms_before": rms_b, "rms_after": rms_a, "floor": floor,
            "position_ratio_before": gyro.position_ratio,
            "position_ratio_after": after.summaries["gyro_drift_dph"].position_ratio,
            "heading_before_deg": report.get("heading_rmse_before_deg"),
            "heading_after_deg": report.get("heading_rmse_after_deg"), "out": out}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
