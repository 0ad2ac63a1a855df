"""Renderers: the heading table's files and figure, the compensation, drift, cycle and
parameter reports, the comparison with a baseline table (Markdown, CSV, JSON, PNG)."""

from .baseline import BaselineComparison, CellChange, compare_tables, write_baseline_comparison
from .table_files import plot_heading_table, write_table

__all__ = ["plot_heading_table", "write_table", "BaselineComparison", "CellChange",
           "compare_tables", "write_baseline_comparison"]
