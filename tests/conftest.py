"""Fixtures shared by the test modules."""

import os

import pytest
from threadpoolctl import threadpool_limits

from nfs.cli import main

if os.environ.get("PYTEST_XDIST_WORKER"):
    # Each pytest-xdist worker is one of the run's processes: a BLAS pool per worker as
    # well would oversubscribe the cores (two workers of two threads on two cores spend
    # their time waiting on each other).
    threadpool_limits(1)


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
