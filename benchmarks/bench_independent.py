"""Hit rate and false-alarm rate of ``nfs fit`` + ``nfs diagnose`` on units the model did not make.

The runs come from the independent generator of the tests (``tests/independent/``; it imports
nothing of ``nfs``).  By default every set is a unit of its *family* (``family.py``): its own
seed draws the coil's layers and geometry, the lumped capacities, powers and links, optional
extra heat paths, where each thermometer sits, the TEC law, the gyro's noise law, the
chamber's wander and cycling, an unfinished soak per run (with its history in the sidecar or
not), and the hidden effect's strength (log-uniform 1-3x its channel's noise floor, on the
part a fitted model cannot take up).  A rule tuned to one structure then shows up as misses.
``--fixed`` runs the old single unit (``generate_set``) instead.

Each set holds the 7 start temperatures x 2.5 h at 1 Hz with one hidden effect, none, or one
outside the library (``outside``: a quadrantal bias).  For every set the package does what a
user does with a real unit's chamber runs: fit the lumped model (:func:`nfs.fit.fit_unit`, as `nfs fit` does,
default free set), then diagnose (:func:`nfs.diagnose.diagnose`) and read its one answer
(:func:`answer_of`):

- a hidden library effect is a *hit* when the answer is to add it (the label's effect, and
  its target where :data:`TARGETS` names one); a *tie* that holds it is honest, not a hit;
  anything else (another effect, a tie without it, nothing) is a *miss*.  An extra
  thermometer lag has the signature of the thermometer's own lag, extra heat at a node that of
  the node's power, which the fit frees: it is also a hit when the fitted number moved, from
  the fit of the same unit's runs without the effect, by the hidden amount (:func:`_absorbed`);
- a clean or outside-library set raises a *false alarm* when the answer adds an effect; a
  tie is counted apart.

Printed: one line per set as it finishes; per case the hits, honest ties and misses (or false
alarms and ties); the hit rate and the false-alarm rate with 95 % Wilson intervals against
the goals (>= 90 % hits, <= 5 % false alarms, the truth inside every tie); the world in one
line; median fit and diagnose time per set and the wall time.

The model starts from the default instrument with the effects the generator's units have in
kind (:data:`MODEL_EFFECTS`: the TEC law, the bias's temperature law, the Shupe integral over
the winding), so that each hidden one is missing from it.

Run: ``python benchmarks/bench_independent.py [--sets 60] [--effects magnetic,none]
[--jobs 2] [--seed0 1] [--fixed] [--param heat_source.power=3]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

from joblib import Parallel, delayed

from nfs.diagnose import diagnose
from nfs.fit import fit_unit
from nfs.instrument import load_instrument
from nfs.io.measurement import read_runs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import (HIDDEN_EFFECTS, Unit, draw_unit,  # noqa: E402
                       generate_family_set, generate_set)

#: Effects of the default instrument that the generator's unit also has (in its own form):
#: the TEC law, the bias's temperature law and the Shupe integral over the winding (the
#: generator's layer Shupe term and its mean-rate term, which ``shupe_winding``'s k_m and
#: L_asym take up); the lumped forms for a model whose coil is lumped (``nfs preset lumped``).
MODEL_EFFECTS = ("tec_power", "bias_temperature", "shupe_winding", "shupe_gradient",
                 "shupe_rate")
#: Hidden effect -> the target a correct answer names (None: any target).
TARGETS = {"thermometer_lag": "fog", "acc_bias_temperature": "x", "aux_linear": "aux_osc_v"}
#: Cases with nothing of the library hidden: an answer that adds an effect is a false alarm.
NULL_CASES = ("none", "outside")
#: Every case: the clean set, the outside-library effect, each library effect.
CASES = NULL_CASES + tuple(e for e in HIDDEN_EFFECTS if e != "outside")
#: Goals: hit rate, false-alarm rate.
GOAL_HITS, GOAL_FALSE_ALARMS = 0.90, 0.05
#: The drift's structural alternative, as a tie names it when the diagnosis has no answer.
RATE_ALTERNATIVE = "a rate term on every node"


def independent_model(preset: str = "default"):
    """The preset instrument (the default: its coil wound; ``lumped``: two coil nodes) with
    only :data:`MODEL_EFFECTS`."""
    inst = load_instrument(preset)
    return inst.with_effects([e for e in inst.effects if e.name in MODEL_EFFECTS])


def _label(s) -> str:
    return s.effect if s.target is None else f"{s.effect}:{s.target}"


def answer_of(d) -> tuple[str, tuple[str, ...]]:
    """(kind, labels) of a diagnosis: its ``answer`` when it has one (kind ``add``, ``tie``,
    ``nothing``, ``unexplained`` or ``undetermined``), otherwise the same read from the
    ranking: the top significant candidate no other explains is added, or tied when it is in
    ``drift_structure.tied``; else the first candidate tied with a thermal structure
    (``structure_tie``); else nothing."""
    answer = getattr(d, "answer", None)
    if answer is not None:
        return answer.kind, tuple(answer.labels)
    own = [s for s in d.ranking if s.significant and s.explained_by is None]
    if own:
        lab = _label(own[0])
        ds = d.drift_structure
        if ds is not None and lab in ds.tied:
            return "tie", (lab, RATE_ALTERNATIVE)
        return "add", (lab,)
    ties = [s for s in d.ranking if getattr(s, "structure_tie", None)]
    if ties:
        return "tie", (_label(ties[0]), ties[0].structure_tie)
    return "nothing", ()


def _names(label: str, hidden: str) -> bool:
    """Does an effect label (``name`` or ``name:target``) name the hidden effect (and the
    target :data:`TARGETS` asks for)?"""
    effect, _, target = label.partition(":")
    want = TARGETS.get(hidden)
    return effect == hidden and (want is None or target == want)


def absorbed_path(hidden: str | None, params: dict) -> str | None:
    """The fit's free number a hidden effect has the signature of (its thermometer's own lag,
    the power of the node a heat source sits at), or None."""
    if hidden == "thermometer_lag":
        return f"thermometers.{params['thermometer']}.lag_s"
    if hidden == "heat_source":
        return f"thermal.nodes.{params['node']}.power_w"
    return None


def twin_fit(seed: int, hidden: str | None, params: dict, model: str = "default"):
    """The fit of the same drawn unit's runs without the hidden effect (the same soaks,
    chamber and noise: the generator's streams do not depend on it), when the hidden effect
    has the signature of a free number (:func:`absorbed_path`); else None."""
    if absorbed_path(hidden, params) is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        generate_family_set(tmp, seed=seed, hidden=None)
        return fit_unit(independent_model(model), read_runs(tmp))


def _absorbed(hidden: str | None, fit, twin, params: dict) -> str:
    """A hidden effect the fit takes up in a number it frees anyway (an extra thermometer lag
    in the thermometer's own lag, extra heat at a node in the node's power): the parameter
    and what it moved by, or ''.  Found when the fitted value moved from the ``twin`` fit (the
    same unit without the hidden effect, :func:`twin_fit`) by the hidden amount: the 95 %
    interval of the difference, sd sqrt(se^2 + se_twin^2), holds it and excludes 0 (two
    first-order lags in series delay a slow signal by the sum of their time constants; a
    heat source adds its power, plus what it changes of a TEC's at that node)."""
    path = absorbed_path(hidden, params)
    if path is None or twin is None:
        return ""
    v, e = fit.params.get(path), fit.stderr.get(path)
    v0, e0 = twin.params.get(path), twin.stderr.get(path)
    if None in (v, e, v0, e0) or not (0 < e < math.inf and 0 < e0 < math.inf):
        return ""
    want = params["tau"] if hidden == "thermometer_lag" else params["power"]
    d, sd = v - v0, math.hypot(e, e0)
    if abs(d - want) <= 1.96 * sd < abs(d):
        return f"fitted {path} moved {d:.3g} +- {sd:.2g} from the unit without it " \
               f"(hidden {want:.3g})"
    return ""


def classify(case: str, kind: str, labels: tuple[str, ...], absorbed: str = "") -> str:
    """``hit``, ``tie`` (holding the truth), ``miss`` for a hidden library effect;
    ``false alarm``, ``tie``, ``quiet`` for a clean or outside-library set."""
    if case in NULL_CASES:
        return {"add": "false alarm", "tie": "tie"}.get(kind, "quiet")
    if absorbed or (kind == "add" and _names(labels[0], case)):
        return "hit"
    if kind == "tie" and any(_names(lab, case) for lab in labels):
        return "tie"
    return "miss"


def one_set(case: str, seed: int, params: dict | None = None, fixed: bool = False) -> dict:
    """Generate one set (the family's unit of ``seed``, or the fixed unit), fit, diagnose;
    the outcome."""
    warnings.simplefilter("ignore")
    hidden = None if case == "none" else case
    t0 = time.perf_counter()
    row = {"case": case, "seed": seed, "t_fit_s": math.nan, "t_diagnose_s": math.nan}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            if fixed:
                truth = generate_set(tmp, hidden=hidden, seed=seed, params=params)
                unit, world = Unit(), "fixed unit"
            else:
                truth = generate_family_set(tmp, seed=seed, hidden=hidden, params=params)
                draw = draw_unit(seed)
                unit = draw.unit
                world = (f"{unit.coil.n_layers} layers, {unit.tec_law}, {unit.bias_noise}"
                         f"{', ' + '+'.join(draw.paths) if draw.paths else ''}")
            runs = read_runs(tmp)
        t_gen = time.perf_counter() - t0
        fit = fit_unit(independent_model(), runs)
        t_fit = time.perf_counter() - t0 - t_gen
        d = diagnose(fit.instrument, runs)
        t_diag = time.perf_counter() - t0 - t_gen - t_fit
    except Exception as exc:       # a benchmark reports a failing set, it does not stop
        row.update(outcome="miss" if case not in NULL_CASES else "error", kind="error",
                   labels=(f"{type(exc).__name__}: {exc}",), world="?", strength=None)
        return row
    kind, labels = answer_of(d)
    params_t = truth.get("params", {})
    twin = None if fixed else twin_fit(seed, hidden, params_t)
    absorbed = _absorbed(hidden, fit, twin, params_t)
    strength = (truth.get("strength") or {}).get("achieved")
    row.update(outcome=classify(case, kind, labels, absorbed), kind=kind, labels=labels,
               absorbed=absorbed, world=world, strength=strength, t_fit_s=t_fit,
               t_diagnose_s=t_diag)
    return row


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion k/n (Wilson, JASA 22(158) 209, 1927)."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    den = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, centre - half), min(1.0, centre + half)


def _rate(k: int, n: int) -> str:
    lo, hi = wilson(k, n)
    return f"{k}/{n} = {100 * k / n:.0f} % [95 % CI {100 * lo:.0f}-{100 * hi:.0f} %]"


def schedule(cases, n_sets: int, seed0: int) -> list[tuple[str, int]]:
    """Set i gets seed seed0 + i (its own unit) and case i mod len(cases): the sets spread
    evenly over the cases (the first ones get one more when n_sets does not divide)."""
    return [(cases[i % len(cases)], seed0 + i) for i in range(n_sets)]


def _world(rows, fixed: bool, seeds) -> str:
    if fixed:
        return ("world: the fixed unit of generate_set (8 layers, quadratic TEC, Gauss-Markov "
                f"bias, soaked at T0), seeds {min(seeds)}-{max(seeds)}")
    draws = [draw_unit(s) for s in seeds]
    tec = Counter(d.unit.tec_law for d in draws)
    noise = Counter(d.unit.bias_noise for d in draws)
    layers = [d.unit.coil.n_layers for d in draws]
    strengths = [r["strength"] for r in rows if r.get("strength") is not None]
    st = (f"; hidden strength achieved {min(strengths):.2f}-{max(strengths):.2f}x (target "
          "log-uniform 1-3x)" if strengths else "")
    return (f"world: the family, one unit per set (seeds {min(seeds)}-{max(seeds)}): coil "
            f"{min(layers)}-{max(layers)} layers; TEC "
            + "/".join(f"{k} {v}" for k, v in sorted(tec.items())) + "; bias noise "
            + "/".join(f"{k} {v}" for k, v in sorted(noise.items()))
            + f"; extra paths in {sum(bool(d.paths) for d in draws)}; soak history in the "
            f"sidecar for {sum(d.sidecar for d in draws)}" + st)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=60,
                    help="total sets, spread evenly over the cases (default 60)")
    ap.add_argument("--effects", default="",
                    help="comma-separated cases (default: all; 'none' for clean, 'outside' "
                         "for the outside-library effect)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel sets (joblib)")
    ap.add_argument("--seed0", type=int, default=1, help="seed of the first set (default 1)")
    ap.add_argument("--fixed", action="store_true",
                    help="the old single unit (generate_set) instead of the family")
    ap.add_argument("--param", action="append", default=[], metavar="EFFECT.KEY=VALUE",
                    help="override a hidden effect's parameter, e.g. heat_source.power=3 "
                         "(repeatable; an amplitude given is kept, not scaled)")
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
    cases = tuple(e.strip() for e in args.effects.split(",") if e.strip()) or CASES
    unknown = set(cases) - set(CASES)
    if unknown:
        ap.error(f"unknown case(s) {', '.join(sorted(unknown))}; valid: {', '.join(CASES)}")
    if args.sets < 1:
        ap.error("--sets must be >= 1")
    plan = schedule(cases, args.sets, args.seed0)
    t0 = time.perf_counter()
    print(f"{'case':26s} {'seed':>4s}  {'outcome':11s} answer  [unit; strength; fit + "
          "diagnose s]", flush=True)
    rows = []
    # Each set is printed as it finishes; the summary below is in the order of the plan.
    for r in Parallel(n_jobs=args.jobs, return_as="generator_unordered")(
            delayed(one_set)(c, s, overrides.get(c), args.fixed) for c, s in plan):
        rows.append(r)
        st = "" if r.get("strength") is None else f"; {r['strength']:.2f}x"
        print(f"{r['case']:26s} {r['seed']:4d}  {r['outcome']:11s} {r['kind']} "
              f"{', '.join(r['labels']) or '-'}"
              f"{' (' + r['absorbed'] + ')' if r.get('absorbed') else ''}  [{r['world']}{st}; "
              f"{r['t_fit_s']:.0f} + {r['t_diagnose_s']:.0f} s]", flush=True)
    order = {case: i for i, case in enumerate(plan)}
    rows.sort(key=lambda r: order[(r["case"], r["seed"])])
    wall = time.perf_counter() - t0
    print()
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        n = Counter(r["outcome"] for r in sub)
        if case in NULL_CASES:
            print(f"{case:26s} false alarms {n['false alarm']}/{len(sub)}, ties "
                  f"{n['tie']}/{len(sub)}, errors {n['error']}")
        else:
            print(f"{case:26s} hits {n['hit']}/{len(sub)}, honest ties {n['tie']}/{len(sub)}, "
                  f"misses {n['miss']}/{len(sub)}")
    hits = [r for r in rows if r["case"] not in NULL_CASES]
    nulls = [r for r in rows if r["case"] in NULL_CASES]
    if hits:
        k = sum(r["outcome"] == "hit" for r in hits)
        print(f"hit rate (the answer adds the hidden effect): {_rate(k, len(hits))} "
              f"(goal >= {100 * GOAL_HITS:.0f} %)")
        ties = [r for r in hits if r["kind"] == "tie"]
        bad = [r for r in ties if r["outcome"] != "tie"]
        print(f"  ties on hidden-effect sets: {len(ties)}, the truth outside {len(bad)} "
              "(goal: inside every tie)")
        print(f"  hits plus honest ties: "
              f"{_rate(sum(r['outcome'] in ('hit', 'tie') for r in hits), len(hits))}")
    if nulls:
        k = sum(r["outcome"] == "false alarm" for r in nulls)
        print(f"false-alarm rate (a clean or outside-library set adds an effect): "
              f"{_rate(k, len(nulls))} (goal <= {100 * GOAL_FALSE_ALARMS:.0f} %); ties "
              f"{sum(r['outcome'] == 'tie' for r in nulls)}/{len(nulls)}")
    print(_world(rows, args.fixed, [s for _, s in plan]))
    tf = sorted(r["t_fit_s"] for r in rows if not math.isnan(r["t_fit_s"]))
    td = sorted(r["t_diagnose_s"] for r in rows if not math.isnan(r["t_diagnose_s"]))

    def med(x):
        return f"{x[len(x) // 2]:.0f} s" if x else "-"

    print(f"per set ({args.jobs} at once on this machine): fit median {med(tf)}, "
          f"diagnose median {med(td)}; {len(rows)} sets in {wall:.0f} s")


if __name__ == "__main__":
    main()
