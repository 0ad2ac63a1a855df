"""Fixtures and hooks shared by the test modules.

Optional dependencies.  A test that needs what the package itself does not (optuna,
pyarrow, Dask, an environment variable) is marked ``@pytest.mark.requires("optuna")``
(module names; ``env="NAME"`` for a variable that must be set).  Without it the test is not
run: it is deselected at collection and the run ends with one line that names what is
missing and how many tests it cost, instead of one skip per test.  scikit-learn's estimator
checks are marked here by name (:data:`SKLEARN_CHECK_NEEDS`); the part of a check that
scikit-learn itself skips without pandas, after the rest of the check ran, is counted on
that line too (the ``sklearn_check`` fixture).
"""

import collections
import importlib.util
import os
import re
from unittest import SkipTest

import pytest
from threadpoolctl import threadpool_limits

from nfs.cli import main

if os.environ.get("PYTEST_XDIST_WORKER"):
    # Each pytest-xdist worker is one of the run's processes: a BLAS pool per worker as
    # well would oversubscribe the cores (two workers of two threads on two cores spend
    # their time waiting on each other).
    threadpool_limits(1)


# ------------------------------------------------------------------------------------------
# optional dependencies: one line for the tests they cost

#: scikit-learn's estimator checks (``parametrize_with_checks``) that skip as a whole without
#: an optional dependency: check name -> (modules, environment variables) it needs.
#: check_array_api_input reads SCIPY_ARRAY_API, which must be set before SciPy is imported.
SKLEARN_CHECK_NEEDS = {"check_array_api_input": ((), ("SCIPY_ARRAY_API",))}
#: scikit-learn's checks that run their other parts first and then skip the part that needs
#: pandas (check_regressor_data_not_an_array: NotAnArray inputs, then a DataFrame).
SKLEARN_CHECKS_PARTLY_PANDAS = ("check_regressor_data_not_an_array",)
#: scikit-learn's words for a missing optional dependency ("pandas is not installed: ...",
#: "SCIPY_ARRAY_API is not set: ...")
_SKLEARN_NEED = re.compile(r"^(\S+) is not (?:installed|set)\b")

#: what is missing -> tests deselected for it ("tests": how many in all); in this process, or
#: under pytest-xdist, as the first worker to finish collected it (each collects the whole run)
_NOT_RUN: dict[str, int] = {}
#: what is missing -> tests that ran without a part that needs it; and how many in all
_PART_RUN: collections.Counter = collections.Counter()
#: the key of both: a worker's output to the controller, a test report's user property
_KEY = "nfs-optional-not-run"


def _importable(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


def _check_name(item) -> str | None:
    """The name of the scikit-learn check an item of parametrize_with_checks runs."""
    check = getattr(getattr(item, "callspec", None), "params", {}).get("check")
    if check is None:
        return None
    return getattr(getattr(check, "func", check), "__name__", None)


def _missing(item) -> list[str]:
    """What ``item`` needs and this environment lacks (module names, then variables)."""
    modules, env = [], []
    for mark in item.iter_markers("requires"):
        modules += mark.args
        wanted = mark.kwargs.get("env", ())
        env += [wanted] if isinstance(wanted, str) else list(wanted)
    sk_modules, sk_env = SKLEARN_CHECK_NEEDS.get(_check_name(item), ((), ()))
    return ([m for m in (*modules, *sk_modules) if not _importable(m)]
            + [v for v in (*env, *sk_env) if not os.environ.get(v)])


@pytest.hookimpl(trylast=True)        # after -m and -k have deselected what they do
def pytest_collection_modifyitems(config, items):
    kept, dropped, counts = [], [], collections.Counter()
    for item in items:
        missing = _missing(item)
        (dropped if missing else kept).append(item)
        counts.update(missing)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept
    _NOT_RUN.clear()
    _NOT_RUN.update(counts, tests=len(dropped))
    if hasattr(config, "workeroutput"):      # a pytest-xdist worker: tell the controller
        config.workeroutput[_KEY] = dict(_NOT_RUN)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    got = getattr(node, "workeroutput", {}).get(_KEY)
    if got and not _NOT_RUN:
        _NOT_RUN.update(got)


def pytest_runtest_logreport(report):
    if report.when == "call":
        needs = {need for key, need in report.user_properties if key == _KEY}
        _PART_RUN.update(needs)
        _PART_RUN["tests"] += bool(needs)


def pytest_terminal_summary(terminalreporter):
    not_run, part = dict(_NOT_RUN), dict(_PART_RUN)
    n_not_run, n_part = not_run.pop("tests", 0), part.pop("tests", 0)
    if not n_not_run and not n_part:
        return
    names = sorted(set(not_run) | set(part))
    packages = [n for n in names if not n.isupper()]
    variables = [n for n in names if n.isupper()]
    what = "; ".join(
        ([f"optional packages not installed: {', '.join(packages)}"] if packages else [])
        + ([f"{', '.join(variables)} not set"] if variables else []))

    def by_need(counts):
        return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    cost = ([f"{n_not_run} tests not run ({by_need(not_run)})"] if n_not_run else []) \
        + ([f"{n_part} run in part ({by_need(part)})"] if n_part else [])
    terminalreporter.write_line(f"{what}: {', '.join(cost)}")


@pytest.fixture
def sklearn_check(request):
    """Run one of scikit-learn's estimator checks: ``sklearn_check(check, estimator)``.

    A check of :data:`SKLEARN_CHECKS_PARTLY_PANDAS` runs its other parts and then skips the
    part that needs pandas when pandas is not installed: the parts that ran passed, and the
    part left out is counted on the run's last line.  Any other skip stays a skip."""
    def run(check, estimator):
        try:
            check(estimator)
        except SkipTest as exc:
            if not str(exc).startswith("pandas is not installed") \
                    or _check_name(request.node) not in SKLEARN_CHECKS_PARTLY_PANDAS:
                raise
            request.node.user_properties.append((_KEY, "pandas"))
    return run


@pytest.fixture
def optional_skip(request):
    """``optional_skip(message)``: for a scikit-learn skip message that names a missing
    optional dependency ("pandas is not installed: ...", "SCIPY_ARRAY_API is not set: ..."),
    count it on the run's last line and return its name; None for any other message."""
    def note(message):
        m = _SKLEARN_NEED.match(message)
        if m is None:
            return None
        request.node.user_properties.append((_KEY, m.group(1)))
        return m.group(1)
    return note


# ------------------------------------------------------------------------------------------
# the command line


@pytest.fixture
def cli(capsys):
    """Run ``nfs ARGV...`` in-process: returns (exit code, stdout, stderr)."""
    def run(*argv):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err
    return run


def _scenario_text(name, seed, start_temperatures_c, duration_s, *, latitude_deg=30.0,
                   true_heading_deg=40.0, extra=""):
    temps = ", ".join(f"{t!r}" for t in start_temperatures_c)
    return (f'\nname = "{name}"\nseed = {seed}\nstart_temperatures_c = [{temps}]\n'
            f"duration_s = {duration_s!r}\nlatitude_deg = {latitude_deg!r}\n"
            f"true_heading_deg = {true_heading_deg!r}\n[schedule]\n"
            "positions_deg = [0.0, 90.0, 180.0, 270.0]\ndwell_s = 150.0\nmove_s = 10.0\n"
            + extra)


@pytest.fixture(scope="session")
def scenario_text():
    """Text of a small scenario file for the command-line tests:
    ``scenario_text(name, seed, temps, duration_s, latitude_deg=30, true_heading_deg=40,
    extra="")`` with the 4-position schedule (dwell 150 s, move 10 s); ``extra`` is appended
    (e.g. a ``[compensation]`` table)."""
    return _scenario_text
