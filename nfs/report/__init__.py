"""Renderers: the heading table's files and figure, the compensation, drift, cycle and
parameter reports, the comparison with a baseline table (Markdown, CSV, JSON, PNG)."""

import warnings
from importlib import import_module

from .baseline import baseline_comparison_markdown, write_baseline_comparison
from .table_files import plot_heading_table, write_table

__all__ = ["plot_heading_table", "write_table", "baseline_comparison_markdown",
           "write_baseline_comparison"]

#: Statistics that moved to :mod:`nfs.scoring` (nfs/scoring/baseline.py).
_MOVED = dict.fromkeys(["BaselineComparison", "CellChange", "compare_tables"],
                       "nfs.scoring.baseline")


def __getattr__(name: str):
    """A name that moved: warn and hand it over, for one release (PEP 562)."""
    module = _MOVED.get(name)
    if module is None:
        raise AttributeError(f"module 'nfs.report' has no attribute {name!r}")
    warnings.warn(f"nfs.report.{name} moved to nfs.scoring.{name}; import it from there "
                  "(the old name goes in the next release)", DeprecationWarning, stacklevel=2)
    return getattr(import_module(module), name)
