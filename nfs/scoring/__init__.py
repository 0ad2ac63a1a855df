"""Scoring: heading RMSE by stage and start temperature, bootstrap intervals and paired
comparisons, the heading table as data, and a table's comparison with a baseline table
(renderers are in :mod:`nfs.report`)."""

from .baseline import BaselineComparison, CellChange, compare_tables
from .heading_table import (NOT_APPLICABLE, REFERENCE_ROWS, STAGE_ROWS, HeadingTable, TableRow,
                            pooled_rmse)
from .intervals import PairedComparison, bc_interval, cluster_bootstrap, compare_rows
from .tablefile import TableData, read_table

__all__ = ["HeadingTable", "TableRow", "pooled_rmse", "NOT_APPLICABLE", "REFERENCE_ROWS",
           "STAGE_ROWS", "PairedComparison", "bc_interval", "cluster_bootstrap", "compare_rows",
           "TableData", "read_table", "BaselineComparison", "CellChange", "compare_tables"]
