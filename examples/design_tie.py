"""When the runs cannot decide: a tie, the run that decides it, and the verdict after it.

A unit whose electronics have a turn-on transient (a = 0.1 deg/h, tau = 120 s) that the
model lacks.  Seven soak-and-start runs (the default scenario, 2.5 h at 1 Hz) cannot tell
the transient from a rate term on every node: right after power-on every node's rate decays
like a transient, at every start temperature.  The design finds the cheapest chamber run
that would (a warm restart: the transient restarts at full amplitude while the nodes have
barely cooled), the run is made (here: simulated from the same unit), and the rivals are
put to all the runs.  In Python, with :class:`nfs.UnitChain` (every step's result is typed
and saves itself as JSON with ``to_dict``); from the command line, the same::

    nfs fit runs/ --model model.toml -o fitted.toml --start soaked
    nfs diagnose runs/ --model fitted.toml --json diagnosis.json --start soaked --decide
    nfs design runs/ --model fitted.toml --diagnosis diagnosis.json -o design/ --start soaked
    # ... run design/scenario.toml in the chamber, add the run to runs/ ...
    nfs fit runs/ --model model.toml -o fitted2.toml --start soaked
    nfs diagnose runs/ --model fitted2.toml --start soaked --rivals turn_on_transient \\
        "a rate term on every node"

``start_state=None`` (``--start soaked``): these simulated runs are soaked exactly at T0.
Run as ``python examples/design_tie.py [OUT_DIR]`` (about two minutes on two cores).
"""

from __future__ import annotations

import dataclasses
import json
import sys
import tempfile
from pathlib import Path

import nfs
from nfs.effects import make_effect
from nfs.report.design_report import write_design

TRUTH = {"a": 0.1, "tau": 120.0}
SEED = 11


def main(out_dir: str | Path | None = None) -> dict:
    out = Path(out_dir or tempfile.mkdtemp(prefix="nfs_design_tie_"))
    out.mkdir(parents=True, exist_ok=True)
    default = nfs.load_instrument("default")
    model = default.with_effects([e for e in default.effects if e.name != "turn_on_transient"])
    truth = model.with_effects(list(model.effects) + [make_effect("turn_on_transient", TRUTH)])
    scenario = dataclasses.replace(nfs.load_scenario().nominal(), duration_s=9000.0, seed=SEED)
    runs = [nfs.simulate_run(truth, cond).run for cond in scenario.conditions()]
    print(f"0. 7 runs of a unit with turn_on_transient {TRUTH} that the model lacks")

    chain = nfs.UnitChain(model, runs, start_state=None)
    chain.fit()
    finding = chain.diagnose(decide=True)
    (out / "diagnosis.json").write_text(json.dumps(finding.to_dict(), indent=1))
    print("1. diagnose:", finding.verdict)

    design = chain.design()                  # the rivals the finding could not tell apart
    write_design(design, out / "design", runs, model.name)
    print("2. design:", design.verdict)

    # the chamber run, made by the same unit (simulated from the truth, its own noise)
    cond = dataclasses.replace(design.experiment.conditions(nfs.design.base_conditions(runs)),
                               seed=(SEED, 99))
    runs2 = runs + [nfs.simulate_run(truth, cond).run]
    print(f"3. the designed run made: {design.experiment.describe()}")

    after_chain = nfs.UnitChain(model, runs2, start_state=None)
    after_chain.fit()
    after = after_chain.diagnose(rivals=[r.label for r in design.rivals])
    print("4. diagnose with the designed run's rivals:", after.verdict)
    return {"tie": finding.tie or finding.answer, "before": finding.answer,
            "design": design, "after": after.answer, "interval": after.settlement.interval,
            "truth": TRUTH, "out": out}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
