"""When the runs cannot decide: a tie, the run that decides it, and the verdict after it.

A unit whose electronics have a turn-on transient (a = 0.1 deg/h, tau = 120 s) that the
model lacks.  Seven soak-and-start runs (the default scenario, 2.5 h at 1 Hz) cannot tell
the transient from a rate term on every node: right after power-on every node's rate decays
like a transient, at every start temperature.  ``nfs design`` finds the cheapest chamber run
that would (a warm restart: the transient restarts at full amplitude while the nodes have
barely cooled), the run is made (here: simulated from the same unit), and the rivals are
put to all the runs.  From the command line::

    nfs fit runs/ --model model.toml -o fitted.toml --start soaked
    nfs diagnose runs/ --model fitted.toml --json diagnosis.json --start soaked --decide
    nfs design runs/ --model fitted.toml --diagnosis diagnosis.json -o design/ --start soaked
    # ... run design/scenario.toml in the chamber, add the run to runs/ ...
    nfs fit runs/ --model model.toml -o fitted2.toml --start soaked
    nfs diagnose runs/ --model fitted2.toml --start soaked --rivals turn_on_transient \\
        "a rate term on every node"

(the rivals the tie left standing: the runs taken already rule out heat inside the coil
and the model as it is).

``--start soaked``: these simulated runs are soaked exactly at T0.  Run as
``python examples/design_tie.py [OUT_DIR]`` (about two minutes on two cores).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import shutil
import sys
import tempfile
from pathlib import Path

import nfs
from nfs.cli import main as nfs_main
from nfs.effects import make_effect

TRUTH = {"a": 0.1, "tau": 120.0}
SEED = 11


def _nfs(*argv: str) -> str:
    """Run one nfs command, return what it printed (exit code checked)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = nfs_main([str(a) for a in argv])
    if code != 0:
        raise RuntimeError(f"nfs {' '.join(map(str, argv))} exited {code}")
    return out.getvalue()


def main(out_dir: str | Path | None = None) -> dict:
    out = Path(out_dir or tempfile.mkdtemp(prefix="nfs_design_tie_"))
    out.mkdir(parents=True, exist_ok=True)
    default = nfs.load_instrument("default")
    model = default.with_effects([e for e in default.effects if e.name != "turn_on_transient"])
    truth = model.with_effects(list(model.effects) + [make_effect("turn_on_transient", TRUTH)])
    (out / "model.toml").write_text(model.to_toml(), encoding="utf-8")
    scenario = dataclasses.replace(nfs.load_scenario().nominal(), duration_s=9000.0, seed=SEED)
    runs = out / "runs"
    shutil.rmtree(runs, ignore_errors=True)
    for cond in scenario.conditions():
        nfs.write_run(nfs.simulate_run(truth, cond).run, runs)
    print(f"0. 7 runs of a unit with turn_on_transient {TRUTH} that the model lacks")

    _nfs("fit", runs, "--model", out / "model.toml", "-o", out / "fitted.toml",
         "--start", "soaked", "--overwrite", "-q")
    _nfs("diagnose", runs, "--model", out / "fitted.toml", "--json", out / "diagnosis.json",
         "--start", "soaked", "--overwrite", "-q", "--decide")
    diag = json.loads((out / "diagnosis.json").read_text(encoding="utf-8"))
    print("1. nfs diagnose:", diag["verdict"])

    printed = _nfs("design", runs, "--model", out / "fitted.toml", "--diagnosis",
                   out / "diagnosis.json", "-o", out / "design", "--start", "soaked",
                   "--overwrite", "-q")
    design = json.loads((out / "design" / "design.json").read_text(encoding="utf-8"))
    print("2. nfs design:", printed.strip())

    # the chamber run, made by the same unit (simulated from the truth, its own noise)
    sc = nfs.load_scenario(out / "design" / "scenario.toml")
    cond = dataclasses.replace(sc.conditions()[0], seed=(SEED, 99))
    nfs.write_run(nfs.simulate_run(truth, cond).run, runs)
    print(f"3. the designed run made: {design['experiment']['description']}")

    _nfs("fit", runs, "--model", out / "model.toml", "-o", out / "fitted2.toml",
         "--start", "soaked", "--overwrite", "-q")
    rivals = [r["label"] for r in design["rivals"]]
    _nfs("diagnose", runs, "--model", out / "fitted2.toml", "--json", out / "after.json",
         "--start", "soaked", "--overwrite", "-q", "--rivals", *rivals)
    after = json.loads((out / "after.json").read_text(encoding="utf-8"))
    print("4. nfs diagnose --rivals ...:", after["verdict"])
    return {"tie": diag.get("tie", diag["answer"]), "before": diag["answer"],
            "design": design, "after": after["answer"],
            "interval": after["settlement"]["interval"], "truth": TRUTH, "out": out}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
