"""Fixtures shared by the test modules."""

import pytest

from nfs.cli import main


@pytest.fixture
def cli(capsys):
    """Run ``nfs ARGV...`` in-process: returns (exit code, stdout, stderr)."""
    def run(*argv):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err
    return run
