"""Tables, figures and reports."""

from .baseline import BaselineComparison, CellChange, compare_tables, write_baseline_comparison
from .table import HeadingTable, TableRow, plot_heading_table, pooled_rmse, write_table
from .tablefile import TableData, read_table

__all__ = ["HeadingTable", "TableRow", "plot_heading_table", "pooled_rmse", "write_table",
           "BaselineComparison", "CellChange", "compare_tables", "write_baseline_comparison",
           "TableData", "read_table"]
