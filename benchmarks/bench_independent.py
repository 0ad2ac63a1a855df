"""Hit rate and false-alarm rate of ``nfs fit`` + ``nfs diagnose`` on runs the model did not make.

The runs come from the independent generator of the tests (``tests/independent/generator.py``:
a finite-difference coil of 8 radial layers, thermometers on mixes of nodes, its own TEC law,
a Gauss-Markov bias, a cycling chamber; it imports nothing of ``nfs``).  Each set holds the 7
start temperatures x 2.5 h at 1 Hz with one hidden effect, none, or one outside the library.
For every set the package does what a user does with a real unit's chamber runs: fit the
lumped model (:func:`nfs.diagnose.fit_model`, default free set), then diagnose
(:func:`nfs.diagnose.diagnose`).

``structure`` says which structural check flagged the model (``thermal``: the thermometers
do not fit and no generic alternative does better; ``drift``: a significant drift candidate
is tied with a rate term on every node).  A significant drift candidate that does not stand
beyond a rate term on every node is *tied* with that structural alternative (the verdict
says the runs cannot tell them apart): it counts as naming an effect neither for a hit nor
for a false alarm; both rates are also printed counting ties.  An extra thermometer lag has
the signature of the thermometer's own lag, which the fit frees: it is found when the fitted
lag's 95 % interval holds the unit's lag plus the hidden one (and not the unit's alone).

Printed per hidden effect: how often the hidden effect is the top significant candidate (the
first significant one that no other explains; goal >= 90 %), and for the clean and the
outside-library sets how often an effect is named (goal <= 5 %); then the time per set.

The model starts from the default instrument with the effects the generator's unit has in
kind (``tec_power``, ``bias_temperature``, ``shupe_gradient``, ``shupe_rate``), so that each
hidden one is missing from it.

Run: ``python benchmarks/bench_independent.py [--seeds 3] [--effects magnetic,none]
[--jobs 2] [--param heat_source.node=coil_outer --param heat_source.power=3]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

from joblib import Parallel, delayed

from nfs.diagnose import diagnose, fit_model
from nfs.instrument import load_instrument
from nfs.io.measurement import read_runs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import HIDDEN_EFFECTS, Unit, generate_set  # noqa: E402

#: Effects of the default instrument that the generator's unit also has (in its own form).
MODEL_EFFECTS = ("tec_power", "bias_temperature", "shupe_gradient", "shupe_rate")
#: Hidden effect -> the target a correct answer names (None: any target).
TARGETS = {"thermometer_lag": "fog", "acc_bias_temperature": "x", "aux_linear": "aux_osc_v"}


def independent_model():
    """The default instrument with only :data:`MODEL_EFFECTS`."""
    inst = load_instrument("default")
    return inst.with_effects([e for e in inst.effects if e.name in MODEL_EFFECTS])


def _absorbed(hidden: str | None, fit) -> str:
    """A hidden effect the fit takes up at its true value in a free parameter of the model
    (an extra thermometer lag adds to the thermometer's own free lag): the parameter and
    its value, or ''.  Found when the 95 % interval of the fitted lag holds the unit's own
    lag plus the hidden one and excludes the unit's own lag alone."""
    if hidden != "thermometer_lag":
        return ""
    th = HIDDEN_EFFECTS[hidden]["thermometer"]
    own = Unit().thermometer_lag_s[{"acc_x": "x", "acc_y": "y"}.get(th, th)]
    path = f"thermometers.{th}.lag_s"
    v, e = fit.params.get(path), fit.stderr.get(path)
    if v is None or e is None or not e > 0:
        return ""
    want = own + HIDDEN_EFFECTS[hidden]["tau"]
    if abs(v - want) <= 1.96 * e < abs(v - own):
        return f"fitted {path} = {v:.0f} +- {e:.0f} s (unit {own:g} + hidden {want - own:g})"
    return ""


def one_set(hidden: str | None, seed: int, params: dict | None = None) -> dict:
    """Generate one set (the hidden effect's ``params`` over its defaults), fit, diagnose;
    the outcome."""
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        generate_set(tmp, hidden=hidden, seed=seed, params=params)
        runs = read_runs(tmp)
    t_gen = time.perf_counter() - t0
    fit = fit_model(independent_model(), runs)
    t_fit = time.perf_counter() - t0 - t_gen
    d = diagnose(fit.instrument, runs)
    t_diag = time.perf_counter() - t0 - t_gen - t_fit
    own = [s for s in d.ranking if s.significant and s.explained_by is None]
    top = own[0] if own else None
    label = None if top is None else (top.effect if top.target is None
                                      else f"{top.effect}:{top.target}")
    absorbed = _absorbed(hidden, fit)
    tied = top is not None and d.drift_structure is not None and label in d.drift_structure.tied
    if hidden in (None, "outside"):
        ok = top is None or tied
    elif absorbed:
        ok = True
        label = absorbed
    else:
        want = TARGETS.get(hidden)
        ok = (top is not None and top.effect == hidden and (want is None or top.target == want)
              and not tied)
    flagged = [name for name, st in (("thermal", d.thermal_structure),
                                     ("drift", d.drift_structure))
               if st is not None and not st.adequate]
    return {"hidden": hidden or "none", "seed": seed, "top": label, "ok": ok, "tied": tied,
            "structure": ",".join(flagged) or "-",
            "n_significant": len([s for s in d.ranking if s.significant]),
            "verdict": d.verdict, "t_fit_s": t_fit, "t_diagnose_s": t_diag}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="sets per hidden effect (seeds 1..N)")
    ap.add_argument("--effects", default="",
                    help="comma-separated hidden effects (default: all, 'none' for clean)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel sets (joblib)")
    ap.add_argument("--param", action="append", default=[], metavar="EFFECT.KEY=VALUE",
                    help="override a hidden effect's parameter, e.g. heat_source.power=3 "
                         "(repeatable)")
    args = ap.parse_args(argv)
    overrides: dict[str, dict] = {}
    for item in args.param:
        key, _, value = item.partition("=")
        effect, _, name = key.partition(".")
        if not (effect and name and value) or effect not in HIDDEN_EFFECTS:
            ap.error(f"--param {item!r}: expected EFFECT.KEY=VALUE with EFFECT one of "
                     + ", ".join(HIDDEN_EFFECTS))
        try:
            overrides.setdefault(effect, {})[name] = float(value)
        except ValueError:
            overrides.setdefault(effect, {})[name] = value
    effects = ([e.strip() for e in args.effects.split(",") if e.strip()] if args.effects
               else ["none", *HIDDEN_EFFECTS])
    cases = [(None if e == "none" else e, s) for e in effects for s in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    print(f"{'hidden':26s} {'seed':>4s}  {'ok':3s} {'structure':13s} top significant "
          "(n significant)", flush=True)
    rows = []
    # Each set is printed as it finishes (a run of ~1.5 h shows its progress as it goes);
    # the summary below is in the order of the cases.
    for r in Parallel(n_jobs=args.jobs, return_as="generator_unordered")(
            delayed(one_set)(h, s, overrides.get(h)) for h, s in cases):
        rows.append(r)
        print(f"{r['hidden']:26s} {r['seed']:4d}  {'yes' if r['ok'] else 'NO ':3s} "
              f"{r['structure']:13s} {r['top']}{' (tied)' if r['tied'] else ''} "
              f"({r['n_significant']})", flush=True)
    order = {case: i for i, case in enumerate((h or "none", s) for h, s in cases)}
    rows.sort(key=lambda r: order[(r["hidden"], r["seed"])])
    wall = time.perf_counter() - t0
    print()
    hits = [r for r in rows if r["hidden"] not in ("none", "outside")]
    nulls = [r for r in rows if r["hidden"] in ("none", "outside")]
    for name in dict.fromkeys(r["hidden"] for r in rows):
        sub = [r for r in rows if r["hidden"] == name]
        what = "flags nothing" if name in ("none", "outside") else "hidden effect on top"
        print(f"{name:26s} {what}: {sum(r['ok'] for r in sub)}/{len(sub)}")
    if hits:
        print(f"hit rate (hidden effect is the top significant candidate): "
              f"{sum(r['ok'] for r in hits)}/{len(hits)} = "
              f"{100 * sum(r['ok'] for r in hits) / len(hits):.0f} % (goal >= 90 %)")
    if nulls:
        fa = sum(not r["ok"] for r in nulls)
        print(f"false alarms (clean and outside-library sets name an effect that is not tied "
              f"with a structural alternative): {fa}/{len(nulls)} = "
              f"{100 * fa / len(nulls):.0f} % (goal <= 5 %)")
        fa_t = sum(r["top"] is not None for r in nulls)
        print(f"  counting ties too: {fa_t}/{len(nulls)} = {100 * fa_t / len(nulls):.0f} %")
    if hits:
        with_ties = sum(r["ok"] or (r["tied"] and r["top"].startswith(r["hidden"]))
                        for r in hits)
        print(f"  hidden effect on top counting ties too: {with_ties}/{len(hits)}")
    tf = sorted(r["t_fit_s"] for r in rows)
    td = sorted(r["t_diagnose_s"] for r in rows)
    print(f"per set (with {args.jobs} sets at once on this machine): fit median "
          f"{tf[len(tf) // 2]:.1f} s, diagnose median {td[len(td) // 2]:.1f} s; "
          f"{len(rows)} sets in {wall:.0f} s")


if __name__ == "__main__":
    main()
