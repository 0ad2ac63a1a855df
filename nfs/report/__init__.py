"""Tables, figures and reports."""

from .table import HeadingTable, TableRow, plot_heading_table, pooled_rmse, write_table

__all__ = ["HeadingTable", "TableRow", "plot_heading_table", "pooled_rmse", "write_table"]
