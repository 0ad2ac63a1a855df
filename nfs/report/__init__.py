"""Renderers: the heading table's files and figure, the compensation, drift, cycle and
parameter reports, the comparison with a baseline table, the Allan deviation of a set of
runs (Markdown, CSV, JSON, PNG)."""

from ..errors import moved_names
from .allan_figure import allan_figure, plot_allan, write_allan
from .baseline import baseline_comparison_markdown, write_baseline_comparison
from .table_files import plot_heading_table, write_table

__all__ = ["plot_heading_table", "write_table", "baseline_comparison_markdown",
           "write_baseline_comparison", "plot_allan", "allan_figure", "write_allan"]

#: Statistics that moved to :mod:`nfs.scoring` (nfs/scoring/baseline.py).
_MOVED = dict.fromkeys(["BaselineComparison", "CellChange", "compare_tables"],
                       "nfs.scoring.baseline")

__getattr__ = moved_names('nfs.report', _MOVED)
