"""Time of a design (``nfs design``) on 7 runs with two rivals, beside the time of one fit.

The runs: the default scenario's 7 start temperatures (2.5 h at 1 Hz, the nominal world)
from the default instrument with a turn-on transient of 0.1 deg/h, 120 s, and the model
without it (the tie of tests/design/test_loop.py).  Timed in one process, in order:

1. one fit of the model (:func:`nfs.fit.fit_model`, both stages): the baseline;
2. the two rivals fitted (``turn_on_transient`` and ``a rate term on every node``,
   :func:`nfs.rivals.rival_models`);
3. the search over the default experiment space (:func:`nfs.design.design_experiment`:
   the runs taken replayed, the grid, the local refinement).

Printed: each time, the design (2 + 3) over the fit, the design in reference units
(``python ../shared/tools/refwork.py`` timed here, when the shared folder is beside the
checkout) and against the goal of 2 minutes on 2 cores.

Run: ``python benchmarks/bench_design.py [--draws 8]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import time
from pathlib import Path

from nfs.config.scenario import load_scenario
from nfs.design import design_experiment
from nfs.rivals import rival_models
from nfs.design.space import base_conditions, default_space
from nfs.fit import fit_model
from nfs.effects import make_effect
from nfs.experiment import simulate_run
from nfs.instrument import load_instrument

#: Goal: the design on 7 runs with two rivals [s] on 2 cores.
GOAL_S = 120.0
RIVALS = ("turn_on_transient", "a rate term on every node")


def refwork_s() -> float | None:
    """Seconds of the shared reference workload on this machine, or None without it."""
    tool = Path(__file__).resolve().parents[2] / "shared" / "tools" / "refwork.py"
    if not tool.exists():
        return None
    t = time.perf_counter()
    subprocess.run([sys.executable, str(tool)], check=True, capture_output=True)
    return time.perf_counter() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=8, help="parameter draws per rival")
    args = ap.parse_args(argv)
    default = load_instrument("default")
    model = default.with_effects([e for e in default.effects if e.name != "turn_on_transient"])
    truth = model.with_effects(list(model.effects)
                               + [make_effect("turn_on_transient", {"a": 0.1, "tau": 120.0})])
    sc = dataclasses.replace(load_scenario().nominal(), duration_s=9000.0, seed=11)
    runs = [simulate_run(truth, c).run for c in sc.conditions()]

    t = time.perf_counter()
    fr = fit_model(model, runs, start_state=None)
    t_fit = time.perf_counter() - t
    t = time.perf_counter()
    rivals = rival_models(fr.instrument, runs, RIVALS, start_state=None)
    t_rivals = time.perf_counter() - t
    t = time.perf_counter()
    design = design_experiment(rivals, runs, base_conditions(runs), default_space(runs),
                               n_draws=args.draws)
    t_search = time.perf_counter() - t
    ref = refwork_s()
    total = t_rivals + t_search
    print(f"one fit (baseline):         {t_fit:7.1f} s")
    print(f"rivals fitted (2):          {t_rivals:7.1f} s")
    print(f"search ({len(design.trials)} experiments):   {t_search:7.1f} s")
    print(f"design (rivals + search):   {total:7.1f} s = {total / t_fit:.1f} fits"
          + (f" = {total / ref:.1f} reference units (refwork {ref:.2f} s)" if ref else ""))
    print(f"goal: <= {GOAL_S:.0f} s on 2 cores: {'met' if total <= GOAL_S else 'NOT met'}")
    print(design.verdict)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
