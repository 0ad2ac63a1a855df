"""Which physical effect is my model missing?  fit -> compare -> diagnose -> add, on runs that
our own simulator did not make.

The "measurements" come from the independent generator of the tests
(``tests/independent/generator.py``: a fibre coil of 8 radial finite-difference layers,
thermometers that sit between nodes, its own TEC law, a Gauss-Markov gyro bias, a cycling
chamber; it imports nothing of ``nfs``), seven start temperatures x 2.5 h, with a magnetic
(Faraday) bias hidden in the gyro: m cos(A - D_mag), m = 0.012 deg/h, D_mag = 40 deg, which
follows the turntable position.  The default lumped model does not have it, and its thermal
network is not the generator's.  The steps are those a user takes with a real unit's chamber
runs (in Python, :class:`nfs.UnitChain`; from the command line the same)::

    python tests/independent/generator.py runs/ --hidden magnetic --seed 3
    nfs fit runs/ --model default -o fitted.toml
    nfs compare runs/ --model fitted.toml -o report/
    nfs diagnose runs/ --model fitted.toml --json diag.json
    nfs diagnose runs/ --model fitted.toml --apply magnetic -o fitted2.toml
    nfs compare runs/ --model fitted2.toml -o report2/

Run as ``python examples/missing_effect.py [OUT_DIR]`` (under a minute on two cores).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import nfs

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "independent"))
from generator import generate_set  # noqa: E402  (the independent generator, not nfs)

HIDDEN = "magnetic"
SEED = 3


def main(out_dir: str | Path | None = None) -> dict:
    out = Path(out_dir or tempfile.mkdtemp(prefix="nfs_missing_effect_"))
    truth = generate_set(out / "runs", hidden=HIDDEN, seed=SEED)
    runs = nfs.read_runs(out / "runs")
    print(f"0. {len(runs)} runs from the independent generator, hidden: {truth['hidden']} "
          f"{truth['params']}")

    chain = nfs.UnitChain("default", runs)          # the default model and the unit's runs
    fit = chain.fit()                                # what `nfs fit` does
    chain.write_model(out / "fitted.toml")
    print("1. nfs fit: thermometer residual "
          + ", ".join(f"{k} {v:.3g} K" for k, v in fit.rms_after.items() if k.startswith("temp"))
          + f"; drift {fit.rms_after.get('drift_dph', float('nan')):.3g} deg/h")

    before = chain.compare()
    gyro = before.summaries["gyro_drift_dph"]
    print("2. the fitted model beside the measurements:")
    print("   " + gyro.sentence)
    print("   " + before.heading.sentence(gyro.consistent, gyro.position_ratio >= 3.0))

    d = chain.diagnose().diagnosis
    own = [s for s in d.ranking if s.significant and s.explained_by is None]
    top = own[0] if own else d.ranking[0]
    print(f"3. diagnosis ({d.answer.kind}): " + d.verdict)

    applied = chain.apply(top.effect, top.target)    # the chain moves to the new model
    chain.write_model(out / "fitted2.toml")
    after = chain.compare()
    print(f"4. with {top.effect} added and refitted: "
          + ", ".join(f"{k} = {v:.4g}" for k, v in applied.fit.params.items()
                      if top.effect in k))
    print("   " + after.summaries["gyro_drift_dph"].sentence)
    print("   " + after.heading.sentence())
    print(f"   start-up heading RMSE {applied.heading_rmse_before_deg:.4f} -> "
          f"{applied.heading_rmse_after_deg:.4f} deg")
    rms_b, floor = gyro.stages["all"]
    rms_a, _ = after.summaries["gyro_drift_dph"].stages["all"]
    return {"top": top.effect, "significant": [s.effect for s in own],
            "coefficient": dict(top.coefficient), "interval": dict(top.interval),
            "rms_before": rms_b, "rms_after": rms_a, "floor": floor,
            "position_ratio_before": gyro.position_ratio,
            "position_ratio_after": after.summaries["gyro_drift_dph"].position_ratio,
            "heading_before_deg": applied.heading_rmse_before_deg,
            "heading_after_deg": applied.heading_rmse_after_deg,
            "verdict": d.verdict, "answer": d.answer.kind, "labels": d.answer.labels,
            "gyro_consistent_before": gyro.consistent,
            "heading_consistent_before": before.heading.consistent,
            "heading_consistent_after": after.heading.consistent,
            "truth": truth, "out": out}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
