"""Fixtures of the tests of ``nfs import``: a chamber log of three files written from a run
the package simulates (tests/io/chamber_logs.py)."""

from __future__ import annotations

import shutil

import pytest

from chamber_logs import simulate, write_log


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """The simulated run the log is written from."""
    return simulate(tmp_path_factory.mktemp("simulated"))


@pytest.fixture(scope="module")
def written_log(simulated, tmp_path_factory):
    """The folder of the three-file log of ``simulated`` (do not change it: copy it)."""
    return write_log(simulated, tmp_path_factory.mktemp("log")).parent


@pytest.fixture
def log(written_log, tmp_path):
    """A copy of the log to change: its mapping's path."""
    folder = tmp_path / "log"
    shutil.copytree(written_log, folder)
    return folder / "log.toml"
