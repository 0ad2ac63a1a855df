"""Scoring: heading RMSE by stage and start temperature, bootstrap intervals and paired
comparisons, and the heading table as data (renderers are in :mod:`nfs.report`)."""

from .heading_table import (NOT_APPLICABLE, REFERENCE_ROWS, STAGE_ROWS, HeadingTable, TableRow,
                            pooled_rmse)
from .intervals import PairedComparison, bc_interval, cluster_bootstrap, compare_rows
from .tablefile import TableData, read_table

__all__ = ["HeadingTable", "TableRow", "pooled_rmse", "NOT_APPLICABLE", "REFERENCE_ROWS",
           "STAGE_ROWS", "PairedComparison", "bc_interval", "cluster_bootstrap", "compare_rows",
           "TableData", "read_table"]
