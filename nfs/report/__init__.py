"""Renderers: the heading table's files and figure, the compensation, drift, cycle and
parameter reports, the comparison with a baseline table (Markdown, CSV, JSON, PNG)."""

from ..scoring.baseline import BaselineComparison, CellChange, compare_tables
from .baseline import baseline_comparison_markdown, write_baseline_comparison
from .table_files import plot_heading_table, write_table

# BaselineComparison, CellChange and compare_tables are statistics and live in nfs.scoring
# (nfs/scoring/baseline.py); they stay importable from here, where they were documented,
# for one release.
__all__ = ["plot_heading_table", "write_table", "BaselineComparison", "CellChange",
           "compare_tables", "baseline_comparison_markdown", "write_baseline_comparison"]
