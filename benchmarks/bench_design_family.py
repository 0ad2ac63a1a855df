"""How often one designed run breaks a tie of ``nfs diagnose`` on units the model did not make.

The runs come from the independent generator of the tests (``tests/independent/``; it imports
nothing of ``nfs``), one unit of its *family* per set (``family.py``: the unit's structure,
noise, chamber, unfinished soak and the hidden effect's strength drawn from the set's seed),
as in ``bench_independent.py``, whose cases, answers and hit rule this benchmark reuses.  For
every set the package does what a user does when a diagnosis ends in a tie:

1. the 7 start temperatures x 2.5 h at 1 Hz (:func:`generate_family_set`), read back, fitted
   (:func:`nfs.fit.fit_unit` on :func:`bench_independent.independent_model`) and
   diagnosed (:func:`nfs.diagnose.diagnose`);
2. a tie is put to the runs (:func:`nfs.rivals.decide.settle_tie`, as ``nfs diagnose
   --decide`` does): the *before* answer is the settlement's when the diagnosis tied, else the
   diagnosis's own;
3. if the before answer is still a tie: the rivals of the settlement get a designed run
   (:func:`nfs.design.design_experiment` over :func:`nfs.design.space.default_space`), which
   the generator then runs on the same drawn unit with the same hidden effect and
   parameters (run index 7: its own soak and noise; the design's start temperature, power
   cycles as ``power_off_s`` spans, a chamber ramp as the program's departure from T0 added
   to the unit's own chamber air, the design's turntable dwell and its length).  It is written, read back, added
   to the runs; the 8 runs are fitted and diagnosed again and the design's rivals put to
   them (``settle_tie(..., labels=the design's rivals)``, ``nfs diagnose --rivals``): the
   *after* answer.

Counted per case (bench_independent's rule, :func:`bench_independent.classify`): for a
hidden library effect, the sets tied before, and of those the hidden effect named after
(*hit*), an honest tie after (the truth among the labels) or a *miss*; for a clean or
outside-library set, false alarms (an answer that adds an effect) before and after.  A set
that raises is printed with its seed and counted as *error* (a tied set that fails after the
tie counts against the naming rate).  Each set runs on one BLAS thread (:func:`one_set`): the
answers on these runs depend on the linear algebra's rounding, so ``--jobs`` must not change
them.

Printed: one line per set as it finishes (before and after answers, the designed run, the
time of each step); per case the counts; the naming rate over the sets tied before (0 before
by definition: a tie names nothing; after the designed run) with 95 % Wilson intervals
against the goal (>= 80 %), the before hit rate over all hidden-effect sets, the false-alarm
rate before and after; the median time of each step and the wall time.

Slow: tens of seconds to minutes per set (two fits, two diagnoses, three settlements and a
design).  Run: ``python benchmarks/bench_design_family.py [--sets 22] [--jobs 2]
[--seed0 1] [--effects turn_on_transient,heat_source,none]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from nfs.design import design_experiment
from nfs.rivals.decide import settle_tie
from nfs.design.space import base_conditions, default_space
from nfs.diagnose import diagnose
from nfs.fit import fit_unit
from nfs.io.measurement import read_runs

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_independent import (CASES, NULL_CASES, _absorbed, _rate, twin_fit,  # noqa: E402
                               answer_of, classify, independent_model, schedule, wilson)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "independent"))
from generator import _write_run  # noqa: E402
from family import (draw_unit, generate_family_set, simulate_family_run,  # noqa: E402
                    start_state)

#: Goal: share of the sets tied before that the designed run lets the package name.
GOAL_NAMED = 0.80
#: Run index of the designed run (the set's runs are 0-6).
DESIGNED_INDEX = 7
#: Steps timed per set, in order.
STEPS = ("generate", "fit", "diagnose", "settle", "design", "run", "fit2", "diagnose2",
         "settle2")


def _answer(a) -> tuple[str, tuple[str, ...]]:
    return a.kind, tuple(a.labels)


def designed_run(folder: Path, draw, truth: dict, experiment, base) -> str:
    """Run ``experiment`` (nfs.design) on the generator's drawn unit with the set's hidden
    effect and parameters; write it into ``folder``; its name."""
    cond = experiment.conditions(base)
    sched = cond.schedule                        # the design may change the dwell
    if tuple(sched.positions_deg) != (0.0, 90.0, 180.0, 270.0):
        raise ValueError(f"the generator turns through 0, 90, 180, 270 deg only; the design "
                         f"asks for {sched.positions_deg}")
    t0 = float(experiment.start_temperature_c)
    fs = float(base.sample_rate_hz)
    duration = float(experiment.duration_s)
    n = int(round(duration * fs))
    start = start_state(draw, DESIGNED_INDEX, t0, duration_s=duration, sample_rate_hz=fs)
    offset = None
    if experiment.event == "ramp":
        # the program's departure from T0 on the run's samples, on top of the unit's air
        offset = np.asarray(cond.chamber_c(np.arange(n) / fs), dtype=float) - t0
    run = simulate_family_run(
        draw, DESIGNED_INDEX, t0, hidden=truth["hidden"],
        params=truth["params"] if truth["hidden"] else None, duration_s=duration,
        sample_rate_hz=fs, latitude_deg=base.latitude_deg,
        true_heading_deg=base.true_heading_deg, start=start,
        power_off_s=tuple(cond.power_off_s), chamber_offset_c=offset,
        dwell_s=float(sched.dwell_s), move_s=float(sched.move_s))
    rd = draw.run_draw(DESIGNED_INDEX)
    extra = ({"soak_from_c": round(rd.soak_from_c, 1), "soak_h": round(rd.soak_h, 2)}
             if draw.sidecar else None)
    _write_run(run, folder, latitude_deg=float(base.latitude_deg),
               true_heading_deg=base.true_heading_deg, sample_rate_hz=fs, extra=extra,
               instrument="independent generator family (tests/independent)")
    return run.name


def one_set(case: str, seed: int) -> dict:
    """:func:`_one_set` on one BLAS thread: the fits' answers on these runs depend on the
    rounding of the linear algebra (seen: heat_source seed 12 tied on one thread, "add
    shupe_rate:qfa_x" on two), so a set's outcome must not depend on ``--jobs`` or on the
    machine's core count."""
    with threadpool_limits(limits=1):
        return _one_set(case, seed)


def _one_set(case: str, seed: int) -> dict:
    """Generate, fit, diagnose, settle; if still tied: design, run it, fit, diagnose and
    settle again.  The outcome and the time of each step."""
    warnings.simplefilter("ignore")
    hidden = None if case == "none" else case
    row = {"case": case, "seed": seed, "times": {}, "tied": None, "diagnosis": None,
           "settled": "", "before": None,
           "before_outcome": None, "after": None, "after_outcome": None, "design": "",
           "met": None, "error": "", "stage": "", "strength": None}
    clock = [time.perf_counter()]

    def lap(step: str) -> None:
        now = time.perf_counter()
        row["times"][step] = now - clock[0]
        clock[0] = now

    step = "generate"
    try:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            truth = generate_family_set(folder, seed=seed, hidden=hidden)
            draw = draw_unit(seed)
            row["strength"] = (truth.get("strength") or {}).get("achieved")
            params = truth.get("params", {})
            runs = read_runs(folder)
            lap(step)
            step = "fit"
            fit = fit_unit(independent_model(), runs)
            lap(step)
            step = "diagnose"
            d = diagnose(fit.instrument, runs)
            lap(step)
            step = "settle"
            kind, labels = answer_of(d)
            row["diagnosis"] = (kind, labels)
            settle = None
            if kind == "tie":
                # a diagnosis without an answer of its own (answer_of read the tie from
                # the ranking): its labels put to the runs
                settle = settle_tie(d, fit.instrument, runs,
                                    labels=None if d.answer is not None else list(labels))
                if settle is not None:
                    kind, labels = _answer(settle.answer)
                    row["settled"] = "; ".join(
                        f"{x.a} vs {x.b}: ln LR {x.llr:+.1f}, Z {x.evidence.z:+.1f}, "
                        f"{x.separation_sigma:.1f} sigma"
                        for x in settle.decisions)
            lap(step)
            twin = twin_fit(seed, hidden, params)
            clock[0] = time.perf_counter()      # the oracle's twin fit: not timed
            absorbed = _absorbed(hidden, fit, twin, params)
            row.update(before=(kind, labels),
                       before_outcome=classify(case, kind, labels, absorbed),
                       tied=kind == "tie")
            if kind != "tie":
                row.update(after=row["before"], after_outcome=row["before_outcome"])
                return row
            step = "design"
            base = base_conditions(runs)
            # the rivals the tie left standing (the model as it is among them when no
            # explanation beat it)
            design = design_experiment(settle.standing, runs, base, default_space(runs),
                                       seed=seed)
            e = design.experiment
            row.update(design=f"{e.describe()} ({e.hours:.1f} h)", met=design.met)
            lap(step)
            step = "run"
            designed_run(folder, draw, truth, e, base)
            runs2 = read_runs(folder)
            lap(step)
            step = "fit2"
            fit2 = fit_unit(independent_model(), runs2)
            lap(step)
            step = "diagnose2"
            d2 = diagnose(fit2.instrument, runs2)
            lap(step)
            step = "settle2"
            after = settle_tie(d2, fit2.instrument, runs2,
                               labels=[r.label for r in design.rivals])
            lap(step)
            kind2, labels2 = _answer(after.answer)
            absorbed2 = _absorbed(hidden, fit2, twin, params)   # beside the 7-run twin
            row.update(after=(kind2, labels2),
                       after_outcome=classify(case, kind2, labels2, absorbed2))
    except Exception as exc:     # a benchmark reports a failing set, it does not stop
        lap(step)
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        row.update(error=f"{type(exc).__name__}: {exc} ({Path(tb.filename).name}:"
                         f"{tb.lineno})", stage=step)
    return row


def _fmt(answer) -> str:
    if answer is None:
        return "-"
    kind, labels = answer
    return f"{kind} {', '.join(labels) or '-'}"


def _line(r: dict) -> str:
    t = r["times"]
    times = " + ".join(f"{k} {t[k]:.0f}" for k in STEPS if k in t)
    total = sum(t.values())
    st = "" if r.get("strength") is None else f"{r['strength']:.2f}x; "
    head = f"{r['case']:26s} {r['seed']:4d}  "
    if r["error"]:
        return (head + f"error in {r['stage']}: {r['error']}  [{st}{times} = {total:.0f} s]")
    diag = ("" if r["diagnosis"] is None or r["diagnosis"] == r["before"] else
            f"diagnosis {_fmt(r['diagnosis'])}, put to the runs ({r['settled']}): ")
    if not r["tied"]:
        return (head + f"{r['before_outcome']:11s} no tie after all: {diag}"
                f"{_fmt(r['before'])}  [{st}{times} = {total:.0f} s]"
                if diag else head + f"{r['before_outcome']:11s} no tie: {_fmt(r['before'])}"
                f"  [{st}{times} = {total:.0f} s]")
    return (head + f"{r['after_outcome']:11s} {diag}tie {', '.join(r['before'][1])} -> "
            f"designed: {r['design']}{'' if r['met'] else ' (margin not met)'} -> "
            f"{_fmt(r['after'])}  [{st}{times} = {total:.0f} s]")


def summary(rows: list[dict]) -> list[str]:
    """The per-case counts and the rates (module docstring)."""
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        sub = [r for r in rows if r["case"] == case]
        err = sum(bool(r["error"]) for r in sub)
        tied = [r for r in sub if r["tied"]]
        if case in NULL_CASES:
            fa_b = sum(r["before"] is not None and r["before"][0] == "add" for r in sub)
            fa_a = sum(r["after"] is not None and r["after"][0] == "add" for r in sub)
            out.append(f"{case:26s} sets {len(sub)}: false alarms before {fa_b}, after "
                       f"{fa_a}; tied before {len(tied)}; errors {err}")
        else:
            n = Counter(r["after_outcome"] for r in tied if not r["error"])
            hit_b = sum(r["before_outcome"] == "hit" for r in sub)
            out.append(f"{case:26s} sets {len(sub)}: hits before {hit_b}; tied before "
                       f"{len(tied)}, of them named after {n['hit']}, honest ties "
                       f"{n['tie']}, misses {n['miss']}, errors "
                       f"{sum(bool(r['error']) for r in tied)}; errors in all {err}")
    hid = [r for r in rows if r["case"] not in NULL_CASES]
    nul = [r for r in rows if r["case"] in NULL_CASES]
    if hid:
        done = [r for r in hid if r["before"] is not None]
        k = sum(r["before_outcome"] == "hit" for r in done)
        out.append(f"before: hit rate over all hidden-effect sets "
                   f"{_rate(k, len(done)) if done else '-'}"
                   + (f" ({len(hid) - len(done)} set(s) failed before an answer)"
                      if len(done) < len(hid) else ""))
        tied = [r for r in hid if r["tied"]]
        if tied:
            named = sum(r["after_outcome"] == "hit" for r in tied)
            honest = sum(r["after_outcome"] == "tie" for r in tied)
            out.append(f"tied sets named before: {_rate(0, len(tied))} (a tie names nothing)")
            lo, _ = wilson(named, len(tied))
            verdict = ("goal met" if lo >= GOAL_NAMED else
                       "goal not met" if named / len(tied) < GOAL_NAMED else
                       "goal met in the estimate, not at its 95 % lower bound")
            out.append(f"tied sets named after the designed run: {_rate(named, len(tied))} "
                       f"(goal >= {100 * GOAL_NAMED:.0f} %: {verdict}); honest ties after "
                       f"{honest}, misses {len(tied) - named - honest} (errors included)")
            unmet = sum(r["met"] is False for r in tied)
            if unmet:
                out.append(f"  designs that did not reach their margin: {unmet}/{len(tied)}")
        else:
            out.append("no hidden-effect set tied before: the naming rate is undefined")
    if nul:
        done = [r for r in nul if r["before"] is not None]
        fa_b = sum(r["before"][0] == "add" for r in done)
        fa_a = sum(r["after"] is not None and r["after"][0] == "add" for r in done)
        if done:
            out.append(f"false-alarm rate (a clean or outside-library set adds an effect): "
                       f"before {_rate(fa_b, len(done))}, after {_rate(fa_a, len(done))}")
            what = Counter(r["after"][1][0] for r in done
                           if r["after"] is not None and r["after"][0] == "add")
            if what:
                out.append("  added after: " + ", ".join(f"{k} {v}" for k, v in
                                                         what.most_common()))
            ties = sum(r["diagnosis"] is not None and r["diagnosis"][0] == "tie"
                       and r["before"][0] == "add" for r in done)
            if ties:
                out.append(f"  of the false alarms before, {ties} were the diagnosis's ties "
                           "decided by settle_tie")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=22,
                    help="total sets, spread evenly over the cases (default 22)")
    ap.add_argument("--effects", default="",
                    help="comma-separated cases (default: all of bench_independent's; "
                         "'none' for clean, 'outside' for the outside-library effect)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel sets (joblib)")
    ap.add_argument("--seed0", type=int, default=1, help="seed of the first set (default 1)")
    ap.add_argument("--seeds", default="",
                    help="comma-separated seeds instead of seed0, seed0 + 1, ... (one per "
                         "set, cycling over the cases as the default plan does)")
    args = ap.parse_args(argv)
    cases = tuple(e.strip() for e in args.effects.split(",") if e.strip()) or CASES
    unknown = set(cases) - set(CASES)
    if unknown:
        ap.error(f"unknown case(s) {', '.join(sorted(unknown))}; valid: {', '.join(CASES)}")
    if args.seeds:
        try:
            seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
        except ValueError:
            ap.error(f"--seeds {args.seeds!r}: expected comma-separated integers")
        plan = [(cases[i % len(cases)], s) for i, s in enumerate(seeds)]
    else:
        if args.sets < 1:
            ap.error("--sets must be >= 1")
        plan = schedule(cases, args.sets, args.seed0)
    t0 = time.perf_counter()
    print(f"{'case':26s} {'seed':>4s}  {'outcome':11s} before -> designed run -> after  "
          "[strength; step times s]", flush=True)
    rows = []
    for r in Parallel(n_jobs=args.jobs, return_as="generator_unordered")(
            delayed(one_set)(c, s) for c, s in plan):
        rows.append(r)
        print(_line(r), flush=True)
    order = {cs: i for i, cs in enumerate(plan)}
    rows.sort(key=lambda r: order[(r["case"], r["seed"])])
    wall = time.perf_counter() - t0
    print()
    for line in summary(rows):
        print(line)
    med = []
    for k in STEPS:
        v = sorted(r["times"][k] for r in rows if k in r["times"])
        if v:
            med.append(f"{k} {v[len(v) // 2]:.0f}")
    totals = sorted(sum(r["times"].values()) for r in rows)
    print(f"per set ({args.jobs} at once on this machine), median s: " + ", ".join(med)
          + f"; a whole set median {totals[len(totals) // 2]:.0f} s, longest "
          f"{totals[-1]:.0f} s; {len(rows)} sets in {wall:.0f} s")


if __name__ == "__main__":
    main()
