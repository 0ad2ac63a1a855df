"""Mutants of the default inputs: the command either runs to finite output or refuses in a
few lines, never with a traceback, never after the work has started.

A mutant is one of four inputs (the default scenario, the default instrument, a sweep file,
a simulated measurement) with one value changed: a key deleted, a value replaced by another
type (text, a boolean, a list, a table), made negative, zero, NaN, infinite, huge (1e300,
2**62) or tiny (1e-300), a list emptied or its first entry doubled; for the measurement also
a CSV column deleted, put in another unit (x3600, /3600, x9.81, +273.15, sign) or one sample
changed.  The real command line runs it in-process on a cheap path (``nfs table
--no-compensation`` on one start-up, ``nfs simulate``, ``nfs sweep --jobs 1`` of one cell,
``nfs northfind``).

Oracle (an invariant of the command line, docs/measurement-format.md and nfs.errors): exit 0
with no NaN or infinity in what it prints or writes, or exit 2 with at most 3 lines on stderr,
the last ``nfs: error: ...``, no traceback, and no run file written (refused before any work).

Hypothesis draws the mutants with ``derandomize=True``: the default run is the same 40
mutants every time (about 15 s); the slow profile draws 600 (``pytest -m slow -s
tests/test_mutants.py`` prints the count of each outcome).
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import re
import tempfile
import tomllib
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nfs.cli import main
from nfs.instrument import preset_path
from nfs.config.presets import default_scenario_path
from nfs.io.tomlio import dumps_toml

TINY = ('start_temperatures_c = [17.0]\nduration_s = 1200.0\n[compensation]\n'
        'test_repeats = 1\n')

#: Replacement values of a TOML leaf: (name, value or a function of the old value).
VALUE_MUTATIONS = (
    ("delete", None), ("text", "abc"), ("bool", True), ("list", [1.0]), ("table", {"x": 1.0}),
    ("negative", lambda v: -v if _is_number(v) and v else -1.0), ("zero", 0),
    ("nan", math.nan), ("inf", math.inf), ("-inf", -math.inf), ("huge", 1e300),
    ("huge int", 2 ** 62), ("tiny", 1e-300), ("empty list", []),
    ("doubled entry", lambda v: [v[0], *v] if isinstance(v, list) and v else [v, v]),
)

#: Changes of a whole CSV column of the measurement.
COLUMN_MUTATIONS = (
    ("delete", None), ("x3600", lambda c: c * 3600.0), ("/3600", lambda c: c / 3600.0),
    ("x9.81", lambda c: c * 9.80665), ("+273.15", lambda c: c + 273.15),
    ("sign", lambda c: -c), ("all nan", lambda c: c * math.nan),
)

#: Replacements of one CSV sample.
SAMPLE_MUTATIONS = ("nan", "inf", "-inf", "1e300", "-1e300", "0", "-1", "1e-300", "abc", "")


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _paths(tree, path=()):
    """Every key path of a parsed TOML tree, containers and leaves (dict keys, list items)."""
    items = tree.items() if isinstance(tree, dict) else enumerate(tree) \
        if isinstance(tree, list) else ()
    for k, v in items:
        yield (*path, k)
        yield from _paths(v, (*path, k))


def _mutated(tree, path, mutation):
    out = copy.deepcopy(tree)
    parent = out
    for k in path[:-1]:
        parent = parent[k]
    name, value = mutation
    if name == "delete":
        del parent[path[-1]]
    else:
        parent[path[-1]] = value(parent[path[-1]]) if callable(value) else value
    return out


# -- the four inputs, built once

_CACHE: dict = {}


def _workdir() -> Path:
    return _CACHE["dir"]


def _bases() -> dict:
    if "bases" in _CACHE:
        return _CACHE["bases"]
    work = _workdir()
    scenario = tomllib.loads(default_scenario_path().read_text())
    scenario.update(start_temperatures_c=[17.0], duration_s=1200.0)
    scenario["compensation"]["test_repeats"] = 1
    instrument = tomllib.loads(preset_path("default").read_text())
    (work / "tiny.toml").write_text(TINY)
    sweep = {"scenario": str(work / "tiny.toml"), "seeds": [1], "spec_deg": 0.02,
             "rmse_window_cycles": 5,
             "axes": {"schedule": {"dwell_s": [150.0]},
                      "gyro.arw_deg_per_rth_h": {"low": 0.0003, "high": 0.001}},
             "draws": {"sampler": "random", "count": 1, "seed": 0}}
    run_dir = work / "run"
    code = main(["simulate", str(work / "tiny.toml"), "-o", str(run_dir), "-q"])
    assert code == 0
    csv = next(run_dir.glob("*.csv"))
    header, *rows = csv.read_text().splitlines()
    measurement = {"sidecar": tomllib.loads(csv.with_suffix(".toml").read_text()),
                   "columns": header.split(","),
                   "data": np.array([[float(x) for x in r.split(",")] for r in rows])}
    _CACHE["bases"] = {"scenario": scenario, "instrument": instrument, "sweep": sweep,
                       "measurement": measurement}
    _CACHE["paths"] = {k: list(_paths(v)) for k, v in _CACHE["bases"].items()
                       if k != "measurement"}
    _CACHE["paths"]["measurement"] = list(_paths(measurement["sidecar"]))
    return _CACHE["bases"]


# -- one mutant through the command line

def _run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:                     # argparse
            code = exc.code
    return code, out.getvalue(), err.getvalue()


_NON_FINITE = re.compile(r"\b(nan|inf|infinity)\b", re.I)


def _write_measurement(folder: Path, base: dict, sidecar: dict, column_change) -> Path:
    names, data = list(base["columns"]), base["data"].copy()
    texts = [[repr(float(x)) for x in row] for row in data]
    if column_change is not None:
        kind, col, change, row = column_change
        j = names.index(col)
        if kind == "column" and change[0] == "delete":
            names.pop(j)
            texts = [r[:j] + r[j + 1:] for r in texts]
        elif kind == "column":
            new = change[1](data[:, j])
            for i, r in enumerate(texts):
                r[j] = repr(float(new[i]))
        else:
            texts[row][j] = change
    csv = folder / "run.csv"
    csv.write_text(",".join(names) + "\n" + "\n".join(",".join(r) for r in texts) + "\n")
    (folder / "run.toml").write_text(dumps_toml(sidecar) + "\n")
    return csv


def _mutant(data) -> str:
    """Draw one mutant, run it, check the oracle; the outcome's name."""
    bases = _bases()
    target = data.draw(st.sampled_from(("scenario", "instrument", "sweep", "measurement")),
                       label="input")
    base = bases[target]
    column_change = None
    if target == "measurement" and data.draw(st.booleans(), label="a CSV column"):
        col = data.draw(st.sampled_from(base["columns"]), label="column")
        if data.draw(st.booleans(), label="whole column"):
            change = data.draw(st.sampled_from(COLUMN_MUTATIONS), label="change")
            column_change, what = ("column", col, change, None), f"{col} {change[0]}"
        else:
            row = data.draw(st.integers(0, len(base["data"]) - 1), label="row")
            value = data.draw(st.sampled_from(SAMPLE_MUTATIONS), label="sample")
            column_change, what = ("sample", col, value, row), f"{col}[{row}] = {value!r}"
        tree = base["sidecar"]
    else:
        path = data.draw(st.sampled_from(_CACHE["paths"][target]), label="key")
        mutation = data.draw(st.sampled_from(VALUE_MUTATIONS), label="mutation")
        tree = _mutated(base["sidecar"] if target == "measurement" else base, path, mutation)
        what = f"{'.'.join(map(str, path))} {mutation[0]}"
    work = Path(tempfile.mkdtemp(dir=_workdir()))
    out_dir = work / "out"
    if target == "scenario":
        (work / "s.toml").write_text(dumps_toml(tree) + "\n")
        argv = ["table", work / "s.toml", "--no-compensation", "-q", "-o", out_dir]
    elif target == "instrument":
        (work / "i.toml").write_text(dumps_toml(tree) + "\n")
        (work / "s.toml").write_text(f'instrument = "{work / "i.toml"}"\n' + TINY)
        argv = ["simulate", work / "s.toml", "-q", "-o", out_dir]
    elif target == "sweep":
        (work / "w.toml").write_text(dumps_toml(tree) + "\n")
        argv = ["sweep", work / "w.toml", "-q", "--jobs", "1", "-o", out_dir]
    else:
        csv = _write_measurement(work, base, tree, column_change)
        argv = ["northfind", csv]
    code, out, err = _run(argv)
    errors = [line for line in err.splitlines() if line.strip()]
    context = f"{target}: {what}: exit {code}\nstdout: {out[-800:]}\nstderr: {err[-1500:]}"
    assert "Traceback" not in err, context
    if code == 0:
        assert not _NON_FINITE.search(out), context
        assert all(line.startswith("nfs: ") for line in errors), context
        for csv_path in out_dir.glob("*.csv") if target == "instrument" else ():
            values = np.genfromtxt(csv_path, delimiter=",", skip_header=1)
            assert np.isfinite(values).all(), context
    else:
        assert code == 2, context
        assert 1 <= len(errors) <= 3 and errors[-1].startswith("nfs: error: "), context
        assert not list(out_dir.rglob("*.csv")), context      # refused before any work
    return f"{target} exit {code}"


COUNTS: Counter = Counter()


def _property(data):
    COUNTS[_mutant(data)] += 1


def _profile(n: int):
    return settings(max_examples=n, derandomize=True, database=None, deadline=None,
                    suppress_health_check=list(HealthCheck), print_blob=True)


def _start(folder: Path) -> None:
    """A fresh cache of the inputs, built in ``folder`` (pytest's tmp_path)."""
    _CACHE.clear()
    _CACHE["dir"] = folder
    COUNTS.clear()


def test_mutants_short_profile(tmp_path):
    _start(tmp_path)
    _profile(40)(given(data=st.data())(_property))()
    assert sum(COUNTS.values()) >= 40
    assert {k.split()[0] for k in COUNTS} == {"scenario", "instrument", "sweep",
                                              "measurement"}, COUNTS


@pytest.mark.slow
def test_mutants_long_profile(tmp_path):
    _start(tmp_path)
    _profile(600)(given(data=st.data())(_property))()
    print("\nmutants: " + ", ".join(f"{k}: {v}" for k, v in sorted(COUNTS.items()))
          + f" ({sum(COUNTS.values())} in all)")
    assert sum(COUNTS.values()) >= 500
